"""Status and physics warnings end to end: issued and recorded, integer statuses in the files,
and what each solver reports when it fails."""
import json
import warnings

import pytest

from conftest import SCENARIOS
from tca_casadi import PhysicsWarning, Simulation
from tca_casadi.solvers import shooting
from tca_casadi.status import Status

BENDING = SCENARIOS / "bending_module.yaml"
PUSHED = ["bending.tca2.temperature=25", "bending.tca3.temperature=25",
          "loads=[{name: push, kind: point, module: bending, force: [0.02, 0, 0]}]"]


def test_physics_warnings_are_issued_recorded_and_written(tmp_path):
    sim = Simulation.from_file(BENDING, PUSHED)
    with pytest.warns(PhysicsWarning) as issued:
        solution = sim.solve()
    assert solution.converged and solution.status == Status.CONVERGED
    assert [w.kind for w in solution.warnings] == ["compression"]
    assert [w.message for w in issued] == solution.warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")                        # nothing is issued with warn=False
        quiet = sim.solve(warm_start=solution, warn=False)
    assert quiet.warnings == solution.warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", PhysicsWarning)        # a user can make them exceptions
        with pytest.raises(PhysicsWarning, match="bending.tca1 is in compression"):
            sim.solve(warm_start=solution)
    data = json.loads(solution.save(tmp_path)[0].read_text())
    assert data["status"] == 0 and data["result"]["success"] is True
    assert data["warning_kinds"] == ["compression"] and "compression" in data["warnings"][0]


def test_ipopt_at_its_iteration_limit():
    sim = Simulation.from_file(BENDING, ["solver.max_iterations=1", "solver.algorithm=ipopt"])
    solution = sim.solve(continuation="never", warn=False)
    assert not solution.converged and solution.status == Status.MAX_ITERATIONS
    assert solution.result.algorithm == "IPOPT" and solution.iterations == 1
    assert solution.to_dict()["status"] == 1
    assert solution.warnings[0].kind == "not_converged" and "iteration limit" in str(solution.warnings[0])


def test_a_stalled_continuation_says_so():
    sim = Simulation.from_file(BENDING, ["tip_force.force=[0, 0, 5]"])
    solution = sim.solve(warn=False)
    assert not solution.converged and solution.status == Status.STALLED
    assert solution.max_residual > solution.result.tolerance        # judged at the user's parameters


def test_failed_shots_are_an_integration_failure(monkeypatch):
    monkeypatch.setattr(shooting, "RHS_BUDGET", 3)      # every shot is abandoned
    sim = Simulation.from_file(SCENARIOS / "analytic" / "tip_load.yaml", method="shooting")
    solution = sim.solve(continuation="never", warn=False)
    assert solution.status == Status.INTEGRATION_FAILED and solution.max_residual == float("inf")


def test_the_shooting_tolerance_floor_is_a_warning():
    solver = Simulation.from_file(BENDING, ["solver.tolerance=1e-12"]).solver("shooting")
    assert solver.tolerance == shooting.TOLERANCE_FLOOR
    [floored] = solver._notices(5e-10)
    assert floored.kind == "tolerance_floor" and "5.0e-10" in str(floored)
    assert solver._notices(1e-13) == [] and solver._notices(2e-9) == []

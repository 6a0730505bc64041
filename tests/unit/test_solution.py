"""The Solution (solution.py): what it writes is what it holds, its failure is never hidden, its
iterate is typed; on a tendon-loaded rod whose equilibrium is known in closed form."""
import json

import numpy as np
import pytest
from analytic import beam_scenario, tendon_arc
from numpy.testing import assert_allclose

from tca_casadi import Simulation
from tca_casadi.errors import SolverError
from tca_casadi.solution import Iterate

TENSION, OFFSET = 0.05, 0.002


@pytest.fixture(scope="module")
def tendon_rod():
    tendon = {"name": "tendon", "kind": "tendon", "tension": TENSION,
              "route": {"kind": "straight", "radius": OFFSET, "angle": 0.0}}
    scenario = beam_scenario(intervals=8, actuators=[tendon])
    scenario["solver"]["refine"] = "off"
    sim = Simulation.from_file(scenario)
    return sim, sim.solve(warn=False)


def test_the_solution_holds_the_closed_form_and_writes_what_it_holds(tendon_rod, tmp_path):
    sim, solution = tendon_rod
    module = sim.robot.modules[0]
    u, v3 = tendon_arc(TENSION, OFFSET, module.stiffness[0], module.stiffness[5])
    assert_allclose(np.abs(solution.modules[0].u[1]), u, rtol=1e-9)            # the curvature of the arc
    assert_allclose(solution.modules[0].v[2], v3, rtol=0, atol=1e-12)
    json_path, npz_path = solution.save(tmp_path)
    written = json.loads(json_path.read_text())
    assert written["converged"] is True and written["method"] == "collocation"
    assert_allclose(written["tip"]["position"], solution.tip_position, rtol=0, atol=0)
    assert_allclose(written["actuators"]["rod.tendon"]["tension"], TENSION, rtol=0, atol=1e-15)
    assert written["global_balance"]["relative"] < 1e-9
    with np.load(npz_path) as arrays:
        assert_allclose(arrays["rod/p"], solution.modules[0].p, rtol=0, atol=0)
        assert arrays["rod.tendon/path"].shape == solution.actuators["rod.tendon"].path.shape
    assert f"{1e3 * solution.tip_position[2]:+.4f}" in solution.summary()


def test_the_iterate_is_typed_and_fits_only_its_solver(tendon_rod):
    sim, solution = tendon_rod
    iterate, size = solution.iterate, sim.solver().nlp.scale.size
    assert isinstance(iterate, Iterate) and iterate.method == "collocation" and iterate.values is iterate.w
    assert iterate.fits("collocation", size) and not iterate.fits("shooting", size)
    assert not iterate.fits("collocation", size + 1) and not Iterate("shooting", z=np.zeros(3)).fits("shooting", 3)


def test_a_failed_solve_raises_only_when_asked(tendon_rod):
    sim, _ = tendon_rod
    scenario = sim.scenario.model_dump(mode="json")
    scenario["solver"].update(algorithm="ipopt", continuation="never", max_iterations=1)
    failed = Simulation.from_file(scenario).solve(warn=False)
    assert not failed.converged and failed.to_dict()["converged"] is False
    assert failed.warnings[0].kind == "not_converged" and "NOT CONVERGED" in failed.summary()
    with pytest.raises(SolverError) as raised:
        failed.raise_if_failed()
    assert raised.value.solution is failed

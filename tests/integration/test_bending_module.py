"""The paper's 3D bending module: direction of bending, the passive TCA, warm re-solves."""
import numpy as np
from numpy.testing import assert_allclose
import pytest

from tca_casadi import Simulation


@pytest.fixture(scope="module")
def bending(request):
    from conftest import SCENARIOS
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    return sim, sim.solve()


def test_heated_tcas_bend_the_module_away_from_tca1(bending):
    sim, solution = bending
    assert solution.converged
    tca1_direction = np.array([1.0, 0.0, 0.0])     # body +x at the base = global +x (hanging)
    tip_shift = solution.tip_position - np.array([0, 0, -0.045])
    assert tip_shift @ tca1_direction < -5e-3        # more than 5 mm away from TCA 1
    assert abs(tip_shift[1]) < 1e-9                  # TCA 2 and 3 equally heated: no sideways bend


def test_passive_tca_is_stretched_and_in_tension(bending):
    _, solution = bending
    tca1 = solution.actuators["bending.tca1"]
    assert tca1.stroke > 0 and tca1.tension > 0
    for key, actuator in solution.actuators.items():
        assert actuator.tension > 0, key                 # the physical branch
    heated = solution.actuators["bending.tca2"]
    assert heated.free_stroke < heated.stroke < 0        # contracts, but less than free
    assert not solution.warnings


def test_law_holds_at_the_solution(bending):
    sim, solution = bending
    for actuator in sim.robot.tcas:
        result = solution.actuators[actuator.key]
        law = actuator.law
        assert result.stroke == pytest.approx(law.free_stroke(result.temperature) + law.stretch(result.tension),
                                              abs=1e-12)


def test_base_reaction_balances_the_weight(bending):
    sim, solution = bending
    module = sim.robot.modules[0]
    weight = module.weight_density * module.length * np.array(sim.get_parameter("gravity"))
    # each scaled equilibrium row holds to 10 x tolerance x EI/L^2 = 1.2e-12 N; 16 points add up
    assert solution.modules[0].base_reaction["force"] == pytest.approx(-weight, abs=2e-11)


def test_new_temperature_reuses_the_built_nlp_and_warm_starts(bending):
    from conftest import SCENARIOS
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    first = sim.solve()
    solver = sim.solver()
    solves = solver.solve_count     # a cold start at 100 degC continues from the reference state
    assert "continuation" in first.message  # cold start: followed up from the reference state
    sim.set("bending.tca2.temperature", "101 degC")
    sim.set("bending.tca3.temperature", 101)
    warm = sim.solve(warm_start=first)
    assert sim.solver() is solver and solver.solve_count == solves + 1   # no rebuild, one solve
    assert warm.converged and warm.iterations < first.iterations
    cold = Simulation.from_file(SCENARIOS / "bending_module.yaml",
                                ["bending.tca2.temperature=101", "bending.tca3.temperature=101"]).solve()
    assert_allclose(warm.modules[0].p, cold.modules[0].p, rtol=0, atol=1e-10)
    sim.set("bending.length", "40 mm")                             # structure: rebuilds
    assert sim.solver() is not solver


def test_cold_direct_solve_can_leave_the_physical_branch(scenarios):
    """SPEC section 6's trap, and why solve() continues from the reference state by default."""
    sim = Simulation.from_file(scenarios / "twisting_module.yaml")
    direct = sim.solve(continuation="never")
    assert not direct.converged or min(direct.tensions.values()) < 0     # the TCA pushes: wrong branch
    followed = sim.solve()
    assert followed.converged and min(followed.tensions.values()) > 0
    assert "continuation" in followed.message


def test_unconverged_solve_is_reported_as_such(scenarios):
    sim = Simulation.from_file(scenarios / "bending_module.yaml", ["solver.max_iterations=1"])
    solution = sim.solve(continuation="never")
    assert not solution.converged
    assert solution.warnings[0].kind == "not_converged"
    with pytest.raises(Exception, match="did not converge"):
        solution.raise_if_failed()


def test_compressed_passive_tca_is_reported(scenarios):
    """A tip force towards TCA 1 bends the cold module so that TCA 1 is on the concave side."""
    sim = Simulation.from_file(scenarios / "bending_module.yaml", [
        "bending.tca2.temperature=25", "bending.tca3.temperature=25",
        "loads=[{name: push, kind: point, module: bending, force: [0.02, 0, 0]}]"])
    solution = sim.solve()
    tca1 = solution.actuators["bending.tca1"]
    assert solution.converged and tca1.tension < 0 and tca1.stroke < 0
    assert any("bending.tca1 is in compression" in w for w in solution.warning_texts())
    law = sim.robot.tcas[0].law                      # the C1 extension of G_t below zero force
    assert tca1.stroke == pytest.approx(float(law.stretch(tca1.tension)), abs=1e-12)


def test_tension_beyond_the_fit_is_reported(scenarios):
    solution = Simulation.from_file(scenarios / "twisting_module.yaml", ["twisting.tca.temperature=140"]).solve()
    assert solution.converged and solution.actuators["twisting.tca"].tension > 0.1504
    assert any("beyond the fit's monotone range" in w for w in solution.warning_texts())

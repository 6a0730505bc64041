"""The solving strategy (solvers/strategy.py) behind a thin Simulation: parameters as arguments,
problems named, stall reports, the solvers it builds."""
import numpy as np
import pytest
from analytic import beam_scenario
from numpy.testing import assert_allclose

from tca_casadi import Simulation
from tca_casadi.errors import ScenarioError, TcaError
from tca_casadi.status import Status


@pytest.fixture
def beam():
    scenario = beam_scenario(intervals=8, loads=[{"name": "tip", "kind": "point", "module": "rod", "at": "end",
                                                   "force": [0.0, 0.0, 0.0], "frame": "global"}])
    scenario["solver"]["refine"] = "off"
    return Simulation.from_file(scenario)


def _with(sim, name, value):
    params = sim.params.copy()
    params[sim.robot.layout[name]] = value
    return params


def test_parameters_as_an_argument_equal_parameters_set(beam):
    loaded = _with(beam, "tip.force", [1e-3, 0, 0])
    by_argument = beam.solve(params=loaded, warn=False)
    assert_allclose(beam.params, loaded, rtol=0, atol=0)                    # kept as the current ones
    other = Simulation.from_file(beam.scenario.model_dump(mode="json"))
    other.set_parameter("tip.force", [1e-3, 0, 0])
    by_setting = other.solve(warn=False)
    assert_allclose(by_argument.tip_position, by_setting.tip_position, rtol=0, atol=1e-15)


def test_solve_at_leaves_the_simulations_state_alone(beam):
    first = beam.solve(warn=False)
    params = beam.params.copy()
    elsewhere = beam.solve_at(_with(beam, "tip.force", [0, 2e-3, 0]))
    assert elsewhere.converged and elsewhere.tip_position[1] > 1e-4
    assert beam.last is first and np.array_equal(beam.params, params)


def test_a_point_the_robot_cannot_take_is_named(beam):
    with pytest.raises(TcaError, match=r"module rod: E = -5 Pa .* must be positive"):
        beam.solve_near(None, _with(beam, "materials.m.youngs_modulus", -5.0))


def test_a_stall_report_says_how_far_it_got_at_the_requested_parameters(beam):
    strategy, solver = beam.strategy, beam.solver()
    rest, target = beam.params.copy(), _with(beam, "tip.force", [4e-3, 0, 0])
    halfway = beam.solve_at(rest + 0.5 * (target - rest))
    report = strategy.stalled(solver, halfway, rest, target, 0.5, 1e-3, "Newton did not converge", 7, 0.25)
    assert report.status == Status.STALLED and not report.converged and report.iterations == 7
    assert_allclose(report.parameters, target, rtol=0, atol=0)          # reported where it was asked
    detail = report.result.detail
    assert "stalled at lambda = 0.5000 of 1" in detail and "tip.force [0.002, 0, 0] of [0.004, 0, 0]" in detail
    assert detail.endswith("last step: Newton did not converge")


def test_the_strategy_builds_the_solvers_it_is_asked_for(beam):
    assert beam.solver("shooting").method == "shooting" and beam.solver() is beam.strategy.solver("collocation")
    with pytest.raises(ScenarioError, match="unknown solver method 'euler'; available: collocation, shooting"):
        beam.solver("euler")

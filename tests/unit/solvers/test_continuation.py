"""Continuation (solvers/continuation.py): the trapezoid test's error against its closed form on
synthetic branches, and the path walker against independent cold solves of a small beam."""
import numpy as np
import pytest
from analytic import beam_scenario, cantilever_deflection
from numpy.testing import assert_allclose

from tca_casadi import Simulation
from tca_casadi.solvers.continuation import NOISE, BranchFollower, BranchPoint, walk_branch


def _point(lam, w, rate):
    return BranchPoint(lam, None, np.asarray(w, float), np.asarray(rate, float))


def test_the_trapezoid_test_is_exact_on_a_quadratic_branch():
    # w(lam) = a lam + b lam^2: w' is linear, which the trapezoidal rule integrates exactly
    a, b = np.array([0.3, -2.0, 5.0]), np.array([1.5, 0.25, -4.0])
    w, rate = (lambda x: a * x + b * x * x), (lambda x: a + 2 * b * x)
    for lam0, h in [(0.0, 0.5), (0.2, 0.01), (0.7, 0.3)]:
        assert BranchFollower.inconsistency(_point(lam0, w(lam0), rate(lam0)),
                                            _point(lam0 + h, w(lam0 + h), rate(lam0 + h))) < 1e-14


@pytest.mark.parametrize("h", [0.2, 0.05, 0.01])
def test_the_trapezoid_error_of_a_cubic_branch_is_its_closed_form(h):
    # w = lam^3 from lam = 1: change 3h + 3h^2 + h^3, trapezoid error -h^3/2 exactly
    a, b = _point(1.0, [1.0], [3.0]), _point(1.0 + h, [(1 + h) ** 3], [3 * (1 + h) ** 2])
    assert_allclose(BranchFollower.inconsistency(a, b), 0.5 * h ** 3 / (3 * h + 3 * h ** 2 + h ** 3), rtol=1e-9)


def test_a_jump_to_another_branch_is_order_one_and_noise_is_nothing():
    a = _point(0.0, [1.0, 2.0], [1.0, 0.0])
    jumped = _point(0.01, [1.01 + 0.5, 2.0], [1.0, 0.0])         # the tangents say 0.01, it moved 0.51
    assert BranchFollower.inconsistency(a, jumped) > 0.9
    still = _point(0.5, [1.0 + 0.1 * NOISE, 2.0], [7.0, 7.0])     # below the solver's noise: no step at all
    assert BranchFollower.inconsistency(a, still) == 0.0


@pytest.fixture(scope="module")
def beam():
    """A short cantilever with a transverse tip force (a parameter)."""
    scenario = beam_scenario(intervals=8, loads=[{"name": "tip", "kind": "point", "module": "rod", "at": "end",
                                                   "force": [0.0, 0.0, 0.0], "frame": "global"}])
    scenario["solver"]["refine"] = "off"
    return Simulation.from_file(scenario)


def _with_force(sim, force):
    params = sim.params.copy()
    params[sim.robot.layout["tip.force"]] = force
    return params


def test_the_walker_reaches_every_target_as_independent_solves_do(beam):
    start_params, end_params = _with_force(beam, [0, 0, 0]), _with_force(beam, [2e-3, 0, 0])
    start = beam.solve_at(start_params)
    recorded = []
    walk = walk_branch(beam.solver(), start, start_params, end_params, targets=(0.25, 0.5, 1.0),
                       record=lambda point, substeps: recorded.append((point.lam, substeps)))
    assert walk.completed and walk.failure is None and walk.point.lam == 1.0
    assert [lam for lam, _ in walk.reached] == [0.25, 0.5, 1.0]
    assert [lam for lam, _ in recorded] == [0.0, 0.25, 0.5, 1.0] and recorded[0][1] == 0
    assert walk.substeps == sum(s for _, s in recorded) and walk.iterations > 0
    for lam, solution in walk.reached:                     # each against a cold solve at its parameters
        cold = beam.solve_at(start_params + lam * (end_params - start_params))
        assert_allclose(solution.tip_position, cold.tip_position, rtol=0, atol=1e-10)


def test_the_walked_deflection_is_the_beams(beam):
    # a small force (P L^2 / EI = 3e-3): the end deflection is Timoshenko's to the geometric
    # nonlinearity's order, (P L^2 / EI)^2 ~ 1e-5 relative
    force = 1e-5
    start_params = _with_force(beam, [0, 0, 0])
    walk = walk_branch(beam.solver(), beam.solve_at(start_params), start_params, _with_force(beam, [force, 0, 0]))
    module = beam.robot.modules[0]
    ei, ga = module.stiffness[0], module.stiffness[3]
    expected = cantilever_deflection(force, module.length, ei, ga)
    assert_allclose(walk.point.solution.tip_position[0], expected, rtol=1e-4)

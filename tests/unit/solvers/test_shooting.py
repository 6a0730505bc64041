"""The shooting solver (solvers/shooting.py) on its own: a pure end moment bends a rod into a
circular arc (closed form), and its exact (variational) Jacobian and forward differences reach
the same root."""
import numpy as np
import pytest
from analytic import beam_scenario
from numpy.testing import assert_allclose

from tca_casadi import Simulation
from tca_casadi.solvers.shooting import ShootingSolver

MOMENT = 1e-5          # [N m] about +x: the rod curls towards -y


@pytest.fixture(scope="module")
def arc():
    scenario = beam_scenario(loads=[{"name": "tip", "kind": "point", "module": "rod", "at": "end",
                                     "moment": [MOMENT, 0, 0], "frame": "global"}])
    scenario["solver"]["method"] = "shooting"
    return Simulation.from_file(scenario)


def test_a_pure_moment_gives_the_circular_arc(arc):
    solution = arc.solve(warn=False)
    assert solution.converged and solution.method == "shooting"
    module = arc.robot.modules[0]
    radius = module.stiffness[0] / MOMENT
    phi = module.length / radius
    assert_allclose(solution.tip_position, [0.0, -radius * (1 - np.cos(phi)), radius * np.sin(phi)], rtol=0, atol=1e-10)
    distance = np.linalg.norm(solution.modules[0].p - np.array([[0.0], [-radius], [0.0]]), axis=0)
    assert_allclose(distance, radius, rtol=0, atol=1e-10)              # every point on the circle


def test_exact_and_difference_jacobians_reach_the_same_root(arc):
    params = arc.params.copy()
    exact = ShootingSolver(arc.robot, arc.scenario.solver).solve(params)
    differences = ShootingSolver(arc.robot, arc.scenario.solver, jacobian="differences").solve(params)
    assert exact.converged and differences.converged
    assert_allclose(exact.tip_position, differences.tip_position, rtol=0, atol=1e-11)
    assert exact.iterate.method == "shooting" and exact.iterate.w is None and exact.iterate.z.size > 0

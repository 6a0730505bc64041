"""Collocation against exact solutions: pure moment, small and large tip loads, tendon arc."""
import math

import numpy as np
from numpy.testing import assert_allclose
import pytest
from analytic import ELASTICA_TABLE, cantilever_deflection, elastica_tip, tendon_arc

from tca_casadi import Simulation


def stiffness(sim):
    k = sim.robot.modules[0].stiffness
    return k[0], k[3], k[5]   # EI, GA, EA


def test_pure_moment_gives_exact_arc(scenarios):
    # 12 intervals: every node (not only the superconvergent tip) on the circle to 1e-9
    sim = Simulation.from_file(scenarios / "analytic" / "pure_moment.yaml", ["solver.intervals=12"])
    solution = sim.solve()
    assert solution.converged
    ei = stiffness(sim)[0]
    moment = sim.get_parameter("tip_moment.moment")[0]
    radius = ei / moment
    p = solution.modules[0].p
    center = np.array([0.0, -radius, 0.0])       # a moment about +x curls the rod towards -y
    distance = np.linalg.norm(p - center[:, None], axis=0)
    assert np.max(np.abs(distance - radius)) / radius < 1e-9
    assert_allclose(solution.modules[0].u[0], moment / ei, rtol=1e-9, atol=0)
    assert_allclose(solution.modules[0].v, np.broadcast_to([[0], [0], [1]], solution.modules[0].v.shape), rtol=0, atol=1e-12)
    # the tip tangent has turned by phi = M L / EI (about a quarter circle) towards -y
    phi = moment * sim.robot.modules[0].length / ei
    assert phi == pytest.approx(math.pi / 2, rel=1e-4)
    assert solution.tip_rotation[:, 2] == pytest.approx([0, -math.sin(phi), math.cos(phi)], abs=1e-9)


def test_small_tip_load_matches_shear_corrected_cantilever(scenarios):
    sim = Simulation.from_file(scenarios / "analytic" / "pure_moment.yaml",
                               ["tip_moment.moment=[0, 0, 0]", "tip_moment.force=[1e-7, 0, 0]"])
    solution = sim.solve()
    ei, ga, _ = stiffness(sim)
    length = sim.robot.modules[0].length
    expected = cantilever_deflection(1e-7, length, ei, ga)   # P L^2/EI = 3e-5
    shear_part = 1e-7 * length / ga
    assert shear_part / expected > 1e-3                       # the shear term is resolved ...
    assert solution.tip_position[0] == pytest.approx(expected, rel=1e-6)   # ... nonlinear part ~1e-9


@pytest.mark.parametrize("alpha", sorted(ELASTICA_TABLE))
def test_large_tip_load_matches_published_elastica(scenarios, alpha):
    sim = Simulation.from_file(scenarios / "analytic" / "tip_load.yaml")
    ei, length = stiffness(sim)[0], sim.robot.modules[0].length
    sim.set_parameter("tip_force.force", [-alpha * ei / length**2, 0.0, 0.0])
    solution = sim.solve()
    assert solution.converged
    deflection = -solution.tip_position[0] / length
    shortening = 1.0 - solution.tip_position[2] / length
    published = ELASTICA_TABLE[alpha]
    assert deflection == pytest.approx(published[0], abs=1e-5)
    assert shortening == pytest.approx(published[1], abs=1e-5)
    reference = elastica_tip(alpha)             # independent quadrature of the elastica
    assert deflection == pytest.approx(reference[0], abs=2e-6)
    assert shortening == pytest.approx(reference[1], abs=2e-6)


def test_straight_tendon_gives_constant_curvature_arc(scenarios):
    sim = Simulation.from_file(scenarios / "analytic" / "tendon_arc.yaml")
    solution = sim.solve()
    assert solution.converged
    ei, _, ea = stiffness(sim)
    u_y, v_z = tendon_arc(0.005, 0.002, ei, ea)
    module = solution.modules[0]
    assert_allclose(module.u[1], u_y, rtol=1e-9, atol=0)
    assert_allclose(module.u[[0, 2]], 0.0, rtol=0, atol=1e-9 * u_y)
    assert_allclose(module.v[2], v_z, rtol=1e-12, atol=0)
    radius = v_z / u_y                           # of the deformed centerline
    center = np.array([radius, 0.0, 0.0])        # curls towards the tendon at +x
    distance = np.linalg.norm(module.p - center[:, None], axis=0)
    assert np.max(np.abs(distance - radius)) / radius < 1e-9
    # the tendon's loads are internal: no reaction at the base
    assert_allclose(module.base_reaction["force"], 0.0, rtol=0, atol=1e-12)
    assert_allclose(module.base_reaction["moment"], 0.0, rtol=0, atol=1e-14)
    # the body is compressed by the tendon's tension
    assert_allclose(module.force[2] / np.cos(0), -0.005 * module.R[2, 2], rtol=1e-9, atol=0)
    assert solution.actuators["rod.tendon"].stroke == pytest.approx(
        length_change(sim, u_y, v_z), rel=1e-9)


def length_change(sim, u_y, v_z):
    """Tendon path at x = r: |a| = v_z - u_y r, constant."""
    length = sim.robot.modules[0].length
    return (v_z - u_y * 0.002) * length - length


def test_elastica_reference_is_self_consistent():
    deflection, shortening, theta0 = elastica_tip(2.0)
    assert 0 < theta0 < math.pi / 2
    assert deflection == pytest.approx(0.49346, abs=6e-6)

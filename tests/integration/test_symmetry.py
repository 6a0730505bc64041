"""Symmetry: rotating every route by 120 deg rotates the solution; mirrored routes mirror it."""
import math

import numpy as np
from numpy.testing import assert_allclose
import pytest

from tca_casadi import Simulation
from tca_casadi.model.rotations import rotation_numpy


def rotation_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def global_map(sim, body_map):
    """A body-frame map at the base, expressed in the global frame (base at the origin)."""
    base = rotation_numpy(sim.get_parameter("base.quaternion"))
    return base @ body_map @ base.T


def test_rotating_all_tcas_by_120_deg_rotates_the_shape(scenarios):
    path = scenarios / "bending_module.yaml"
    original = Simulation.from_file(path, ["bending.tca3.temperature=80"])
    rotated = Simulation.from_file(path, ["bending.tca3.temperature=80", "bending.tca1.route.angle=120 deg",
                                          "bending.tca2.route.angle=240 deg", "bending.tca3.route.angle=360 deg"])
    a, b = original.solve(), rotated.solve()
    assert a.converged and b.converged
    Q = global_map(original, rotation_z(math.radians(120)))
    assert np.max(np.abs(Q @ a.modules[0].p - b.modules[0].p)) < 1e-9
    assert_allclose(Q @ a.tip_rotation @ rotation_z(math.radians(120)).T, b.tip_rotation, rtol=0, atol=1e-9)
    for key in a.actuators:
        assert b.actuators[key].tension == pytest.approx(a.actuators[key].tension, rel=1e-8)
    # not trivially symmetric: the shape really moved
    assert np.max(np.abs(a.modules[0].p - b.modules[0].p)) > 1e-3


MIRROR = np.diag([1.0, -1.0, 1.0])   # body y -> -y


def test_mirrored_straight_routes_mirror_the_shape(scenarios):
    path = scenarios / "bending_module.yaml"
    base = ["bending.tca3.temperature=80", "bending.tca1.route.angle=10 deg"]
    a = Simulation.from_file(path, base).solve()
    sim = Simulation.from_file(path, ["bending.tca3.temperature=80", "bending.tca1.route.angle=-10 deg",
                                      "bending.tca2.route.angle=-120 deg", "bending.tca3.route.angle=-240 deg"])
    b = sim.solve()
    Q = global_map(sim, MIRROR)
    assert np.max(np.abs(Q @ a.modules[0].p - b.modules[0].p)) < 1e-9
    assert np.max(np.abs(a.modules[0].p - b.modules[0].p)) > 1e-3


def test_mirrored_helix_twists_the_other_way(scenarios):
    path = scenarios / "twisting_module.yaml"
    right = Simulation.from_file(path, ["twisting.tca.temperature=80"])
    left = Simulation.from_file(path, ["twisting.tca.temperature=80", "twisting.tca.route.turns=-5"])
    a, b = right.solve(), left.solve()
    Q = global_map(right, MIRROR)
    assert np.max(np.abs(Q @ a.modules[0].p - b.modules[0].p)) < 1e-9
    twist = [m.u[2].mean() for m in (a.modules[0], b.modules[0])]
    assert twist[0] == pytest.approx(-twist[1], rel=1e-9)
    assert abs(twist[0]) > 10.0   # rad/m: a real twist
    assert a.actuators["twisting.tca"].tension == pytest.approx(b.actuators["twisting.tca"].tension, rel=1e-9)


def curve_scenario(sign):
    points = [[0.0, 0.0, 0.0], [0.02, 0.001, sign * 0.0015], [0.05, 0.0015, sign * -0.001],
              [0.08, -0.001, sign * 0.0012], [0.1, 0.0, sign * 0.0015]]
    return {"name": "curve", "gravity": [0, 0, -9.81],
            "materials": {"m": {"youngs_modulus": "1 MPa", "density": 1000}},
            "modules": [{"name": "rod", "length": 0.1, "material": "m",
                         "cross_section": {"shape": "circle", "diameter": "5 mm"},
                         "actuators": [{"name": "t", "kind": "tendon", "tension": "20 mN",
                                        "route": {"kind": "curve", "points": points}}]}]}


def test_mirrored_curve_route_mirrors_the_shape():
    a = Simulation.from_file(curve_scenario(1.0)).solve()
    b = Simulation.from_file(curve_scenario(-1.0)).solve()
    assert a.converged and b.converged
    assert np.max(np.abs(MIRROR @ a.modules[0].p - b.modules[0].p)) < 1e-9
    assert np.max(np.abs(a.modules[0].p[1])) > 1e-4

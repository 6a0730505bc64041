"""Shapes and the body-outline gap (issue 17's geometry) against closed forms, their normals
against finite differences of the distance, and CasADi against numpy."""
import math
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.model.obstacles import Box, Cylinder, Plane, Sphere, contact_point, gap, support
from tca_casadi.model.rotations import rotation_matrix as symbolic_rotation


def rotation_matrix(quaternion):
    return np.array(ca.DM(symbolic_rotation(ca.DM(quaternion))))


TILTED = rotation_matrix(np.array([math.cos(0.4), math.sin(0.4) * 0.6, math.sin(0.4) * 0.8, 0.0]))
SHAPES = [Plane("floor", np.array([0.0, 0.0, -0.01]), normal=np.array([0.0, 0.3, 1.0])),
          Sphere("ball", np.array([0.01, 0.0, 0.02]), radius=0.005),
          Cylinder("post", np.array([0.0, 0.01, 0.0]), TILTED, radius=0.004),
          Box("brick", np.array([0.005, -0.01, 0.0]), TILTED, size=np.array([0.01, 0.02, 0.006]))]
CIRCLE = SimpleNamespace(shape="circle", diameter=0.006)
RECTANGLE = SimpleNamespace(shape="rectangle", width=0.004, height=0.002)


def test_closed_forms():
    plane = Plane("p", np.zeros(3), normal=np.array([0.0, 0.0, 2.0]))
    assert_allclose(plane.signed_distance(np.array([1.0, 2.0, 0.3]))[0], 0.3, rtol=0, atol=1e-15)
    ball = Sphere("b", np.array([1.0, 0.0, 0.0]), radius=0.5)
    d, n = ball.signed_distance(np.array([1.0, 2.0, 0.0]))
    assert_allclose([d, *n], [1.5, 0, 1, 0], rtol=0, atol=1e-15)
    post = Cylinder("c", np.zeros(3), radius=0.1)                     # along z
    assert_allclose(post.signed_distance(np.array([0.3, 0.4, 7.0]))[0], 0.4, rtol=0, atol=1e-15)
    box = Box("x", np.zeros(3), size=np.array([2.0, 4.0, 6.0]))
    for point, expected in (([3.0, 0.0, 0.0], 2.0),                 # a face
                            ([2.0, 3.0, 0.0], math.sqrt(2.0)),      # an edge
                            ([2.0, 3.0, 4.0], math.sqrt(3.0)),      # a corner
                            ([0.5, 0.0, 0.0], -0.5),                # inside: to the nearest face
                            ([0.0, 0.0, -2.5], -0.5)):
        assert_allclose(box.signed_distance(np.array(point))[0], expected, rtol=0, atol=1e-15)


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: s.name)
def test_normal_is_the_distance_gradient_and_points_to_the_closest_point(shape):
    rng = np.random.default_rng(3)
    for _ in range(20):
        x = shape.position + rng.normal(size=3) * 0.02
        d, n = shape.signed_distance(x)
        if isinstance(shape, Box) and d < 0:
            continue                        # inside a box the distance has ridges
        step = 1e-7
        gradient = [(shape.signed_distance(x + step * e)[0] - shape.signed_distance(x - step * e)[0]) / (2 * step)
                    for e in np.eye(3)]
        assert_allclose(gradient, n, rtol=0, atol=1e-6)
        assert_allclose(np.linalg.norm(n), 1.0, rtol=1e-12)
        assert abs(shape.signed_distance(x - d * n)[0]) < 1e-12       # the closest surface point


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: s.name)
@pytest.mark.parametrize("outline", [CIRCLE, RECTANGLE], ids=["circle", "rectangle"])
def test_casadi_and_numpy_give_the_same_gap(shape, outline):
    p, h = ca.MX.sym("p", 3), ca.MX.sym("h", 4)
    R = symbolic_rotation(h)
    g, n = gap(shape, outline, p, R)
    function = ca.Function("g", [p, h], [g, n])
    rng = np.random.default_rng(5)
    for _ in range(10):
        point = shape.position + rng.normal(size=3) * 0.02
        quaternion = rng.normal(size=4)
        rotation = rotation_matrix(quaternion)
        expected, normal = gap(shape, outline, point, rotation)
        got, got_normal = (np.array(v).ravel() for v in function(point, quaternion))
        assert_allclose(got, expected, rtol=0, atol=1e-13)
        assert_allclose(got_normal, normal, rtol=0, atol=1e-12)


def test_a_rod_on_a_plane_lying_standing_and_tilted():
    """The outline's lowest point: a disc of radius a lying (tangent along the plane) reaches
    a below its centre, standing end-on 0, tilted by theta a cos(theta); a rectangle flat on its
    face reaches h / 2, turned by 45 deg about its tangent (w + h) / (2 sqrt 2)."""
    floor = Plane("floor", np.zeros(3))
    a = CIRCLE.diameter / 2
    lying = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])        # d3 along global y
    standing = np.eye(3)                                            # d3 along global z
    for rotation, expected in ((lying, a), (standing, 0.0)):
        # atol: the smoothing moves the support by up to SMOOTHING x the section's size
        assert_allclose(0.01 - gap(floor, CIRCLE, np.array([0, 0, 0.01]), rotation)[0], expected, rtol=0, atol=1e-11)
    theta = 0.3
    tilted = rotation_matrix(np.array([math.cos(theta / 2), math.sin(theta / 2), 0, 0]))   # d3 tilted by theta
    assert_allclose(support(CIRCLE, np.array([0, 0, 1.0]), *tilted.T), a * math.sin(theta), rtol=0, atol=1e-11)
    flat = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])         # d2 along global z: flat on its face
    assert_allclose(support(RECTANGLE, np.array([0, 0, 1.0]), *flat.T), RECTANGLE.height / 2, rtol=0, atol=1e-11)
    c = math.sqrt(0.5)
    turned = np.array([[c, 0, -c], [0, 1.0, 0], [c, 0, c]]).T @ flat  # 45 deg about the tangent
    assert_allclose(support(RECTANGLE, np.array([0, 0, 1.0]), *turned.T),
                    (RECTANGLE.width + RECTANGLE.height) / (2 * math.sqrt(2)), rtol=0, atol=1e-11)


def test_contact_point_lies_on_the_outline_at_the_gap():
    ball = Sphere("ball", np.zeros(3), radius=0.01)
    rotation = np.eye(3)                                            # d3 along z, section in xy
    p = np.array([0.02, 0.0, 0.0])
    point = contact_point(ball, CIRCLE, p, rotation)
    assert_allclose(point, [0.02 - CIRCLE.diameter / 2, 0, 0], rtol=0, atol=1e-11)
    assert_allclose(ball.signed_distance(point)[0], gap(ball, CIRCLE, p, rotation)[0], rtol=0, atol=1e-11)

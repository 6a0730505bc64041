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


def _rotation_about(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _box_distances(box, points):
    """The box's signed distance at each of ``points`` (m, 3), vectorised (section 1's formula)."""
    q = np.abs((points - box.position) @ box.rotation) - np.asarray(box.size) / 2
    return np.linalg.norm(np.maximum(q, 0), axis=1) + np.minimum(q.max(axis=1), 0)


def _section_points(p, rotation, width, height, n=301):
    grid = np.linspace(-1, 1, n)
    return (p + width / 2 * grid[:, None, None] * rotation[:, 0]
            + height / 2 * grid[None, :, None] * rotation[:, 1]).reshape(-1, 3)


@pytest.mark.parametrize("tilt", [1e-3, -1e-3, 0.0, 0.05])
def test_a_flat_section_beside_a_box_face_and_over_its_edge(tilt):
    """A 6 x 3 mm section end-on beside a 12 x 5 x 5 mm box's side face, its 6 mm upright, slid
    up past the top edge (the arm's fingertip on its bar), tilted about the edge's direction.
    Where the section's point nearest the box lies over the face, the gap equals the smallest
    distance from a 301 x 301 grid of its points to the box (1e-9 m, plus the grid's own error
    at the tilt: 10 um times its sine), also with the centerline's end above the edge, where the
    normal there turns about the edge (the face's own axis takes over). Where that point is
    beyond an edge (tilted over it) the gap is a lower bound, short by at most the tilt times the
    overhang. The contact acts over the face, never beyond its edges."""
    from types import SimpleNamespace
    from tca_casadi.model.obstacles import separation
    box = Box(name="bar", position=np.zeros(3), size=np.array([0.012, 0.005, 0.005]))
    section = SimpleNamespace(shape="rectangle", width=0.006, height=0.003)
    rotation = _rotation_about([1, 0, 0], tilt) @ np.column_stack([[0, 0, 1], [1, 0, 0], [0, -1, 0]])
    over = 0
    for z in (-0.002, 0.0015, 0.0024, 0.0026, 0.004, 0.0053, 0.0056):
        p = np.array([0.0, 0.0025 + 2e-4, z])                  # clear of the face, tilted or not
        points = _section_points(p, rotation, 0.006, 0.003)
        distances = _box_distances(box, points)
        nearest, where = float(np.min(distances)), points[np.argmin(distances)]
        g, n, point = separation(box, section, p, rotation)
        assert g <= nearest + 1e-9
        if abs(where[2]) < 0.0025 - 2e-5:
            over += 1
            assert_allclose(g, nearest, rtol=0, atol=1e-9 + 10e-6 * abs(np.sin(tilt)))
        elif z < 0.0055:
            assert nearest - g <= abs(np.sin(tilt)) * 0.006 + 1e-9
        across = np.abs(n) < 0.5                             # the point's coordinates in the face
        if z < 0.0055:                                       # the section beside the face
            assert np.all(np.abs(point[across]) <= np.array([0.006, 0.0025, 0.0025])[across] + 1e-12)
    assert over >= 1


def test_the_gap_to_a_box_is_a_lower_bound_and_exact_off_its_edges():
    """Random sections (discs and rectangles) at random poses about a tilted box: the gap never
    exceeds the smallest distance from the outline's points to the box (every axis separates),
    and equals it where the whole outline lies over one face (the plane's case of section 1), to
    1e-7 m, the sampling of the discs (2000 points on each of 60 rings)."""
    from types import SimpleNamespace
    from tca_casadi.model.obstacles import separation
    rng = np.random.default_rng(5)
    exact = 0
    for _ in range(200):
        rotation = _rotation_about(rng.normal(size=3), rng.uniform(0, np.pi))
        box = Box(name="b", position=rng.normal(size=3) * 0.01, rotation=rotation,
                  size=rng.uniform(0.004, 0.02, size=3))
        frame = _rotation_about(rng.normal(size=3), rng.uniform(0, np.pi))
        beside = rng.choice([-1.0, 1.0], size=3) * rng.choice([0.0, 1.0], size=3)      # a face, an edge or a corner
        p = box.position + rotation @ ((np.asarray(box.size) / 2 + rng.uniform(0.0, 0.004, size=3)) * beside)
        if rng.uniform() < 0.5:
            w, h = rng.uniform(0.001, 0.006, size=2)
            section = SimpleNamespace(shape="rectangle", width=w, height=h)
            points = _section_points(p, frame, w, h, 121)
        else:
            a = rng.uniform(0.0005, 0.003)
            section = SimpleNamespace(shape="circle", diameter=2 * a)
            angle = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
            radii = np.linspace(0, a, 60)
            ring = np.cos(angle)[:, None] * frame[:, 0] + np.sin(angle)[:, None] * frame[:, 1]
            points = (p + radii[:, None, None] * ring[None, :, :]).reshape(-1, 3)
        nearest = float(np.min(_box_distances(box, points)))
        g = separation(box, section, p, frame)[0]
        assert g <= nearest + 1e-7 * max(np.max(box.size), 1.0)        # the disc's 2000 points: 1e-7 m
        local = np.abs((points - box.position) @ rotation) - np.asarray(box.size) / 2
        over_one_face = np.sum(local.max(axis=0) > 0) == 1          # every point within two slabs
        if nearest > 0 and over_one_face:
            exact += 1
            assert_allclose(g, nearest, rtol=0, atol=1e-7)
    assert exact > 20

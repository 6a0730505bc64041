"""Routes as CasADi expressions of s (what the shooting solver integrates) equal the numpy
routes (what collocation samples), for every kind."""
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.model.routes import make_route, route_expressions

POINTS = [[0, 0.001, 0], [0.01, 0.002, 0.001], [0.02, 0.0, 0.002], [0.03, 0.001, 0.0], [0.05, 0, 0]]


@pytest.mark.parametrize("route", [SimpleNamespace(kind="straight", radius=0.003, angle=0.7),
                                   SimpleNamespace(kind="helix", radius=0.003, turns=-2.3, phase=0.4),
                                   SimpleNamespace(kind="curve", points=POINTS)], ids=lambda r: r.kind)
def test_route_expressions_equal_the_numpy_route(route):
    """At the nominal placement and at a symbolic one (radius and angle moved, as parameters):
    the CasADi route equals numpy's route, built with those values, and :meth:`placed`."""
    geometry = make_route(route, (0.0, 0.05))
    s, radius, angle = ca.SX.sym("s"), ca.SX.sym("radius"), ca.SX.sym("angle")
    function = ca.Function("route", [s, radius, angle], list(route_expressions(geometry, s, radius, angle)))
    points = np.linspace(0.0, 0.05, 41)
    nominal = geometry.placement
    for placement in (nominal, (0.8 * nominal[0], nominal[1] + 1.1)):
        moved = geometry.moved(*placement)
        expected = moved.evaluate(points)
        placed = geometry.placed(points, *placement)
        for k, scale in enumerate((1e-3, 1e-1, 1e1)):      # r [m], r' [-], r'' [1/m]
            got = np.hstack([np.array(function(p, *placement)[k]) for p in points])
            assert_allclose(got, expected[k], rtol=0, atol=1e-12 * scale)
            assert_allclose(placed[k], expected[k], rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("route", [SimpleNamespace(kind="straight", radius=0.003, angle=0.7),
                                   SimpleNamespace(kind="helix", radius=0.003, turns=-2.3, phase=0.4),
                                   SimpleNamespace(kind="curve", points=POINTS)], ids=lambda r: r.kind)
def test_reference_length_by_quadrature(route):
    """``l*`` on a straight body: the span (straight), ``sqrt(L^2 + (2 pi r n)^2)`` (helix);
    on a precurved body against a fine trapezoidal rule (any kind); symbolic = numeric."""
    from tca_casadi.model.routes import reference_path_length
    geometry = make_route(route, (0.0, 0.05))
    straight = np.array([0, 0, 0, 0, 0, 1.0])
    exact = {"straight": 0.05, "helix": float(np.hypot(0.05, 2 * np.pi * 0.003 * 2.3))}
    if route.kind in exact:
        assert_allclose(reference_path_length(geometry, straight), exact[route.kind], rtol=1e-14, atol=0)
    curved = np.array([3.0, -2.0, 0.5, 0.01, 0.0, 1.02])
    s = np.linspace(0.0, 0.05, 400001)
    r, dr, _ = geometry.evaluate(s)
    speed = np.linalg.norm(curved[3:, None] + np.cross(curved[:3], r, axis=0) + dr, axis=0)
    trapezoid = float(np.sum((speed[1:] + speed[:-1]) / 2) * (s[1] - s[0]))
    assert_allclose(reference_path_length(geometry, curved), trapezoid, rtol=1e-10, atol=0)
    radius, angle = ca.SX.sym("radius"), ca.SX.sym("angle")
    symbolic = ca.Function("l", [radius, angle], [reference_path_length(geometry, curved, radius, angle)])
    moved = (0.9 * geometry.placement[0], geometry.placement[1] - 0.3)
    assert_allclose(float(symbolic(*moved)), reference_path_length(geometry.moved(*moved), curved), rtol=1e-14, atol=0)

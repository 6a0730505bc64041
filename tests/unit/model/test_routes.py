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
    geometry = make_route(route, (0.0, 0.05))
    s = ca.SX.sym("s")
    function = ca.Function("route", [s], list(route_expressions(geometry, s)))
    points = np.linspace(0.0, 0.05, 41)
    expected = geometry.evaluate(points)
    for k, scale in enumerate((1e-3, 1e-1, 1e1)):      # r [m], r' [-], r'' [1/m]
        got = np.hstack([np.array(function(p)[k]) for p in points])
        assert_allclose(got, expected[k], rtol=0, atol=1e-12 * scale)

"""Actuator routes: the body-frame path ``r(s) = [x(s), y(s), 0]`` and its first two derivatives
over a span ``[s_a, s_b]`` of a module (SPEC section 7). Pure numpy: the route is structure, so
both solvers evaluate it at the points they need and hand the values to the CasADi physics."""
import math
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class RouteGeometry:
    """A route over ``span`` [m]. ``evaluate(s)`` -> ``(r, dr, ddr)``, each shape (3, n)."""
    kind: str
    span: tuple
    params: dict = field(default_factory=dict)

    def evaluate(self, s):
        s = np.atleast_1d(np.asarray(s, dtype=float))
        return _EVALUATORS[self.kind](self, s)

    def samples(self, count=200):
        """``r`` at ``count`` points across the span, shape (3, count)."""
        return self.evaluate(np.linspace(*self.span, count))[0]


def make_route(route, span):
    """:class:`RouteGeometry` from a scenario route and its span."""
    if route.kind == "straight":
        params = {"radius": route.radius, "angle": route.angle}
    elif route.kind == "helix":
        params = {"radius": route.radius, "turns": route.turns, "phase": route.phase}
    else:
        from scipy.interpolate import CubicSpline
        points = np.asarray(route.points, dtype=float)
        params = {"x": CubicSpline(points[:, 0], points[:, 1]),
                  "y": CubicSpline(points[:, 0], points[:, 2]),
                  "knots": tuple(points[:, 0])}
    return RouteGeometry(route.kind, tuple(float(v) for v in span), params)


def _straight(route, s):
    c, sn = math.cos(route.params["angle"]), math.sin(route.params["angle"])
    r = np.outer([route.params["radius"] * c, route.params["radius"] * sn, 0.0], np.ones_like(s))
    zero = np.zeros((3, s.size))
    return r, zero, zero.copy()


def _helix(route, s):
    s_a, s_b = route.span
    rate = 2.0 * math.pi * route.params["turns"] / (s_b - s_a)
    b = route.params["phase"] + rate * (s - s_a)
    radius, zero = route.params["radius"], np.zeros_like(s)
    r = radius * np.vstack([np.cos(b), np.sin(b), zero])
    dr = radius * rate * np.vstack([-np.sin(b), np.cos(b), zero])
    ddr = -radius * rate**2 * np.vstack([np.cos(b), np.sin(b), zero])
    return r, dr, ddr


def _curve(route, s):
    x, y, zero = route.params["x"], route.params["y"], np.zeros_like(s)
    r = np.vstack([x(s), y(s), zero])
    dr = np.vstack([x(s, 1), y(s, 1), zero])
    ddr = np.vstack([x(s, 2), y(s, 2), zero])
    return r, dr, ddr


_EVALUATORS = {"straight": _straight, "helix": _helix, "curve": _curve}


def route_expressions(route, s):
    """``(r, r', r'')`` of ``route`` as CasADi expressions of the symbol ``s`` (3 each), equal to
    :meth:`RouteGeometry.evaluate` inside the span (a curve: the same cubic pieces as scipy's
    spline, selected by ``if_else`` on its knots)."""
    import casadi as ca
    zero = ca.SX.zeros(3)
    if route.kind == "straight":
        r, _, _ = route.evaluate(route.span[0])
        return ca.DM(r[:, 0]), zero, zero
    if route.kind == "helix":
        s_a, s_b = route.span
        rate = 2.0 * math.pi * route.params["turns"] / (s_b - s_a)
        b = route.params["phase"] + rate * (s - s_a)
        radius = route.params["radius"]
        c, n = ca.cos(b), ca.sin(b)
        return (radius * ca.vertcat(c, n, 0), radius * rate * ca.vertcat(-n, c, 0),
                -radius * rate**2 * ca.vertcat(c, n, 0))
    x = _piecewise_cubic(route.params["x"], s)
    y = _piecewise_cubic(route.params["y"], s)
    return tuple(ca.vertcat(x[k], y[k], 0) for k in range(3))


def _piecewise_cubic(spline, s):
    """Value and first two derivatives of a scipy ``CubicSpline`` as CasADi expressions."""
    import casadi as ca
    knots, coefficients = spline.x, spline.c          # c[k, i]: coefficient of (s - x_i)^(3-k)
    values = [0, 0, 0]
    for i in reversed(range(len(knots) - 1)):
        t = s - knots[i]
        c3, c2, c1, c0 = coefficients[:, i]
        piece = (((c3 * t + c2) * t + c1) * t + c0, (3 * c3 * t + 2 * c2) * t + c1, 6 * c3 * t + 2 * c2)
        if i == len(knots) - 2:
            values = list(piece)
        else:
            values = [ca.if_else(s < knots[i + 1], p, v) for p, v in zip(piece, values)]
    return values

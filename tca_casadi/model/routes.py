"""Actuator routes: the body-frame path ``r(s) = [x(s), y(s), 0]`` and its first two derivatives
over a span ``[s_a, s_b]`` of a module (SPEC section 7).

The kind, span, turns and a curve's points are structure; a straight route's radius and angle
and a helix's radius and phase are parameters (:mod:`tca_casadi.model.parameters`). Both enter
as a *placement* ``radius Rz(angle)`` applied to the route's unit data (radius 1, angle 0), so
the solvers evaluate the unit data where they need it (numpy) and place it with numbers or
CasADi symbols alike (:meth:`RouteGeometry.placed`)."""
import math
from dataclasses import dataclass, field, replace

import numpy as np

from .arith import matmul, placement_matrix

#: the key of a placed route's angle: a straight route's ``angle``, a helix's ``phase``
ANGLE_KEY = {"straight": "angle", "helix": "phase"}


@dataclass(frozen=True)
class RouteGeometry:
    """A route over ``span`` [m]. ``evaluate(s)`` -> ``(r, dr, ddr)``, each shape (3, n)."""
    kind: str
    span: tuple
    params: dict = field(default_factory=dict)

    def evaluate(self, s):
        """``(r, dr, ddr)`` at arc lengths ``s`` [m], each (3, n); the last few grids' values
        are kept (a solver's nodes do not move). Do not modify the arrays returned."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        cache = self.__dict__.setdefault("_evaluated", {})
        key = s.tobytes()
        if key not in cache:
            if len(cache) >= 8:
                cache.pop(next(iter(cache)))
            values = _EVALUATORS[self.kind](self, s)
            for array in values:
                array.flags.writeable = False
            cache[key] = values
        return cache[key]

    @property
    def smoothness_breaks(self):
        """Arc lengths [m] inside the span where the route is less smooth than elsewhere: a
        curve's knots, where its cubic spline's third derivative jumps (so do the strains'
        derivatives, through ``r''`` in the actuator's load). The meshes put breakpoints there:
        an interval across a knot loses the collocation's order (and global balance with it)."""
        if self.kind != "curve":
            return ()
        s_a, s_b = self.span
        return tuple(k for k in self.params["knots"] if s_a < k < s_b)

    def samples(self, count=200):
        """``r`` at ``count`` points across the span, shape (3, count)."""
        return self.evaluate(np.linspace(*self.span, count))[0]

    @property
    def has_placement(self):
        """True for routes with a radius and an angle (straight, helix); a curve has none."""
        return self.kind in ANGLE_KEY

    @property
    def placement(self):
        """Nominal ``(radius, angle)`` [m, rad] (a curve: ``(1, 0)``, the identity)."""
        if not self.has_placement:
            return 1.0, 0.0
        return self.params["radius"], self.params[ANGLE_KEY[self.kind]]

    def unit(self):
        """The same route with radius 1 and angle (phase) 0."""
        if not self.has_placement:
            return self
        return replace(self, params={**self.params, "radius": 1.0, ANGLE_KEY[self.kind]: 0.0})

    def moved(self, radius, angle):
        """The same route at a new numeric ``radius`` and ``angle`` (phase)."""
        if not self.has_placement:
            return self
        return replace(self, params={**self.params, "radius": float(radius), ANGLE_KEY[self.kind]: float(angle)})

    def placed(self, s, radius, angle):
        """``(r, r', r'')`` (3, n each) at ``s`` for a placement given as numbers or CasADi
        symbols: ``radius Rz(angle)`` times the unit route's values."""
        if not self.has_placement:
            return self.evaluate(s)
        matrix = placement_matrix(radius, angle)
        return tuple(matmul(matrix, part) for part in self.unit().evaluate(s))


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


def route_expressions(route, s, radius, angle):
    """``(r, r', r'')`` of ``route`` as CasADi expressions of the symbol ``s`` (3 each) at the
    placement ``(radius, angle)`` (numbers or symbols), equal to :meth:`RouteGeometry.placed`
    inside the span (a curve: the same cubic pieces as scipy's spline, selected by ``if_else``
    on its knots; its placement is ignored)."""
    import casadi as ca
    zero = ca.SX.zeros(3)
    if route.kind == "straight":
        return placement_matrix(radius, angle) @ ca.DM([1.0, 0.0, 0.0]), zero, zero
    if route.kind == "helix":
        s_a, s_b = route.span
        rate = 2.0 * math.pi * route.params["turns"] / (s_b - s_a)
        b = rate * (s - s_a)
        c, n = ca.cos(b), ca.sin(b)
        matrix = placement_matrix(radius, angle)
        return (matrix @ ca.vertcat(c, n, 0), rate * matrix @ ca.vertcat(-n, c, 0),
                -rate**2 * matrix @ ca.vertcat(c, n, 0))
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


def reference_path_length(route, xi_star, radius=None, angle=None):
    """``l*`` [m]: the route's length in the reference configuration, ``int |v* + u* x r + r'| ds``
    over its span, at the placement ``(radius, angle)`` (numbers or CasADi symbols; default the
    nominal one). Composite Gauss-Legendre, 8 points on 16 panels plus 8 per helix turn (a curve:
    4 per knot interval): exact for straight routes and helices on a straight body, to roundoff
    for smooth integrands otherwise."""
    if radius is None:
        radius, angle = route.placement
    s, weights = _length_grid(route)
    r, dr, _ = route.placed(s, radius, angle)
    u, v = np.asarray(xi_star[0:3], float), np.asarray(xi_star[3:6], float)
    cross = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    if type(r).__module__.split(".")[0] == "casadi":
        import casadi as ca
        a = ca.repmat(ca.DM(v), 1, s.size) + ca.mtimes(ca.DM(cross), r) + dr
        return ca.mtimes(ca.sqrt(ca.sum1(a * a)), ca.DM(weights))
    a = v[:, None] + cross @ r + dr
    return float(np.sqrt(np.sum(a * a, axis=0)) @ weights)


def _length_grid(route):
    s_a, s_b = route.span
    if route.kind == "curve":
        knots = np.asarray(route.params["knots"], float)
        edges = np.unique(np.clip(np.concatenate([np.linspace(k0, k1, 5) for k0, k1 in zip(knots[:-1], knots[1:])]),
                                  s_a, s_b))
    else:
        edges = np.linspace(s_a, s_b, 17 + int(np.ceil(8 * abs(route.params.get("turns", 0.0)))))
    nodes, gauss = _GAUSS_8
    half = np.diff(edges)[:, None] / 2
    return (edges[:-1, None] + (nodes + 1) * half).ravel(), (gauss * half).ravel()


_GAUSS_8 = np.polynomial.legendre.leggauss(8)

"""Rigid shapes and the gap between a rod's body and them (issue 17, contact: the geometry).

Each shape lives in its own frame, placed by ``position`` and ``rotation`` (3, 3) (the shape's
axes as columns, in the global frame). :meth:`Shape.signed_distance` gives, for a point ``x``
(3,), the signed distance ``d`` [m] to the surface (negative inside) and the unit outward normal
``n`` at the closest surface point (the gradient of ``d``; ``x - d n`` is that point):

* ``Plane``: the half-space below the plane through ``position`` with outward normal ``n``:
  ``d = n . (x - position)``;
* ``Sphere`` of radius ``R``: ``d = |x - c| - R``;
* ``Cylinder`` of radius ``R`` about its frame's z axis (infinitely long: a post or a bar):
  ``d = |x_perp| - R``, ``x_perp`` the part of ``x - position`` across the axis;
* ``Box`` of edges ``size`` along its frame's axes (half-edges ``b``), in the frame
  ``q = |x_local| - b``: ``d = |max(q, 0)| + min(max_k q_k, 0)`` (exact: to a face, an edge or
  a corner outside; to the nearest face inside).

**The body's outline against a shape** (:func:`gap`). A rod's cross-section at arc length ``s``
is a flat outline in the plane of its body axes ``d1, d2`` (``d3`` the tangent), centred on the
centerline point ``p``: a disc of radius ``a`` or a ``w x h`` rectangle (the section's
``envelope`` where one is given). How far it reaches towards the shape, along ``-n``, is its
support::

    disc:       a |n - (n . d3) d3| = a sqrt(1 - (n . d3)^2)
    rectangle:  (w / 2) |n . d1| + (h / 2) |n . d2|

and the gap is ``g = d(p) - support(n(p))``: the distance between the outline and the shape
along the shape's normal at the centerline's closest point. It is exact for a plane (the
outline's lowest point, whatever the section's tilt: a rod lying on a plane touches it at
``d = a``, one standing on it end-on at ``d = 0``). For a curved shape (sphere, cylinder, a box's
edge) the outline's closest point lies off the normal through ``p`` when the section is tilted
against it, and the gap is then an over-estimate by at most ``a^2 / (2 R)`` (``R`` the
shape's radius of curvature), zero where the section's plane contains the normal (a rod
pressed sideways against a post or a ball).

**A box** (:func:`separation`). ``g`` is the separation of the outline and the shape along one
axis, ``n(p)``; any unit axis gives one, each a lower bound on the distance. Near a box's edge
``n(p)`` turns about it, and a flat section held end-on against a face with its centerline
above the edge would seem to cut into the box. So a box adds its three faces towards ``p`` as
axes, and the gap is the largest separation, made smooth on one side (:func:`_one_sided`): the
same as ``g`` wherever the face's normal is ``n(p)``. A section overhanging a face has its
support point beyond it: the force acts over the face's edge (:meth:`Box.nearest_point`).

Every function takes numbers (numpy) or CasADi symbols; the absolute values and the disc's
square root are smoothed by :data:`SMOOTHING` (``sqrt(x^2 + eps^2) - eps``) so that Newton
sees a C-infinity function, moving the gap by less than ``eps`` times the section's size.
"""
from dataclasses import dataclass, field

import numpy as np

from .arith import is_casadi

#: smoothing of |x| and of the disc's square root, relative (a gap moves by less than this x a)
SMOOTHING = 1e-9
#: a rectangle's contact point slides from corner to corner over this tilt [rad] (:func:`contact_point`)
ARM_SMOOTHING = 1e-3
#: a box's face takes over from the normal at the centerline's closest point over this much of
#: separation [m] (:func:`separation`; the gap is then at most half this much below the larger)
EDGE_SMOOTHING = 1e-8
#: where a flat section's contact acts on a box is clamped to its faces (across the normal) smoothly
#: over this [m] (it moves a point inside a face by at most ``tau^2 / (4 b)``, 1e-16 m here)
CLAMP_SMOOTHING = 1e-9


def _ops(*values):
    """CasADi when any value is symbolic, else numpy: ``(module, is_symbolic)``."""
    if any(is_casadi(v) for v in values):
        import casadi as ca
        return ca, True
    return np, False


def _smooth_abs(x, ops):
    return ops.sqrt(x * x + SMOOTHING ** 2) - SMOOTHING


def _dot(a, b, symbolic):
    if symbolic:
        import casadi as ca
        return ca.dot(a, b)
    return float(np.dot(a, b))


def _column(x, symbolic):
    if symbolic:
        import casadi as ca
        return ca.reshape(x, 3, 1) if not isinstance(x, (list, tuple)) else ca.vertcat(*x)
    return np.asarray(x, float).reshape(3)


@dataclass(frozen=True)
class Shape:
    """Base of every rigid shape: ``name``, ``position`` (3,) [m], ``rotation`` (3, 3) (its axes
    as columns), ``friction`` (Coulomb's coefficient)."""
    name: str
    position: np.ndarray
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    friction: float = 0.0

    def local(self, x, symbolic):
        """``R^T (x - position)``: the point in the shape's frame."""
        offset = x - (self.position if not symbolic else _constant(self.position))
        return (self.rotation.T @ offset) if not symbolic else _constant(self.rotation.T) @ offset

    def to_global(self, v, symbolic):
        return (self.rotation @ v) if not symbolic else _constant(self.rotation) @ v

    def signed_distance(self, x):
        """``(d, n)``: signed distance [m] of ``x`` (3,) and the unit outward normal (3,)."""
        raise NotImplementedError

    def separating_axes(self, x):
        """The shape's separating axes beside its normal at ``x`` (3,): a list of ``(beyond,
        a)``, ``beyond`` how far a plane through ``x`` across the unit axis ``a`` (3,) lies beyond
        the shape's furthest point along ``a`` [m] (:func:`separation`). Empty for a smooth
        shape: its normal at the closest point is the only axis."""
        return []

    def nearest_point(self, x, normal):
        """The point where a contact along ``normal`` (3,) at the outline point ``x`` (3,) acts:
        ``x`` itself but for a box (a flat section can overhang its face)."""
        return x


def _constant(array):
    """A CasADi constant of ``array``, or ``array`` itself when it is already symbolic (an
    obstacle's position as an NLP parameter)."""
    if is_casadi(array):
        return array
    import casadi as ca
    return ca.DM(np.asarray(array, float))


@dataclass(frozen=True)
class Plane(Shape):
    """The half-space below the plane through ``position``; ``normal`` (3,) points out of it."""
    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))

    def signed_distance(self, x):
        ops, symbolic = _ops(x)
        x = _column(x, symbolic)
        n = np.asarray(self.normal, float) / np.linalg.norm(self.normal)
        offset = x - (_constant(self.position) if symbolic else self.position)
        distance = _dot(_constant(n) if symbolic else n, offset, symbolic)
        return distance, (_constant(n) if symbolic else n)


@dataclass(frozen=True)
class Sphere(Shape):
    """A ball of ``radius`` [m] centred on ``position``."""
    radius: float = 0.0

    def signed_distance(self, x):
        ops, symbolic = _ops(x)
        x = _column(x, symbolic)
        offset = x - (_constant(self.position) if symbolic else self.position)
        length = ops.sqrt(_dot(offset, offset, symbolic))
        if not symbolic and length == 0.0:            # at the centre: every direction is the normal
            return -self.radius, np.array([0.0, 0.0, 1.0])
        return length - self.radius, offset / length


@dataclass(frozen=True)
class Cylinder(Shape):
    """An infinitely long cylinder of ``radius`` [m] about its frame's z axis through ``position``."""
    radius: float = 0.0

    def signed_distance(self, x):
        ops, symbolic = _ops(x)
        x = _column(x, symbolic)
        q = self.local(x, symbolic)
        across = q[0] * q[0] + q[1] * q[1]
        length = ops.sqrt(across)
        if not symbolic and length == 0.0:            # on the axis: every radial direction is the normal
            return -self.radius, self.to_global(np.array([1.0, 0.0, 0.0]), False)
        radial = (ops.vertcat(q[0], q[1], 0) if symbolic else np.array([q[0], q[1], 0.0])) / length
        return length - self.radius, self.to_global(radial, symbolic)


@dataclass(frozen=True)
class Box(Shape):
    """A box of edges ``size`` (3,) [m] along its frame's axes, centred on ``position``."""
    size: np.ndarray = field(default_factory=lambda: np.ones(3))

    def signed_distance(self, x):
        ops, symbolic = _ops(x)
        x = _column(x, symbolic)
        q_local = self.local(x, symbolic)
        half = self.size / 2 if is_casadi(self.size) else np.asarray(self.size, float) / 2
        if not symbolic:
            sign = np.where(q_local >= 0, 1.0, -1.0)
            q = np.abs(q_local) - half
            outside = np.maximum(q, 0.0)
            if np.any(q > 0):
                length = float(np.linalg.norm(outside))
                return length, self.rotation @ (sign * outside / length)
            k = int(np.argmax(q))                     # inside: to the nearest face
            normal = np.zeros(3)
            normal[k] = sign[k]
            return float(q[k]), self.rotation @ normal
        import casadi as ca
        sign = ca.sign(q_local) + (q_local == 0)      # +1 on a face's plane, like numpy's branch
        q = ca.fabs(q_local) - _constant(half)
        outside = ca.fmax(q, 0)
        length = ca.norm_2(outside)
        deepest = ca.fmax(ca.fmax(q[0], q[1]), q[2])
        face = ca.vertcat(*[(q[k] >= deepest) * sign[k] for k in range(3)])
        normal = ca.if_else(length > 0, sign * outside / ca.fmax(length, 1e-300), face)
        distance = ca.if_else(length > 0, length, deepest)
        return distance, self.to_global(normal, True)

    def separating_axes(self, x):
        """Its three faces towards ``x``: ``beyond = |x_local_k| - b_k`` along each face's outward
        normal (a flat section beside a face separates from the box along that face's normal
        even where the centerline's closest point is on an edge)."""
        ops, symbolic = _ops(x)
        x = _column(x, symbolic)
        q_local = self.local(x, symbolic)
        half = self._half(symbolic)
        if symbolic:
            import casadi as ca
            sign, magnitude = ca.sign(q_local) + (q_local == 0), ca.fabs
            unit = [ca.DM(row) for row in np.eye(3)]
        else:
            sign, unit, magnitude = np.where(q_local >= 0, 1.0, -1.0), list(np.eye(3)), np.abs
        return [(magnitude(q_local[k]) - half[k], self.to_global(sign[k] * unit[k], symbolic))
                for k in range(3)]

    def nearest_point(self, x, normal):
        """``x`` (3,) with its coordinates across ``normal`` (3,, unit) clamped to the box's
        half-edges, smoothly over :data:`CLAMP_SMOOTHING`: a flat section overhanging a face
        presses on the face's edge, not beyond it. The coordinate along the normal is kept
        (each is clamped in proportion ``1 - n_k^2``, ``n_k`` the normal's component along
        the box's axis ``k``), so a contact inside a face stays where the outline touches it."""
        ops, symbolic = _ops(x, normal)
        x = _column(x, symbolic)
        q = self.local(x, symbolic)
        normal = _column(normal, symbolic)
        across = _constant(self.rotation.T) @ normal if symbolic else self.rotation.T @ normal
        half = self._half(symbolic)
        clamped = [q[k] + (1 - across[k] * across[k])
                   * (_soft_plus(-half[k] - q[k], ops) - _soft_plus(q[k] - half[k], ops)) for k in range(3)]
        local = ops.vertcat(*clamped) if symbolic else np.array(clamped)
        centre = _constant(self.position) if symbolic else np.asarray(self.position, float)
        return centre + self.to_global(local, symbolic)

    def _half(self, symbolic):
        half = self.size / 2 if is_casadi(self.size) else np.asarray(self.size, float) / 2
        return _constant(half) if symbolic else half


def _soft_plus(y, ops):
    """``max(y, 0)`` made smooth over :data:`CLAMP_SMOOTHING`: ``(y + sqrt(y^2 + tau^2)) / 2``."""
    return (y + ops.sqrt(y * y + CLAMP_SMOOTHING ** 2)) / 2


def support(outline, normal, d1, d2, d3):
    """How far the outline (a scenario ``Circle`` or ``Rectangle``: ``shape``, ``diameter`` or
    ``width``/``height``) reaches along ``-normal`` from the centerline [m]; ``d1, d2, d3`` the
    body axes (3,) in the global frame (see the module docstring)."""
    ops, symbolic = _ops(normal, d1, d2, d3)
    if outline.shape == "circle":
        along = _dot(normal, d3, symbolic)
        across = 1.0 - along * along
        smooth = ops.sqrt(ops.fmax(across, 0.0) + SMOOTHING ** 2) - SMOOTHING if symbolic else \
            np.sqrt(max(across, 0.0) + SMOOTHING ** 2) - SMOOTHING
        return outline.diameter / 2 * smooth
    return (outline.width / 2 * _smooth_abs(_dot(normal, d1, symbolic), ops)
            + outline.height / 2 * _smooth_abs(_dot(normal, d2, symbolic), ops))


def gap(shape, outline, p, rotation):
    """``(g, n)``: the gap [m] between the body's outline at centerline point ``p`` (3,) with body
    axes ``rotation`` (3, 3, columns d1 d2 d3) and ``shape``, and the direction the contact
    force takes (the shape's outward normal there; module docstring). Negative: the body
    penetrates the shape."""
    g, n, _ = separation(shape, outline, p, rotation)
    return g, n


def contact_point(shape, outline, p, rotation):
    """Where a contact force acts (3,): the outline's point nearest the shape, ``p`` moved by the
    support along ``-n`` (on a box, the box's point nearest that); its arm about the centerline
    is ``point - p``."""
    return separation(shape, outline, p, rotation)[2]


def separation(shape, outline, p, rotation):
    """``(g, n, point)``: the gap [m], the force's direction (3,) and the point where it acts
    (3,), from the largest separation of the outline and the shape along the shape's normal at
    ``p`` and, for a box, along its faces' normals (module docstring: a separating axis each,
    so the largest is the nearest the true distance and still never above it)."""
    distance, normal = shape.signed_distance(p)
    ops, symbolic = _ops(p, rotation, normal)
    columns = [rotation[:, k] for k in range(3)]
    g = distance - support(outline, normal, *columns)
    axes = shape.separating_axes(p)
    for beyond, axis in axes:
        other = beyond - support(outline, axis, *columns)
        taken, weight = _one_sided(other - g, ops)
        g = g + taken
        normal = (1 - weight) * normal + weight * axis
    if not axes:
        return g, normal, _outline_point(outline, normal, p, columns, ops, symbolic)
    normal = normal / ops.sqrt(_dot(normal, normal, symbolic))
    return g, normal, shape.nearest_point(_outline_point(outline, normal, p, columns, ops, symbolic), normal)


def _one_sided(x, ops):
    """``(phi, phi')`` of ``phi(x) = y^3 / (y^2 + tau^2)``, ``y = max(x, 0)``, ``tau`` =
    :data:`EDGE_SMOOTHING`: exactly 0 for ``x <= 0``, ``x - tau^2 / x`` far above (twice
    differentiable), so ``a + phi(b - a)`` is ``max(a, b)`` made smooth on one side only: where
    ``a`` is the larger (a face's own normal, where both axes are the same) it is ``a`` exactly."""
    y = ops.fmax(x, 0.0) if ops is not np else max(float(x), 0.0)
    y2, t2 = y * y, EDGE_SMOOTHING ** 2
    return y * y2 / (y2 + t2), y2 * (y2 + 3 * t2) / ((y2 + t2) * (y2 + t2))


def _outline_point(outline, normal, p, columns, ops, symbolic):
    """The outline's point furthest along ``-normal`` (its support point), smoothed as
    :func:`_smooth_sign` says for a rectangle."""
    if outline.shape == "circle":
        d3 = columns[2]
        across = normal - _dot(normal, d3, symbolic) * d3
        size = ops.sqrt(_dot(across, across, symbolic) + SMOOTHING ** 2)
        return p - outline.diameter / 2 * across / size
    d1, d2 = columns[0], columns[1]
    a, b = _dot(normal, d1, symbolic), _dot(normal, d2, symbolic)
    return p - outline.width / 2 * _smooth_sign(a, ops) * d1 - outline.height / 2 * _smooth_sign(b, ops) * d2


def _smooth_sign(x, ops):
    """``sign(x)`` made continuous over ``|x| < ARM_SMOOTHING``: a rectangle pressed flat on a
    face touches along an edge, and its contact point moves from one corner to the other as it
    tilts through flat (a jump Newton cannot take) over a tilt of about that many radians."""
    return x / ops.sqrt(x * x + ARM_SMOOTHING ** 2)

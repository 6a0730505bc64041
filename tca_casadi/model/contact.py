"""Contact between the rods and fixed rigid shapes, written once for every solver (issue 17;
the derivation is ``docs/contact.md``).

A *contact* is one candidate point (arc length ``s`` of module ``m``) against one obstacle. It
carries an unknown normal force ``f >= 0`` [N] along the obstacle's outward normal ``n``,
applied at the point of the body's outline nearest the obstacle; with the gap ``g`` between
that outline and the obstacle (:func:`tca_casadi.model.obstacles.gap`) the condition is the
complementarity ``g >= 0, f >= 0, f g = 0``, written as the smoothed Fischer-Burmeister
equation the slack actuators use (:mod:`.compatibility`)::

    f / f_s + g / g_s - sqrt((f / f_s)^2 + (g / g_s)^2 + eps^2) = 0

``f_s = EI / L^2`` the module's force scale, ``g_s`` its outline's size. At a closed contact it
leaves a gap of about ``eps^2 g_s f_s / (2 f)`` (far below 1e-9 m); on an open one a force of
about ``eps^2 f_s g_s / (2 g)``.

Candidates are each module's ends, ``contact.points`` evenly spaced points inside it, the
scenario's ``contact.at`` points and those localisation added (:func:`candidate_points`).
Every function takes numbers or CasADi symbols; states are deviation states
``[p, h, u - u*, v - v*]`` (:mod:`.rod`).
"""
from dataclasses import dataclass, replace

import numpy as np

from .arith import cross, is_casadi, sqrt
from .obstacles import Box, Cylinder, Plane, Sphere, gap, separation
from .rod import POINT_WRENCH
from .rotations import rotation_matrix, rotation_numpy

#: smoothing of the complementarity (as the slack actuators')
SMOOTHING = 1e-9
#: a contact whose force is below this fraction of its module's force scale is open (the
#: smoothing leaves about 1e-18 of it on an open contact)
CLOSED = 1e-6
#: candidates closer than this fraction of the module's length are one
MERGE = 1e-9


@dataclass(frozen=True)
class ContactModel:
    """One contact candidate: module index ``module``, arc length ``s`` [m], obstacle index
    ``obstacle`` into ``robot.obstacles``; ``index`` its position in ``robot.contacts``;
    ``number`` its place among its module's candidates (the names of its history parameters
    against an obstacle with friction, :mod:`.history`). A grip (against a free body,
    :mod:`.bodies`) has ``body`` (index into ``robot.bodies``) instead of ``obstacle`` and
    ``index`` into ``robot.grips``."""
    module: int
    s: float
    obstacle: object
    index: int
    body: object = None
    number: int = 0


def shape_of(config):
    """The :mod:`.obstacles` shape of a scenario obstacle (``obstacles:`` entry)."""
    common = {"name": config.name, "position": np.asarray(config.position, float), "friction": config.friction}
    if config.shape == "plane":
        normal = np.asarray(config.normal, float)
        return Plane(**common, normal=normal / np.linalg.norm(normal))
    if config.shape == "sphere":
        return Sphere(**common, radius=config.radius)
    rotation = rotation_numpy(np.asarray(config.orientation.as_quaternion(), float))
    if config.shape == "cylinder":
        return Cylinder(**common, rotation=rotation, radius=config.radius)
    return Box(**common, rotation=rotation, size=np.asarray(config.size, float))


def outline_of(module):
    """The outline contact sees: the section's envelope where given, else the section."""
    return module.section.envelope or module.section


def outline_size(module):
    """The outline's size [m] (a disc's diameter, a rectangle's larger side): the gap scale."""
    outline = outline_of(module)
    return outline.diameter if outline.shape == "circle" else max(outline.width, outline.height)


def candidate_points(length, points, given=(), added=()):
    """Sorted candidate arc lengths [m] of a module of ``length``: its ends, ``points`` evenly
    spaced inside, then each ``given`` and ``added`` point, which replaces the evenly spaced
    ones closer to it than a quarter of their spacing (no needlessly short mesh intervals)."""
    spacing = length / (points + 1)
    even = [k * spacing for k in range(1, points + 1)]
    chosen = list(given) + list(added)
    even = [s for s in even if all(abs(s - c) >= spacing / 4 for c in chosen)]
    out = []
    for s in sorted([0.0, length] + even + [min(max(float(c), 0.0), length) for c in chosen]):
        if not out or s - out[-1] > MERGE * length:
            out.append(s)
    return out


def contact_frame(state):
    """``(p (3,), R (3, 3))`` of a deviation state, numbers or CasADi."""
    p, h = state[0:3], state[3:7]
    if is_casadi(state):
        return p, rotation_matrix(h)
    return np.asarray(p, float).reshape(3), rotation_numpy(np.asarray(h, float).reshape(4))


def contact_geometry(shape, module, state):
    """``(g, n, point)``: gap [m], the obstacle's outward normal (3,) and the outline point
    nearest the obstacle (3,) (global frame) at a deviation state. On MX (an NLP's build), one
    call of the SX Function :func:`geometry_function`: the same expression once expanded, built
    in one node instead of hundreds (the arm holding a bar: its build 1.6 -> 0.9 s)."""
    import casadi as ca
    if isinstance(state, ca.MX):
        function, inputs = geometry_function(shape, outline_of(module))
        return function(state[0:7], *[getattr(shape, name) for name in inputs])
    p, R = contact_frame(state)
    return separation(shape, outline_of(module), p, R)


_GEOMETRY_FUNCTIONS = {}
#: a shape's fields that are always the geometry Function's inputs (a body moves; an obstacle's
#: position may be an NLP parameter)
PLACED = ("position", "rotation")


def geometry_function(shape, outline):
    """``(Function, names)``: :func:`~.obstacles.separation` as an SX Function of a deviation
    state's ``p, h`` (7,) and the shape's fields ``names`` (its position and rotation, and any
    other given as a CasADi symbol) -> ``(g, n (3,), point (3,))``, built once per shape
    type, its other fields and the outline."""
    import casadi as ca
    inputs = [name for name, value in vars(shape).items() if name in PLACED or is_casadi(value)]
    numeric = {name: value for name, value in vars(shape).items() if name not in inputs and not isinstance(value, str)}
    key = (type(shape).__name__, tuple((name, np.asarray(value, float).tobytes()) for name, value in numeric.items()),
           tuple((name, _shape2(getattr(shape, name))) for name in inputs), _outline_key(outline))

    def build():
        x = ca.SX.sym("x", 7)
        fields = {name: ca.SX.sym(name, *_shape2(getattr(shape, name))) for name in inputs}
        g, n, point = separation(replace(shape, **fields), outline, x[0:3], rotation_matrix(x[3:7]))
        return ca.Function("contact_geometry", [x, *fields.values()], [g, n, point])
    return _kept(_GEOMETRY_FUNCTIONS, key, build), inputs


def _kept(cache, key, build, limit=256):
    """``cache[key]``, built by ``build()`` the first time (the cache emptied past ``limit``
    entries: a long study of moving obstacles must not grow it without end)."""
    if key not in cache:
        if len(cache) > limit:
            cache.clear()
        cache[key] = build()
    return cache[key]


def _shape2(value):
    """A field's shape as CasADi's (rows, columns): a vector (3,) is a column."""
    shape = tuple(np.shape(value)) if not is_casadi(value) else value.shape
    return shape if len(shape) == 2 else (shape[0] if shape else 1, 1)


def held_point(state, offset):
    """The rod's material point that friction holds (3,) [m]: ``p + R offset`` at a deviation
    state, ``offset`` (3,) its place in the section frame (the history's ``offset``, recorded
    where the contact touched: :mod:`.history`)."""
    p, R = contact_frame(state)
    return p + R @ offset


def contact_wrench(module, state, shape, force, tangential=None, offset=None):
    """Body-frame wrench ``[moment; force]`` of a normal force ``force`` [N] along the
    obstacle's normal at the outline's nearest point, plus a ``tangential`` force (3,) [N]
    (friction) at the material point ``offset`` (:func:`held_point`), about the centerline point
    of ``state`` (the same jump a point load makes, :func:`tca_casadi.model.boundary.point_wrenches`)."""
    import casadi as ca
    p, _ = contact_frame(state)
    _, n, point = contact_geometry(shape, module, state)
    global_force, moment = force * n, cross(point - p, force * n)
    if tangential is not None:
        global_force = global_force + tangential
        moment = moment + cross(held_point(state, offset) - p, tangential)
    zero = ca.DM.zeros(3)
    return POINT_WRENCH(state[3:7], global_force, moment, zero, zero)


_GAP_FUNCTIONS = {}


def gap_function(shape, outline):
    """CasADi Function ``(p (3,), h (4,)) -> g``: the gap [m] of :func:`gap` at a centerline
    point and quaternion, built once per shape and outline (kept by their description)."""
    import casadi as ca

    def build():
        p, h = ca.SX.sym("p", 3), ca.SX.sym("h", 4)
        g, _ = gap(shape, outline, p, rotation_matrix(h))
        return ca.Function("gap", [p, h], [g])
    return _kept(_GAP_FUNCTIONS, _key(shape, outline), build)


def _key(shape, outline):
    """What a numeric shape and an outline are, as a hashable key (cheaper than their repr)."""
    values = tuple(np.asarray(value, float).tobytes() for value in vars(shape).values()
                   if not isinstance(value, str))
    return (type(shape).__name__, values) + _outline_key(outline)


def _outline_key(outline):
    return (outline.shape, getattr(outline, "diameter", None), getattr(outline, "width", None),
            getattr(outline, "height", None))


_MAPPED = {}


def gaps(shape, outline, p, h):
    """Gaps [m] (n,) at centerline points ``p`` (3, n) with quaternions ``h`` (4, n)."""
    p, h = np.asarray(p, float).reshape(3, -1), np.asarray(h, float).reshape(4, -1)
    mapped = _kept(_MAPPED, (_key(shape, outline), p.shape[1]), lambda: gap_function(shape, outline).map(p.shape[1]),
                   limit=1024)
    return np.array(mapped(p, h)).ravel()


def normal_contact(force, g, force_scale, gap_scale):
    """The scaled complementarity of one contact (module docstring): zero on ``g >= 0,
    f >= 0, f g = 0``."""
    f, c = force / force_scale, g / gap_scale
    return f + c - sqrt(f * f + c * c + SMOOTHING ** 2)

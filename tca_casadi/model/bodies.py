"""Grasped objects as free rigid bodies, and sticking friction (issue 17; the derivation is
``docs/contact.md`` sections 4 and 5). Written once, for numbers or CasADi symbols.

A *body* is a scenario object with ``contact: true``: a box of edges ``size`` and mass ``m``
whose pose is unknown, ``r = r0 + delta`` and ``R = R0 R(g)`` with ``r0, R0`` its placed pose
and ``g`` (3,) a Gibbs vector (``q = [1, g / 2] / sqrt(1 + |g|^2 / 4)``, smooth everywhere, the
rotation vector to first order, any turn below 180 deg). It is in equilibrium under its weight,
the contact forces of the modules that may touch it (``held_by``) and the reaction of its
``support`` (a plane obstacle it rests on):

    sum_k (-f_k) + F_s + m g = 0,    sum_k (x_k - r) x (-f_k) + (x_s - r) x F_s + M_s = 0

(``f_k`` the force on the rod at its outline point ``x_k``; ``x_s`` the box's lowest point).

**A grip** (rod candidate against a body) carries a normal force (the complementarity of
:mod:`.contact`) and a tangential force ``f_t`` (3,), with three equations that blend sticking
with no friction by the side of the normal complementarity's corner::

    c P (x - r - R X) / g_s + (1 - c) P f_t / f_s + n (n . f_t) / f_s = 0,
    c = sticks * step(f_n / f_s - g / g_s),   P = I - n n^T

``X`` (3,) the anchor, the body-frame point the rod's outline point stuck to when the contact
closed, and ``sticks`` (0 or 1) whether it had closed: both are parameters copied from the
solution a solve starts from (the history a static solve needs). A closed, anchored contact
sticks (its tangential force is whatever holds it there); an open one carries none; a contact
that closes during a solve comes in frictionless and sticks from the next one. Friction's
coefficient enters only the verdict: margin ``mu f_n - |f_t|``, slipping when negative.

**The support** (body against its plane) carries a force ``F_s`` and a moment ``M_s`` (3 each):
the normal part of ``F_s`` by the complementarity with the gap of the box's lowest point; the
rest, blended the same way, either welds the body to its anchor pose (``r_A``, ``g_A``: lying
where it was put, or where it was at the solve it starts from) or carries nothing::

    c P (r - r_A) / L_o + (1 - c) P F_s / f_o + n FB(n . F_s / f_o, g / L_o) = 0
    c theta(R_A^T R) + (1 - c) M_s / (f_o L_o) = 0

``f_o = m * 9.81 N/kg`` and ``L_o`` the largest edge are the body's scales, ``theta`` the
(small) relative rotation ``vee(A - A^T) / 2``.
"""
from dataclasses import dataclass

import numpy as np

from .arith import cross, is_casadi, sqrt
from .obstacles import SMOOTHING, Box

# (casadi, and the modules that import it, are imported where used: ``validate`` declares the
# history parameters through this module without loading any numerical library)

#: width of the smooth step between sticking and no friction, on ``f / f_s - g / g_s``
STICK_SMOOTHING = 1e-3
#: the same for a support (a body lifted off its support lets go of it over this much of its
#: weight: a weld released within microns of lift is a corner continuation cannot follow)
SUPPORT_SMOOTHING = 1e-3
#: standard gravity [m/s^2]: a body's force scale is its weight at it (whatever the scenario's g)
STANDARD_GRAVITY = 9.81


@dataclass(frozen=True)
class BodyModel:
    """A free rigid box: ``name``, ``index`` into ``robot.bodies``, edges ``size`` (3,) [m], its
    placed pose ``position`` (3,) [m] and ``rotation`` (3, 3), ``friction`` (between it and the
    rods), ``support`` (index into ``robot.obstacles`` of the plane it rests on, or None) and
    ``modules`` (indices of the modules that may touch it), ``mass`` [kg] as the scenario gives
    it (its force scale; the weight itself is the parameter ``NAME.mass``)."""
    name: str
    index: int
    mass: float
    size: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    friction: float
    support: object
    modules: tuple

    @property
    def length_scale(self):
        return float(np.max(self.size))


def body_scales(body):
    """``(f_o [N], L_o [m])``: the body's weight at standard gravity and its largest edge."""
    return body.mass * STANDARD_GRAVITY, body.length_scale


def gibbs_quaternion(g):
    """Unit quaternion (4,) of a Gibbs vector ``g`` (3,): ``[1, g / 2] / sqrt(1 + |g|^2 / 4)``."""
    if is_casadi(g):
        import casadi as ca
        return ca.vertcat(1, g / 2) / ca.sqrt(1 + ca.dot(g, g) / 4)
    g = np.asarray(g, float)
    return np.r_[1.0, g / 2] / np.sqrt(1 + g @ g / 4)


def body_rotation(body, g):
    """``R0 R(g)`` (3, 3): the body's orientation for its Gibbs vector ``g``."""
    from .rotations import rotation_matrix, rotation_numpy
    if is_casadi(g):
        import casadi as ca
        return ca.DM(body.rotation) @ rotation_matrix(gibbs_quaternion(g))
    return body.rotation @ rotation_numpy(gibbs_quaternion(g))


def body_pose(body, pose):
    """``(r (3,), R (3, 3))`` of the pose unknowns ``pose = [delta (3), g (3)]``."""
    if is_casadi(pose):
        import casadi as ca
        return ca.DM(body.position) + pose[0:3], body_rotation(body, pose[3:6])
    pose = np.asarray(pose, float)
    return body.position + pose[0:3], body_rotation(body, pose[3:6])


def body_shape(body, r, R):
    """The body as a :class:`~.obstacles.Box` at position ``r`` and rotation ``R``."""
    return Box(name=body.name, position=r, rotation=R, friction=body.friction, size=np.asarray(body.size, float))


def smooth_step(z, width=STICK_SMOOTHING):
    """0 for ``z << -width``, 1 for ``z >> width``, smooth between."""
    return 0.5 * (1 + z / sqrt(z * z + width ** 2))


def _projector(n):
    import casadi as ca
    return ca.DM.eye(3) - n @ n.T


def grip_friction(point, n, r, R, anchor, sticks, normal_force, tangential, gap, force_scale, gap_scale):
    """The three scaled sticking / no-friction equations of one grip (module docstring)."""
    c = sticks * smooth_step(normal_force / force_scale - gap / gap_scale)
    P = _projector(n)
    slip = P @ (point - r - R @ anchor)
    import casadi as ca
    return c * slip / gap_scale + (1 - c) * (P @ tangential) / force_scale + n * ca.dot(n, tangential) / force_scale


def support_geometry(plane, body, r, R):
    """``(g, n, x_s)``: the gap [m] between the box's lowest point and the support ``plane``
    (outward normal ``n``), and that point (the centre of a face lying flat on it; the smoothed
    ``|.|`` and sign of :mod:`.obstacles`)."""
    distance, n = plane.signed_distance(r)
    half = np.asarray(body.size, float) / 2
    symbolic = is_casadi(r) or is_casadi(R)
    reach, point = 0, r
    for k in range(3):
        axis = R[:, k]
        along = (axis.T @ n) if symbolic else float(axis @ n)
        smooth = sqrt(along * along + SMOOTHING ** 2)
        reach = reach + half[k] * (smooth - SMOOTHING)
        point = point - half[k] * (along / smooth) * axis
    return distance - reach, n, point


def relative_rotation(R_anchor, R):
    """``vee(A - A^T) / 2`` of ``A = R_anchor^T R``: the relative rotation vector to first order."""
    A = R_anchor.T @ R
    import casadi as ca
    return 0.5 * ca.vertcat(A[2, 1] - A[1, 2], A[0, 2] - A[2, 0], A[1, 0] - A[0, 1])


def support_equations(plane, body, r, R, anchor_pose, sticks, force, moment, force_scale):
    """The six scaled support equations (module docstring): ``force``, ``moment`` (3,) the
    support's reaction on the body at its lowest point [N, N m]."""
    import casadi as ca
    from .contact import normal_contact
    length = body.length_scale
    g, n, _ = support_geometry(plane, body, r, R)
    r_anchor, R_anchor = body_pose(body, anchor_pose)
    f_n = ca.dot(n, force)
    c = sticks * smooth_step(f_n / force_scale - g / length, SUPPORT_SMOOTHING)
    P = _projector(n)
    position = c * (P @ (r - r_anchor)) / length + (1 - c) * (P @ force) / force_scale + \
        n * normal_contact(f_n, g, force_scale, length)
    turn = c * relative_rotation(R_anchor, R) + (1 - c) * moment / (force_scale * length)
    return ca.vertcat(position, turn)


def body_equilibrium(r, weight, grips, support=None):
    """``[force (3); moment about r (3)]`` [N, N m] on a body: its ``weight`` (3,) at ``r``, each
    grip ``(point, force on the rod)`` reacted on it, the support ``(point, force, moment)``."""
    force, moment = weight, 0 * weight
    for point, on_rod in grips:
        force = force - on_rod
        moment = moment - cross(point - r, on_rod)
    if support is not None:
        point, reaction, couple = support
        force = force + reaction
        moment = moment + cross(point - r, reaction) + couple
    return force, moment


def anchor_of(r, R, point):
    """The body-frame point (3,) under the global ``point`` for a body at ``(r, R)`` (numpy)."""
    return np.asarray(R, float).T @ (np.asarray(point, float) - np.asarray(r, float))


def contact_objects(scenario):
    """The scenario's objects with ``contact: true``, as ``[(object index, entry), ...]``."""
    return [(k, item) for k, item in enumerate(scenario.objects) if item.contact]


def grip_points(scenario, points=None):
    """``[(body index, module index, K, s), ...]``: the grip candidates of every contact object,
    the candidate points (:func:`~.contact.candidate_points`: ends, ``contact.points`` evenly
    spaced, ``contact.at``) of each module that may touch it, ``K`` numbering them per module."""
    if not contact_objects(scenario):
        return []
    from .contact import candidate_points
    names = [m.name for m in scenario.modules]
    given = {names.index(name): s for name, s in scenario.contact.at.items() if name in names}
    out = []
    for b, (_, item) in enumerate(contact_objects(scenario)):
        for name in item.held_by:
            m = names.index(name)
            spots = candidate_points(scenario.modules[m].length, scenario.contact.points if points is None else points,
                                     given.get(m, ()))
            out.extend((b, m, K, float(s)) for K, s in enumerate(spots))
    return out


def grip_parameter(body, module, number, key):
    """The name of a grip's history parameter ``key`` (``anchor`` or ``sticks``): ``body``,
    ``module`` names, ``number`` its place among the module's candidates."""
    return f"objects.{body}.grip.{module}.{number}.{key}"


def support_parameter(body, key):
    """The name of a body's support history parameter ``key`` (``anchor`` or ``sticks``)."""
    return f"objects.{body}.support.{key}"


#: the first element of a history parameter's ``source`` (it is no scenario key)
HISTORY = "history"


def history_names(scenario):
    """The history parameters of the contact objects, ``[(name, size), ...]`` (module
    docstring): per grip ``objects.NAME.grip.MODULE.K.anchor`` (3) and ``.sticks``; per
    supported body ``objects.NAME.support.anchor`` (6: offset, Gibbs vector) and ``.sticks``."""
    bodies = contact_objects(scenario)
    out = []
    for b, m, K, _ in grip_points(scenario):
        out += [(grip_parameter(bodies[b][1].name, scenario.modules[m].name, K, key), size)
                for key, size in (("anchor", 3), ("sticks", 1))]
    for _, item in bodies:
        if item.support is not None:
            out += [(support_parameter(item.name, "anchor"), 6), (support_parameter(item.name, "sticks"), 1)]
    return out


def gibbs_of(R):
    """The Gibbs vector (3,) of a rotation matrix (numpy): ``2 q_v / q_w``."""
    from .rotations import matrix_to_quaternion
    q = np.asarray(matrix_to_quaternion(np.asarray(R, float)), float).ravel()
    q = q if q[0] >= 0 else -q
    return 2 * q[1:4] / q[0]


def carried_history(robot, params, solution):
    """``params`` with the contact objects' history set from ``solution`` (the state a solve
    starts from; None: a cold start, the scenario's history): each grip closed there is
    anchored where its rod point touched the body (in the body's frame) and sticks, an open one
    does not; a body resting on its support there is anchored at its pose there."""
    params = np.array(params, float)
    if not robot.bodies:
        return params
    layout = robot.layout
    names = history_names_of(robot)
    if solution is None or not solution.bodies:
        for name in names:
            params[layout[name]] = robot.values[layout[name]]
        return params
    results = {b.name: b for b in solution.bodies}
    for c in robot.grips:
        body, module = robot.bodies[c.body], robot.modules[c.module]
        found = results.get(body.name)
        closed = None if found is None else next(
            (g for g in found.grips if g.module == module.name and abs(g.s - c.s) <= 1e-12 * module.length), None)
        params[layout[robot.grip_parameter(c, "sticks")]] = 0.0 if closed is None else 1.0
        if closed is not None:
            params[layout[robot.grip_parameter(c, "anchor")]] = anchor_of(found.position, found.rotation,
                                                                          closed.position)
    for body in robot.bodies:
        found = results.get(body.name)
        if body.support is None or found is None:
            continue
        params[layout[support_parameter(body.name, "sticks")]] = 1.0 if found.resting else 0.0
        if found.resting:
            params[layout[support_parameter(body.name, "anchor")]] = np.r_[found.position - body.position,
                                                      gibbs_of(body.rotation.T @ found.rotation)]
    return params


def history_names_of(robot):
    """The names of a robot's history parameters (declared by :func:`history_names`)."""
    return [name for name in robot.layout.names() if robot.layout.entries[name].source[0] == HISTORY]

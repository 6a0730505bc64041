"""Grasped objects as free rigid bodies, with friction (issue 17; the derivation is
``docs/contact.md`` sections 4 and 5). Written once, for numbers or CasADi symbols.

A *body* is a scenario object with ``contact: true``: a box of edges ``size`` and mass ``m``
whose pose is unknown, ``r = r0 + delta`` and ``R = R0 R(g)`` with ``r0, R0`` its placed pose
and ``g`` (3,) a Gibbs vector (``q = [1, g / 2] / sqrt(1 + |g|^2 / 4)``, smooth everywhere, the
rotation vector to first order, any turn below 180 deg). It is in equilibrium under its weight,
the contact forces of the modules that may touch it (``held_by``) and the reactions of its
``support`` (a plane obstacle) at its corners::

    sum_k (-f_k) + sum_j F_j + m g = 0,    sum_k (x_k - r) x (-f_k) + sum_j (y_j - r) x F_j = 0

(``f_k`` the force on the rod at its outline point ``x_k``; ``F_j`` the support's force on the
body at its corner ``y_j``).

**Friction**, the same at every contact of a body (a grip: a rod candidate against it; a
corner against its support) and of a rod against an obstacle with friction (the anchor
measured from the obstacle's position). A contact carries a normal force ``f_n`` (the complementarity of
:mod:`.contact`), a tangential force ``f_t`` (3,) and a slip multiplier ``lambda >= 0``, with
three equations that blend friction with no friction by the side of the normal
complementarity's corner, and one for ``lambda``::

    c [P u / g_s + (kappa + lambda) P f_t / f_s] + (1 - c) P f_t / f_s + n (n . f_t) / f_s = 0,
    c = sticks * step(f_n / f_s - g / g_s),   P = I - n n^T

``u`` is how far the contact point moved since the solution the solve starts from: for a grip
``x - r - R X``, ``X`` the body-frame point its rod's outline point was at there and ``x = p +
R rho`` the rod's material point that touched there (``rho`` in its section frame: a material
point, so that sticking pins the rod, where the outline point nearest the body runs along a
flat face as the section tilts); for a corner
``y - A``, ``A`` the point of the plane it pressed there. ``X``, ``A`` (anchors) and ``sticks``
(0 or 1: the contact was closed there) are parameters copied from that solution and carried
again after every continuation step (the history a static solve needs). So ``u = -(kappa +
lambda) (g_s / f_s) f_t``: the contact point moves against its friction force or not at all;
``kappa`` is an elastic compliance (0 for grips, whose rods are compliant;
:data:`SUPPORT_COMPLIANCE` for corners, whose body is rigid: four corners on a plane are
indeterminate without it) and ``lambda`` the slip. The law (``contact.friction_law``) says
what fixes ``lambda``:

- ``stick``: ``lambda = 0``. A closed, anchored contact sticks, its tangential force whatever
  holds it there; the coefficient enters only the verdict: margin ``mu f_n - |f_t|``,
  slipping when negative, with the friction it would need ``|f_t| / f_n``.
- ``coulomb``: ``c FB(lambda, (mu f_n - |f_t|) / f_s) + (1 - c) lambda = 0``, the slip's
  complementarity with the friction margin (the smoothed Fischer-Burmeister of
  :mod:`.contact`): a contact sticks inside Coulomb's cone and slides on it, so a grasp whose
  normal force falls lets go continuously (release) and an object too heavy for its grip slides
  out of it. A contact on the sliding side is reported slipping. With ``mu = 0`` the contact is
  frictionless (``f_t = 0``).

An open contact carries no tangential force; a contact that closes during a solve comes in
frictionless and takes friction from the next continuation step.

**The support** acts at the box's eight corners ``y_j = r + R c_j``: each corner's normal force
is complementary to its gap to the plane, with a normal compliance too, ``FB(f_n / f_o, g / L_o
+ kappa f_n / f_o)`` (a corner sinks ``kappa L_o`` per weight it carries). So a box lies on a
face (four corners), an edge (two) or a corner (one), lands on an edge when put down tilted and
rolls flat as it is pressed, and tips when its centre of pressure would leave its face: no
contact patch is assumed. ``f_o = m * 9.81 N/kg`` and ``L_o`` the largest edge are the body's
scales.
"""
from dataclasses import dataclass

import numpy as np

from .arith import cross, is_casadi, tanh
from .friction import cone_margin
from .obstacles import Box

# (casadi, and the modules that import it, are imported where used: ``validate`` declares the
# history parameters through this module without loading any numerical library)

#: width of the smooth step between friction and no friction, on ``f / f_s - g / g_s``
STICK_SMOOTHING = 1e-5
#: smoothing of ``|f_t|`` on Coulomb's cone, as a fraction of the force scale
CONE_SMOOTHING = 1e-9
#: a corner's compliance against its support, normal and tangential: it gives by this fraction
#: of the body's largest edge under the body's weight (12 nm for a 12 mm, 0.5 g bar)
SUPPORT_COMPLIANCE = 1e-6
#: standard gravity [m/s^2]: a body's force scale is its weight at it (whatever the scenario's g)
STANDARD_GRAVITY = 9.81
#: the corners of a box, as signs of its half-edges (8, 3)
CORNER_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
#: unknowns per contact of a body: normal force, tangential force (3), slip multiplier
CONTACT_UNKNOWNS = 5


@dataclass(frozen=True)
class BodyModel:
    """A free rigid box: ``name``, ``index`` into ``robot.bodies``, edges ``size`` (3,) [m], its
    placed pose ``position`` (3,) [m] and ``rotation`` (3, 3), ``friction`` (between it and the
    rods), ``support`` (index into ``robot.obstacles`` of the plane it rests on, or None) and
    ``modules`` (indices of the modules that may touch it), ``mass`` [kg] as the scenario gives
    it (its force scale; the weight itself is the parameter ``NAME.mass``),
    ``support_friction`` (between it and its support)."""
    name: str
    index: int
    mass: float
    size: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    friction: float
    support: object
    modules: tuple
    #: the friction law (``contact.friction_law``): False sticks whatever the force (the
    #: verdict says when that needs more friction than the body has), True slides on
    #: Coulomb's cone
    sliding: bool = False
    support_friction: float = 0.0

    @property
    def length_scale(self):
        return float(np.max(self.size))

    @property
    def corners(self):
        """The box's corners in its own frame (8, 3) [m]."""
        return CORNER_SIGNS * (np.asarray(self.size, float) / 2)


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
    """0 for ``z << -width``, 1 for ``z >> width``, smooth between: ``(1 + tanh(z / width)) / 2``
    (its tails fall off exponentially: a contact let go of leaves no tangential force)."""
    return 0.5 * (1 + tanh(z / width))


def friction_equations(moved, n, sticks, normal_force, tangential, slip, gap, force_scale, gap_scale, friction,
                       sliding, compliance=0.0):
    """The four scaled friction equations of one contact (module docstring): three on the
    tangential force ``tangential`` (3,) [N], one on the slip multiplier ``slip``
    (dimensionless). ``moved`` (3,) [m] how far the contact point moved since its anchor,
    ``friction`` Coulomb's coefficient, ``sliding`` the law, ``compliance`` ``kappa``."""
    import casadi as ca
    from .contact import normal_contact
    P = ca.DM.eye(3) - n @ n.T
    along = P @ tangential
    normal_part = n * ca.dot(n, tangential) / force_scale
    if sliding and friction <= 0:                       # Coulomb with no friction: frictionless
        return ca.vertcat(along / force_scale + normal_part, slip)
    c = sticks * smooth_step(normal_force / force_scale - gap / gap_scale)
    tangent = c * (P @ moved / gap_scale + (compliance + slip) * along / force_scale) + \
        (1 - c) * along / force_scale + normal_part
    if not sliding:
        return ca.vertcat(tangent, slip)
    margin = cone_margin(friction, normal_force, along, CONE_SMOOTHING * force_scale)
    return ca.vertcat(tangent, c * normal_contact(slip * force_scale, margin, force_scale, force_scale) + (1 - c) * slip)


def grip_friction(point, n, r, R, anchor, sticks, normal_force, tangential, slip, gap, force_scale, gap_scale,
                  friction=0.0, sliding=False):
    """The four friction equations of one grip: ``point`` the rod's material point that
    friction holds (:func:`~.contact.held_point`), ``(r, R)`` the body's pose, ``anchor`` (3,)
    the body-frame point it was at."""
    return friction_equations(point - r - R @ anchor, n, sticks, normal_force, tangential, slip, gap, force_scale,
                              gap_scale, friction, sliding)


def slides(slip, margin, force_scale):
    """True on the sliding side of a contact's slip complementarity's corner (``slip`` its
    multiplier, ``margin`` [N] its friction margin)."""
    return float(slip) > float(margin) / force_scale


def corner_points(body, r, R):
    """The box's corners at pose ``(r, R)``: a list of eight (3,) points [m] (numbers or
    CasADi)."""
    if is_casadi(r) or is_casadi(R):
        import casadi as ca
        return [r + R @ ca.DM(corner) for corner in body.corners]
    return [np.asarray(r, float).ravel() + np.asarray(R, float) @ corner for corner in body.corners]


def placed_corners(body):
    """The corners at the body's placed pose (8, 3) [m]: where the support anchors are measured from."""
    return np.array(corner_points(body, body.position, body.rotation))


def support_gaps(plane, body, r, R):
    """``(gaps, n)``: each corner's distance above the support ``plane`` [m] (8 numbers or
    symbols) and the plane's outward normal."""
    found = [plane.signed_distance(point) for point in corner_points(body, r, R)]
    return [g for g, _ in found], found[0][1]


def support_equations(plane, body, r, R, anchors, sticks, corner_unknowns):
    """The support's scaled equations, five per corner (normal complementarity with its
    compliance, then :func:`friction_equations`): ``anchors`` (8, 3) how far each corner's
    anchor lies from its placed position [m], ``sticks`` (8,), ``corner_unknowns`` per corner
    ``(f_n [N], f_t (3,) [N], lambda)``."""
    import casadi as ca
    from .contact import normal_contact
    fo, lo = body_scales(body)
    gaps, n = support_gaps(plane, body, r, R)
    out = []
    for point, origin, anchor, g, (f, t, slip), stick in zip(corner_points(body, r, R), placed_corners(body), anchors,
                                                             gaps, corner_unknowns, sticks):
        out.append(normal_contact(f, g + SUPPORT_COMPLIANCE * lo * f / fo, fo, lo))
        moved = point - ca.DM(origin) - anchor
        out.append(friction_equations(moved, n, stick, f, t, slip, g, fo, lo, body.support_friction,
                                      body.sliding, SUPPORT_COMPLIANCE))
    return ca.vertcat(*out)


def body_equilibrium(r, weight, grips, support=(), inertial=None):
    """``[force (3); moment about r (3)]`` [N, N m] on a body: its ``weight`` (3,) at ``r``, each
    grip ``(point, force on the rod)`` reacted on it, each support force ``(point, force on the
    body)``, and in dynamics its ``inertial`` (d'Alembert) force and moment about ``r``
    (:func:`inertial_wrench`)."""
    force, moment = weight, 0 * weight
    if inertial is not None:
        force, moment = force + inertial[0], moment + inertial[1]
    for point, on_rod in grips:
        force = force - on_rod
        moment = moment - cross(point - r, on_rod)
    for point, reaction in support:
        force = force + reaction
        moment = moment + cross(point - r, reaction)
    return force, moment


# ----------------------------------------------------------------------------- inertia (issue 33)
def box_moments(size, mass):
    """The principal moments of inertia [kg m^2] (3,) of a uniform box of edges ``size`` (3,) [m]
    and ``mass`` [kg] (number or symbol) about its centre, in its own frame:
    ``m (b^2 + c^2) / 12``, ...; the box's frame is its principal frame."""
    a, b, c = (float(x) ** 2 for x in size)
    return [mass * (b + c) / 12.0, mass * (a + c) / 12.0, mass * (a + b) / 12.0]


def angular_velocity(g, rate):
    """The body-frame angular velocity [rad/s] (3,) of ``R0 R(g)`` when its Gibbs vector ``g``
    changes at ``rate`` [1/s]: ``(g_t - g x g_t / 2) / (1 + |g|^2 / 4)`` (from
    ``R^T R_t = [omega]x``; numbers or symbols)."""
    if is_casadi(g) or is_casadi(rate):
        import casadi as ca
        return (rate - 0.5 * ca.cross(g, rate)) / (1 + ca.dot(g, g) / 4)
    g, rate = np.asarray(g, float), np.asarray(rate, float)
    return (rate - 0.5 * cross(g, rate)) / (1 + g @ g / 4)


def body_motion(c0, pose, history):
    """``(v, omega, a, omega_t)`` (3,) each of a free body in a time step whose rates are
    ``x_t = c0 x + h``: its velocity ``c0 delta + h_delta``, body-frame angular velocity
    ``omega(g, c0 g + h_g)`` (:func:`angular_velocity`) and their rates ``c0 v + h_v``,
    ``c0 omega + h_omega``, from its pose ``[delta, g]`` (6,) and its ``history`` (12,)
    (numbers or symbols)."""
    rate = c0 * pose[0:6] + history[0:6]
    velocity, omega = rate[0:3], angular_velocity(pose[3:6], rate[3:6])
    return velocity, omega, c0 * velocity + history[6:9], c0 * omega + history[9:12]


def inertial_wrench(mass, moments, R, acceleration, omega, omega_rate):
    """The d'Alembert force [N] and moment about the centre [N m] (global frame) of a rigid box:
    ``-m a`` and ``-R (J omega_t + omega x J omega)`` (Euler's equations in the body frame;
    ``omega``, ``omega_rate`` body frame, ``moments`` the diagonal of ``J``)."""
    if any(is_casadi(x) for x in (mass, R, acceleration, omega, omega_rate)):
        import casadi as ca
        J = ca.vertcat(*moments)
        return -mass * acceleration, -(R @ (J * omega_rate + ca.cross(omega, J * omega)))
    J = np.asarray([float(x) for x in moments])
    omega, omega_rate = np.asarray(omega, float), np.asarray(omega_rate, float)
    return -mass * np.asarray(acceleration, float), -(np.asarray(R, float) @ (J * omega_rate + cross(omega, J * omega)))


def kinetic_energy(mass, moments, velocity, omega):
    """``m |v|^2 / 2 + omega . J omega / 2`` [J] of a rigid box (numbers)."""
    velocity, omega = np.asarray(velocity, float), np.asarray(omega, float)
    return 0.5 * mass * float(velocity @ velocity) + 0.5 * float(np.asarray(moments, float) @ (omega * omega))


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

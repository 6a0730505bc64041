"""Point wrenches and junction links, written once for both solvers (SPEC sections 3 and 5).

Every function takes CasADi symbols or numbers. States are deviation states
``[p, h, u - u*, v - v*]`` (see :mod:`.rod`); a wrench is ``[moment; force]`` in the body frame.
``tension(actuator)`` and ``param(name)`` give an actuator's tension [N] and a parameter's value.
"""
import casadi as ca
import numpy as np

from .arith import is_casadi
from .contact import contact_wrench
from .rod import ANCHOR_WRENCH, POINT_WRENCH
from .rotations import quaternion_product, rotation_matrix

P_, H_ = slice(0, 3), slice(3, 7)


def stiffness(module, param):
    """(6,) stiffness diagonal at the parameters, as a CasADi column."""
    k = module.stiffness_of(param)
    return k if is_casadi(k) else ca.DM(k)


def internal_wrench(module, state, param):
    """``K (xi - xi*)`` [N m; N] of a deviation state."""
    return stiffness(module, param) * state[7:13]


def tangent_wrench(module, actuator, s, state, tension, param):
    """``[r x F t; F t]`` (body frame) of an actuator at s, ``t`` its unit tangent computed from
    ``state`` (the state on one side of s)."""
    r, dr, _ = actuator.route_values(s, param)
    u = state[7:10] + ca.DM(module.xi_star[0:3])
    v = state[10:13] + ca.DM(module.xi_star[3:6])
    return ANCHOR_WRENCH(u, v, r[:, 0], dr[:, 0], tension)


def point_load_wrench(load, h, param):
    """Wrench of a point force/moment or a point mass's weight at the centerline."""
    zero = ca.DM.zeros(3)
    if load.kind == "object":
        weight = param(f"{load.name}.held") * param(f"{load.name}.mass") * load.share * param("gravity")
        return POINT_WRENCH(h, weight, zero, zero, zero)
    if load.kind == "mass":
        return POINT_WRENCH(h, param(f"{load.name}.mass") * param("gravity"), zero, zero, zero)
    force, moment = param(f"{load.name}.force"), param(f"{load.name}.moment")
    if load.frame == "global":
        return POINT_WRENCH(h, force, moment, zero, zero)
    return POINT_WRENCH(h, zero, zero, force, moment)


def actuators_after(robot, m, s):
    """Actuators of module m that pull at s with their tangent just after s: those starting at
    s, and those running through s when the strains may jump there (:func:`strains_jump`)."""
    module, tol = robot.modules[m], 1e-12 * robot.modules[m].length
    starting = [a for a in module.actuators if abs(a.route.span[0] - s) <= tol]
    if not starting and not _events_at(robot, m, s):
        return []
    return [a for a in module.actuators if a.route.span[0] - tol <= s < a.route.span[1] - tol]


def actuators_before(robot, m, s):
    """Actuators of module m that pull at s with their tangent just before s: those ending at s,
    and those running through s when the strains may jump there."""
    module, tol = robot.modules[m], 1e-12 * robot.modules[m].length
    if not _events_at(robot, m, s):
        return []
    return [a for a in module.actuators if a.route.span[0] + tol < s <= a.route.span[1] + tol]


def _events_at(robot, m, s):
    """True where the strains may jump at s: an actuator is anchored there or a point load or
    mass acts there. Elsewhere the strains are continuous, so running actuators have no
    corner and are left out (that keeps the Jacobians sparse and the shots cheap)."""
    module, tol = robot.modules[m], 1e-12 * robot.modules[m].length
    return bool(loads_at(robot, m, s)) or bool(robot.contacts_at(m, s)) or any(
        abs(a.route.span[0] - s) <= tol or abs(a.route.span[1] - s) <= tol for a in module.actuators)


def loads_at(robot, m, s):
    module = robot.modules[m]
    return [load for load in robot.point_loads if load.module == m and abs(load.s - s) <= 1e-12 * module.length]


def point_wrenches(robot, m, s, before, after, tension, param, contact=None):
    """Sum of the point wrenches applied at arc length s of module m, or ``None`` if none is.

    Each actuator present at s pulls the body with ``F (t+ - t-)`` at ``r(s)``, ``t-``/``t+`` its
    unit tangent just before/after s and zero outside its span: ``+F t+`` where it starts (its
    anchor), ``-F t-`` where it ends, and the corner force ``F (t+ - t-)`` where it runs through
    a point at which the strains jump (a point load, another actuator's anchor). This is the
    delta part of the distributed load ``F q = F R^T t'`` (SPEC section 3) at a jump of ``t``.
    Point loads and masses are added, and the contacts at s (``contact(c)``: ``(shape, normal
    force [N], tangential force (3,) [N] or None)`` of :class:`~tca_casadi.model.contact.ContactModel`
    c, the shape placed; :func:`.contact.contact_wrench`).
    ``before``/``after`` (deviation states either side of s) may be None at the module's ends.
    """
    module, total = robot.modules[m], None
    if after is not None:
        for actuator in actuators_after(robot, m, s):
            total = add(total, tangent_wrench(module, actuator, s, after, tension(actuator), param))
    if before is not None:
        for actuator in actuators_before(robot, m, s):
            total = add(total, -tangent_wrench(module, actuator, s, before, tension(actuator), param))
    h = (after if after is not None else before)[H_]
    for load in loads_at(robot, m, s):
        total = add(total, point_load_wrench(load, h, param))
    state = after if after is not None else before
    for c in robot.contacts_at(m, s):
        total = add(total, contact_wrench(module, state, *contact(c)))
    return total


def connector_of(module):
    """``(offset (3,), quaternion (4,), rotation (3, 3))`` of the link into ``module``."""
    connector = module.connector
    offset = np.zeros(3) if connector is None else connector.offset
    quaternion = np.array([1.0, 0, 0, 0]) if connector is None else connector.quaternion
    return offset, quaternion, np.array(rotation_matrix(ca.DM(quaternion)))


def junction_pose(end, next_module):
    """Base position and quaternion of ``next_module`` from the previous module's end state."""
    offset, quaternion, _ = connector_of(next_module)
    return end[P_] + rotation_matrix(end[H_]) @ ca.DM(offset), quaternion_product(end[H_], ca.DM(quaternion))


def transmit(base_wrench, next_module):
    """A wrench at the next module's base (its frame) expressed at the previous tip (its frame)."""
    offset, _, rotation = connector_of(next_module)
    force = ca.DM(rotation) @ base_wrench[3:6]
    return ca.vertcat(ca.DM(rotation) @ base_wrench[0:3] + ca.cross(ca.DM(offset), force), force)


def untransmit(tip_wrench, next_module):
    """Inverse of :func:`transmit`."""
    offset, _, rotation = connector_of(next_module)
    force = ca.DM(rotation).T @ tip_wrench[3:6]
    moment = ca.DM(rotation).T @ (tip_wrench[0:3] - ca.cross(ca.DM(offset), tip_wrench[3:6]))
    return ca.vertcat(moment, force)


def connector_weight(end, next_module, param):
    """Wrench of the connector's weight at the previous tip (its frame), or None."""
    connector = next_module.connector
    if connector is None or connector.mass <= 0:
        return None
    weight = rotation_matrix(end[H_]).T @ (connector.mass * param("gravity"))
    return ca.vertcat(ca.cross(ca.DM(connector.center_of_mass), weight), weight)


def child_wrench(end, child, base_wrench, param):
    """Wrench that a child module puts on its parent's tip (parent tip frame, ``end`` the
    parent's end state): the child's base wrench through the connector plus the connector's
    weight. A decoupled child passes on only the force (its weight and payload: the net external
    force on it), not the moment (SPEC section 5)."""
    total = add(transmit(base_wrench, child), connector_weight(end, child, param))
    if child.decoupled:
        return ca.vertcat(ca.DM.zeros(3), total[3:6])
    return total


def base_wrench(robot, m, start, tension, param, viscous=None, extra=None, contact=None):
    """``W(0-)`` of module m: the internal wrench at its start plus the point wrenches there
    (what its base support, or its parent's tip, carries). Dynamics: ``viscous``, the viscous
    part of the internal wrench at the start, and ``extra``, further applied wrenches there
    (point masses' inertia), (6,) each or None."""
    internal = add(internal_wrench(robot.modules[m], start, param), viscous)
    return add(add(internal, point_wrenches(robot, m, 0.0, None, start, tension, param, contact)), extra)


def tip_balance(robot, m, end, starts, tension, param, viscous=None, extra=None, contact=None):
    """``W(L) - point wrenches at L - sum of what the children in ``starts`` ({child: start
    state}) put on the tip`` (parent tip frame, SPEC section 5): zero at equilibrium when every
    child is included; with some left out, what those must carry. Dynamics: ``viscous``, the
    viscous parts of the internal wrenches, and ``extra``, further applied wrenches (inertia of
    point and connector masses), each ``{m: at the tip (its frame), c: at child c's base}``."""
    module, viscous, extra = robot.modules[m], viscous or {}, extra or {}
    applied = add(point_wrenches(robot, m, module.length, end, None, tension, param, contact), extra.get(m))
    balance = add(internal_wrench(module, end, param), viscous.get(m)) - add(ca.DM.zeros(6), applied)
    for c, start in starts.items():
        base = base_wrench(robot, c, start, tension, param, viscous.get(c), extra.get(c), contact)
        balance = balance - child_wrench(end, robot.modules[c], base, param)
    return balance


def add(a, b):
    """Sum where ``None`` means nothing."""
    if a is None:
        return b
    return a if b is None else a + b

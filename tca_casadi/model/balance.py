"""Global equilibrium of the whole robot, from a solution alone: a conservation check that does
not trust either solver's discretisation.

The actuators (TCAs, tendons) are internal: their distributed loads ``F q``, anchor forces and
corner forces sum to zero over each actuator. What the base support transmits must therefore
balance every external load: self-weight, distributed loads, point loads, point masses, held
objects and connector masses. With ``x_0`` the base point, the residuals are

    force:  F_base + sum F_i = 0,     moment:  M_base + sum ((x_i - x_0) x F_i + M_i) = 0,

``F_base``, ``M_base`` the reaction on the first module's base (global frame). Integrals along
the modules use each solution's own quadrature weights (``ModuleResult.weights``). A decoupled
module passes only its net force to its parent's tip (SPEC section 5), so the loads on a
decoupled subtree enter as forces at the point where it hangs, with no moment of their own.
"""
from dataclasses import dataclass

import numpy as np

from .arith import cross

@dataclass
class GlobalBalance:
    """Residual force [N] and moment about the base point [N m] of the whole robot, and the
    scales they are judged against: the sum of the magnitudes of the external forces and the
    actuator tensions, and of the external moments about the base point and the tensions times
    their module's length."""
    force: np.ndarray
    moment: np.ndarray
    force_scale: float
    moment_scale: float

    @property
    def relative(self):
        """Largest residual relative to its scale (0 when nothing is loaded)."""
        f = np.max(np.abs(self.force)) / self.force_scale if self.force_scale > 0 else 0.0
        m = np.max(np.abs(self.moment)) / self.moment_scale if self.moment_scale > 0 else 0.0
        return float(max(f, m))

    def as_dict(self):
        return {"force_residual": self.force.tolist(), "moment_residual": self.moment.tolist(),
                "force_scale": self.force_scale, "moment_scale": self.moment_scale,
                "relative": self.relative}


def global_balance(robot, modules, params, tensions, extra_loads=None, contact_loads=None):
    """:class:`GlobalBalance` of a solution's ``modules`` (``ModuleResult`` list) at ``params``,
    with the actuators' ``tensions`` [N] (``robot.actuators`` order) in the scales: each
    actuator's internal loads are of the order of its tension (and its tension times the module's
    length for moments), so that is what a residual is small against. ``extra_loads``:
    ``(points, forces, moments)`` (3, k) global, further loads (a dynamic step's inertia);
    ``contact_loads``: ``{m: (points, forces)}`` (3, k) global, the contact forces on module m."""
    base = modules[0].p[:, 0]
    force, moment = modules[0].base_reaction["force"].copy(), modules[0].base_reaction["moment"].copy()
    pulls = [abs(float(t)) for t in tensions]
    force_scale = float(sum(pulls))
    moment_scale = float(sum(p * robot.modules[a.module].length for p, a in zip(pulls, robot.actuators)))
    value = _values(robot, params)
    for m, result in enumerate(modules):
        points, forces, moments = _module_loads(robot, m, result, modules, value,
                                                (contact_loads or {}).get(m))           # (3, k) each
        hanger = _decoupled_root(robot, m)
        if hanger is not None:           # a decoupled subtree: its net force at its attachment
            points = modules[robot.modules[hanger].parent].p[:, -1:]
            forces, moments = forces.sum(axis=1, keepdims=True), np.zeros((3, 1))
        arms = cross(points - base[:, None], forces)
        force, moment = force + forces.sum(axis=1), moment + arms.sum(axis=1) + moments.sum(axis=1)
        force_scale += float(np.linalg.norm(forces, axis=0).sum())
        moment_scale += float(np.linalg.norm(arms, axis=0).sum() + np.linalg.norm(moments, axis=0).sum())
    if extra_loads is not None:
        points, forces, moments = extra_loads
        arms = cross(points - base[:, None], forces)
        force, moment = force + forces.sum(axis=1), moment + arms.sum(axis=1) + moments.sum(axis=1)
        force_scale += float(np.linalg.norm(forces, axis=0).sum())
        moment_scale += float(np.linalg.norm(arms, axis=0).sum() + np.linalg.norm(moments, axis=0).sum())
    return GlobalBalance(force, moment, force_scale, moment_scale)


def _module_loads(robot, m, result, modules, value, contacts=None):
    """``(points, forces, moments)``, each (3, k): every external load on module m (global
    frame), its self-weight as one load per quadrature node, ``contacts`` ``(points, forces)``
    (3, k) its contact forces."""
    module, g, w = robot.modules[m], value("gravity"), result.weights
    loads = [(result.p, module.weight_density * np.outer(g, w), np.zeros((3, w.size)))]
    if module.connector is not None and module.connector.mass > 0:
        tip = modules[module.parent]
        point = tip.p[:, -1] + tip.R[:, :, -1] @ module.connector.center_of_mass
        loads.append(_columns(point, module.connector.mass * g, np.zeros(3)))
    for load in robot.point_loads:
        if load.module == m:
            loads.append(_columns(*_point_load(load, result, value)))
    for load in robot.distributed_loads:
        if load.module == m:
            loads.append(_distributed_load(load, result, value))
    if contacts is not None:
        loads.append((contacts[0], contacts[1], np.zeros_like(contacts[1])))
    return tuple(np.hstack(parts) for parts in zip(*loads))


def _columns(*vectors):
    return tuple(np.asarray(v, float).reshape(3, 1) for v in vectors)


def _point_load(load, result, value):
    i = int(np.argmin(np.abs(result.s - load.s)))
    point = result.p[:, i]
    if load.kind == "object":
        return point, value(f"{load.name}.held")[0] * value(f"{load.name}.mass")[0] * load.share * value("gravity"), np.zeros(3)
    if load.kind == "mass":
        return point, value(f"{load.name}.mass")[0] * value("gravity"), np.zeros(3)
    force, moment = value(f"{load.name}.force"), value(f"{load.name}.moment")
    if load.frame == "body":
        R = result.R[:, :, i]
        force, moment = R @ force, R @ moment
    return point, force, moment


def _distributed_load(load, result, value):
    """``(points, forces, moments)`` (3, k) of a distributed load at the quadrature nodes in its span."""
    inside = np.flatnonzero((result.s > load.span[0]) & (result.s <= load.span[1]) & (result.weights != 0))
    force, moment = value(f"{load.name}.force"), value(f"{load.name}.moment")
    w = result.weights[inside]
    if load.frame == "body":
        R = result.R[:, :, inside]
        return result.p[:, inside], np.einsum("ijk,j->ik", R, force) * w, np.einsum("ijk,j->ik", R, moment) * w
    return result.p[:, inside], np.outer(force, w), np.outer(moment, w)


def load_markers(robot, modules, params):
    """Point loads and masses for drawings: ``[{name, kind, position (3,), force (3,), moment (3,)}]``
    (global frame, SI), held objects' shares included."""
    value = _values(robot, params)
    out = []
    for load in robot.point_loads:
        point, force, moment = _point_load(load, modules[load.module], value)
        out.append({"name": load.name, "kind": load.kind, "position": point, "force": force, "moment": moment})
    return out


def _decoupled_root(robot, m):
    """The outermost decoupled module on the path from m to the base (m included), or None."""
    root = None
    while m is not None and m > 0:
        if robot.modules[m].decoupled:
            root = m
        m = robot.modules[m].parent
    return root


def _values(robot, params):
    params = np.asarray(params, float)
    return lambda name: np.atleast_1d(params[robot.layout[name]])

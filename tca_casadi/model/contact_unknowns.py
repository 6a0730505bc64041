"""The unknowns of contact and of free bodies, and their conditions, written once for every
solver (issue 33: collocation and shooting share them).

Per contact candidate against an obstacle (:mod:`.contact`) its normal force ``f`` [N]; against
an obstacle with friction also its tangential force ``f_t`` (3) [N] and slip multiplier
``lambda``; per grip (a candidate against a free body, :mod:`.bodies`) ``(f, f_t, lambda)``; per
free body its pose ``[delta (3) [m], g (3)]`` (:func:`~.bodies.body_pose`) and, on a support, per
corner ``(f, f_t, lambda)``. :class:`ContactUnknowns` lays them out as one block (the order the
collocation NLP declares them in: normal forces, frictions, grips, then per body its pose and
corners) with their scales; :class:`ContactViews` names the pieces of a block (symbolic or
numeric) and :func:`contact_conditions` writes their equations: per contact the normal
complementarity (:func:`~.contact.normal_contact`) and, with friction, four friction equations;
per grip the same against the body at its unknown pose; per body its six equilibrium equations
and five per support corner. The count equals the block's size: the conditions square the
unknowns.
"""
from dataclasses import dataclass, field

import numpy as np

from .bodies import (CONTACT_UNKNOWNS, CORNER_SIGNS, body_equilibrium, body_pose, body_scales, body_shape,
                     corner_points, friction_equations, grip_friction, support_equations)
from .contact import contact_geometry, held_point, normal_contact, outline_size
from .history import support_parameter


@dataclass
class ContactViews:
    """The pieces of a contact block (physical units; CasADi or numpy): ``contact_forces`` (n,)
    of ``robot.contacts``; ``frictions`` ``{contact index: (f_t (3,), lambda)}``; ``grips``
    ``[(f, f_t (3,), lambda)]`` of ``robot.grips``; ``poses`` ``[(6,)]`` and ``body_shapes`` of
    ``robot.bodies``; ``supports`` ``{body index: [(f, f_t, lambda)] * 8}``."""
    contact_forces: object
    frictions: dict = field(default_factory=dict)
    grips: list = field(default_factory=list)
    poses: list = field(default_factory=list)
    body_shapes: list = field(default_factory=list)
    supports: dict = field(default_factory=dict)

    def contact_of(self, robot, param):
        """``contact -> (shape, f_n [N], f_t (3,) [N] or None, offset (3,) or None)`` for
        :mod:`.boundary`: the obstacle placed at the parameters, or (a grip) the body at its
        pose; ``offset`` where on the rod's section friction acts (:func:`~.contact.held_point`)."""
        def of(contact):
            if contact.body is not None:
                return ((self.body_shapes[contact.body],) + tuple(self.grips[contact.index][0:2])
                        + (param(robot.grip_parameter(contact, "offset")),))
            if contact.index not in self.frictions:
                return robot.obstacle_of(contact.obstacle, param), self.contact_forces[contact.index], None, None
            return (robot.obstacle_of(contact.obstacle, param), self.contact_forces[contact.index],
                    self.frictions[contact.index][0], param(robot.contact_parameter(contact, "offset")))
        return of


class ContactUnknowns:
    """The contact and body unknowns of ``robot`` as one block: ``size``, ``scale`` (physical =
    scale * scaled) and :meth:`views`."""

    def __init__(self, robot):
        self.robot = robot
        scales = [np.array([robot.modules[c.module].force_scale for c in robot.contacts])]
        self._frictions = [c for c in robot.contacts if robot.frictional(c)]
        for c in self._frictions:
            scales.append(_frictional_scale(robot.modules[c.module].force_scale, normal=False))
        for c in robot.grips:
            scales.append(_frictional_scale(robot.modules[c.module].force_scale))
        for body in robot.bodies:
            fo, lo = body_scales(body)
            scales.append(np.r_[np.full(3, lo), np.ones(3)])
            if body.support is not None:
                scales += [_frictional_scale(fo)] * len(CORNER_SIGNS)
        self.scale = np.concatenate(scales) if scales else np.zeros(0)
        self.size = self.scale.size

    def views(self, block):
        """:class:`ContactViews` of a physical block (CasADi column or numpy (size,))."""
        robot, offset = self.robot, len(self.robot.contacts)
        views = ContactViews(block[0:offset])
        for c in self._frictions:
            views.frictions[c.index] = (block[offset:offset + 3], block[offset + 3])
            offset += CONTACT_UNKNOWNS - 1
        for _ in robot.grips:
            views.grips.append((block[offset], block[offset + 1:offset + 4], block[offset + 4]))
            offset += CONTACT_UNKNOWNS
        for body in robot.bodies:
            pose = block[offset:offset + 6]
            views.poses.append(pose)
            views.body_shapes.append(body_shape(body, *body_pose(body, pose)))
            offset += 6
            if body.support is not None:
                corners = []
                for _ in range(len(CORNER_SIGNS)):
                    corners.append((block[offset], block[offset + 1:offset + 4], block[offset + 4]))
                    offset += CONTACT_UNKNOWNS
                views.supports[body.index] = corners
        return views

    def solution_values(self, block):
        """The keyword arguments of :func:`~tca_casadi.solvers.assemble.build_solution` for a
        numeric physical block: ``contact_forces``, ``frictions`` and ``bodies``."""
        views = self.views(np.asarray(block, float))
        out = {}
        if self.robot.obstacles:
            out["contact_forces"] = np.asarray(views.contact_forces, float)
            out["frictions"] = {c: (np.asarray(t, float), float(slip)) for c, (t, slip) in views.frictions.items()}
        if self.robot.bodies:
            out["bodies"] = {"grips": [np.r_[f, t, slip] for f, t, slip in views.grips],
                             "poses": [np.asarray(p, float) for p in views.poses],
                             "supports": {b: np.concatenate([np.r_[f, t, slip] for f, t, slip in corners])
                                          for b, corners in views.supports.items()}}
        return out


def _frictional_scale(force_scale, normal=True):
    """Scales of one frictional contact's ``(f_n, f_t (3), lambda)`` (without ``f_n``)."""
    size = CONTACT_UNKNOWNS - (0 if normal else 1)
    return np.r_[np.full(size - 1, force_scale), 1.0]


def contact_conditions(robot, views, state_at, param, inertia=None):
    """The equations of a contact block (module docstring), a list of CasADi columns.
    ``state_at(module, s)``: the deviation state (13,) at a candidate (its pose is what counts);
    ``param(name)``: a parameter; ``inertia(body, pose)``: in dynamics, a body's d'Alembert force
    and moment (:func:`~.bodies.inertial_wrench`) at its pose unknowns (6,)."""
    out = []
    for c in robot.contacts:
        module = robot.modules[c.module]
        shape = robot.obstacle_of(c.obstacle, param)
        state = state_at(c.module, c.s)
        g, n, _ = contact_geometry(shape, module, state)
        f, fs, gs = views.contact_forces[c.index], module.force_scale, outline_size(module)
        out.append(normal_contact(f, g, fs, gs))
        if c.index in views.frictions:
            tangential, slip = views.frictions[c.index]
            held = held_point(state, param(robot.contact_parameter(c, "offset")))
            moved = held - shape.position - param(robot.contact_parameter(c, "anchor"))
            out.append(friction_equations(moved, n, param(robot.contact_parameter(c, "sticks")), f, tangential, slip,
                                          g, fs, gs, robot.obstacles[c.obstacle].friction,
                                          robot.friction_law == "coulomb"))
    return out + body_conditions(robot, views, state_at, param, inertia)


def body_conditions(robot, views, state_at, param, inertia=None):
    """Per grip its normal complementarity and four friction equations; per body its six
    equilibrium equations (scaled by ``f_o`` and ``f_o L_o``; in dynamics with the ``inertia`` of
    :func:`contact_conditions`) and, on a support, five per corner."""
    import casadi as ca
    out, on_body = [], [[] for _ in robot.bodies]
    poses = [(shape.position, shape.rotation) for shape in views.body_shapes]
    for c in robot.grips:
        module, body = robot.modules[c.module], robot.bodies[c.body]
        state = state_at(c.module, c.s)
        g, n, point = contact_geometry(views.body_shapes[c.body], module, state)
        held = held_point(state, param(robot.grip_parameter(c, "offset")))
        fs, gs = module.force_scale, outline_size(module)
        f, t, slip = views.grips[c.index]
        out.append(normal_contact(f, g, fs, gs))
        out.append(grip_friction(held, n, *poses[c.body], param(robot.grip_parameter(c, "anchor")),
                                 param(robot.grip_parameter(c, "sticks")), f, t, slip, g, fs, gs,
                                 body.friction, body.sliding))
        on_body[c.body] += [(point, f * n), (held, t)]
    for body in robot.bodies:
        fo, lo = body_scales(body)
        r, R = poses[body.index]
        weight = param(f"{body.name}.mass") * param("gravity")
        support = []
        if body.index in views.supports:
            corners = views.supports[body.index]
            plane = robot.obstacle_of(body.support, param)
            anchors = [param(support_parameter(body.name, j, "anchor")) for j in range(len(corners))]
            sticks = [param(support_parameter(body.name, j, "sticks")) for j in range(len(corners))]
            out.append(support_equations(plane, body, r, R, anchors, sticks, corners))
            n = plane.signed_distance(r)[1]
            support = [(point, f * n + t) for point, (f, t, _) in zip(corner_points(body, r, R), corners)]
        inertial = None if inertia is None else inertia(body, views.poses[body.index])
        force, moment = body_equilibrium(r, weight, on_body[body.index], support, inertial)
        out.append(ca.vertcat(force / fo, moment / (fo * lo)))
    return out


__all__ = ["ContactUnknowns", "ContactViews", "body_conditions", "contact_conditions"]

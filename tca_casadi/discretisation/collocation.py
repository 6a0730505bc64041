"""Direct collocation of a robot: one CasADi NLP per scenario structure (SPEC section 6).

Glossary of the NLP (written down once; the solvers and the guess rely on it):

Variables ``w`` (scaled: the physical value is ``scale * w``):
    1. for each module m, for each interval i, for each node j = 0..d (j = 0 is the interval
       start, then the collocation points): the deviation state
       ``[p (3), h (4), (u - u*) (3), (v - v*) (3)]``, scaled by ``[L, 1, F_s L / K_bt, F_s / K_se]``
       (``F_s = EI / L^2``: the strains become order-one internal moments and forces);
    2. for each module, the length of each of its actuators from the module's base to the end of
       each interval (cumulative, [/L]: the compatibility equations touch only the last one, so
       every column of the Jacobian is local and it stays block-banded);
    3. the unknown tensions [/F_s] (TCAs and displacement-controlled tendons), in
       ``robot.unknowns`` order (``tension_index``);
    4. the normal force of each contact candidate against an obstacle [/F_s of its module], in
       ``robot.contacts`` order (``contact_index``);
    5. per contact against an obstacle with friction, its tangential force (3) [/F_s] and slip
       multiplier (``friction_index``);
    6. per grip of a free body, its normal and tangential forces (1 + 3) [/F_s] and slip
       multiplier (``grip_index``); per free body its pose ``[delta (3) /L_o, g (3)]``
       (``pose_index``) and, on a support, per corner its normal and tangential forces [/f_o]
       and slip multiplier (``support_index``); ``body_index`` spans blocks 6;
    7. a dynamic NLP (:mod:`.dynamics`) appends the velocities ``[q (3), w (3)]`` at every node
       (``velocity_index``).
    ``contact_block_index`` spans blocks 4-6 (:mod:`tca_casadi.model.contact_unknowns`).
Parameters ``P``: the robot's parameter vector (``robot.layout``, declared in
    :mod:`tca_casadi.model.parameters`): gravity, base pose, material moduli and density, TCA
    geometry and fits, route placements, temperatures, tendon tensions, load forces/moments/masses.
    The variables' scales use the scenario's values; the equations use ``P``. A dynamic NLP
    appends ``c0``, the damping and the integrator's history (:mod:`tca_casadi.solvers.integrators`).
Constraints ``g`` (equalities, each scaled to order one), per module in order:
    the base pose (first module only); the rod equations at every collocation point,
    ``[p' - R v, h' - Omega h / 2, equilibrium (6)]``; the cumulative lengths (each the one
    before plus the Gauss quadrature of ``|a|`` over the interval); at the interior breakpoints, continuity of p and h and the wrench
    jump ``K (xi+ - xi-) + point wrenches = 0``; at the module's end, the pose link to each child
    module (through its connector) and the wrench balance (the tip wrench when it has none).
    Then one compatibility equation per unknown tension (a TCA's law multiplied through by
    ``G_t(F)``, a tendon's length condition; Fischer-Burmeister for ``tension_only``). Last, the
    contact block's conditions, one per unknown of blocks 4-6 (complementarity, Coulomb's cone,
    the free bodies' equilibria: :func:`~tca_casadi.model.contact_unknowns.contact_conditions`).
The forward problem is square: ``len(w) == len(g)``.
"""
import casadi as ca
import numpy as np

from ..model import boundary
from ..model.compatibility import compatibility_residuals
from ..model.bodies import CONTACT_UNKNOWNS, CORNER_SIGNS, body_pose, body_scales, body_shape
from ..model.contact_unknowns import ContactViews, contact_conditions
from ..model.loads import distributed_fields, is_active
from ..model.rod import STATE_SIZE, rod_equations
from .mesh import CollocationScheme, build_mesh

P_, H_ = slice(0, 3), slice(3, 7)


class CollocationNLP:
    """The collocation NLP of ``robot`` with ``intervals`` per module, ``degree`` and ``scheme``.

    Attributes: ``problem`` (dict for ``ca.nlpsol``), ``scale`` (w_physical = scale * w),
    ``outputs`` (Function ``(w, P) -> (lengths, ends, base_wrenches)``), ``meshes``.
    """

    def __init__(self, robot, intervals=12, degree=4, scheme="legendre", meshes=None):
        self.robot = robot
        self.scheme = CollocationScheme.create(degree, scheme)
        self.meshes = list(meshes) if meshes is not None else \
            [build_mesh(robot, m, intervals) for m in range(len(robot.modules))]
        self._declare_variables()
        self.P = ca.MX.sym("P", self.parameter_size)
        self._g, self._lengths = [], [0] * len(robot.actuators)
        self._viscous_ends = {}                # module -> viscous wrench at its tip (dynamics)
        self._partial_exprs = []
        self._ends, self._base_wrenches = [], []
        self._node_at = {}                     # module -> {breakpoint s: deviation state there}
        #: the rod equations' calls, cut out of the constraints (:mod:`.structure`)
        self.rod_calls = []
        for m in range(len(robot.modules)):
            self._module_constraints(m)
        self._compatibility()
        self._contact_conditions()
        #: the constraints with the rod equations' outputs as inputs: ``(w, P, Y_1..Y_k) -> g``
        self.split = ca.Function("nlp_g_split", [self.w, self.P] + [c.outputs for c in self.rod_calls],
                                 [ca.vertcat(*self._g)])
        g = self._joined(self.split)
        self.problem = {"x": self.w, "p": self.P, "f": ca.MX(0), "g": g}
        self.outputs = ca.Function(
            "outputs", [self.w, self.P],
            [ca.vertcat(*self._lengths), ca.horzcat(*self._ends), ca.horzcat(*self._base_wrenches)],
            ["w", "P"], ["lengths", "ends", "base_wrenches"])
        #: scaled cumulative lengths implied by the states (to initialise those unknowns)
        partials = ca.vertcat(*self._partial_exprs) if self._partial_exprs else ca.MX(0, 1)
        self.partials = ca.Function("partials", [self.w, self.P], [self._joined(ca.Function(
            "partials_split", [self.w, self.P] + [c.outputs for c in self.rod_calls], [partials]))])

    # ------------------------------------------------------------------ variables
    def _declare_variables(self):
        d = self.scheme.degree
        blocks, scales, self.state_index, self.node_scale, self.state_offset = [], [], [], [], []
        offset = 0
        for m, mesh in enumerate(self.meshes):
            module = self.robot.modules[m]
            count = len(mesh.intervals) * (d + 1) * STATE_SIZE
            blocks.append(ca.MX.sym(f"x_{module.name}", count))
            # strains as deviations from xi*, scaled by stiffness: order-one internal wrenches
            per_node = module.state_scale
            self.node_scale.append(per_node)
            self.state_offset.append(np.r_[np.zeros(7), module.xi_star])
            scales.append(np.tile(per_node, count // STATE_SIZE))
            index = offset + np.arange(count).reshape(len(mesh.intervals), d + 1, STATE_SIZE)
            self.state_index.append(index.transpose(0, 2, 1))  # (n_int, 13, d+1)
            offset += count
        # cumulative lengths: one per (actuator, interval) of each module, so that the
        # compatibility equations touch one unknown instead of every state (keeps the Jacobian
        # sparse), and each length two intervals' equations (keeps it banded)
        self._partials, self.partial_index = [], []
        for m, mesh in enumerate(self.meshes):
            module = self.robot.modules[m]
            count = len(module.actuators) * len(mesh.intervals)
            block = ca.MX.sym(f"l_{module.name}", count)
            self._partials.append(ca.reshape(block, len(module.actuators), len(mesh.intervals)) * module.length)
            blocks.append(block)
            scales.append(np.full(count, module.length))
            self.partial_index.append(offset + np.arange(count))
            offset += count
        unknowns = self.robot.unknowns
        blocks.append(ca.MX.sym("F", len(unknowns)))
        scales.append(np.array([self.robot.modules[a.module].force_scale for a in unknowns]))
        self.tension_index = offset + np.arange(len(unknowns))
        offset += len(unknowns)
        self._tensions = blocks[-1] * ca.DM(scales[-1]) if len(unknowns) else ca.MX(0, 1)
        contacts = self.robot.contacts
        blocks.append(ca.MX.sym("f_contact", len(contacts)))
        scales.append(np.array([self.robot.modules[c.module].force_scale for c in contacts]))
        self.contact_index = offset + np.arange(len(contacts))
        offset += len(contacts)
        self._contact_forces = blocks[-1] * ca.DM(scales[-1]) if len(contacts) else ca.MX(0, 1)
        self._frictions, self.friction_index = {}, {}
        for c in contacts:                 # against obstacles with friction: f_t (3) and the slip
            if self.robot.frictional(c):
                index = []
                (_, tangential, slip), offset = self._contact_block(f"friction_{c.index}",
                                                                    self.robot.modules[c.module].force_scale,
                                                                    blocks, scales, offset, index, normal=False)
                self._frictions[c.index], self.friction_index[c.index] = (tangential, slip), index[0]
        offset = self._declare_bodies(blocks, scales, offset)
        self.w = ca.vertcat(*blocks)
        self.scale = np.concatenate(scales)
        # deviation states [p, h, u - u*, v - v*] in SI units, per interval (13, d+1)
        self._states = []
        for m, block in enumerate(blocks[:len(self.meshes)]):
            matrix = ca.reshape(block, STATE_SIZE, -1)
            self._states.append(ca.diag(ca.DM(self.node_scale[m])) @ matrix)

    def _declare_bodies(self, blocks, scales, offset):
        """The free bodies' unknowns (:mod:`tca_casadi.model.bodies`): per grip its normal force,
        tangential force (3) [/F_s of its module] and slip multiplier; per body its pose
        ``[delta (3) /L_o, g (3)]`` and, on a support, per corner its normal force, tangential
        force (3) [/f_o] and slip multiplier. Returns the next offset; ``body_index`` holds every
        index of these unknowns."""
        robot, start = self.robot, offset
        self._grips, self._poses, self._supports = [], [], {}
        self.grip_index, self.pose_index, self.support_index = [], [], {}
        for c in robot.grips:
            block, offset = self._contact_block(f"grip_{c.index}", robot.modules[c.module].force_scale, blocks, scales,
                                                offset, self.grip_index)
            self._grips.append(block)
        self._body_shapes = []
        for body in robot.bodies:
            fo, lo = body_scales(body)
            block = ca.MX.sym(f"pose_{body.name}", 6)
            blocks.append(block)
            scales.append(np.r_[np.full(3, lo), np.ones(3)])
            self.pose_index.append(offset + np.arange(6))
            offset += 6
            pose = ca.vertcat(block[0:3] * lo, block[3:6])
            self._poses.append(pose)
            self._body_shapes.append(body_shape(body, *body_pose(body, pose)))
            if body.support is not None:
                corners, indices = [], []
                for j in range(len(CORNER_SIGNS)):
                    block, offset = self._contact_block(f"support_{body.name}_{j}", fo, blocks, scales, offset, indices)
                    corners.append(block)
                self._supports[body.index] = corners
                self.support_index[body.index] = np.concatenate(indices)
        self.body_index = np.arange(start, offset)
        return offset

    @staticmethod
    def _contact_block(name, force_scale, blocks, scales, offset, index, normal=True):
        """One frictional contact's unknowns ``(f_n [N], f_t (3,) [N], lambda)`` (``normal``
        False: without ``f_n``, which is None), appended to ``blocks``/``scales`` (forces scaled
        by ``force_scale``) and their indices to ``index``; returns them and the next offset."""
        size = CONTACT_UNKNOWNS - (0 if normal else 1)
        block = ca.MX.sym(name, size)
        blocks.append(block)
        scales.append(np.r_[np.full(size - 1, force_scale), 1.0])
        index.append(offset + np.arange(size))
        first = 1 if normal else 0
        return ((block[0] * force_scale if normal else None), block[first:first + 3] * force_scale,
                block[first + 3]), offset + size

    @property
    def slip_index(self):
        """Indices of every slip multiplier ``lambda`` (grips, support corners, contacts against
        obstacles with friction): zero when the history is carried from the state itself (each
        contact anchored where it is has not slipped)."""
        out = [index[CONTACT_UNKNOWNS - 1] for index in self.grip_index]
        out += [index[CONTACT_UNKNOWNS - 1::CONTACT_UNKNOWNS] for index in self.support_index.values()]
        out += [index[-1] for index in self.friction_index.values()]
        return np.array(np.hstack(out) if out else [], int)

    @property
    def parameter_size(self):
        """Length of ``P``: the robot's parameter vector (a dynamic NLP appends its history)."""
        return self.robot.layout.size

    def tension_of(self, actuator):
        """Symbolic tension [N] of an actuator: a variable when unknown, else a parameter."""
        if actuator.unknown_tension:
            return self._tensions[self.robot.unknowns.index(actuator)]
        return self.P[self.robot.layout[actuator.parameter]][0]

    @property
    def contact_block_index(self):
        """Indices in ``w`` of the contact block in the order of
        :class:`~tca_casadi.model.contact_unknowns.ContactUnknowns` (normal forces, frictions,
        grips, per body its pose and corners): what another solver warm-starts from."""
        parts = [self.contact_index] + [self.friction_index[c] for c in sorted(self.friction_index)]
        parts += list(self.grip_index)
        for body in self.robot.bodies:
            parts.append(self.pose_index[body.index])
            if body.index in self.support_index:
                parts.append(self.support_index[body.index])
        return np.concatenate(parts).astype(int) if parts else np.zeros(0, int)

    @property
    def contact_views(self):
        """:class:`~tca_casadi.model.contact_unknowns.ContactViews` of this NLP's contact and body
        unknowns (symbolic, physical units)."""
        return ContactViews(self._contact_forces, self._frictions, self._grips, self._poses, self._body_shapes,
                            self._supports)

    def contact_of(self, contact):
        """``(shape, normal force [N], tangential force (3,) [N] or None)`` of a contact
        (:class:`~tca_casadi.model.contact.ContactModel`): the obstacle placed at the
        parameters, or (a grip) the body at its unknown pose, symbolic."""
        return self.contact_views.contact_of(self.robot, self.param)(contact)

    def param(self, name):
        return self.P[self.robot.layout[name]]

    # ------------------------------------------------------------------ one module
    def _module_constraints(self, m):
        """Collocation equations of module m (one mapped call of the rod Function over all its
        collocation points), then the interval links and the module's end condition."""
        module, mesh, scheme = self.robot.modules[m], self.meshes[m], self.scheme
        d, n_int = scheme.degree, len(mesh.intervals)
        X = self._states[m]                                   # (13, n_int (d+1)) deviation states
        steps = np.array([s1 - s0 for s0, s1 in mesh.intervals])
        if m == 0:
            self._g.append((X[P_, 0] - self.param("base.position")) / module.length)
            self._g.append(X[H_, 0] - self.param("base.quaternion"))
        self._base_wrenches.append(self._base_wrench(m, X[:, 0]))
        nodes = mesh.node_s(scheme)                           # (n_int, d+1)
        colloc = (np.arange(n_int)[:, None] * (d + 1) + np.arange(1, d + 1)).ravel().tolist()
        s_colloc = nodes[:, 1:].ravel()
        interval_of = np.repeat(np.arange(n_int), d)
        derivative = _derivative_matrix(scheme, steps)        # (n_int (d+1), n_int d)
        dX = X @ derivative
        Xc = X[:, colloc]
        active = self._active_mask(m, nodes[:, 0] + 0.5 * steps)[:, interval_of]   # (nA, npts)
        viscous = self._viscous_nodes(m, X)                   # (6, nodes) or None (statics)
        rod = rod_equations(module.xi_star, len(module.actuators), viscous is not None)
        stiffness = boundary.stiffness(module, self.param) @ ca.DM.ones(1, len(colloc))
        loads = self._distributed(m, nodes[:, 0] + 0.5 * steps, interval_of)
        inertial = self._inertial_loads(m, Xc, colloc)
        if inertial is not None:                              # body-frame force and moment
            loads[2], loads[3] = loads[2] + inertial[0], loads[3] + inertial[1]
        extra = [] if viscous is None else [viscous[:, colloc], viscous @ derivative]
        kin, eq, speed = self._rod(rod, len(colloc), [Xc, dX[7:13, :], self._route_data(m, s_colloc, active),
                                                      self._tension_field(m, active), stiffness, *loads, *extra])
        fs, length = module.force_scale, module.length
        eq_scale = np.r_[np.ones(3), np.full(4, length), np.full(3, 1 / fs), np.full(3, length / fs)]
        self._g.append(ca.vec(ca.diag(ca.DM(eq_scale)) @ ca.vertcat(dX[0:7, :] - kin, eq)))
        if module.actuators:
            per_interval = _quadrature_matrix(scheme, steps)                 # (npts, n_int)
            partial = (speed * ca.DM(active)) @ per_interval                  # (nA, n_int)
            running = self._partials[m]                                       # (nA, n_int) cumulative
            before = ca.horzcat(ca.MX.zeros(len(module.actuators), 1), running[:, :-1])
            self._partial_exprs.append(ca.vec(ca.cumsum(partial, 1)) / module.length)
            self._g.append(ca.vec(running - before - partial) / module.length)
        for k, actuator in enumerate(module.actuators):
            position = self.robot.actuators.index(actuator)
            self._lengths[position] = self._partials[m][k, -1]
        ends = X @ ca.DM(_end_matrix(scheme, n_int))           # (13, n_int)
        self._motion_constraints(m, Xc, colloc, derivative)
        starts = ((np.arange(1, n_int)) * (d + 1)).tolist()
        if viscous is not None:                               # at interval ends, the next starts, the tip
            viscous_ends = viscous @ ca.DM(_end_matrix(scheme, n_int))
            self._viscous_ends[m] = viscous_ends[:, -1]
            viscous = (viscous_ends[:, :-1], viscous[:, starts])
        self._link_intervals(m, ends, X[:, starts], viscous)
        self._ends.append(ends[:, -1])
        self._node_at[m] = {s0: X[:, i * (d + 1)] for i, (s0, _) in enumerate(mesh.intervals)} | \
            {module.length: ends[:, -1]}
        self._module_end(m, ends[:, -1])

    def _rod(self, rod, points, inputs):
        """``(kin, eq, speed)`` of ``rod`` (the rod equations at one point) at ``points`` points
        whose inputs are the columns of ``inputs`` (one matrix per input of ``rod``): symbols
        standing for the outputs, the call recorded in :attr:`rod_calls`
        (:class:`~tca_casadi.discretisation.structure.RodCall`), so that the Jacobian can go
        through the rod equations at one point, mapped, rather than through their expansion at
        every point."""
        from .structure import RodCall
        call = RodCall.create(rod, points, inputs, len(self.rod_calls))
        self.rod_calls.append(call)
        Y = call.outputs
        return Y[0:7, :], Y[7:13, :], Y[13:, :]

    def _joined(self, split):
        """The MX expression of ``split(w, P, Y_1..Y_k)`` with each rod call's true outputs."""
        return split(self.w, self.P, *[c.evaluated() for c in self.rod_calls])

    def _inertial_loads(self, m, Xc, colloc):
        """Body-frame inertial force and moment per unit length (3, npts) at the collocation
        points ``colloc`` of module m, added to the distributed loads: none in statics (a
        dynamic NLP's, :mod:`tca_casadi.discretisation.dynamics`)."""
        return None

    def _motion_constraints(self, m, Xc, colloc, derivative):
        """The velocity states' equations of module m: none in statics."""

    def _viscous_nodes(self, m, X):
        """The viscous part of the internal wrench (Kelvin-Voigt ``B xi_t``) at every node of
        module m (6, nodes), ``X`` its states: none in statics."""
        return None

    def _viscous_start(self, m):
        """The viscous wrench at module m's base (6,), or None (statics)."""
        return None

    def _base_inertia(self, m):
        """Inertial wrench of the point masses at module m's base (its frame), or None."""
        return None

    def _tip_inertia(self, m):
        """Inertial wrench at module m's tip (its frame): its point masses' and its children's
        connector masses', or None (statics)."""
        return None

    def _route_data(self, m, s, active):
        """Route values ``[r; r'; r'']`` (9, nA npts) at the points ``s`` (zero where inactive),
        column ``j nA + k`` for actuator k at point j: each route's unit data placed by its
        parameters (:meth:`ActuatorModel.route_values`)."""
        module = self.robot.modules[m]
        if not module.actuators:
            return ca.DM(9, 0)
        blocks = []
        for k, actuator in enumerate(module.actuators):
            values = actuator.route_values(np.clip(s, *actuator.route.span), self.param)
            blocks.append(ca.vertcat(*[v if isinstance(v, ca.MX) else ca.MX(ca.DM(v)) for v in values])
                          * ca.DM(np.tile(active[k], (9, 1))))
        return ca.reshape(ca.vertcat(*blocks), 9, len(module.actuators) * len(s))

    def _active_mask(self, m, s_mid):
        """(nA, n_int) 1 where the actuator runs through the interval with midpoint ``s_mid``."""
        module = self.robot.modules[m]
        return np.array([[float(is_active(a, s)) for s in s_mid] for a in module.actuators]).reshape(
            len(module.actuators), len(s_mid))

    def _tension_field(self, m, active):
        """(nA, npts) tension of each actuator at each collocation point (0 where absent)."""
        module = self.robot.modules[m]
        if not module.actuators:
            return ca.DM(0, active.shape[1])
        tension = ca.vertcat(*[self.tension_of(a) for a in module.actuators])
        return (tension @ ca.DM.ones(1, active.shape[1])) * ca.DM(active)

    def _distributed(self, m, s_mid, interval_of):
        """Distributed loads (3, npts) each: global force (self-weight included) and moment,
        body-frame force and moment, per collocation point (:func:`model.loads.distributed_fields`
        of each interval, spread over its points)."""
        per_interval = [distributed_fields(self.robot, m, s, self.param) for s in s_mid]
        points = interval_of.size
        spread = ca.DM(ca.Sparsity.triplet(len(s_mid), points, interval_of.tolist(), list(range(points))), 1.0)
        return [ca.horzcat(*[fields[k] for fields in per_interval]) @ spread for k in range(4)]

    # ------------------------------------------------------------------ point wrenches
    def _point_wrenches(self, m, s, before, after):
        return boundary.point_wrenches(self.robot, m, s, before, after, self.tension_of, self.param, self.contact_of)

    def _wrench(self, m, x):
        """Internal wrench ``K (xi - xi*)`` [N m; N] of a deviation state."""
        return boundary.internal_wrench(self.robot.modules[m], x, self.param)

    def _wrench_scale(self, m):
        return ca.DM(self.robot.modules[m].wrench_scale)

    def _base_wrench(self, m, start):
        """Internal wrench just before the module's base, ``W(0-) = W(0+) + point wrenches``."""
        return boundary.base_wrench(self.robot, m, start, self.tension_of, self.param, self._viscous_start(m),
                                    self._base_inertia(m), self.contact_of)

    # ------------------------------------------------------------------ links
    def _link_intervals(self, m, ends, starts, viscous=None):
        """Continuity of p and h and the wrench jump ``K (xi+ - xi-) + point wrenches = 0`` at
        every interior breakpoint of module m (ends: (13, n_int), starts: (13, n_int - 1));
        ``viscous``: ``(before, after)`` (6, n_int - 1) viscous wrenches, whose jump adds in."""
        mesh = self.meshes[m]
        if starts.shape[1] == 0:
            return
        before = ends[:, :-1]
        length = self.robot.modules[m].length
        self._g.append(ca.vec((starts[P_, :] - before[P_, :]) / length))
        self._g.append(ca.vec(starts[H_, :] - before[H_, :]))
        stiffness = boundary.stiffness(self.robot.modules[m], self.param)
        jump = stiffness @ ca.DM.ones(1, starts.shape[1]) * (starts[7:13, :] - before[7:13, :])
        columns = []
        for b, (_, s) in enumerate(mesh.intervals[:-1]):
            wrench = self._point_wrenches(m, s, before[:, b], starts[:, b])
            columns.append(wrench if wrench is not None else ca.DM.zeros(6))
        jump = jump + ca.horzcat(*columns)
        if viscous is not None:
            jump = jump + viscous[1] - viscous[0]
        self._g.append(ca.vec(ca.diag(self._wrench_scale(m)) @ jump))

    def _module_end(self, m, end):
        """The pose link to each child module (through its connector) and the wrench balance at
        the tip: ``W(L) = point wrenches + what the children put on it`` (none: a free tip)."""
        module = self.robot.modules[m]
        starts = {c: self._states[c][:, 0] for c in self.robot.children(m)}
        for c, start in starts.items():
            position, quaternion = boundary.junction_pose(end, self.robot.modules[c])
            self._g.append((start[P_] - position) / module.length)
            self._g.append(start[H_] - quaternion)
        viscous = {c: self._viscous_start(c) for c in starts} | {m: self._viscous_ends.get(m)}
        extra = {c: self._base_inertia(c) for c in starts} | {m: self._tip_inertia(m)}
        balance = boundary.tip_balance(self.robot, m, end, starts, self.tension_of, self.param, viscous, extra,
                                       self.contact_of)
        self._g.append(balance * self._wrench_scale(m))

    # ------------------------------------------------------------------ TCA law
    def _compatibility(self):
        self._g.extend(compatibility_residuals(self.robot, self._lengths, self.tension_of, self.param))

    def _contact_conditions(self):
        """The contact block's equations (:func:`~tca_casadi.model.contact_unknowns.contact_conditions`)
        on the states at the candidates' nodes."""
        def state_at(m, s):
            return self._node_at[m][_breakpoint(self._node_at[m], s)]
        self._g.extend(contact_conditions(self.robot, self.contact_views, state_at, self.param, self._body_inertia))

    #: a free body's d'Alembert force and moment at its pose unknowns (none in statics;
    #: :class:`~tca_casadi.discretisation.dynamics.DynamicCollocationNLP` gives them)
    _body_inertia = None

    # ------------------------------------------------------------------ helpers for solvers
    def banded_columns(self):
        """A column order of ``w`` in which the Jacobian is block-banded: module by module,
        interval by interval, each interval's node states then its cumulative lengths (and any
        per-interval unknowns a subclass adds, :meth:`_interval_columns`), each module's unknown
        tensions after its intervals; the unknowns that couple modules (contact forces, bodies)
        last. (n,) indices."""
        order = []
        for m, index in enumerate(self.state_index):
            running = self.partial_index[m].reshape(index.shape[0], -1) if self.partial_index[m].size else None
            for i in range(index.shape[0]):
                order.append(index[i].T.ravel())
                order.extend(self._interval_columns(m, i))
                if running is not None:
                    order.append(running[i])
            # the module's own unknown tensions after its intervals: their fill stays in the
            # module's rows (at the very end, every row of the robot would fill them)
            order.append(np.array([self.tension_index[k] for k, a in enumerate(self.robot.unknowns) if a.module == m],
                                  int))
        first = np.concatenate(order) if order else np.zeros(0, int)
        rest = np.setdiff1d(np.arange(self.scale.size), first, assume_unique=False)
        return np.concatenate([first, rest]).astype(int)

    def _interval_columns(self, m, i):
        """Further unknowns of interval i of module m, in the banded order (none in statics)."""
        return []

    def node_s(self, m):
        """Arc length of every node of module m, shape (n_intervals, d+1)."""
        return self.meshes[m].node_s(self.scheme)

    def node_weights(self, m):
        """Quadrature weights [m] of every node of module m and of its end (n_int (d+1) + 1,):
        the scheme's weights on the collocation points, zero at interval starts and at the end
        (computed once; a read-only array)."""
        cache = self.__dict__.setdefault("_node_weights", {})
        if m not in cache:
            steps = np.diff(np.array(self.meshes[m].intervals), axis=1).ravel()
            weights = np.hstack([np.zeros((steps.size, 1)), steps[:, None] * self.scheme.weights[None, :]])
            cache[m] = np.append(weights.ravel(), 0.0)
            cache[m].flags.writeable = False
        return cache[m]


def _breakpoint(nodes, s):
    """The key of ``nodes`` ({s: ...}) nearest s (a contact candidate is a breakpoint)."""
    return min(nodes, key=lambda key: abs(key - s))


def _derivative_matrix(scheme, steps):
    """(n_int (d+1), n_int d): node values -> d/ds at the collocation points, per interval
    (sparse: block diagonal)."""
    d = scheme.degree
    return _block_diagonal([scheme.C[:, 1:] / step for step in steps], d + 1, d)


def _quadrature_matrix(scheme, steps):
    """(n_int d, n_int): collocation-point values -> integral over each interval (sparse)."""
    d = scheme.degree
    return _block_diagonal([(step * scheme.weights)[:, None] for step in steps], d, 1)


def _end_matrix(scheme, n_int):
    """(n_int (d+1), n_int): node values -> value at each interval's end (sparse)."""
    d = scheme.degree
    return _block_diagonal([scheme.D[:, None]] * n_int, d + 1, 1)


def _block_diagonal(blocks, rows, cols):
    """A sparse DM with the dense ``blocks`` (each (rows, cols)) along its diagonal; built from
    triplets, never dense (a fine mesh's dense matrix would not fit in memory)."""
    count = len(blocks)
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    k = np.arange(count)[:, None, None]
    row = (k * rows + r[None]).ravel().tolist()
    col = (k * cols + c[None]).ravel().tolist()
    values = np.concatenate([np.asarray(b, float).ravel() for b in blocks]) if count else np.zeros(0)
    return ca.DM.triplet(row, col, ca.DM(values), count * rows, count * cols)

"""Direct collocation of a robot: one CasADi NLP per scenario structure (SPEC section 6).

Glossary of the NLP (the ordering is block-banded, module by module):

Variables ``w`` (all scaled, see :attr:`CollocationNLP.scale`):
    for each module m, for each interval i, for each node j = 0..d (j = 0 is the interval start):
        ``x = [p (3), h (4), u (3), v (3)]`` at ``s = s0 + tau_j (s1 - s0)``
    then the TCA tensions ``F`` (one per TCA, in ``robot.tcas`` order).
Parameters ``P``: the robot's parameter vector (``robot.layout``): gravity, base pose,
    temperatures, tendon tensions, load forces/moments/masses.
Constraints ``g`` (all scaled to order one, all equalities ``g = 0``):
    for each module, for each interval: d collocation blocks ``[p' - R v, h' - Omega h / 2,
    equilibrium (6)]``, then the link to the next interval (continuity of p, h; wrench jump of
    point wrenches at the breakpoint), or at the module's end the junction link to the next
    module (pose through the connector, wrench balance) or, for the last module, the tip wrench;
    the base pose of the first module comes first; last, one compatibility equation per TCA.
The forward problem is square: ``len(w) == len(g)``.
"""
import casadi as ca
import numpy as np

from ..model.rod import ANCHOR_WRENCH, POINT_WRENCH, STATE_SIZE, rod_equations
from ..model.rotations import quaternion_product, rotation_matrix
from .mesh import CollocationScheme, build_mesh

P_, H_, U_, V_ = slice(0, 3), slice(3, 7), slice(7, 10), slice(10, 13)


class CollocationNLP:
    """The collocation NLP of ``robot`` with ``intervals`` per module, ``degree`` and ``scheme``.

    Attributes: ``problem`` (dict for ``ca.nlpsol``), ``scale`` (w_physical = scale * w),
    ``outputs`` (Function ``(w, P) -> (lengths, ends, base_wrenches)``), ``meshes``.
    """

    def __init__(self, robot, intervals=12, degree=4, scheme="legendre"):
        self.robot = robot
        self.scheme = CollocationScheme.create(degree, scheme)
        self.meshes = [build_mesh(robot, m, intervals) for m in range(len(robot.modules))]
        self._declare_variables()
        self.P = ca.SX.sym("P", robot.layout.size)
        self._g, self._lengths = [], [0] * len(robot.actuators)
        self._ends, self._base_wrenches = [], []
        for m in range(len(robot.modules)):
            self._module_constraints(m)
        self._compatibility()
        g = ca.vertcat(*self._g)
        self.problem = {"x": self.w, "p": self.P, "f": ca.SX(0), "g": g}
        self.outputs = ca.Function(
            "outputs", [self.w, self.P],
            [ca.vertcat(*self._lengths), ca.horzcat(*self._ends), ca.horzcat(*self._base_wrenches)],
            ["w", "P"], ["lengths", "ends", "base_wrenches"])

    # ------------------------------------------------------------------ variables
    def _declare_variables(self):
        d = self.scheme.degree
        blocks, scales, self.state_index, self.node_scale, self.state_offset = [], [], [], [], []
        offset = 0
        for m, mesh in enumerate(self.meshes):
            module = self.robot.modules[m]
            count = len(mesh.intervals) * (d + 1) * STATE_SIZE
            blocks.append(ca.SX.sym(f"x_{module.name}", count))
            # strains as deviations from xi*, scaled by stiffness: order-one internal wrenches
            per_node = np.r_[np.full(3, module.length), np.ones(4),
                             module.force_scale * module.length / module.stiffness[0:3],
                             module.force_scale / module.stiffness[3:6]]
            self.node_scale.append(per_node)
            self.state_offset.append(np.r_[np.zeros(7), module.xi_star])
            scales.append(np.tile(per_node, count // STATE_SIZE))
            index = offset + np.arange(count).reshape(len(mesh.intervals), d + 1, STATE_SIZE)
            self.state_index.append(index.transpose(0, 2, 1))  # (n_int, 13, d+1)
            offset += count
        tcas = self.robot.tcas
        blocks.append(ca.SX.sym("F", len(tcas)))
        scales.append(np.array([self.robot.modules[a.module].force_scale for a in tcas]))
        self.tension_index = offset + np.arange(len(tcas))
        self.w = ca.vertcat(*blocks)
        self.scale = np.concatenate(scales)
        # deviation states [p, h, u - u*, v - v*] in SI units, per interval (13, d+1)
        w_phys = self.w * ca.DM(self.scale)
        self._states = [[ca.reshape(w_phys[_flat(idx)], STATE_SIZE, d + 1)
                         for idx in self.state_index[m]] for m in range(len(self.meshes))]
        self._tensions = w_phys[self.tension_index.tolist()] if len(tcas) else ca.SX(0, 1)

    def full_state(self, m, deviation):
        """``[p, h, u, v]`` from the deviation state ``[p, h, u - u*, v - v*]``."""
        return deviation + ca.DM(self.state_offset[m])

    def tension_of(self, actuator):
        """Symbolic tension [N] of an actuator: a variable for a TCA, a parameter for a tendon."""
        if actuator.kind == "tca":
            return self._tensions[self.robot.tcas.index(actuator)]
        return self.P[self.robot.layout[actuator.parameter]][0]

    def param(self, name):
        return self.P[self.robot.layout[name]]

    # ------------------------------------------------------------------ one module
    def _module_constraints(self, m):
        module, mesh, scheme = self.robot.modules[m], self.meshes[m], self.scheme
        rod = rod_equations(module.stiffness, module.xi_star, len(module.actuators))
        fs, length = module.force_scale, module.length
        eq_scale = ca.DM(np.r_[np.ones(3), np.full(4, length), np.full(3, 1 / fs), np.full(3, length / fs)])
        states = self._states[m]
        if m == 0:
            self._g.append((states[0][P_, 0] - self.param("base.position")) / length)
            self._g.append(states[0][H_, 0] - self.param("base.quaternion"))
        self._base_wrenches.append(self._base_wrench(m, states[0][:, 0]))
        for i, (s0, s1) in enumerate(mesh.intervals):
            X, step = states[i], s1 - s0
            loads = self._distributed(m, 0.5 * (s0 + s1), X)
            tensions = self._active_tensions(m, 0.5 * (s0 + s1))
            for j in range(1, scheme.degree + 1):
                s = s0 + scheme.tau[j] * step
                dX = (X[:, 1:] - X[:, 0] @ ca.DM.ones(1, scheme.degree)) @ ca.DM(scheme.C[1:, j]) / step
                kin, eq, speed = rod(self.full_state(m, X[:, j]), dX[7:13], self._route_data(m, s, tensions[1]),
                                     tensions[0], *loads)
                self._g.append(ca.vertcat(dX[0:7] - kin, eq) * eq_scale)
                self._accumulate_lengths(m, tensions[1], speed, step * scheme.weights[j - 1])
            end = X @ ca.DM(scheme.D)
            if i + 1 < len(mesh.intervals):
                self._link_intervals(m, s1, end, states[i + 1][:, 0])
            else:
                self._ends.append(end)
                self._module_end(m, end)

    def _route_data(self, m, s, active):
        module = self.robot.modules[m]
        data = np.zeros((9, len(module.actuators)))
        for k, actuator in enumerate(module.actuators):
            if active[k]:
                r, dr, ddr = actuator.route.evaluate(s)
                data[:, k] = np.concatenate([r[:, 0], dr[:, 0], ddr[:, 0]])
        return ca.DM(data)

    def _active_tensions(self, m, s_mid):
        module = self.robot.modules[m]
        active = [a.route.span[0] < s_mid < a.route.span[1] for a in module.actuators]
        tension = [self.tension_of(a) if on else 0 for a, on in zip(module.actuators, active)]
        return (ca.vertcat(*tension) if tension else ca.SX(0, 1)), active

    def _distributed(self, m, s_mid, X):
        module = self.robot.modules[m]
        f_glob = module.weight_density * self.param("gravity")
        l_glob, f_body, l_body = ca.SX.zeros(3), ca.SX.zeros(3), ca.SX.zeros(3)
        for load in self.robot.distributed_loads:
            if load.module == m and load.span[0] < s_mid < load.span[1]:
                force, moment = self.param(f"{load.name}.force"), self.param(f"{load.name}.moment")
                if load.frame == "global":
                    f_glob, l_glob = f_glob + force, l_glob + moment
                else:
                    f_body, l_body = f_body + force, l_body + moment
        return f_glob, l_glob, f_body, l_body

    def _accumulate_lengths(self, m, active, speed, weight):
        module = self.robot.modules[m]
        for k, actuator in enumerate(module.actuators):
            if active[k]:
                position = self.robot.actuators.index(actuator)
                self._lengths[position] = self._lengths[position] + weight * speed[k]

    # ------------------------------------------------------------------ point wrenches
    def _point_wrenches(self, m, s, before, after):
        """Sum of point wrenches [N m; N] (body frame) applied at arc length s of module m:
        anchors starting at s (evaluated with the state after s), anchors ending at s (state
        before s), point loads and point masses."""
        module = self.robot.modules[m]
        total = ca.SX.zeros(6)
        tol = 1e-12 * module.length
        for actuator in module.actuators:
            s_a, s_b = actuator.route.span
            for s_anchor, state, sign in ((s_a, after, 1.0), (s_b, before, -1.0)):
                if state is not None and abs(s_anchor - s) <= tol:
                    r, dr, _ = actuator.route.evaluate(s_anchor)
                    full = self.full_state(m, state)
                    total += sign * ANCHOR_WRENCH(full[U_], full[V_], r[:, 0], dr[:, 0],
                                                  self.tension_of(actuator))
        h = (after if after is not None else before)[H_]
        for load in self.robot.point_loads:
            if load.module == m and abs(load.s - s) <= tol:
                total += self._point_load_wrench(load, h)
        return total

    def _point_load_wrench(self, load, h):
        zero = ca.SX.zeros(3)
        if load.kind == "mass":
            return POINT_WRENCH(h, self.param(f"{load.name}.mass") * self.param("gravity"), zero, zero, zero)
        force, moment = self.param(f"{load.name}.force"), self.param(f"{load.name}.moment")
        if load.frame == "global":
            return POINT_WRENCH(h, force, moment, zero, zero)
        return POINT_WRENCH(h, zero, zero, force, moment)

    def _wrench(self, m, x):
        """Internal wrench ``K (xi - xi*)`` [N m; N] of a deviation state."""
        return ca.DM(self.robot.modules[m].stiffness) * x[7:13]

    def _wrench_scale(self, m):
        module = self.robot.modules[m]
        return ca.DM(np.r_[np.full(3, 1 / (module.force_scale * module.length)),
                           np.full(3, 1 / module.force_scale)])

    def _base_wrench(self, m, start):
        """Internal wrench just before the module's base, ``W(0-) = W(0+) + point wrenches``."""
        return self._wrench(m, start) + self._point_wrenches(m, 0.0, None, start)

    # ------------------------------------------------------------------ links
    def _link_intervals(self, m, s, end, start):
        length = self.robot.modules[m].length
        self._g.append((start[P_] - end[P_]) / length)
        self._g.append(start[H_] - end[H_])
        jump = self._wrench(m, start) - self._wrench(m, end) + self._point_wrenches(m, s, end, start)
        self._g.append(jump * self._wrench_scale(m))

    def _module_end(self, m, end):
        module = self.robot.modules[m]
        applied = self._point_wrenches(m, module.length, end, None)
        if m + 1 == len(self.robot.modules):
            self._g.append((self._wrench(m, end) - applied) * self._wrench_scale(m))
            return
        start = self._states[m + 1][0][:, 0]
        connector = self.robot.modules[m + 1].connector
        offset = np.zeros(3) if connector is None else connector.offset
        q_c = np.array([1.0, 0, 0, 0]) if connector is None else connector.quaternion
        R_end = rotation_matrix(end[H_])
        self._g.append((start[P_] - end[P_] - R_end @ ca.DM(offset)) / module.length)
        self._g.append(start[H_] - quaternion_product(end[H_], ca.DM(q_c)))
        transmitted = self._base_wrench(m + 1, start)
        R_c = ca.DM(np.array(rotation_matrix(ca.DM(q_c))))
        force = R_c @ transmitted[3:6]
        moment = R_c @ transmitted[0:3] + ca.cross(ca.DM(offset), force)
        balance = self._wrench(m, end) - applied - ca.vertcat(moment, force)
        if connector is not None and connector.mass > 0:
            weight = R_end.T @ (connector.mass * self.param("gravity"))
            balance -= ca.vertcat(ca.cross(ca.DM(connector.center_of_mass), weight), weight)
        self._g.append(balance * self._wrench_scale(m))

    # ------------------------------------------------------------------ TCA law
    def _compatibility(self):
        for actuator in self.robot.tcas:
            position = self.robot.actuators.index(actuator)
            stroke = self._lengths[position] - actuator.reference_length
            law = actuator.law
            residual = law.residual(stroke, self.tension_of(actuator), self.param(actuator.parameter)[0])
            self._g.append(residual / law.residual_scale)

    # ------------------------------------------------------------------ helpers for solvers
    def node_s(self, m):
        """Arc length of every node of module m, shape (n_intervals, d+1)."""
        return self.meshes[m].node_s(self.scheme)


def _flat(index):
    """Indices of one interval's (13, d+1) block in column-major (node-major) order."""
    return index.T.ravel().tolist()

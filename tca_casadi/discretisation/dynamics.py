"""The collocation NLP of one implicit time step of the rod dynamics (issue 16).

Everything of the static :class:`~tca_casadi.discretisation.collocation.CollocationNLP` (states,
partial lengths, tensions, the rod equations, links, TCA laws) plus, per module and node, the
body-frame velocities ``y = [q (3), w (3)]`` (scaled by ``[V, V, V, W, W, W]`` with
``W = 1 / T_ref``, ``V = L W`` and ``T_ref = sqrt(rho A L^4 / EI)``, the module's own time
scale) and their equations (:mod:`tca_casadi.model.dynamics`):

* at every collocation point, the velocity compatibility ``q' = v_t - u x q + w x v``,
  ``w' = u_t - u x w``, and the section's inertia as body-frame loads in the balance laws;
* at every interior breakpoint, continuity of ``q`` and ``w``;
* at the base of the first module, the base's velocity (at rest: ``q = w = 0``); at the base
  of a child module, the rigid connector's: ``q_c = Rc^T (q + w x offset)``, ``w_c = Rc^T w``.

Kelvin-Voigt damping makes the internal wrench ``K (xi - xi*) + B xi_t`` everywhere it appears
(the balance laws, the interval links, the tip and base wrenches), with ``B`` the diagonal
viscous matrix of each module (6,) [N m^2 s, N s].

Time derivatives are ``x_t = c0 x + x_hist`` for the strain deviations and the velocities,
with the scalar ``c0`` [1/s] and the history ``x_hist`` (per module, per node, ``[xi (6), q (3),
w (3)]``, physical units per second), appended with ``B`` to the parameter vector:
``P = [robot parameters; c0; B per module; history per module; history per free body]``.

A free body (a contact object, :mod:`tca_casadi.model.bodies`) keeps its pose unknowns
``[delta, g]``; its velocity and angular velocity are not unknowns but follow from them by the
same rule, ``v = c0 delta + h``, ``omega = omega(g, c0 g + h)``, and its d'Alembert force and
moment ``-m (c0 v + h)``, ``-R (J (c0 omega + h) + omega x J omega)`` enter its equilibrium. One NLP serves every step, every step
size and every integrator (:mod:`tca_casadi.solvers.dynamics` sets ``c0`` and the history).
"""
import casadi as ca
import numpy as np

from ..errors import ModelError
from ..model.bodies import body_motion, body_rotation, box_moments, inertial_wrench
from ..model.boundary import add, connector_of, loads_at
from ..model.dynamics import inertia_per_length, inertial_loads, point_inertia, point_mass_of, velocity_rates
from .collocation import CollocationNLP, _end_matrix

#: history values per node: strain deviations (6), q (3), w (3)
HISTORY_SIZE = 12
#: history values per free body: its pose (delta (3), Gibbs vector (3)), its velocity (3) and
#: body-frame angular velocity (3)
BODY_HISTORY_SIZE = 12


def time_scale(module):
    """``T_ref = sqrt(rho A L^4 / EI)`` [s] at the module's nominal values (1/T_ref is of the
    order of its first bending frequency)."""
    mass = module.weight_density
    if not mass > 0:
        raise ModelError(f"dynamics: module {module.name} has no mass (its material's density is 0)")
    return float(np.sqrt(mass * module.length ** 4 / module.bending_stiffness))


class DynamicCollocationNLP(CollocationNLP):
    """One implicit time step of ``robot``'s dynamics on the static NLP's mesh (see the module
    docstring). Extra attributes: ``velocity_index`` (per module (n_int, 6, d+1) indices into
    ``w``), ``history_index`` (per module (n_int (d+1), 12) indices into ``P``), ``c0_index``."""

    def _interval_columns(self, m, i):
        """The velocity states of interval i of module m, beside its node states (banded order)."""
        return [self.velocity_index[m][i].T.ravel()]

    def _declare_variables(self):
        super()._declare_variables()
        d, offset = self.scheme.degree, self.w.numel()
        blocks, scales, self.velocity_index, self.velocity_scale = [self.w], [self.scale], [], []
        self._velocities = []
        for m, mesh in enumerate(self.meshes):
            module = self.robot.modules[m]
            rate = 1.0 / time_scale(module)
            per_node = np.r_[np.full(3, module.length * rate), np.full(3, rate)]
            count = len(mesh.intervals) * (d + 1) * 6
            block = ca.MX.sym(f"y_{module.name}", count)
            blocks.append(block)
            scales.append(np.tile(per_node, count // 6))
            index = offset + np.arange(count).reshape(len(mesh.intervals), d + 1, 6)
            self.velocity_index.append(index.transpose(0, 2, 1))
            self.velocity_scale.append(per_node)
            self._velocities.append(ca.diag(ca.DM(per_node)) @ ca.reshape(block, 6, -1))
            offset += count
        self.w = ca.vertcat(*blocks)
        self.scale = np.concatenate(scales)
        size, self.history_index = self.robot.layout.size + 1, []
        self.c0_index = self.robot.layout.size
        self.damping_index = []
        for _ in self.meshes:
            self.damping_index.append(size + np.arange(6))
            size += 6
        for mesh in self.meshes:
            count = len(mesh.intervals) * (d + 1)
            self.history_index.append(size + np.arange(count * HISTORY_SIZE).reshape(count, HISTORY_SIZE))
            size += count * HISTORY_SIZE
        self.body_history_index = []
        for _ in self.robot.bodies:
            self.body_history_index.append(size + np.arange(BODY_HISTORY_SIZE))
            size += BODY_HISTORY_SIZE
        self._parameter_size = size

    @property
    def parameter_size(self):
        return self._parameter_size

    def _history(self, m, columns):
        """(12, k) history ``[xi; q; w]`` [per s] at node columns ``columns`` of module m."""
        index = self.history_index[m][columns]                # (k, 12)
        return ca.reshape(self.P[index.ravel().tolist()], HISTORY_SIZE, len(columns))   # node-major

    def _viscous_nodes(self, m, X):
        c0 = self.P[self.c0_index]
        damping = self.P[self.damping_index[m].tolist()]
        columns = list(range(X.shape[1]))
        rates = c0 * X[7:13, :] + self._history(m, columns)[0:6, :]
        return (damping @ ca.DM.ones(1, len(columns))) * rates

    def _viscous_start(self, m):
        c0 = self.P[self.c0_index]
        damping = self.P[self.damping_index[m].tolist()]
        return damping * (c0 * self._states[m][7:13, 0] + self._history(m, [0])[0:6, 0])

    # ------------------------------------------------------------------ free bodies
    def _body_inertia(self, body, pose):
        """A free body's d'Alembert force and moment (:func:`~tca_casadi.model.bodies.inertial_wrench`)
        at its pose unknowns ``pose`` (6,): its velocity ``v = c0 delta + h_delta``, the rate of
        its Gibbs vector ``g_t = c0 g + h_g`` and so its angular velocity ``omega(g, g_t)``, and
        their rates ``c0 v + h_v``, ``c0 omega + h_omega`` (``h`` the body's history)."""
        history = self.P[self.body_history_index[body.index].tolist()]
        _, omega, acceleration, omega_rate = body_motion(self.P[self.c0_index], pose, history)
        mass = self.param(f"{body.name}.mass")[0]
        return inertial_wrench(mass, box_moments(body.size, mass), body_rotation(body, pose[3:6]), acceleration,
                               omega, omega_rate)

    # ------------------------------------------------------------------ rigid point inertias
    def _motion_at(self, m, where):
        """``(q, w, q_t, w_t)`` (3,) each of module m at node column ``where`` or at its tip
        (``where`` None: the end of the last interval)."""
        c0 = self.P[self.c0_index]
        Y = self._velocities[m]
        columns = list(range(Y.shape[1]))
        rates = c0 * Y + self._history(m, columns)[6:12, :]
        if where is None:
            end = _end_matrix(self.scheme, len(self.meshes[m].intervals))[:, -1]
            y, y_t = Y @ end, rates @ end
        else:
            y, y_t = Y[:, where], rates[:, where]
        return y[0:3], y[3:6], y_t[0:3], y_t[3:6]

    def _masses_at(self, m, s, where):
        """Inertial wrench (its frame) of the point masses and held objects at s of module m."""
        total = None
        for load in loads_at(self.robot, m, s):
            mass = point_mass_of(load, self.param)
            if load.kind != "point":
                total = add(total, point_inertia(mass, *self._motion_at(m, where)))
        return total

    def _point_wrenches(self, m, s, before, after):
        static = super()._point_wrenches(m, s, before, after)
        starts = [k for k, (s0, _) in enumerate(self.meshes[m].intervals) if abs(s0 - s) <= 1e-12 * self.robot.modules[m].length]
        if not starts:
            return static
        return add(static, self._masses_at(m, s, starts[0] * (self.scheme.degree + 1)))

    def _base_inertia(self, m):
        return self._masses_at(m, 0.0, 0)

    def _tip_inertia(self, m):
        module = self.robot.modules[m]
        total = self._masses_at(m, module.length, None)
        for c in self.robot.children(m):
            connector = self.robot.modules[c].connector
            if connector is not None and connector.mass > 0:
                total = add(total, point_inertia(connector.mass, *self._motion_at(m, None), offset=connector.center_of_mass))
        return total

    def _rates(self, m, Xc, colloc):
        """``(xi_t (6, k), y (6, k), y_t (6, k))`` at the collocation points of module m."""
        c0 = self.P[self.c0_index]
        history = self._history(m, colloc)
        Y = self._velocities[m][:, colloc]
        return c0 * Xc[7:13, :] + history[0:6, :], Y, c0 * Y + history[6:12, :]

    def _inertial_loads(self, m, Xc, colloc):
        module = self.robot.modules[m]
        mass, rotary = inertia_per_length(module, self.param)
        _, Y, Y_t = self._rates(m, Xc, colloc)
        return inertial_loads(Y[0:3, :], Y[3:6, :], Y_t[0:3, :], Y_t[3:6, :], mass, rotary)

    def _motion_constraints(self, m, Xc, colloc, derivative):
        module, d = self.robot.modules[m], self.scheme.degree
        Y = self._velocities[m]
        n_int = len(self.meshes[m].intervals)
        xi_t, Yc, _ = self._rates(m, Xc, colloc)
        u = Xc[7:10, :] + ca.DM(module.xi_star[0:3])
        v = Xc[10:13, :] + ca.DM(module.xi_star[3:6])
        dq, dw = velocity_rates(u, v, Yc[0:3, :], Yc[3:6, :], xi_t[0:3, :], xi_t[3:6, :])
        dY = Y @ derivative
        scale = ca.DM(module.length / self.velocity_scale[m])
        self._g.append(ca.vec(ca.diag(scale) @ (dY - ca.vertcat(dq, dw))))
        ends = Y @ _end_matrix(self.scheme, n_int)            # (6, n_int)
        starts = Y[:, (np.arange(1, n_int) * (d + 1)).tolist()]
        inverse = ca.DM(1.0 / self.velocity_scale[m])
        if n_int > 1:
            self._g.append(ca.vec(ca.diag(inverse) @ (starts - ends[:, :-1])))
        if m == 0:
            self._g.append(inverse * Y[:, 0])                  # the base at rest
        for c in self.robot.children(m):
            child = self.robot.modules[c]
            offset, _, rotation = connector_of(child)
            q, w = ends[0:3, -1], ends[3:6, -1]
            start = self._velocities[c][:, 0]
            linked = ca.vertcat(ca.DM(rotation).T @ (q + ca.cross(w, ca.DM(offset))), ca.DM(rotation).T @ w)
            self._g.append(ca.DM(1.0 / self.velocity_scale[c]) * (start - linked))

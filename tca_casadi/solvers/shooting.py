"""The shooting solver (SPEC section 6): an independent cross-check of collocation.

Unknowns ``z``: the base strains (deviations from xi*) of every module whose start is not fixed by
its parent's tip balance (the first module, each decoupled module, each finger of a tree after
the first) and the unknown tensions. A *shot* integrates the explicit equilibrium
``xi' = (K + A)^-1 (...)`` (paper eq. 25, obtained by solving the same CasADi rod residual that
collocation imposes, which is linear in xi') module by module with ``scipy.integrate.solve_ivp``
(DOP853, tight tolerances), segment by segment between breakpoints, applying the wrench jumps of
:mod:`tca_casadi.model.boundary` at anchors, point loads and junctions. Residuals: the tip
balance of every module whose tip balance does not start a child, and every compatibility
equation, solved by MINPACK's Powell dog-leg trust region (``hybr``).

Only the discretisation differs from collocation; the physics Functions are the same. What makes
a shot cheap:

* the right-hand side of each segment, routes included (as CasADi expressions of ``s``), is one
  CasADi Function;
* the shot's Jacobian ``dr/dz`` comes from the variational equations integrated alongside the
  state, ``S' = (df/dy) S + (df/dF) dF/dz``, and from the CasADi Jacobians of every jump, junction
  and residual (chain rule), so one integration per Newton iteration replaces one per unknown.
"""
import logging
import time

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root

from ..discretisation.mesh import module_breakpoints
from ..errors import PhysicsWarning
from ..status import SolveStatus, Status
from ..model import boundary
from ..model.compatibility import compatibility_residuals
from ..model.contact_unknowns import ContactUnknowns, contact_conditions
from ..model.loads import distributed_fields, is_active
from ..model.rod import STATE_SIZE, explicit_strain_rate, rod_equations
from ..model.routes import route_expressions
from ..solution import Iterate
from .assemble import build_solution
from ..buffers import BufferedFunction

log = logging.getLogger(__name__)

#: points per integration segment written to the solution's arrays
OUTPUT_POINTS = 9
#: Gauss-Legendre points per panel of a segment, for integrals over the solution (weights)
GAUSS_POINTS = 8
#: right-hand-side evaluations allowed per segment before a shot is abandoned
RHS_BUDGET = 20000
#: the smallest scaled residual shooting accepts: what DOP853 at rtol 1e-11 delivers
TOLERANCE_FLOOR = 1e-9


class _ShotFailed(Exception):
    """A trial point whose integration cannot finish (far from any equilibrium)."""


class ShootingSolver:
    """Single shooting with scipy. ``solve(params, initial=None)`` -> :class:`Solution`."""
    method = "shooting"
    #: no square system (continuation is by warm-started solves) and no error estimate: the
    #: integrator's tolerances set the accuracy
    has_square_system = False
    estimates_error = False

    def __init__(self, robot, options, rtol=1e-11, atol=1e-12, jacobian="variational"):
        start = time.perf_counter()
        self.robot, self.options = robot, options
        self.rtol, self.atol = rtol, atol
        #: "variational" (exact, one augmented shot) or "differences" (forward differences, one
        #: shot per unknown: the previous method, kept for scripts/bench.py's comparison)
        self.jacobian = jacobian
        self._free = free_starts(robot)
        self._segments = [_segments(robot, m) for m in range(len(robot.modules))]
        #: contact forces and free bodies (:mod:`tca_casadi.model.contact_unknowns`): unknowns after
        #: the tensions, their conditions residuals after the compatibility equations
        self._contact = ContactUnknowns(robot)
        self._candidates = contact_candidates(robot)
        #: each candidate's breakpoint (the segment end the shot passes through there)
        self._break_of = {key: (key[0], _nearest(module_breakpoints(robot, key[0]), key[1])) for key in self._candidates}
        self._recorded = set(self._break_of.values())
        n_unknowns = 6 * len(self._free) + len(robot.unknowns) + self._contact.size
        self._rhs = [[_segment_rhs(module, [module.actuators[k] for k in active], n_unknowns)
                      for _, _, active in self._segments[m]] for m, module in enumerate(robot.modules)]
        self._jumps = [[_jump_function(robot, m, s0, self._contact) for s0, _, _ in self._segments[m][1:]]
                       for m in range(len(robot.modules))]
        self._ends = [_end_function(robot, m, self._free, self._contact) for m in range(len(robot.modules))]
        self._compatibility = _compatibility_function(robot)
        self._conditions = _conditions_function(robot, self._contact, self._candidates)
        self._bases = [None] * len(robot.modules)          # base wrench Functions, built on first output
        self._tension_map = _tension_map(robot)
        #: optional extra output arc lengths per module (e.g. another solver's nodes)
        self.sample_s = None
        self.build_time_s = time.perf_counter() - start
        self.solve_count = 0

    # ------------------------------------------------------------------ unknowns
    def _unknown_scale(self):
        strains = [self.robot.modules[m].state_scale[7:13] for m in self._free]
        tensions = [self.robot.modules[a.module].force_scale for a in self.robot.unknowns]
        return np.r_[np.concatenate(strains), tensions, self._contact.scale]

    @property
    def _contact_start(self):
        """Index of the first contact unknown in ``z``."""
        return 6 * len(self._free) + len(self.robot.unknowns)

    def initial_guess(self, initial=None):
        """Scaled unknowns from a previous Solution (any method), else the reference state. The
        contact block comes from the Solution's own (``iterate.contact``, both solvers write it)
        when it has the same size, else it starts at zero forces and the placed bodies."""
        n_strain = 6 * len(self._free)
        z = np.zeros(self._contact_start + self._contact.size)
        if initial is not None:
            for k, m in enumerate(self._free):
                start, module = initial.modules[m], self.robot.modules[m]
                z[6 * k:6 * k + 6] = np.r_[start.u[:, 0], start.v[:, 0]] - module.xi_star
            z[n_strain:self._contact_start] = [initial.actuators[a.key].tension for a in self.robot.unknowns]
            block = np.asarray(initial.iterate.contact, float)
            if block.size == self._contact.size:
                z[self._contact_start:] = block
        return z / self._unknown_scale()

    # ------------------------------------------------------------------ solve
    def solve(self, params, initial=None):
        """Solve at ``params`` from ``initial`` (a Solution of either method) or the reference."""
        params = np.asarray(params, dtype=float)
        z0 = self.initial_guess(initial)
        scale = self._unknown_scale()
        start = time.perf_counter()
        shots = [0]
        cache = {}

        # the unknown is the change from z0: MINPACK sizes its first trust region from |x|,
        # which must not be a tiny nonzero start value
        def evaluate(change, derivatives):
            key = (change.tobytes(), derivatives)
            if key not in cache:
                shots[0] += 1
                try:
                    cache[key] = self._shot(z0 + change, scale, params, derivatives)
                except _ShotFailed:       # a wild trial point: let the trust region shrink
                    cache[key] = (np.full(change.size, 1e6), np.eye(change.size))
            return cache[key]

        def differences(change, step=1e-6):
            base = evaluate(change, False)[0]
            return np.column_stack([(evaluate(change + step * e, False)[0] - base) / step
                                    for e in np.eye(change.size)])

        jacobian = differences if self.jacobian == "differences" else (lambda c: evaluate(c, True)[1])
        result = root(lambda c: evaluate(c, False)[0], np.zeros_like(z0), method="hybr", jac=jacobian,
                      options={"xtol": 1e-13, "maxfev": 50 * (z0.size + 1)})
        result.x = z0 + result.x
        try:
            residual_value, trajectory = self._trajectory(result.x, params)
        except _ShotFailed as exc:
            return self._failed(params, str(exc), time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        self.solve_count += 1
        worst = float(np.max(np.abs(residual_value))) if residual_value.size else 0.0
        status = SolveStatus.judged("scipy root (hybr)", worst, self.tolerance, nit=int(result.nfev),
                                    solve_time_s=elapsed, build_time_s=self.build_time_s,
                                    detail=f"{self.jacobian} Jacobian: {result.message.strip()}; {shots[0]} shots")
        return self._solution(params, trajectory, status, result.x, self._notices(worst))

    def evaluate(self, z, params, status):
        """A :class:`Solution` of one shot from scaled unknowns ``z`` at ``params``; ``status``
        the :class:`SolveStatus` of the algorithm that found ``z`` (its residual is replaced by
        the shot's)."""
        params = np.asarray(params, dtype=float)
        try:
            residual_value, trajectory = self._trajectory(np.asarray(z, float), params)
        except _ShotFailed as exc:
            return self._failed(params, str(exc), status.solve_time_s)
        worst = float(np.max(np.abs(residual_value))) if residual_value.size else 0.0
        status = SolveStatus.judged(status.algorithm, worst, self.tolerance, status.status, nit=status.nit,
                                    solve_time_s=status.solve_time_s, build_time_s=self.build_time_s,
                                    detail=status.detail)
        return self._solution(params, trajectory, status, np.asarray(z, float), self._notices(worst))

    def _failed(self, params, message, elapsed):
        """A Solution-shaped failure carrying the reference shape's arrays; converged False."""
        trial = _reference_trajectory(self.robot, params)
        status = SolveStatus(Status.INTEGRATION_FAILED, "scipy root (hybr)", residual=float("inf"),
                             tolerance=self.tolerance, solve_time_s=elapsed, build_time_s=self.build_time_s,
                             detail=message)
        return build_solution(self.robot, params, *trial, status, self.method, Iterate(self.method),
                              **self._contact.solution_values(np.zeros(self._contact.size)))

    def _solution(self, params, trajectory, status, z, notices):
        """The :class:`Solution` of a shot at scaled unknowns ``z``: its contact forces and bodies
        from the contact block, which ``iterate.contact`` keeps (physical) for warm starts."""
        block = (z * self._unknown_scale())[self._contact_start:]
        return build_solution(self.robot, params, *trajectory, status, self.method, Iterate(self.method, z=np.asarray(z, float), contact=np.asarray(block, float)),
                              notices, **self._contact.solution_values(block))

    def _notices(self, residual):
        """A ``tolerance_floor`` warning when the accepted ``residual`` met the floored
        tolerance (:data:`TOLERANCE_FLOOR`) but not ``solver.tolerance``."""
        if not self.options.tolerance < residual <= self.tolerance:
            return []
        return [PhysicsWarning("tolerance_floor", f"shooting accepted a max scaled residual of {residual:.1e}, "
                               f"above solver.tolerance {self.options.tolerance:.0e}: integration at rtol "
                               f"{self.rtol:.0e} cannot resolve less than {TOLERANCE_FLOOR:.0e}")]

    @property
    def tolerance(self):
        """Accepted scaled residual: the scenario's tolerance, floored by what the integrator's
        tolerances can deliver (:data:`TOLERANCE_FLOOR`; the solution says so when it applies)."""
        return max(self.options.tolerance, TOLERANCE_FLOOR)

    # ------------------------------------------------------------------ one shot
    def _shot(self, z, scale, params, derivatives):
        """Residuals at scaled unknowns ``z`` and, with ``derivatives``, their Jacobian
        ``dr/dz`` (variational equations and the chain rule)."""
        r, dr, _ = self._integrate_all(z * scale, params, derivatives, outputs=False)
        return r, (dr * scale[None, :] if derivatives else None)

    def _trajectory(self, z, params):
        """Residuals and ``(module_data, tensions, lengths)`` of the shot at scaled ``z``."""
        r, _, trajectory = self._integrate_all(z * self._unknown_scale(), params, False, outputs=True)
        return r, trajectory

    def _integrate_all(self, unknowns, params, derivatives, outputs):
        """One shot at physical unknowns: ``(residuals, d residuals / d unknowns or None,
        trajectory or None)``. Every quantity is carried with its derivative ``D`` with respect
        to the unknowns (``None`` when ``derivatives`` is off)."""
        robot, n = self.robot, unknowns.size
        T, F0 = self._tension_map
        F0 = F0(params)
        first = self._contact_start
        forces = F0 + T @ unknowns[6 * len(self._free):first]
        dF = np.hstack([np.zeros((T.shape[0], 6 * len(self._free))), T, np.zeros((T.shape[0], n - first))]) \
            if derivatives else None
        contact = unknowns[first:]
        dC = _selection(n, range(first, n), 0) if derivatives else None
        found = {}                      # (module, s) of each contact candidate -> (state, d state / dz)
        starts = {0: (np.r_[params[robot.layout["base.position"]], params[robot.layout["base.quaternion"]],
                            unknowns[0:6]], _selection(n, range(0, 6), 7) if derivatives else None)}
        residuals, jacobians = [], []
        lengths = np.zeros(len(robot.actuators))
        length_D = np.zeros((len(robot.actuators), n)) if derivatives else None
        module_data = []
        for m, module in enumerate(robot.modules):
            x0, D0 = starts[m]
            own = [robot.actuators.index(a) for a in module.actuators]
            end, D_end, mod_lengths, D_lengths, data = self._integrate(m, x0, D0, forces, dF, contact, dC, params,
                                                                       outputs, found)
            lengths[own] = mod_lengths
            if derivatives:
                length_D[own] = D_lengths
            free_children = [c for c in robot.children(m) if c in self._free]
            strains = [unknowns[6 * self._free.index(c):6 * self._free.index(c) + 6] for c in free_children]
            values = self._ends[m](end, *strains, forces, contact, params)
            values = [np.array(v, float) for v in values]
            count = 1 + len(free_children)           # main output, then each free child's start
            mains, jac = values[:count], values[count:]
            if derivatives:
                # jac: for each output, d/d end, d/d each strain, d/d forces, d/d contact unknowns
                per = 3 + len(free_children)
                D_outs = []
                for o in range(count):
                    block = jac[o * per:(o + 1) * per]
                    D = block[0] @ D_end + block[-2] @ dF + block[-1] @ dC
                    for k, c in enumerate(free_children):
                        cols = range(6 * self._free.index(c), 6 * self._free.index(c) + 6)
                        D = D + block[1 + k] @ _selection(n, cols, 0)
                    D_outs.append(D)
            main = mains[0].ravel()
            for k, c in enumerate(free_children):
                starts[c] = (mains[1 + k].ravel(), D_outs[1 + k] if derivatives else None)
            continued = _continued_child(robot, m, self._free)
            if continued is None:
                residuals.append(main)
                if derivatives:
                    jacobians.append(D_outs[0])
            else:
                starts[continued] = (main, D_outs[0] if derivatives else None)
            if outputs:
                module_data.append(data + (self._base_wrench(m, x0, forces, contact, params),))
        compat = [np.array(v, float) for v in self._compatibility(lengths, forces, params)]
        residuals.append(compat[0].ravel())
        if derivatives:
            jacobians.append(compat[1] @ length_D + compat[2] @ dF)
        if self._contact.size:
            states = np.column_stack([found[self._break_of[key]][0] for key in self._candidates])
            conditions = [np.array(v, float) for v in self._conditions(states, contact, params)]
            residuals.append(conditions[0].ravel())
            if derivatives:
                D_states = np.vstack([found[self._break_of[key]][1] for key in self._candidates])   # (13 k, n)
                jacobians.append(conditions[1] @ D_states + conditions[2] @ dC)
        r = np.concatenate(residuals)
        dr = np.vstack(jacobians) if derivatives else None
        trajectory = None
        if outputs:
            trajectory = ([(s, states, wrench, weights) for s, states, weights, wrench in module_data],
                          list(forces), lengths)
        return r, dr, trajectory

    def _integrate(self, m, x0, D0, forces, dF, contact, dC, params, outputs, found):
        """Integrate module m from its base state ``x0`` (with ``D0 = dx0/dz`` when derivatives
        are on; ``forces`` and ``dF`` of every actuator, ``contact`` and ``dC`` the contact
        block's). Returns the end state and its derivative, the actuator lengths and their
        derivatives, and (with ``outputs``) ``(s, states (13, n) with xi* added, weights)``;
        records in ``found`` the state (and derivative) at each contact candidate of the module."""
        module = self.robot.modules[m]
        own = [self.robot.actuators.index(a) for a in module.actuators]
        scale = module.state_scale
        n_act = len(module.actuators)
        size = STATE_SIZE + n_act
        y = np.r_[x0 / scale, np.zeros(n_act)]
        S = None if D0 is None else np.vstack([D0 / scale[:, None], np.zeros((n_act, D0.shape[1]))])
        loads_of = _load_values(self.robot, m, params)
        param = self.robot.param_function(params)
        constants = module.stiffness_of(param)
        out_s, out_x, out_w = [], [], []
        for index, (s0, s1, active) in enumerate(self._segments[m]):
            if (m, s0) in self._recorded:                    # the pose there (continuous across the jump)
                found[(m, s0)] = (y[:STATE_SIZE] * scale, None if S is None else S[:STATE_SIZE] * scale[:, None])
            if index > 0:
                y, S = self._jump(m, index - 1, y, S, scale, forces, dF, contact, dC, params)
            rhs = self._rhs[m][index]
            columns = [own[k] for k in active]
            F_act, dF_act = forces[columns], (None if dF is None else dF[columns].ravel(order="F"))
            loads = np.r_[loads_of(0.5 * (s0 + s1)), constants,
                          [v for k in active for v in module.actuators[k].placement_of(param)]]
            budget = [RHS_BUDGET]

            def derivative(s, state, rhs=rhs, F_act=F_act, dF_act=dF_act, loads=loads, budget=budget):
                budget[0] -= 1
                if budget[0] < 0 or not np.all(np.isfinite(state)):
                    raise _ShotFailed(f"integration of module {module.name} did not finish "
                                      f"(state too far from equilibrium)")
                if dF_act is None:
                    return rhs.value(s, state, F_act, loads).copy()
                return rhs.augmented(s, state, F_act, dF_act, loads).copy()

            grid = None
            if outputs:
                extra = None if self.sample_s is None else np.asarray(self.sample_s[m], float)
                grid, weights = segment_grid(s0, s1, extra, _panels(module, s1 - s0))
            state0 = y if S is None else np.r_[y, S.ravel(order="F")]
            sol = solve_ivp(derivative, (s0, s1), state0, method="DOP853", t_eval=grid,
                            rtol=self.rtol, atol=self._atol(size, S))
            if not sol.success:
                raise _ShotFailed(f"integration failed in module {module.name}: {sol.message}")
            final = sol.y[:, -1]
            y = final[:size].copy()
            S = None if S is None else final[size:].reshape(size, -1, order="F").copy()
            if outputs:
                out_s.append(sol.t)
                out_x.append(sol.y[:STATE_SIZE] * scale[:, None] + np.r_[np.zeros(7), module.xi_star][:, None])
                out_w.append(weights)
        end = y[:STATE_SIZE] * scale
        D_end = None if S is None else S[:STATE_SIZE] * scale[:, None]
        last = self._segments[m][-1][1]
        if (m, last) in self._recorded:
            found[(m, last)] = (end, D_end)
        lengths = y[STATE_SIZE:] * module.length
        D_lengths = None if S is None else S[STATE_SIZE:] * module.length
        data = (np.concatenate(out_s), np.hstack(out_x), np.concatenate(out_w)) if outputs else None
        return end, D_end, lengths, D_lengths, data

    def _atol(self, size, S):
        """Absolute tolerances: the state's, and a looser one on the sensitivities (the
        Jacobian only steers the root finder; the residual is integrated to full accuracy)."""
        if S is None:
            return self.atol
        return np.r_[np.full(size, self.atol), np.full(S.size, 1e-8)]

    def _jump(self, m, b, y, S, scale, forces, dF, contact, dC, params):
        """Scaled state (and sensitivities) after the b-th interior breakpoint of module m."""
        x_before = y[:STATE_SIZE] * scale
        jump = self._jumps[m][b]
        values = jump(x_before, forces, contact, params)
        x_after = np.array(values[0], float).ravel()
        y = np.r_[x_after / scale, y[STATE_SIZE:]]
        if S is not None:
            D_before = S[:STATE_SIZE] * scale[:, None]
            D_after = (np.array(values[1], float) @ D_before + np.array(values[2], float) @ dF
                       + np.array(values[3], float) @ dC)
            S = np.vstack([D_after / scale[:, None], S[STATE_SIZE:]])
        return y, S

    def _base_wrench(self, m, state, forces, contact, params):
        """``W(0-)`` of module m: internal wrench at its start plus the point wrenches there."""
        if self._bases[m] is None:
            self._bases[m] = _base_function(self.robot, m, self._contact)
        return _as_array(self._bases[m](state, forces, contact, params))


# ----------------------------------------------------------------------------- building blocks
def free_starts(robot):
    """Modules whose base strains are shooting unknowns: the first module, every decoupled module
    and every coupled child after the first of its parent (the first is started from the
    parent's tip balance)."""
    out = [0]
    for m, module in enumerate(robot.modules[1:], start=1):
        if module.decoupled or robot.coupled_children(module.parent)[0] != m:
            out.append(m)
    return out


def _continued_child(robot, m, free):
    """The child of m started from m's tip balance (at most one), else None."""
    for c in robot.children(m):
        if c not in free:
            return c
    return None


class _SegmentRhs:
    """The explicit right-hand side of one segment (routes inside), evaluated through CasADi's
    buffer API: ``value(s, y, F, c) -> y'`` and, for the variational equations,
    ``augmented(s, [y; vec S], F, dF, c) -> [y'; vec(df/dy S + df/dF dF)]`` (column-major
    ``vec``), with ``n_unknowns`` columns of S. ``c`` holds what is constant over the segment:
    the distributed loads (12), the stiffness diagonal (6) and each active route's placement
    ``(radius, angle)``."""

    def __init__(self, module, actuators, n_unknowns):
        equations = rod_equations(module.xi_star, len(actuators))
        rate = explicit_strain_rate(equations)
        scale = module.state_scale
        s = ca.SX.sym("s")
        y = ca.SX.sym("y", STATE_SIZE + len(module.actuators))
        forces = ca.SX.sym("F", len(actuators))
        loads = ca.SX.sym("c", 18 + 2 * len(actuators))
        columns = [ca.vertcat(*route_expressions(a.route, s, loads[18 + 2 * k], loads[19 + 2 * k]))
                   for k, a in enumerate(actuators)]
        routes = ca.horzcat(*columns) if columns else ca.SX(9, 0)
        x = y[:STATE_SIZE] * ca.DM(scale)
        split = [loads[12:18]] + [loads[3 * k:3 * k + 3] for k in range(4)]
        dxi = rate(x, routes, forces, *split)
        kin, _, speed = equations(x, dxi, routes, forces, *split)
        speeds = ca.SX.zeros(len(module.actuators))
        for k, actuator in enumerate(actuators):
            speeds[module.actuators.index(actuator)] = speed[k] / module.length
        f = ca.vertcat(ca.vertcat(kin, dxi) / ca.DM(scale), speeds)
        self._value = BufferedFunction(ca.Function("shooting_rhs", [s, y, forces, loads], [ca.densify(f)]))
        S = ca.SX.sym("S", y.numel(), n_unknowns)
        dF = ca.SX.sym("dF", len(actuators), n_unknowns)
        rate = ca.jacobian(f, y) @ S + ca.jacobian(f, forces) @ dF
        self._augmented = BufferedFunction(ca.Function("shooting_rhs_variational", [s, ca.vertcat(y, ca.vec(S)), forces,
                                                                             ca.vec(dF), loads],
                                                [ca.densify(ca.vertcat(f, ca.vec(rate)))]))

    def value(self, s, y, forces, loads):
        return self._value(s, y, forces, loads)[0]

    def augmented(self, s, y, forces, dF, loads):
        return self._augmented(s, y, forces, dF, loads)[0]


def _segment_rhs(module, actuators, n_unknowns):
    return _SegmentRhs(module, actuators, n_unknowns)


def _symbols(robot):
    """Symbolic tensions (all actuators) and parameters, with the lookups boundary.* expects."""
    forces = ca.MX.sym("F", len(robot.actuators))
    params = ca.MX.sym("P", robot.layout.size)
    tension = lambda a: forces[robot.actuators.index(a)]          # noqa: E731
    param = lambda name: params[robot.layout[name]]                 # noqa: E731
    return forces, params, tension, param


def _contact_symbols(robot, unknowns, param):
    """The symbolic contact block (physical) and its ``contact_of`` for :mod:`.boundary`."""
    block = ca.MX.sym("C", unknowns.size)
    return block, unknowns.views(block).contact_of(robot, param)


def contact_candidates(robot):
    """``[(module, s)]`` of every contact candidate (obstacles and grips), in a fixed order: the
    arc lengths at which a shot records the pose for the contact conditions."""
    keys = [(c.module, c.s) for c in list(robot.contacts) + list(robot.grips)]
    return list(dict.fromkeys(keys))


def _nearest(points, s):
    """The entry of ``points`` nearest ``s``."""
    return min(points, key=lambda point: abs(point - s))


def _conditions_function(robot, unknowns, candidates):
    """Function ``(X (13, k), C, P) -> (residuals, d/d vec X, d/dC)`` of the contact block's
    conditions (:func:`~tca_casadi.model.contact_unknowns.contact_conditions`) with the states
    ``X`` at ``candidates``; None without contact."""
    if not unknowns.size:
        return None
    states = ca.MX.sym("X", STATE_SIZE, len(candidates))
    _, params, _, param = _symbols(robot)
    block, _ = _contact_symbols(robot, unknowns, param)
    where = {key: k for k, key in enumerate(candidates)}
    r = ca.vertcat(*contact_conditions(robot, unknowns.views(block), lambda m, s: states[:, where[(m, s)]], param))
    return ca.Function("contact_conditions", [states, block, params],
                       [r, ca.jacobian(r, ca.vec(states)), ca.jacobian(r, block)])


def _strains_after(robot, m, s, before_pose, target, tension, param):
    """Deviation strains just after s solving ``K dxi + (point wrenches after s)(dxi) = target``
    (a CasADi rootfinder when actuators pull there with the tangent after s; else explicit)."""
    module = robot.modules[m]
    if not boundary.actuators_after(robot, m, s):
        return target / boundary.stiffness(module, param)
    delta = ca.MX.sym("delta", 6)
    data = ca.MX.sym("data", 7 + 6 + len(robot.actuators) + robot.layout.size)
    forces = data[13:13 + len(robot.actuators)]
    inner = data[13 + len(robot.actuators):]
    inner_param = lambda name: inner[robot.layout[name]]            # noqa: E731
    stiffness = boundary.stiffness(module, inner_param)
    state = ca.vertcat(data[0:7], delta)
    t = lambda a: forces[robot.actuators.index(a)]                 # noqa: E731
    residual = stiffness * delta - data[7:13]
    for actuator in boundary.actuators_after(robot, m, s):
        residual += boundary.tangent_wrench(module, actuator, s, state, t(actuator), inner_param)
    solver = ca.rootfinder("jump_solver", "newton",
                           ca.Function("jump", [delta, data], [residual / stiffness]),
                           {"abstol": 1e-15, "max_iter": 50, "error_on_fail": False})
    forces_all = ca.vertcat(*[tension(a) for a in robot.actuators]) if robot.actuators else ca.MX(0, 1)
    params_all = ca.vertcat(*[param(name) for name in robot.layout.names()])
    return solver(target / boundary.stiffness(module, param), ca.vertcat(before_pose, target, forces_all, params_all))


def _jump_function(robot, m, s, unknowns):
    """Function ``(x_before, F, C, P) -> (x_after, dx_after/dx_before, dx_after/dF,
    dx_after/dC)`` at an interior breakpoint s of module m: ``K (xi+ - xi-) + point wrenches = 0``
    (contact forces at s among them)."""
    module = robot.modules[m]
    x_before = ca.MX.sym("x", STATE_SIZE)
    forces, params, tension, param = _symbols(robot)
    block, contact_of = _contact_symbols(robot, unknowns, param)
    rest = boundary.point_wrenches(robot, m, s, x_before, None, tension, param, contact_of)
    target = boundary.add(boundary.internal_wrench(module, x_before, param), None if rest is None else -rest)
    strains = _strains_after(robot, m, s, x_before[0:7], target, tension, param)
    x_after = ca.vertcat(x_before[0:7], strains)
    return ca.Function(f"jump_{m}", [x_before, forces, block, params],
                       [x_after, ca.jacobian(x_after, x_before), ca.jacobian(x_after, forces),
                        ca.jacobian(x_after, block)])


def _end_function(robot, m, free, unknowns):
    """Function ``(x_end, strains of each free child, F, C, P) -> (main, starts of the free
    children, then the Jacobian blocks of each output: d/d x_end, d/d each strain, d/d F, d/d C)``.
    ``main`` is the scaled tip balance of module m, or the start state of its continued child."""
    module = robot.modules[m]
    end = ca.MX.sym("end", STATE_SIZE)
    forces, params, tension, param = _symbols(robot)
    block, contact_of = _contact_symbols(robot, unknowns, param)
    children = [c for c in robot.children(m) if c in free]
    strains = [ca.MX.sym(f"z{c}", 6) for c in children]
    starts = []
    for c, strain in zip(children, strains):
        position, quaternion = boundary.junction_pose(end, robot.modules[c])
        starts.append(ca.vertcat(position, quaternion, strain))
    balance = boundary.tip_balance(robot, m, end, dict(zip(children, starts)), tension, param, contact=contact_of)
    continued = _continued_child(robot, m, free)
    if continued is None:
        main = balance * ca.DM(module.wrench_scale)
    else:
        main = _junction_start(robot, end, balance, continued, tension, param, contact_of)
    outputs = [main] + starts
    inputs = [end] + strains + [forces, block]
    jacobians = [ca.jacobian(out, given) for out in outputs for given in inputs]
    return ca.Function(f"end_{m}", [end] + strains + [forces, block, params], outputs + jacobians)


def _base_function(robot, m, unknowns):
    """Function ``(start, F, C, P) -> W(0-)`` of module m (:func:`~tca_casadi.model.boundary.base_wrench`)."""
    start = ca.MX.sym("start", STATE_SIZE)
    forces, params, tension, param = _symbols(robot)
    block, contact_of = _contact_symbols(robot, unknowns, param)
    wrench = boundary.base_wrench(robot, m, start, tension, param, contact=contact_of)
    return ca.Function(f"base_{m}", [start, forces, block, params], [wrench])


def _junction_start(robot, end, balance, c, tension, param, contact_of=None):
    """Base state of the coupled child c whose base wrench must equal what the parent's tip
    balance leaves (``balance``, parent tip frame; SPEC section 5)."""
    child = robot.modules[c]
    position, quaternion = boundary.junction_pose(end, child)
    weight = boundary.connector_weight(end, child, param)
    transmitted = boundary.untransmit(balance if weight is None else balance - weight, child)
    pose = ca.vertcat(position, quaternion)
    state = ca.vertcat(pose, ca.MX.zeros(6))
    loads = boundary.point_wrenches(robot, c, 0.0, state, None, tension, param, contact_of)
    target = transmitted if loads is None else transmitted - loads
    return ca.vertcat(pose, _strains_after(robot, c, 0.0, pose, target, tension, param))


def _compatibility_function(robot):
    """Function ``(lengths, F, P) -> (residuals, d/d lengths, d/d F)`` of every unknown tension."""
    lengths = ca.MX.sym("l", len(robot.actuators))
    forces, params, tension, param = _symbols(robot)
    out = compatibility_residuals(robot, lengths, tension, param)
    r = ca.vertcat(*out) if out else ca.MX(0, 1)
    return ca.Function("compatibility", [lengths, forces, params],
                       [r, ca.jacobian(r, lengths), ca.jacobian(r, forces)])


def _tension_map(robot):
    """``(T, F0)``: every actuator's tension is ``F0(params) + T @ unknown tensions``."""
    T = np.zeros((len(robot.actuators), len(robot.unknowns)))
    known = []
    for k, actuator in enumerate(robot.actuators):
        if actuator.unknown_tension:
            T[k, robot.unknowns.index(actuator)] = 1.0
        else:
            known.append((k, robot.layout[actuator.parameter]))

    def F0(params):
        out = np.zeros(len(robot.actuators))
        for k, slot in known:
            out[k] = params[slot][0]
        return out
    return T, F0


def _load_values(robot, m, params):
    """``loads(s_mid)`` -> (12,) distributed loads of a segment: global force (self-weight
    included) and moment, body force and moment per length (:mod:`tca_casadi.model.boundary`
    conventions), from the parameters."""
    value = lambda name: np.asarray(params[robot.layout[name]], float)      # noqa: E731
    return lambda s_mid: np.concatenate(distributed_fields(robot, m, s_mid, value))


def _segments(robot, m):
    """``(s0, s1, active)`` between the module's breakpoints, ``active`` the indices (within the
    module) of the actuators running through the segment."""
    module = robot.modules[m]
    breaks = module_breakpoints(robot, m)
    out = []
    for s0, s1 in zip(breaks[:-1], breaks[1:]):
        mid = 0.5 * (s0 + s1)
        active = [k for k, a in enumerate(module.actuators) if is_active(a, mid)]
        out.append((s0, s1, active))
    return out


def _panels(module, length):
    """Quadrature panels over a segment of ``length``: one, plus four per helix turn that the
    module's routes make over it (the centerline follows a helical route's wobble)."""
    per_metre = sum(abs(a.route.params.get("turns", 0.0)) / (a.route.span[1] - a.route.span[0])
                    for a in module.actuators)
    return 1 + int(np.ceil(4 * per_metre * length))


def segment_grid(s0, s1, extra=None, panels=1):
    """Output arc lengths of one integration segment and their quadrature weights [m]:
    ``OUTPUT_POINTS`` equispaced points (ends included), ``GAUSS_POINTS`` Gauss-Legendre points
    on each of ``panels`` equal panels carrying the weights (exact for polynomials of degree
    ``2 GAUSS_POINTS - 1`` on each), and any ``extra`` points inside (weight zero)."""
    nodes, gauss = np.polynomial.legendre.leggauss(GAUSS_POINTS)
    edges = np.linspace(s0, s1, panels + 1)
    half = np.diff(edges)[:, None] / 2
    s = np.r_[np.linspace(s0, s1, OUTPUT_POINTS), (edges[:-1, None] + (nodes + 1) * half).ravel()]
    w = np.r_[np.zeros(OUTPUT_POINTS), (gauss * half).ravel()]
    if extra is not None:
        inside = extra[(extra > s0) & (extra < s1)]
        s, w = np.r_[s, inside], np.r_[w, np.zeros(inside.size)]
    grid, inverse = np.unique(s, return_inverse=True)
    return grid, np.bincount(inverse, weights=w, minlength=grid.size)


def _reference_trajectory(robot, params):
    """``(module_data, tensions, lengths)`` of the unloaded reference shape (exact, no integration)."""
    from ..model.kinematics import reference_chain
    grids = [segment_grid(0.0, module.length) for module in robot.modules]
    samples = [s for s, _ in grids]
    module_data = [(s, states, np.zeros(6), w)
                   for (s, w), states in zip(grids, reference_chain(robot, params, samples))]
    return module_data, [0.0] * len(robot.actuators), [a.reference_length for a in robot.at(params).actuators]


def _selection(n, columns, offset):
    """(offset + len(columns), n) matrix selecting ``columns`` of the unknowns into the rows
    after ``offset`` zero rows."""
    columns = list(columns)
    out = np.zeros((offset + len(columns), n))
    out[offset + np.arange(len(columns)), columns] = 1.0
    return out


def _as_array(value):
    return np.array(value, dtype=float).ravel()

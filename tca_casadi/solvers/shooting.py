"""The shooting solver (SPEC section 6): an independent cross-check of collocation.

Unknowns: the base strains (as deviations from xi*) of every module whose start is not fixed by
its parent's tip balance (the first module, each decoupled module, each finger of a tree after
the first) and the unknown tensions.
For a guess, the explicit equilibrium ``xi' = (K + A)^-1 (...)`` (paper eq. 25; obtained by solving
the same CasADi rod residual that collocation imposes, which is linear in xi') is integrated
module by module with ``scipy.integrate.solve_ivp`` (DOP853, tight tolerances), segment by segment
between breakpoints, applying the wrench jumps at anchors, point loads and junctions (a small
Newton solve where a jump depends on the strain after it). Residuals: the tip wrench of every
module whose tip balance is not used to start a child, and every compatibility equation, solved
by MINPACK's Powell dog-leg trust region (``hybr``).
Only the discretisation differs from collocation: the physics Functions are the same.
"""
import logging
import time

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import root

from ..discretisation.mesh import module_breakpoints
from ..model import boundary
from ..model.compatibility import compatibility
from ..model.rod import STATE_SIZE, explicit_strain_rate, rod_equations
from .assemble import build_solution

log = logging.getLogger(__name__)

#: points per integration segment written to the solution's arrays
OUTPUT_POINTS = 9
#: right-hand-side evaluations allowed per segment before a shot is abandoned
RHS_BUDGET = 20000
#: finite-difference step on the scaled unknowns
FD_STEP = 1e-6


class _ShotFailed(Exception):
    """A trial point whose integration cannot finish (far from any equilibrium)."""


class ShootingSolver:
    """Single shooting with scipy. ``solve(params, initial=None)`` -> :class:`Solution`."""
    method = "shooting"

    def __init__(self, robot, options, rtol=1e-11, atol=1e-12):
        start = time.perf_counter()
        self.robot, self.options = robot, options
        self.rtol, self.atol = rtol, atol
        self._rhs = [_shooting_rhs(module) for module in robot.modules]
        self._segments = [_segments(robot, m) for m in range(len(robot.modules))]
        self._jumps = {}
        self._free = free_starts(robot)
        #: optional extra output arc lengths per module (e.g. another solver's nodes)
        self.sample_s = None
        self.build_time_s = time.perf_counter() - start
        self.solve_count = 0

    # ------------------------------------------------------------------ unknowns
    def _unknown_scale(self):
        strains = [_state_scale(self.robot.modules[m])[7:13] for m in self._free]
        tensions = [self.robot.modules[a.module].force_scale for a in self.robot.unknowns]
        return np.r_[np.concatenate(strains), tensions]

    def initial_guess(self, initial=None):
        """Scaled unknowns from a previous Solution (any method), else the reference state."""
        n_strain = 6 * len(self._free)
        z = np.zeros(n_strain + len(self.robot.unknowns))
        if initial is not None:
            for k, m in enumerate(self._free):
                start, module = initial.modules[m], self.robot.modules[m]
                z[6 * k:6 * k + 6] = np.r_[start.u[:, 0], start.v[:, 0]] - module.xi_star
            z[n_strain:] = [initial.actuators[a.key].tension for a in self.robot.unknowns]
        return z / self._unknown_scale()

    # ------------------------------------------------------------------ solve
    def solve(self, params, initial=None):
        """Solve at ``params`` from ``initial`` (a Solution of either method) or the reference."""
        params = np.asarray(params, dtype=float)
        z0 = self.initial_guess(initial)
        start = time.perf_counter()
        calls = [0]

        # the unknown is the change from z0: MINPACK sizes its first trust region from |x|,
        # which must not be a tiny nonzero start value
        def residual(change):
            calls[0] += 1
            try:
                return self._shoot(z0 + change, params)[0]
            except _ShotFailed:
                return np.full(change.size, 1e6)   # a wild trial point: let the trust region shrink

        def jacobian(change):
            """Forward differences on the order-one scaled unknowns (step 1e-6)."""
            base = residual(change)
            columns = []
            for k in range(change.size):
                step = np.zeros_like(change)
                step[k] = FD_STEP
                columns.append((residual(change + step) - base) / FD_STEP)
            return np.column_stack(columns)

        result = root(residual, np.zeros_like(z0), jac=jacobian, method="hybr",
                      options={"xtol": 1e-13, "maxfev": 50 * (z0.size + 1)})
        result.x = z0 + result.x
        try:
            residual_value, trajectory = self._shoot(result.x, params)
        except _ShotFailed as exc:
            return self._failed(params, str(exc), time.perf_counter() - start)
        elapsed = time.perf_counter() - start
        self.solve_count += 1
        worst = float(np.max(np.abs(residual_value))) if residual_value.size else 0.0
        tolerance = self.tolerance
        converged = bool(worst <= tolerance)
        message = (f"scipy root (hybr): {result.message.strip()}; max scaled residual {worst:.2e} "
                   f"(tolerance {tolerance:.0e}), {calls[0]} shots")
        status = {"converged": converged, "status": "success" if converged else "failure",
                  "message": message, "method": self.method, "max_residual": worst,
                  "iterations": int(result.nfev), "solve_time_s": elapsed,
                  "build_time_s": self.build_time_s, "raw": {"z": result.x, "method": self.method}}
        module_data, tensions, lengths = trajectory
        return build_solution(self.robot, params, module_data, tensions, lengths, status)

    def _failed(self, params, message, elapsed):
        """A Solution-shaped failure carrying the reference shape's arrays; converged False."""
        trial = _reference_trajectory(self.robot, params)
        status = {"converged": False, "status": "failure", "message": f"shooting failed: {message}",
                  "method": self.method, "max_residual": float("inf"), "iterations": 0,
                  "solve_time_s": elapsed, "build_time_s": self.build_time_s, "raw": {"method": self.method}}
        return build_solution(self.robot, params, *trial, status)

    @property
    def tolerance(self):
        """Accepted scaled residual: the scenario's tolerance, floored by what the integrator's
        tolerances can deliver."""
        return max(self.options.tolerance, 1e-9)

    # ------------------------------------------------------------------ one shot
    def _shoot(self, z, params):
        """Integrate the whole chain from unknowns z; return (residuals, trajectory)."""
        robot = self.robot
        unknowns = z * self._unknown_scale()
        n_strain = 6 * len(self._free)
        tensions = dict(zip([a.key for a in robot.unknowns], unknowns[n_strain:]))
        tension = _tension_lookup(robot, params, tensions)
        param = _param_lookup(robot, params)
        guessed = {m: unknowns[6 * k:6 * k + 6] for k, m in enumerate(self._free)}
        starts = {0: np.r_[params[robot.layout["base.position"]], params[robot.layout["base.quaternion"]],
                           guessed[0]]}
        module_data, lengths = [], np.zeros(len(robot.actuators))
        residuals = []
        for m, module in enumerate(robot.modules):
            state = starts[m]
            base_wrench = self._base_wrench(m, state, tension, param)
            s_out, states, end, module_lengths = self._integrate(m, state, params, tension, param)
            module_data.append((s_out, states + np.r_[np.zeros(7), module.xi_star][:, None], base_wrench))
            for k, actuator in enumerate(module.actuators):
                lengths[robot.actuators.index(actuator)] = module_lengths[k]
            applied = boundary.point_wrenches(robot, m, module.length, end, None, tension, param)
            balance = boundary.internal_wrench(module, end) - boundary.add(ca.DM.zeros(6), applied)
            continued = None
            for c in robot.children(m):
                if c not in guessed:
                    continued = c           # started below from what the others leave
                    continue
                position, quaternion = boundary.junction_pose(end, robot.modules[c])
                starts[c] = np.r_[np.array(position).ravel(), np.array(quaternion).ravel(), guessed[c]]
                balance = balance - boundary.child_wrench(
                    end, robot.modules[c], self._base_wrench(c, starts[c], tension, param), param)
            if continued is None:
                residuals.append(_as_array(balance) * _wrench_scale(module))
            else:
                starts[continued] = self._junction(end, balance, continued, tension, param)
        for actuator in robot.unknowns:
            stroke = lengths[robot.actuators.index(actuator)] - actuator.reference_length
            parameter = params[robot.layout[actuator.parameter]][0]
            residuals.append([compatibility(actuator, stroke, tensions[actuator.key], parameter,
                                            robot.modules[actuator.module].force_scale)])
        all_tensions = [tension(a) for a in robot.actuators]
        return np.concatenate([np.ravel(r) for r in residuals]), (module_data, all_tensions, lengths)

    def _integrate(self, m, state, params, tension, param):
        """Integrate module m from its base state; return output arc lengths, states (13, n),
        the end state and the actuator lengths."""
        module = self.robot.modules[m]
        scale = _state_scale(module)
        n_act = len(module.actuators)
        y = np.r_[state / scale, np.zeros(n_act)]
        outputs_s, outputs = [], []
        for index, (s0, s1, active) in enumerate(self._segments[m]):
            if index > 0:
                y[:STATE_SIZE] = self._interior_jump(m, s0, y[:STATE_SIZE] * scale, tension, param) / scale
            loads = _distributed_loads(self.robot, m, 0.5 * (s0 + s1), param)
            forces = np.array([tension(a) for a in module.actuators]) * active
            rhs = self._rhs[m]

            budget = [RHS_BUDGET]

            def derivative(s, y_scaled, active=active, forces=forces, loads=loads, budget=budget):
                budget[0] -= 1
                if budget[0] < 0 or not np.all(np.isfinite(y_scaled)):
                    raise _ShotFailed(f"integration of module {module.name} did not finish "
                                      f"(state too far from equilibrium)")
                routes = _route_data(module, s, active)
                rate, speed = rhs(y_scaled[:STATE_SIZE] * scale, routes, forces, *loads)
                return np.r_[np.array(rate).ravel() / scale, np.array(speed).ravel() * active / module.length]

            grid = np.linspace(s0, s1, OUTPUT_POINTS)
            if self.sample_s is not None:
                extra = np.asarray(self.sample_s[m], float)
                grid = np.unique(np.r_[grid, extra[(extra > s0) & (extra < s1)]])
            sol = solve_ivp(derivative, (s0, s1), y, method="DOP853", t_eval=grid,
                            rtol=self.rtol, atol=self.atol)
            if not sol.success:
                raise _ShotFailed(f"integration failed in module {module.name}: {sol.message}")
            y = sol.y[:, -1].copy()
            outputs_s.append(sol.t)
            outputs.append(sol.y[:STATE_SIZE] * scale[:, None])
        end = y[:STATE_SIZE] * scale
        return np.concatenate(outputs_s), np.hstack(outputs), end, y[STATE_SIZE:] * module.length

    # ------------------------------------------------------------------ jumps
    def _interior_jump(self, m, s, before, tension, param):
        """State after breakpoint s: ``K (xi+ - xi-) + point wrenches = 0``."""
        module = self.robot.modules[m]
        rest = boundary.point_wrenches(self.robot, m, s, before, None, tension, param)
        target = _as_array(boundary.add(boundary.internal_wrench(module, before),
                                        None if rest is None else -rest))
        after = before.copy()
        after[7:13] = self._solve_start(m, s, target, before[3:7], tension, param)
        return after

    def _base_wrench(self, m, state, tension, param):
        """``W(0-)`` of module m: internal wrench at its start plus the point wrenches there."""
        return _as_array(boundary.add(boundary.internal_wrench(self.robot.modules[m], state),
                                      boundary.point_wrenches(self.robot, m, 0.0, None, state, tension, param)))

    def _junction(self, end, balance, c, tension, param):
        """Base state of the coupled child c whose base wrench must equal what the parent's tip
        balance leaves (``balance``, parent tip frame; SPEC section 5)."""
        robot, child = self.robot, self.robot.modules[c]
        position, quaternion = boundary.junction_pose(end, child)
        h = np.array(quaternion).ravel()
        weight = boundary.connector_weight(end, child, param)
        transmitted = boundary.untransmit(balance if weight is None else balance - weight, child)
        start_state = np.r_[np.array(position).ravel(), h, np.zeros(6)]
        loads = boundary.point_wrenches(robot, c, 0.0, start_state, None, tension, param)
        target = _as_array(transmitted if loads is None else transmitted - loads)
        start_state[7:13] = self._solve_start(c, 0.0, target, h, tension, param)
        return start_state

    def _solve_start(self, m, s, target, h, tension, param):
        """Deviation strains after s solving ``K dxi + (anchors starting at s)(dxi) = target``."""
        module = self.robot.modules[m]
        starting = boundary.starting_anchors(self.robot, m, s)
        guess = target / module.stiffness
        if not starting:
            return guess
        key = (m, round(s / module.length, 12))
        if key not in self._jumps:
            self._jumps[key] = _start_jump_solver(module, s, starting)
        forces = np.array([tension(a) for a in starting])
        return np.array(self._jumps[key](guess, np.r_[target, h, forces])).ravel()


# ----------------------------------------------------------------------------- helpers
def free_starts(robot):
    """Modules whose base strains are shooting unknowns: the first module, every decoupled module
    and every coupled child after the first of its parent (the first is started from the
    parent's tip balance)."""
    out = [0]
    for m, module in enumerate(robot.modules[1:], start=1):
        if module.decoupled or robot.coupled_children(module.parent)[0] != m:
            out.append(m)
    return out


def _reference_trajectory(robot, params):
    """``(module_data, tensions, lengths)`` of the unloaded reference shape (exact, no integration)."""
    from .guess import reference_chain
    samples = [np.linspace(0.0, module.length, OUTPUT_POINTS) for module in robot.modules]
    module_data = [(s, states, np.zeros(6)) for s, states in zip(samples, reference_chain(robot, params, samples))]
    return module_data, [0.0] * len(robot.actuators), [a.reference_length for a in robot.actuators]


def _shooting_rhs(module):
    """CasADi Function ``(x, routes, F, loads...) -> (x', speed)`` of a module (deviation state)."""
    equations = rod_equations(module.stiffness, module.xi_star, len(module.actuators))
    rate = explicit_strain_rate(equations)
    x = ca.SX.sym("x", STATE_SIZE)
    routes = ca.SX.sym("routes", 9, len(module.actuators))
    forces = ca.SX.sym("F", len(module.actuators))
    loads = [ca.SX.sym(name, 3) for name in ("f_glob", "l_glob", "f_body", "l_body")]
    dxi = rate(x, routes, forces, *loads)
    kin, _, speed = equations(x, dxi, routes, forces, *loads)
    return ca.Function("shooting_rhs", [x, routes, forces] + loads, [ca.vertcat(kin, dxi), speed])


def _start_jump_solver(module, s, starting):
    """Newton rootfinder for the strain after a breakpoint where anchors start."""
    delta = ca.SX.sym("delta", 6)
    data = ca.SX.sym("data", 6 + 4 + len(starting))
    target, h, forces = data[0:6], data[6:10], data[10:]
    state = ca.vertcat(ca.SX.zeros(3), h, delta)
    residual = boundary.internal_wrench(module, state) - target
    for k, actuator in enumerate(starting):
        residual += boundary.anchor_wrench(module, actuator, s, state, forces[k])
    residual = residual / ca.DM(module.stiffness)
    equation = ca.Function("jump", [delta, data], [residual])
    return ca.rootfinder("jump_solver", "newton", equation, {"abstol": 1e-15, "max_iter": 50,
                                                             "error_on_fail": True})


def _segments(robot, m):
    """``(s0, s1, active (nA,))`` between the module's breakpoints."""
    module = robot.modules[m]
    breaks = module_breakpoints(robot, m)
    out = []
    for s0, s1 in zip(breaks[:-1], breaks[1:]):
        mid = 0.5 * (s0 + s1)
        active = np.array([a.route.span[0] < mid < a.route.span[1] for a in module.actuators], dtype=float)
        out.append((s0, s1, active))
    return out


def _route_data(module, s, active):
    data = np.zeros((9, len(module.actuators)))
    for k, actuator in enumerate(module.actuators):
        if active[k]:
            r, dr, ddr = actuator.route.evaluate(min(max(s, actuator.route.span[0]), actuator.route.span[1]))
            data[:, k] = np.r_[r[:, 0], dr[:, 0], ddr[:, 0]]
    return data


def _distributed_loads(robot, m, s_mid, param):
    """Global force (self-weight included), global moment, body force, body moment per length."""
    module = robot.modules[m]
    fields = [module.weight_density * np.asarray(param("gravity"), float)] + [np.zeros(3) for _ in range(3)]
    for load in robot.distributed_loads:
        if load.module == m and load.span[0] < s_mid < load.span[1]:
            first = 0 if load.frame == "global" else 2
            fields[first] = fields[first] + param(f"{load.name}.force")
            fields[first + 1] = fields[first + 1] + param(f"{load.name}.moment")
    return fields


def _state_scale(module):
    """Integration scale of the deviation state (same order-one scaling as collocation)."""
    return np.r_[np.full(3, module.length), np.ones(4), module.force_scale * module.length / module.stiffness[0:3],
                 module.force_scale / module.stiffness[3:6]]


def _wrench_scale(module):
    return np.r_[np.full(3, 1 / (module.force_scale * module.length)), np.full(3, 1 / module.force_scale)]


def _tension_lookup(robot, params, unknown_tensions):
    def tension(actuator):
        if actuator.unknown_tension:
            return unknown_tensions[actuator.key]
        return float(params[robot.layout[actuator.parameter]][0])
    return tension


def _param_lookup(robot, params):
    return lambda name: params[robot.layout[name]]


def _as_array(value):
    return np.array(value, dtype=float).ravel()

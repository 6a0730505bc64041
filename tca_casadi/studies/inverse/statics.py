"""Inverse statics (SPEC section 6): a target pose in, TCA temperatures out.

The forward collocation constraints ``g(w, P(tau)) = 0`` stay as equality constraints; the
varied temperatures become bounded decision variables ``T_j = lo_j + (hi_j - lo_j) tau_j``,
``tau_j`` in [0, 1]; the objective is the pose error of a chosen point (a module's end, the tip by
default)::

    f = |p - p*|^2 / e_p^2  +  w_o [(1 - t . d*) + (3 - tr(R*^T R)) / 2] / (e_a^2 / 2)
        +  eps sum tau_j^2

``e_p`` and ``e_a`` are the position and angle tolerances (0.1 mm, 1 deg: an error at the
tolerance costs 1), ``t`` the point's tangent (``R e_z``), ``d*`` a target direction and ``R*``
a target orientation (each term only when asked; both are ``1 - cos(angle)``). The last term,
least total heating (``eps`` = ``regularisation``, default 1e-3), picks one answer where several
reach the target; it moves a reachable answer by about ``eps e_p^2 / |dp/dtau|``, nanometres.

Two methods minimise it. ``reduced`` (the default): least squares over the temperatures only,
every iterate an equilibrium (:mod:`.reduced`). ``ipopt``: the full-space NLP with the
collocation constraints as equalities, exact first and second derivatives from CasADi (built on
first use). Both are built once; the target, weights and all other parameters (loads,
gravity, ...) are NLP parameters. The reduced method is the default because it is the faster on
every shipped robot (``scripts/bench.py``: the bending module about 40 ms against 50 ms per cold
query, the refined arm about 0.4 s against minutes: IPOPT's exact-Hessian iterations on 4272
unknowns need repeated factorisations for inertia correction).
"""
import itertools
import logging
import time

import casadi as ca
import numpy as np

from ...errors import ScenarioError, flag
from ...model.rotations import ROTATION, rotation_angle, rotation_numpy
from ...scenario.checks import closest
from ...solvers.continuation import walk_branch
from ...buffers import BufferedFunction, CscPattern
from ...status import SolveStatus, Status
from ..parameters import resolve_parameters, shown_as_given
from .result import InverseResult
from .targets import Target, TargetLayout

log = logging.getLogger(__name__)


class InverseStatics:
    """Inverse statics on the collocation NLP of ``sim``.

    ``vary``: temperature paths (default every TCA of the chain); ``bounds``: ``(lo, hi)`` degC for
    all of them (default each TCA type's reference to maximum temperature); ``tolerance``: the
    position error [m] under which a target counts as reached; ``angle_tolerance`` [rad] likewise;
    ``starts``: initial temperature sets tried from a cold start (stopping at the first that
    reaches the target).
    """

    def __init__(self, sim, vary=None, bounds=None, tolerance=1e-4, angle_tolerance=np.radians(1.0),
                 regularisation=1e-3, orientation_weight=1.0, starts=4, method="reduced"):
        if method not in ("ipopt", "reduced"):
            raise ScenarioError(f"unknown inverse method {method!r}; available: ipopt, reduced")
        self.method = method
        self.sim, self.robot = sim, sim.robot
        self.solver = sim.solver("collocation")
        vary = list(vary) if vary else [a.parameter for a in self.robot.muscles]
        if not vary:
            raise ScenarioError("inverse statics needs TCAs (or other muscles) to drive; the scenario has none")
        self.parameters = resolve_parameters(self.robot, sim.params, vary)
        inputs = {a.parameter: a for a in self.robot.muscles}
        for parameter in self.parameters:
            if parameter.name not in inputs:
                raise ScenarioError(f"inverse statics varies the muscles' inputs (TCA temperatures, "
                                    f"pressures...); {parameter.path} is not one")
        self._muscle = inputs
        self.bounds = self._bounds(bounds)
        self.parameters = [shown_as_given(p, sim.scenario, *(bounds or ()), values=b)
                           for p, b in zip(self.parameters, self.bounds)]
        self.tolerance, self.angle_tolerance = float(tolerance), float(angle_tolerance)
        self.regularisation, self.orientation_weight = float(regularisation), float(orientation_weight)
        if int(starts) < 1:
            raise ScenarioError(f"starts ({flag('--starts')}) must be at least 1, got {starts}")
        self.starts = int(starts)
        self._forward_cache = {}
        self._start_linearisation = {}
        self.length = sum(m.length for m in self.robot.modules)
        started = time.perf_counter()
        self._build()
        self.build_time_s = time.perf_counter() - started

    @classmethod
    def from_scenario(cls, sim, **overrides):
        """Options from the scenario's ``inverse:`` section (if any), then ``overrides``."""
        section = sim.scenario.inverse
        options = {}
        if section is not None:
            options = {"vary": section.vary, "bounds": section.bounds, "tolerance": section.tolerance,
                       "regularisation": section.regularisation,
                       "orientation_weight": section.orientation_weight, "starts": section.starts,
                       "method": section.method}
        options.update({k: v for k, v in overrides.items() if v is not None})
        return cls(sim, **options)

    def scenario_target(self, point=None):
        """The target of the scenario's ``inverse:`` section (:class:`ScenarioError` if none)."""
        section = self.sim.scenario.inverse
        if section is None or section.target is None:
            raise ScenarioError(f"no target: give one ({flag('--target-position')} X Y Z) or an inverse.target "
                                "in the scenario")
        given = section.target
        return Target.create(given.position, given.direction, given.orientation, point or given.point)

    # ------------------------------------------------------------------ bounds
    def _bounds(self, bounds):
        out = []
        for parameter in self.parameters:
            actuator = self._muscle[parameter.name]
            low, high = actuator.law.inverse_range
            if bounds is None and not (np.isfinite(low) and np.isfinite(high)):
                raise ScenarioError(f"{parameter.path}: its law's range [{low:g}, {high:g}] is not finite; "
                                    f"give bounds ({flag('--bounds')} LOW HIGH)")
            if bounds is None:
                out.append((low, high))
                continue
            lo, hi = (parameter.to_si(b, "the bound") for b in bounds)
            unit = parameter.unit
            if not lo < hi:
                raise ScenarioError(f"bounds [{lo:g}, {hi:g}] {unit} are inverted or empty (need lower < upper)")
            if lo < low - 1e-9 or hi > high + 1e-9:
                raise ScenarioError(
                    f"bounds [{lo:g}, {hi:g}] {unit} leave {parameter.path}'s range [{low:g}, {high:g}] {unit} "
                    f"({actuator.type_path}: {actuator.law.INVERSE_RANGE_TEXT})")
            out.append((lo, hi))
        return np.array(out, float)

    # ------------------------------------------------------------------ the NLP
    def _build(self):
        nlp, robot = self.solver.nlp, self.robot
        k, n_modules = len(self.parameters), len(robot.modules)
        tau = ca.MX.sym("tau", k)
        fixed = ca.MX.sym("P", robot.layout.size)
        self.target_layout = TargetLayout(n_modules)
        target = ca.MX.sym("target", self.target_layout.size)
        parts = self.target_layout.unpack(target)
        position, direction, R_target, select = parts["position"], parts["direction"], parts["rotation"], parts["select"]
        w_position, w_direction, w_rotation = (parts["weights"][k] for k in range(3))
        P = fixed
        for j, parameter in enumerate(self.parameters):
            vector = ca.DM(parameter.vector(robot.layout.size))
            value = self.bounds[j, 0] + (self.bounds[j, 1] - self.bounds[j, 0]) * tau[j]
            P = P + vector * (value - ca.dot(vector, fixed))
        ends = nlp.outputs(nlp.w, P)[1]                               # (13, n_modules)
        state = ends @ select
        R = ROTATION(state[3:7])
        error = state[0:3] - position
        angle_scale = self.angle_tolerance**2 / 2
        objective = (w_position * ca.sumsqr(error) / self.tolerance**2
                     + w_direction * (1 - ca.dot(R[:, 2], direction)) / angle_scale
                     + w_rotation * (3 - ca.trace(R_target.T @ R)) / 2 / angle_scale
                     + self.regularisation * ca.sumsqr(tau))
        self._problem = {"x": ca.vertcat(nlp.w, tau), "p": ca.vertcat(fixed, target), "f": objective,
                         "g": ca.Function("g", [nlp.w, nlp.P], [nlp.problem["g"]])(nlp.w, P)}
        self._ipopt_instance = None
        self._pose = ca.Function("pose", [nlp.w, tau, fixed, target], [state[0:3], R]).expand()
        self._n_w = nlp.w.numel()
        # the same objective as a sum of squares, for the reduced-space method
        residuals = ca.vertcat(ca.sqrt(w_position) * error / self.tolerance,
                               ca.sqrt(w_direction) * (R[:, 2] - direction) / self.angle_tolerance,
                               ca.sqrt(w_rotation) * ca.vec(R - R_target) / (np.sqrt(2) * self.angle_tolerance),
                               np.sqrt(self.regularisation) * tau)
        self._residuals = ca.Function("residuals", [nlp.w, tau, fixed, target],
                                      [residuals, ca.jacobian(residuals, nlp.w),
                                       ca.jacobian(residuals, tau)]).expand()
        self._residual_buffer = BufferedFunction(self._residuals)
        self._residual_patterns = [CscPattern(self._residuals.sparsity_out(k)) for k in (1, 2)]
        self._dP_dtau = np.column_stack([p.vector(robot.layout.size) * (hi - lo)
                                         for p, (lo, hi) in zip(self.parameters, self.bounds)])

    @property
    def _ipopt(self):
        """IPOPT on the full-space problem, built on first use (``method="ipopt"``): the start is
        an equilibrium (feasible) with tau inside the box, so a small initial barrier."""
        if self._ipopt_instance is None:
            options = {"print_level": 0, "sb": "yes", "tol": 1e-8, "mu_init": 1e-6,
                       "constr_viol_tol": self.sim.scenario.solver.tolerance, "max_iter": 300,
                       "nlp_scaling_method": "none", "bound_relax_factor": 0.0}
            self._ipopt_instance = ca.nlpsol("inverse", "ipopt", self._problem,
                                             {"ipopt": options, "print_time": False, "error_on_fail": False,
                                              "expand": True})
        return self._ipopt_instance

    def _target_vector(self, target):
        names = [m.name for m in self.robot.modules]
        point = names[self.robot.tip_index] if target.point == "tip" else target.point
        if point not in names:
            raise ScenarioError(f"target point {target.point!r} is not 'tip' or a module{closest(target.point, names)}")
        select = np.zeros(len(names))
        select[names.index(point)] = 1.0
        direction = target.direction if target.direction is not None else np.zeros(3)
        R_target = rotation_numpy(target.orientation) if target.orientation is not None else np.eye(3)
        weights = [1.0, self.orientation_weight * (target.direction is not None),
                   self.orientation_weight * (target.orientation is not None)]
        return self.target_layout.pack(target.position, direction, R_target, weights, select)

    # ------------------------------------------------------------------ queries
    def values(self, tau):
        return self.bounds[:, 0] + (self.bounds[:, 1] - self.bounds[:, 0]) * np.asarray(tau)

    def params_at(self, tau):
        params = self.sim.params.copy()
        for parameter, value in zip(self.parameters, self.values(tau)):
            params = parameter.with_value(params, value)
        return params

    def start_points(self):
        """Initial ``tau``, one at a time: the middle of the box, then a scrambled Sobol' set
        (seed 0), drawn only if the middle does not reach the target (scipy.stats takes 0.5 s
        to import)."""
        yield np.full(len(self.parameters), 0.5)
        if self.starts > 1:
            from scipy.stats import qmc
            sobol = qmc.Sobol(len(self.parameters), scramble=True, seed=0)
            yield from sobol.random(2 ** int(np.ceil(np.log2(self.starts - 1))))[: self.starts - 1]

    def middle(self):
        """The first start point: the middle of the box."""
        return next(self.start_points())

    def solve(self, target, initial=None):
        """Temperatures that bring the target point to ``target`` (a :class:`Target`).

        ``initial``: a previous :class:`InverseResult` (path tracking: one warm-started solve,
        multi-start only if it fails). Returns an :class:`InverseResult`; an unreachable target
        is not an error: the closest reachable pose, ``reachable=False`` and the distance."""
        started = time.perf_counter()
        vector = self._target_vector(target)
        best, iterations, tried = None, 0, 0
        seeds = [(initial.w, initial.tau)] if initial is not None and initial.w is not None else []
        for candidate in itertools.chain(seeds, self.start_points()):
            w0, tau0 = candidate if isinstance(candidate, tuple) else (self._forward_w(candidate), candidate)
            if w0 is None:
                continue
            tried += 1
            attempt = self._attempt(w0, tau0, vector, target)
            iterations += attempt["iterations"]
            if attempt["equilibrium"] and (best is None or _better(attempt, best)):
                best = attempt
            if best is not None and self._reached(best):
                break
        if tried == 0:       # no start has a forward equilibrium: try from the reference shape
            from ...solvers.guess import reference_guess
            tau0 = self.middle()
            attempt = self._attempt(reference_guess(self.solver.nlp, self.params_at(tau0)), tau0, vector, target)
            iterations, tried = iterations + attempt["iterations"], 1
        if best is None:
            best = attempt
        return self._result(target, best, time.perf_counter() - started, iterations, tried)

    def track(self, targets, progress=None):
        """Solve a path of targets, each warm-started from the previous answer."""
        results, previous = [], None
        for index, target in enumerate(targets):
            previous = self.solve(target, previous)
            results.append(previous)
            if progress is not None:
                progress((index + 1) / len(targets), f"target {index + 1}/{len(targets)}")
        return results

    def _forward(self, tau):
        """The forward Solution at temperatures ``tau`` (continuation from the reference state,
        no error estimate: a start, and where the verification starts from), cached per parameter
        vector: starts are shared by all queries."""
        params = self.params_at(tau)
        key = params.tobytes()
        if key not in self._forward_cache:
            self._forward_cache[key] = self.sim.solve_at(params, method="collocation", estimate=False)
        return self._forward_cache[key]

    def _forward_w(self, tau):
        solution = self._forward(tau)
        return solution.iterate.w if solution.converged else None

    def _attempt(self, w0, tau0, vector, target):
        """One optimisation from ``(w0, tau0)``: a dict with the answer (``w``, ``tau``, pose,
        errors), ``equilibrium`` (the constraints hold) and ``result`` (:class:`SolveStatus`)."""
        started = time.perf_counter()
        if self.method == "reduced":
            from .reduced import reduced_attempt
            w, tau, failure, iterations, detail = reduced_attempt(self, w0, tau0, vector)
            return self._describe_attempt(w, tau, "least squares (dogbox)", failure, float("nan"), iterations,
                                          detail, vector, target, started)
        result = self._ipopt(x0=np.r_[w0, tau0], p=np.r_[self.sim.params, vector],
                             lbx=np.r_[np.full(self._n_w, -np.inf), np.zeros(len(tau0))],
                             ubx=np.r_[np.full(self._n_w, np.inf), np.ones(len(tau0))],
                             lbg=0.0, ubg=0.0)
        stats = self._ipopt.stats()
        x = np.array(result["x"]).ravel()
        w, tau = x[:self._n_w], np.clip(x[self._n_w:], 0.0, 1.0)
        failure = None if stats["success"] else (
            Status.MAX_ITERATIONS if stats["return_status"] == "Maximum_Iterations_Exceeded" else Status.ALGORITHM_FAILED)
        return self._describe_attempt(w, tau, "IPOPT", failure, float(result["f"]), int(stats.get("iter_count", 0)),
                                      f"IPOPT: {stats['return_status']}", vector, target, started)

    def _describe_attempt(self, w, tau, algorithm, failure, objective, iterations, detail, vector, target, started):
        tolerance = self.sim.scenario.solver.tolerance
        residual = self.solver.max_residual(w, self.params_at(tau))
        result = SolveStatus.judged(algorithm, residual, tolerance, failure, nit=iterations, detail=detail,
                                    solve_time_s=time.perf_counter() - started, build_time_s=self.build_time_s)
        position, R = (np.array(v) for v in self._pose(w, tau, self.sim.params, vector))
        position = position.ravel()
        if not np.isfinite(objective):
            objective = float(np.sum(self.residual_values(w, tau, vector)[0] ** 2))
        return {"w": w, "tau": tau, "result": result, "equilibrium": residual <= tolerance,
                "objective": objective, "iterations": iterations,
                "position": position, "R": R, "residual": residual,
                "position_error": float(np.linalg.norm(position - target.position)),
                "angle_error": self._angle_error(R, target)}

    def _angle_error(self, R, target):
        if target.direction is not None:
            return float(np.arccos(np.clip(R[:, 2] @ target.direction, -1.0, 1.0)))
        if target.orientation is not None:
            return float(rotation_angle(R, rotation_numpy(target.orientation)))
        return None

    def _reached(self, attempt):
        """An equilibrium (constraints satisfied) within the tolerances of the target."""
        angle_ok = attempt["angle_error"] is None or attempt["angle_error"] <= self.angle_tolerance
        return attempt["equilibrium"] and attempt["position_error"] <= self.tolerance and angle_ok

    def _result(self, target, best, elapsed, iterations, tried):
        temperatures = {p.path: float(v) for p, v in zip(self.parameters, self.values(best["tau"]))}
        forward, difference = self._verify(best, target)
        reachable = self._reached(best)
        status = best["result"]
        if not best["equilibrium"]:
            message = f"no equilibrium: {status.message}"
        elif reachable:
            message = "target reached" + ("" if status.success else f" ({status.message})")
        elif not status.success:
            message = (f"no start reached the target; the closest pose found, "
                       f"{best['position_error'] * 1e3:.4g} mm away, is not proven optimal "
                       f"({status.message})")
        else:
            message = (f"target unreachable within the bounds: the closest pose found is "
                       f"{best['position_error'] * 1e3:.4g} mm away")
        return InverseResult(target, temperatures, best["position"], best["R"], best["position_error"],
                             best["angle_error"], reachable, status.success, best["objective"],
                             forward, difference, elapsed, iterations, tried, message,
                             best["w"], best["tau"], self.method, status,
                             {p.path: p.unit for p in self.parameters}, self.parameters)

    def residual_values(self, w, tau, vector):
        """The least-squares residuals ``r`` (m,), ``dr/dw`` (sparse) and ``dr/dtau`` (m, k) at
        ``(w, tau)`` for the target ``vector`` (evaluated into buffers)."""
        r, r_w, r_tau = self._residual_buffer(w, tau, self.sim.params, vector)
        w_pattern, tau_pattern = self._residual_patterns
        return r.copy(), w_pattern.matrix(r_w), tau_pattern.matrix(r_tau).toarray()

    def linearisation_at(self, w, params):
        """The solver's linearisation at ``(w, params)``, kept for the last few points asked
        (the starts are the same for every query: their linearisations are computed once)."""
        key = (np.asarray(w, float).tobytes(), np.asarray(params, float).tobytes())
        if key not in self._start_linearisation:
            if len(self._start_linearisation) >= 8:
                self._start_linearisation.pop(next(iter(self._start_linearisation)))
            self._start_linearisation[key] = self.solver.linearise(w, params)
        return self._start_linearisation[key]

    def _verify(self, best, target):
        """Independent forward solve at the answer's temperatures: predictor-corrector
        continuation from the first start's forward equilibrium (not from the answer's state),
        or from the reference state if that fails."""
        params = self.params_at(best["tau"])
        start = self._forward(self.middle())
        forward = None
        if start.converged:
            walk = walk_branch(self.solver, start, start.parameters, params, min_step=1e-3,
                               linearisation=self.linearisation_at(start.iterate.w, start.parameters))
            forward = walk.point.solution if walk.completed else None
        if forward is None:
            forward = self.sim.solve_at(params, method="collocation")
        names = [m.name for m in forward.modules]
        point_name = names[forward.tip_module] if target.point == "tip" else target.point
        achieved = forward.modules[names.index(point_name)].tip_position
        difference = float(np.linalg.norm(achieved - best["position"])) if forward.converged else np.inf
        return forward, difference


def _better(attempt, best):
    """Prefer an IPOPT-optimal attempt, then the lower objective."""
    return (attempt["result"].success, -attempt["objective"]) > (best["result"].success, -best["objective"])



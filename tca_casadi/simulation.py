"""A thin orchestrator: scenario -> robot model -> solver (built once, cached) -> solution.

    sim = Simulation.from_file("scenarios/bending_module.yaml")
    first = sim.solve()
    sim.set("bending.tca2.temperature", 110)      # a parameter: no rebuild
    second = sim.solve(warm_start=first)
"""
import logging
import time
import warnings

import numpy as np

from .errors import ScenarioError, TcaError
from .model import Robot
from .model.history import carried_history, history_names_of
from .solvers.assemble import record_slides
from .scenario import load_scenario
from .scenario.loader import validate
from .scenario.overrides import apply_overrides
from .solvers import CollocationSolver
from .solvers import accuracy
from .solvers.continuation import walk_branch
from .solvers.localisation import localise
from .status import SolveStatus, Status

log = logging.getLogger(__name__)

#: solver methods and the class behind each (the shooting solver imported when first asked for)
SOLVERS = {"collocation": "CollocationSolver", "shooting": "ShootingSolver"}


class Simulation:
    """Holds a scenario, its robot model, the current parameter values and the built solver."""

    def __init__(self, scenario, method=None):
        self.scenario = scenario
        self.robot = Robot.from_scenario(scenario)
        self.params = self.robot.values.copy()
        self.method = method or scenario.solver.method
        self._solvers = {}
        self.last = None

    @classmethod
    def from_file(cls, source, overrides=(), method=None, allow_code=False):
        """Load (YAML path, YAML text or dict), apply ``overrides``, build the model.
        ``allow_code``: run the Python code a ``custom`` muscle law names (refused otherwise,
        see :func:`~tca_casadi.scenario.load_scenario`)."""
        return cls(load_scenario(source, overrides, allow_code=allow_code), method=method)

    # ------------------------------------------------------------------ parameters
    def set(self, path, value):
        """Set a scenario value by dotted path (units allowed: ``"110 degC"``).

        A parameter (temperature, tension, load, gravity, base pose, a material's modulus or
        density, a TCA type's geometry or fit, a route's radius or angle: the names in
        ``robot.layout``) changes only the parameter vector; anything else (a length, a route's
        kind or span, the mesh) rebuilds the model and solver.
        """
        if self.scenario._raw is None:           # built in Python, not loaded: start from its data
            from .scenario.sources import SourceMap
            self.scenario._raw = self.scenario.model_dump(mode="json")
            self.scenario._sources = SourceMap("<scenario>")
        raw = apply_overrides(self.scenario._raw, {path: value}, self.scenario._sources)
        scenario = validate(raw, self.scenario._sources)
        scenario._allow_code = self.scenario._allow_code
        if self.robot.structure_key(scenario) == self.robot.structure_key(self.scenario):
            params = self.robot.parameter_vector(scenario)
            problems = self.robot.problems(params)
            if problems:
                Robot.from_scenario(scenario)        # names the scenario key where it can
                raise ScenarioError(f"--set {path}: " + "; ".join(problems))
            self.scenario, self.params = scenario, params
            return
        log.info("%s changes the structure: rebuilding", path)
        self.__init__(scenario, self.method)

    def set_parameter(self, name, value):
        """Fast path: set a parameter-vector entry (``robot.layout`` name) to an SI value."""
        if name not in self.robot.layout:
            raise ScenarioError(f"{name!r} is not a parameter; parameters: {', '.join(self.robot.layout.names())}")
        self.params[self.robot.layout[name]] = value

    def get_parameter(self, name):
        value = self.params[self.robot.layout[name]]
        return float(value[0]) if value.size == 1 else value.copy()

    def use_meshes(self, meshes, degree=None):
        """Solve by collocation on ``meshes`` (per module, e.g. another process's refined mesh)
        at ``degree`` (default the scenario's): the same NLP wherever it is built."""
        self._solvers["collocation"] = CollocationSolver.shared(
            self.robot, self.scenario.solver, self.robot.structure_key(self.scenario), meshes, degree)

    # ------------------------------------------------------------------ solving
    def solver(self, method=None):
        """The solver for ``method`` (built on first use, then reused while the robot is the same:
        localised contacts make a new robot, for which a solver other than the one that
        localised them is built anew)."""
        method = method or self.method
        if method in self._solvers and self._solvers[method].robot is not self.robot and method != "collocation":
            del self._solvers[method]
        if method not in self._solvers:
            if method not in SOLVERS:
                raise ScenarioError(f"unknown solver method {method!r}; available: {', '.join(SOLVERS)}")
            if method == "collocation":        # built once per structure and process
                self._solvers[method] = CollocationSolver.shared(
                    self.robot, self.scenario.solver, self.robot.structure_key(self.scenario))
            else:
                from . import solvers
                self._solvers[method] = getattr(solvers, SOLVERS[method])(self.robot, self.scenario.solver)
        return self._solvers[method]

    def solve(self, warm_start=None, method=None, continuation=None, refine=True, warn=True, params=None):
        """Equilibrium at ``params`` (a parameter vector, which the simulation keeps as its
        current parameters; None: the current parameters).

        ``warm_start``: a previous Solution, or ``"last"``. ``continuation`` (default from the
        scenario): ``"auto"`` follows the loads up from the unloaded reference state on a cold start
        (SPEC section 6: a direct cold solve may land on a branch where TCAs push) and, after a warm
        start that fails or leaves a TCA in compression; ``"always"``; ``"never"`` (direct solve).

        A cold collocation solve carries an error estimate (``solution.accuracy``); with
        ``refine`` and ``solver.refine: auto`` the mesh is refined where the error is until the
        tip and tensions meet ``solver.tip_tolerance`` / ``tension_tolerance``, and the refined
        solver is kept for later solves (sweeps, inverse statics).

        The solution's :class:`~tca_casadi.errors.PhysicsWarning` s (non-convergence,
        compression, slack, accuracy, ...) are recorded in ``solution.warnings`` and, with
        ``warn``, also issued with :func:`warnings.warn` (studies pass ``warn=False``).
        """
        if params is not None:
            self.params = np.array(params, float)
        solver = self.solver(method)
        continuation = continuation or self.scenario.solver.continuation
        initial = self.last if warm_start == "last" else warm_start
        self.params = carried_history(self.robot, self.params, initial)   # contact objects' grips
        start = self.params.copy()
        if initial is None and continuation == "never":      # continuation checks it itself
            self.robot.check_clear(self.robot.rest_parameters(self.params))
        if continuation == "always" or (continuation == "auto" and initial is None):
            solution = self.continue_from_rest(solver)
            if not solution.converged and continuation == "auto":
                solution = _better(solver.solve(self.params), solution)
        elif self.robot.obstacles and continuation == "auto" and solver.has_square_system:
            solution = self._solve_from(solver, initial)       # contact: closing is a corner
        else:
            solution = solver.solve(self.params, initial)
            if continuation == "auto" and _needs_continuation(solution):
                solution = _better(solution, self.continue_from_rest(solver))
        if self.robot.path_dependent and solution.converged:
            # friction: the state reached carries its path's history (each contact anchored where
            # it ended up), which a refined solve, and the next solve, start from
            self.params = carried_history(self.robot, self.params, solution)
        if initial is None and solution.converged and solver.estimates_error:
            solver, solution, _ = accuracy.control(solver, solution, self.params, refine)
            self._solvers[method or self.method] = solver
        if solution.converged and (solution.penetration > self.robot.contact_tolerance or self.robot.added_contacts) \
                and solver.estimates_error and not self.robot.frictional_contacts:
            solver, solution = localise(self, solver, solution)         # contacts between candidates
            self._solvers[method or self.method] = solver
        record_slides(self.robot, start, solution)
        self.last = solution
        if warn:
            for warning in solution.warnings:
                warnings.warn(warning, stacklevel=2)
        return solution

    def solve_near(self, previous=None, params=None):
        """The equilibrium at ``params`` (a parameter vector; None: the current parameters),
        for one of many nearby points (a study); parameters that the robot cannot take (an
        actuator's temperature out of its law's range, an obstacle cutting the reference
        state) raise a :class:`~tca_casadi.errors.TcaError` naming each problem. The solve:
        Newton from ``previous`` (the Solution at a nearby point; the solver's own warm start
        without a square system), continuation from the reference state when there is none,
        or when Newton fails or leaves a TCA pushing. Newton's first steps are chord steps on
        the Jacobian factorised last (at or near ``previous``). No error estimate, no
        refinement, no warnings issued (they are in ``solution.warnings``)."""
        if params is not None:
            problems = self.robot.problems(params)
            if problems:
                raise TcaError("; ".join(problems))
            self.params = np.array(params, float)
        solver = self.solver()
        solution = None
        self.params = carried_history(self.robot, self.params, previous)
        if previous is not None:
            solution = (solver.solve_newton(self.params, solver.initial_guess(self.params, previous),
                                            lu=solver.square.last_lu)
                        if solver.has_square_system else solver.solve(self.params, previous))
        if solution is None or _needs_continuation(solution):
            cold = self.continue_from_rest(solver)
            solution = cold if solution is None else _better(solution, cold)
        record_slides(self.robot, self.params, solution)
        self.last = solution
        return solution

    def solve_at(self, params, method=None):
        """Solve at the parameter vector ``params`` from the reference state (cold, with
        continuation), leaving this simulation's own parameters and last solution unchanged."""
        saved, last = self.params.copy(), self.last
        try:
            self.params = np.array(params, dtype=float)
            return self.solve(method=method, refine=False, warn=False)
        finally:
            self.params, self.last = saved, last

    def continue_from_rest(self, solver, first_step=0.25, min_step=1e-3):
        """Follow ``P(lam) = P_rest + lam (P - P_rest)`` from the reference state (lam = 0, exact)
        to lam = 1: predictor-corrector steps on the collocation NLP (branch jumps rejected),
        warm-started solves for shooting; failed steps are halved down to ``min_step``."""
        started = time.perf_counter()
        target, rest = self.params.copy(), self.robot.rest_parameters(self.params)
        self.robot.check_clear(rest)
        solution = solver.solve(rest)
        if not solution.converged:
            return solution
        follow = _follow_branch if solver.has_square_system else _warm_steps
        solution, lam, steps, iterations, last_failure = follow(solver, rest, target, solution,
                                                                first_step, min_step)
        if lam < 1.0:
            return self._stalled(solver, solution, rest, target, lam, min_step, last_failure,
                                 iterations, time.perf_counter() - started)
        note = f"continuation from the reference state, {steps} steps"
        solution.result = solution.result.noted(note).replace(                # all steps included
            solve_time_s=time.perf_counter() - started, nit=iterations)
        return solution


    def _solve_from(self, solver, initial):
        """A warm solve of a robot with contacts: Newton (or IPOPT, ``solver.algorithm: ipopt``)
        from ``initial``, then (a contact that closes or opens on the way is a corner Newton may
        not turn) continuation from
        ``initial``'s parameters to these, then from the reference state when that is clear of
        every obstacle, IPOPT last."""
        start = initial.parameters
        if self.robot.path_dependent and initial.converged and start is not None and start.size == self.params.size:
            return self._follow_from(solver, initial)
        ipopt = solver.options.algorithm == "ipopt"
        solution = solver.solve_ipopt(self.params, initial) if ipopt else \
            solver.solve_newton(self.params, solver.initial_guess(self.params, initial))
        if _needs_continuation(solution) and initial.converged and start is not None and start.size == self.params.size:
            follow = _follow_branch(solver, start, self.params.copy(), initial, 0.25, 1e-3)
            solution = _better(solution, follow[0] if follow[1] == 1.0 else solution)
        if _needs_continuation(solution) and self.robot.is_clear(self.robot.rest_parameters(self.params)):
            solution = _better(solution, self.continue_from_rest(solver))
        if _needs_continuation(solution) and not ipopt:
            solution = _better(solution, solver.solve_ipopt(self.params, initial))
        return solution

    def _follow_from(self, solver, initial):
        """A warm solve of a robot with contact objects: continuation from ``initial``'s
        parameters to these (friction depends on the path: the whole step first, halved where
        a grasp closes or opens, a jump refused), never a solve from the reference state (it
        would put the objects back where they were placed); stalled when it cannot go on."""
        started = time.perf_counter()
        start, target = initial.parameters.copy(), self.params.copy()
        solution, lam, steps, iterations, failure = _follow_branch(solver, start, target, initial, 1.0, 1e-4)
        if lam < 1.0:
            return self._stalled(solver, solution, start, target, lam, 1e-4, failure, iterations,
                                 time.perf_counter() - started, origin="the previous solution")
        if solver.options.algorithm == "ipopt":          # the path by Newton steps, its end by IPOPT
            polished = solver.solve_ipopt(carried_history(self.robot, self.params, solution), solution)
            solution = polished if polished.converged else solution
            iterations += polished.iterations
        solution.result = solution.result.noted(f"continuation from the previous solution, {steps} steps").replace(
            solve_time_s=time.perf_counter() - started, nit=iterations)
        return solution

    def _stalled(self, solver, reached, rest, target, lam, min_step, last_failure, iterations, elapsed,
                 origin="the reference state"):
        """The unconverged result of a continuation that stopped at ``lam``: the state it reached,
        reported at the user's parameters (their values in the table, the residual there), with
        how far it got, the parameter values reached and what the last step did."""
        history = set(history_names_of(self.robot))
        changed = [name for name in self.robot.layout.names() if name not in history
                   and np.any(rest[self.robot.layout[name]] != target[self.robot.layout[name]])]
        reached_values = rest + lam * (target - rest)
        where = "; ".join(f"{name} {_format(reached_values[self.robot.layout[name]])} of "
                          f"{_format(target[self.robot.layout[name]])}" for name in changed[:6])
        more = f" and {len(changed) - 6} more" if len(changed) > 6 else ""
        detail = (f"stalled at lambda = {lam:.4f} of 1 (step below {min_step}); reached {where}{more}; "
                  f"the max scaled residual above is at the requested parameters; last step: {last_failure}"
                  f"{_held_by_sliding(reached)}")
        status = SolveStatus(Status.STALLED, f"continuation from {origin}", nit=iterations,
                             tolerance=reached.result.tolerance, solve_time_s=elapsed, detail=detail)
        return solver.evaluate(reached.raw.get("w", reached.raw.get("z")), target, status)


#: a grip within this fraction of its friction (``mu f_n``) of Coulomb's cone is at its limit
AT_LIMIT = 1e-3


def _held_by_sliding(solution):
    """What a stall means for a contact object off its support held by grips that are all at
    their friction limit (sliding, or within :data:`AT_LIMIT` of it): nothing can hold more of
    it there (``""`` if none is)."""
    names = [body.name for body in solution.bodies if body.grips and not body.resting and all(
        c.sliding or c.friction_margin <= AT_LIMIT * c.friction * c.normal_force for c in body.grips)]
    if not names:
        return ""
    return (f"; object {', '.join(map(repr, names))} hangs there on grips all at their friction limit: "
            "past that point the grasp cannot hold it (it would drop)")


def _format(values):
    values = np.atleast_1d(values)
    return f"{values[0]:.6g}" if values.size == 1 else "[" + ", ".join(f"{v:.4g}" for v in values) + "]"


def _follow_branch(solver, rest, target, start, first_step, min_step):
    """Collocation: predictor-corrector continuation. Returns ``(solution, lam, steps,
    iterations, last_failure)`` (``last_failure``: what the last rejected step did, or None)."""
    walk = walk_branch(solver, start, rest, target, first_step=first_step, max_step=0.5, min_step=min_step)
    iterations = start.iterations + walk.iterations
    if not walk.completed:
        return walk.point.solution, walk.point.lam, walk.substeps, iterations, _failure_text(walk.failure)
    return walk.point.solution, 1.0, walk.substeps, iterations, None


def _failure_text(failure):
    """What the last rejected continuation step did."""
    if not failure.trial.converged:
        return failure.trial.message
    if failure.dropped:
        return (f"object {', '.join(map(repr, failure.dropped))} would drop: it jumps {failure.moved * 1e3:.3g} mm "
                "within the smallest step continuation takes (its grasp lets go of it, or it snaps to another "
                "equilibrium); where it lands is not a static result")
    if failure.crossed:
        return ("it converged, but det J changes sign within the step: a fold or a bifurcation "
                "lies between (sweep the parameter with --arclength to follow the branch)")
    return f"it converged only off the branch (a jump to another branch, inconsistency {failure.jump:.2g})"


def _warm_steps(solver, rest, target, solution, first_step, min_step):
    """Shooting: warm-started solves, halving failed steps. Returns ``(solution, lam, steps,
    iterations, last_failure)``."""
    lam, step, steps, iterations = 0.0, first_step, 0, solution.iterations
    while lam < 1.0:
        trial_lam = min(1.0, lam + step)
        trial = solver.solve(rest + trial_lam * (target - rest), solution)
        steps, iterations = steps + 1, iterations + trial.iterations
        if trial.converged:
            lam, solution, step = trial_lam, trial, min(0.5, 1.5 * step)
        elif step / 2 >= min_step:
            step /= 2
        else:
            return solution, lam, steps, iterations, trial.message
    return solution, lam, steps, iterations, None


def _needs_continuation(solution):
    return (not solution.converged) or any(
        a.kind != "tendon" and not a.tension_only and a.tension < 0 for a in solution.actuators.values())


def _better(first, second):
    """The converged one of two attempts; ``second`` when both or neither converged."""
    if first.converged and not second.converged:
        return first
    return second


def solve(source, overrides=(), allow_code=False, **options):
    """One call: load a scenario and solve it. Returns a :class:`Solution`."""
    return Simulation.from_file(source, overrides, allow_code=allow_code).solve(**options)


__all__ = ["Simulation", "solve"]

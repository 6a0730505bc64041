"""The solving strategy: how an equilibrium is found at given parameters (issue 37's review).

:class:`Simulation <tca_casadi.simulation.Simulation>` holds a scenario, its parameters and the
last solution; everything about *how* a point is solved lives here: the choice between a warm
solve and continuation from the unloaded reference state (SPEC section 6), the fallbacks with
contact (continuation from the previous point, from rest, IPOPT last), the path-dependent walk
of contact objects, the accuracy control that refines the mesh, the localisation of contacts
between candidates, and the report of a continuation that stalls. A strategy takes parameter
vectors as arguments and never a Simulation; it owns the robot (localisation replaces it with
one that has more contact candidates) and the solvers built for it (refinement replaces them).
"""
import time

import numpy as np

from ..errors import ScenarioError, TcaError, flag
from ..model.history import carried_history, history_names_of
from ..solution import Iterate
from ..status import SolveStatus, Status
from . import accuracy
from .assemble import record_slides
from .collocation import CollocationSolver
from .continuation import walk_branch

#: solver methods and the class behind each (the shooting solver imported when first asked for)
SOLVERS = {"collocation": "CollocationSolver", "shooting": "ShootingSolver"}


class SolveStrategy:
    """How the equilibria of ``robot`` (built from ``scenario``) are found by ``method``
    (``collocation`` or ``shooting``): the policy of :meth:`solve`, :meth:`solve_near` and
    :meth:`continue_from_rest`, the solvers built for the robot (:meth:`solver`).

    Attributes
    ----------
    robot : Robot
        The robot solved (contact localisation replaces it with one with added candidates).
    """

    def __init__(self, scenario, robot, method):
        self.scenario, self.robot, self.method = scenario, robot, method
        self._solvers = {}

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
                from .. import solvers
                self._solvers[method] = getattr(solvers, SOLVERS[method])(self.robot, self.scenario.solver)
        return self._solvers[method]

    def use_solver(self, solver, method=None):
        """Solve by ``solver`` for ``method`` from now on (a refined mesh, another process's
        mesh, a solver built with other options)."""
        self._solvers[method or self.method] = solver

    def use_meshes(self, meshes, degree=None):
        """Solve by collocation on ``meshes`` (per module) at ``degree`` (default the scenario's)."""
        self._solvers["collocation"] = CollocationSolver.shared(
            self.robot, self.scenario.solver, self.robot.structure_key(self.scenario), meshes, degree)

    # ------------------------------------------------------------------ one point
    def solve(self, params, initial=None, method=None, continuation=None, refine=True, estimate=True):
        """The equilibrium at the parameter vector ``params`` (see :meth:`Simulation.solve
        <tca_casadi.simulation.Simulation.solve>`): ``initial`` a previous Solution to start
        from, or None (a cold start); ``estimate`` False: no error estimate of a cold start (a
        start point for something else, whose own answer is estimated or verified). Returns
        ``(solution, params)``: ``params`` with the contact objects' history carried from the
        path taken (grips anchored where they ended)."""
        solver = self.solver(method)
        continuation = continuation or self.scenario.solver.continuation
        params = carried_history(self.robot, np.array(params, float), initial)   # contact objects' grips
        start = params.copy()
        if initial is None and continuation == "never":      # continuation checks it itself
            self.robot.check_clear(self.robot.rest_parameters(params))
        if continuation == "always" or (continuation == "auto" and initial is None):
            solution = self.continue_from_rest(solver, params)
            if not solution.converged and continuation == "auto":
                solution = _better(solver.solve(params), solution)
        elif self.robot.obstacles and continuation == "auto" and solver.has_square_system:
            solution = self._solve_from(solver, params, initial)       # contact: closing is a corner
        else:
            solution = solver.solve(params, initial)
            if continuation == "auto" and _needs_continuation(solution):
                solution = _better(solution, self.continue_from_rest(solver, params))
        if self.robot.path_dependent and solution.converged:
            # friction: the state reached carries its path's history (each contact anchored where
            # it ended up), which a refined solve, and the next solve, start from
            params = carried_history(self.robot, params, solution)
        if initial is None and solution.converged and solver.estimates_error and estimate:
            solver, solution, _ = accuracy.control(solver, solution, params, refine)
            self.use_solver(solver, method)
        if solution.converged and (solution.penetration > self.robot.contact_tolerance or self.robot.added_contacts) \
                and solver.estimates_error and not self.robot.frictional_contacts:
            from .localisation import localise
            self.robot, solver, solution = localise(self, solver, solution, params)   # contacts between candidates
            self.use_solver(solver, method)
        record_slides(self.robot, start, solution)
        return solution, params

    def solve_near(self, params, previous=None, lean=False):
        """The equilibrium at ``params`` for one of many nearby points (a study; see
        :meth:`Simulation.solve_near <tca_casadi.simulation.Simulation.solve_near>`): Newton from
        ``previous``, continuation from the reference state when there is none or Newton fails
        or leaves a TCA pushing. Parameters the robot cannot take raise a
        :class:`~tca_casadi.errors.TcaError` naming each problem. ``lean``: where Newton
        converges on a robot without contact or friction, the answer is its
        :class:`~tca_casadi.solvers.outputs.StepOutputs` (:func:`lean_enough`), not a Solution.
        ``(solution, params)``."""
        problems = self.robot.problems(params)
        if problems:
            raise TcaError("; ".join(problems))
        solver = self.solver()
        solution = None
        params = carried_history(self.robot, np.array(params, float), previous)
        if previous is not None and solver.has_square_system:
            lu, start = solver.square.last_lu, solver.initial_guess(params, previous)
            if start is previous.iterate.w:          # the tangent from the previous point, on its factors
                start = solver.square.predicted(start, previous.parameters, params, lu)
            if lean and lean_enough(self.robot):
                w, status = solver.square.newton(start, params, solver.options.tolerance, lu=lu)
                solver.solve_count += 1
                if status.success:
                    outputs = solver.outputs(w, params)
                    if not _pushing(self.robot, outputs.actuators):
                        outputs.result, outputs.iterate = status, Iterate(solver.method, w=np.asarray(w, float))
                        return outputs, params
                solution = solver.evaluate(w, params, status)
            else:
                solution = solver.solve_newton(params, start, lu=lu)
        elif previous is not None:
            solution = solver.solve(params, previous)
        if solution is None or _needs_continuation(solution):
            cold = self.continue_from_rest(solver, params)
            solution = cold if solution is None else _better(solution, cold)
        record_slides(self.robot, params, solution)
        return solution, params

    def continue_from_rest(self, solver, params, first_step=0.25, min_step=1e-3):
        """Follow ``P(lam) = P_rest + lam (params - P_rest)`` from the reference state (lam = 0,
        exact) to lam = 1: predictor-corrector steps on the collocation NLP (branch jumps
        rejected), warm-started solves for shooting; failed steps are halved down to ``min_step``."""
        started = time.perf_counter()
        target, rest = np.array(params, float), self.robot.rest_parameters(params)
        self.robot.check_clear(rest)
        solution = solver.solve(rest)
        if not solution.converged:
            return solution
        follow = _follow_branch if solver.has_square_system else _warm_steps
        solution, lam, steps, iterations, last_failure = follow(solver, rest, target, solution,
                                                                first_step, min_step)
        if lam < 1.0:
            return self.stalled(solver, solution, rest, target, lam, min_step, last_failure,
                                iterations, time.perf_counter() - started)
        note = f"continuation from the reference state, {steps} steps"
        solution.result = solution.result.noted(note).replace(                # all steps included
            solve_time_s=time.perf_counter() - started, nit=iterations)
        return solution

    def _solve_from(self, solver, params, initial):
        """A warm solve of a robot with contacts: Newton (or IPOPT, ``solver.algorithm: ipopt``)
        from ``initial``, then (a contact that closes or opens on the way is a corner Newton may
        not turn) continuation from ``initial``'s parameters to ``params``, then from the
        reference state when that is clear of every obstacle, IPOPT last."""
        start = initial.parameters
        comparable = initial.converged and start is not None and start.size == params.size
        if self.robot.path_dependent and comparable:
            return self._follow_from(solver, params, initial)
        ipopt = solver.options.algorithm == "ipopt"
        solution = solver.solve_ipopt(params, initial) if ipopt else \
            solver.solve_newton(params, solver.initial_guess(params, initial))
        if _needs_continuation(solution) and comparable:
            follow = _follow_branch(solver, start, params.copy(), initial, 0.25, 1e-3)
            solution = _better(solution, follow[0] if follow[1] == 1.0 else solution)
        if _needs_continuation(solution) and self.robot.is_clear(self.robot.rest_parameters(params)):
            solution = _better(solution, self.continue_from_rest(solver, params))
        if _needs_continuation(solution) and not ipopt:
            solution = _better(solution, solver.solve_ipopt(params, initial))
        return solution

    def _follow_from(self, solver, params, initial):
        """A warm solve of a robot with contact objects: continuation from ``initial``'s
        parameters to ``params`` (friction depends on the path: the whole step first, halved
        where a grasp closes or opens, a jump refused), never a solve from the reference state
        (it would put the objects back where they were placed); stalled when it cannot go on."""
        started = time.perf_counter()
        start, target = initial.parameters.copy(), params.copy()
        solution, lam, steps, iterations, failure = _follow_branch(solver, start, target, initial, 1.0, 1e-4)
        if lam < 1.0:
            return self.stalled(solver, solution, start, target, lam, 1e-4, failure, iterations,
                                time.perf_counter() - started, origin="the previous solution")
        if solver.options.algorithm == "ipopt":          # the path by Newton steps, its end by IPOPT
            polished = solver.solve_ipopt(carried_history(self.robot, params, solution), solution)
            solution = polished if polished.converged else solution
            iterations += polished.iterations
        solution.result = solution.result.noted(f"continuation from the previous solution, {steps} steps").replace(
            solve_time_s=time.perf_counter() - started, nit=iterations)
        return solution

    def stalled(self, solver, reached, rest, target, lam, min_step, last_failure, iterations, elapsed,
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
        return solver.evaluate(reached.iterate.values, target, status)


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
        return walk.point.solution, walk.point.lam, walk.substeps, iterations, failure_text(walk.failure)
    return walk.point.solution, 1.0, walk.substeps, iterations, None


def failure_text(failure):
    """What the last rejected continuation step did."""
    if not failure.trial.converged:
        return failure.trial.message
    if failure.dropped:
        return (f"object {', '.join(map(repr, failure.dropped))} would drop: it jumps {failure.moved * 1e3:.3g} mm "
                "within the smallest step continuation takes (its grasp lets go of it, or it snaps to another "
                "equilibrium); where it lands is not a static result")
    if failure.crossed:
        return ("it converged, but det J changes sign within the step: a fold or a bifurcation "
                f"lies between (sweep the parameter with {flag('--arclength', 'arclength=True')} to follow the branch)")
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


def _pushes(kind, tension_only, tension):
    """Whether an actuator that only pulls (a muscle, not a tendon, not ``tension_only``) pushes:
    a branch where continuation from rest is needed (SPEC section 6)."""
    return kind != "tendon" and not tension_only and tension < 0


def _needs_continuation(solution):
    return (not solution.converged) or any(
        _pushes(a.kind, a.tension_only, a.tension) for a in solution.actuators.values())


def _pushing(robot, actuators):
    """:func:`_pushes` for any of ``robot``'s actuators in ``actuators`` ({key: state with a
    ``tension``}, e.g. a sample's outputs)."""
    return any(_pushes(a.kind, a.tension_only, actuators[a.key].tension) for a in robot.actuators)


def lean_enough(robot):
    """Whether a sample of ``robot`` may be answered by its outputs without a Solution
    (:meth:`SolveStrategy.solve_near`): no obstacles, objects or friction, whose contacts and
    history only a Solution carries."""
    return not robot.obstacles and not robot.bodies and not robot.path_dependent


def _better(first, second):
    """The converged one of two attempts; ``second`` when both or neither converged."""
    if first.converged and not second.converged:
        return first
    return second


__all__ = ["SolveStrategy", "SOLVERS", "failure_text"]

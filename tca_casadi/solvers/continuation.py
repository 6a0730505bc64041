"""Natural-parameter continuation along ``P(lam) = P0 + lam delta`` on the collocation NLP.

Each step predicts along the branch's tangent ``dw/dlam = -J_w^-1 J_P delta`` and corrects by
Newton on the square system, falling back to IPOPT (warm-started) when Newton fails. A step whose
end is inconsistent with the trapezoidal rule on the branch's tangents (more than
``jump_tolerance``: a jump to another branch, as seen on buckling problems when a step spans the
critical load), or where the sign of ``det J_w`` differs (the Jacobian is singular somewhere
between: a fold or a bifurcation), counts as a failed step and is halved. The trapezoid test is
skipped on a step where a tension-only actuator goes slack or taut: the branch has a corner
there.
Used by cold starts (from the unloaded reference state) and by sweeps. :class:`ArclengthFollower`
is the pseudo-arclength variant that follows a branch through folds (``sweep --arclength``).
"""
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..status import SolveStatus


@dataclass
class BranchPoint:
    """An accepted point: ``w`` scaled NLP variables, ``w_rate = dw/dlam`` (or the tangent's
    w part for arclength), ``lam_rate`` (1, or the tangent's lam part)."""
    lam: float
    solution: object
    w: np.ndarray
    w_rate: np.ndarray
    lam_rate: float = 1.0
    linearisation: object = field(default=None, repr=False)
    det_sign: int = 0             # sign of det J_w (0: singular)


@dataclass
class StepFailure:
    """Why the follower stopped: the last trial and its distance from the predictor."""
    trial: object
    jump: float               # the last trial's inconsistency (inf: it did not converge)
    crossed: bool = False     # det J_w changed sign: a fold or bifurcation, or another branch
    dropped: tuple = ()       # contact objects that jump within the step (a grasp lets go of them)
    moved: float = 0.0        # how far the farthest of them jumps [m]


#: a change of the state below this fraction of its size is the solver's noise
NOISE = 1e-9
#: the trapezoid test's error is relative to at least this fraction of the state's size
SMALL_STEP = 1e-5
#: a contact object moving more than this fraction of its largest edge within one step, off
#: the trapezoidal rule on its tangents (:data:`DROP_INCONSISTENCY`), jumps: a grasp let go of
#: it (it would fall) or it snapped to another equilibrium
DROP = 0.05
DROP_INCONSISTENCY = 0.5


class BranchFollower:
    """Follow the branch of ``solver`` (a CollocationSolver) along ``P0 + lam delta``."""

    def __init__(self, solver, P0, delta, jump_tolerance=0.15):
        self.solver = solver
        self.P0, self.delta = path_parameters(solver.robot, P0, delta)
        self.jump_tolerance = float(jump_tolerance)
        self.iterations = 0
        #: the rules of a path with contact objects (None without them)
        self.grasp = GraspPath(solver) if history_indices(solver.robot).size else None

    def params_at(self, lam):
        return self.P0 + lam * self.delta

    def point(self, lam, solution, w=None, tangent=None, linearisation=None):
        """A :class:`BranchPoint` with the linearisation at ``(w, P(lam))`` (``linearisation``:
        one already computed there)."""
        w = solution.iterate.w if w is None else np.asarray(w, float)
        if self.grasp is not None:
            w = self.grasp.anchored(w)
        linear = linearisation or self.solver.linearise(w, self.params_at(lam))
        try:
            sign = linear.determinant_sign()
            rate = linear.state_derivative(self.delta) if tangent is None else tangent[:-1]
        except RuntimeError:                    # singular: exactly at a fold
            sign, rate = 0, (np.zeros_like(w) if tangent is None else tangent[:-1])
        lam_rate = 1.0 if tangent is None else float(tangent[-1])
        return BranchPoint(lam, solution, w, rate, lam_rate, linear, sign)

    #: IPOPT is tried after a failed Newton step only on steps up to this size (lam); a larger
    #: failed step is halved first, which is much cheaper
    IPOPT_STEP = 1.0 / 16
    def step(self, current, lam):
        """Newton from the tangent predictor at ``lam`` (IPOPT, warm-started, if Newton fails
        on a small step; not with contact objects, where a failed small step is a grasp giving
        or a box tipping, which IPOPT does not mend: a stall there took 45 s instead of 2)."""
        predicted = current.w + (lam - current.lam) * current.w_rate
        lu = current.linearisation.lu if current.linearisation is not None else None
        trial = self.solver.solve_newton(self.params_at(lam), predicted, lu=lu, search=False)
        if not trial.converged and lam - current.lam <= self.IPOPT_STEP + 1e-12 and self.grasp is None:
            trial = self.solver.solve_ipopt(self.params_at(lam), current.solution)
        self.iterations += trial.iterations
        return trial

    @staticmethod
    def inconsistency(a, b):
        """How far the step from point ``a`` to ``b`` is from the trapezoidal rule on the
        branch's tangents, ``|w_b - w_a - (lam_b - lam_a)(w'_a + w'_b)/2| / |w_b - w_a|`` (max
        norms). ``O(h^2)`` on one smooth branch; order one for a jump to another branch. A
        change within :data:`NOISE` of ``|w|`` is the solver's noise, not a step (where the
        state does not depend on the parameter, e.g. a fully transformed SMA wire), and the
        error is measured against at least :data:`SMALL_STEP` of ``|w|`` (a jump to another
        branch moves ``w`` by order one; at a law's C1 corner, e.g. where an SMA wire ends
        its transformation, the trapezoid rule is out by order one of an ever smaller step)."""
        change = b.w - a.w
        size = float(np.max(np.abs(change)))
        scale = max(1.0, float(np.max(np.abs(a.w))))
        if size <= NOISE * scale:
            return 0.0
        error = change - 0.5 * (b.lam - a.lam) * (a.w_rate + b.w_rate)
        return float(np.max(np.abs(error))) / max(size, SMALL_STEP * scale)

    def advance(self, current, target, step, max_step, min_step):
        """Step from ``current`` to ``lam = target``, halving failed steps (growing good ones up
        to ``max_step``). Returns ``(point, step, substeps, failure)``; ``failure`` is a
        :class:`StepFailure` when the step fell below ``min_step`` (``point`` is then the last
        accepted one). The steps skip the search for contacts between candidates (the nodes'
        gaps decide the corners); the point returned has it."""
        point, step, substeps, failure = self._advance(current, target, step, max_step, min_step)
        if point is not current and self.solver.robot.obstacles:
            solution = point.solution
            point = replace(point, solution=self.solver.evaluate(solution.iterate.w, solution.parameters,
                                                                 solution.result))
        return point, step, substeps, failure

    def _advance(self, current, target, step, max_step, min_step):
        substeps = 0
        while current.lam < target - 1e-12:
            lam = min(target, current.lam + step)
            trial = self.step(current, lam)
            jump, crossed, dropped, moved = np.inf, False, (), 0.0
            if trial.converged:
                candidate = self.point(lam, trial)
                # where a tension-only actuator goes slack or taut, or a contact closes or opens,
                # the branch has a corner: the tangents on its two sides differ, so the trapezoid
                # test does not apply, and det J may change sign there without a fold (the
                # complementarity's row turns from the force's to the gap's)
                corner = _slack_pattern(current.solution) != _slack_pattern(trial)
                jump = 0.0 if corner else self.inconsistency(current, candidate)
                crossed = not corner and candidate.det_sign * current.det_sign < 0
                if self.grasp is not None:
                    jump, dropped, moved = self.grasp.judged(current, candidate, corner, jump)
                if jump <= self.jump_tolerance and not crossed:
                    if self.grasp is not None:
                        candidate = self.grasp.stuck(self, lam, trial, candidate)
                    current, substeps = candidate, substeps + 1
                    step = self.grasp.next_step(step, corner, max_step) if self.grasp else min(2 * step, max_step)
                    continue
                if self.grasp is not None and corner and not dropped and lam - current.lam > self.grasp.CORNER_STEP:
                    step = self.grasp.CORNER_STEP      # at once, not halving down to it
                    continue
            step /= 2
            if step < min_step:
                return current, step, substeps, StepFailure(trial, jump, crossed, dropped, moved)
        return current, step, substeps, None


@dataclass
class Walk:
    """Where :func:`walk_branch` got to: the last accepted ``point`` (a :class:`BranchPoint`,
    at ``lam = 1`` unless ``failure``), why it stopped short (a :class:`StepFailure`, or None),
    the Newton ``iterations`` of every trial step, the accepted steps (``substeps``) and the
    points at each of the ``targets`` reached (``reached``: ``(lam, Solution)``)."""
    point: BranchPoint
    failure: object
    iterations: int
    substeps: int
    reached: list = field(default_factory=list)

    @property
    def completed(self):
        """Whether the walk reached its last target."""
        return self.failure is None


def path_parameters(robot, P0, delta):
    """``(P0, delta)`` of the straight path ``P0 + lam delta`` as it is followed: the contact
    objects' history (grip anchors) is the target's from the start, then updated after every
    accepted step (a grip that closes on the way sticks from the next step)."""
    P0, delta = np.array(P0, float), np.array(delta, float)
    history = history_indices(robot)
    P0[history] += delta[history]
    delta[history] = 0.0
    return P0, delta


def walk_branch(solver, start, start_params, end_params, *, first_step=None, max_step=1.0, min_step=1e-4,
                linearisation=None, targets=(1.0,), jump_tolerance=0.15, record=None):
    """Follow the branch of ``solver`` (a CollocationSolver) from the Solution ``start`` at the
    parameter vector ``start_params`` along the straight path to ``end_params``
    (:class:`BranchFollower`: tangent predictor, Newton corrector, branch jumps and folds
    rejected, failed steps halved down to ``min_step``; contact objects' grips anchored as they
    close). ``targets``: the values of ``lam`` in (0, 1] to stop at, in order (the last is 1);
    ``first_step``: the first step's size, then doubled on success up to ``max_step`` and
    carried from one target to the next (None: each target's whole way at first);
    ``linearisation``: ``start``'s, if already known; ``record(point, substeps)``: called with
    the start's :class:`BranchPoint` (0 substeps) and each target's, as it is reached. Every
    study, the time simulation and the cold solve follow paths through this one walker.
    Returns a :class:`Walk`."""
    follower = BranchFollower(solver, start_params, np.asarray(end_params, float) - np.asarray(start_params, float),
                              jump_tolerance)
    point = follower.point(0.0, start, linearisation=linearisation)
    if record is not None:
        record(point, 0)
    reached, substeps, step = [], 0, first_step
    for target in targets:
        step = float(target) - point.lam if first_step is None else step
        point, step, taken, failure = follower.advance(point, float(target), step, max_step, min_step)
        substeps += taken
        if failure is not None:
            return Walk(point, failure, follower.iterations, substeps, reached)
        reached.append((float(target), point.solution))
        if record is not None:
            record(point, taken)
    return Walk(point, None, follower.iterations, substeps, reached)


def history_indices(robot):
    """Indices into the parameter vector of a robot's contact-object history (grip anchors and
    support anchors, :mod:`tca_casadi.model.bodies`)."""
    from ..model.history import history_names_of
    return np.array([i for name in history_names_of(robot) for i in range(robot.layout.size)[robot.layout[name]]],
                    int)


class GraspPath:
    """What following a branch means with contact objects (grasped and resting free bodies):
    friction makes the path matter. A grip sticks from where it closed (the history is carried
    after every accepted step, :meth:`stuck`), a step across a contact's corner is taken only
    up to :data:`CORNER_STEP` (no step jumps across a grasp closing), an object that jumps
    within a step has dropped (:meth:`judged`), points are anchored where they are (nothing has
    slipped yet, :meth:`anchored`), and IPOPT is not tried (a failed small step is a grasp giving
    or a box tipping, which it does not mend). The :class:`BranchFollower` asks it; nothing
    else in the follower knows about contact objects."""

    #: a step on which a contact or actuator changes side of its corner is taken only up to
    #: this size (lam)
    CORNER_STEP = 1.0 / 32

    def __init__(self, solver):
        self.solver = solver

    def next_step(self, step, corner, max_step):
        """The step after an accepted one of ``step``: doubled (up to ``max_step``), but kept
        after a step across a corner, where the next corner is likely near (a grip's contact
        moving from node to node along a fingertip): doubling there cost a rejected trial at
        every other step."""
        return step if corner else min(2 * step, max_step)

    def anchored(self, w):
        """``w`` with every grip's slip set to zero: anchored where it is."""
        w = np.array(w, float)
        w[self.solver.nlp.slip_index] = 0.0
        return w

    def judged(self, current, candidate, corner, jump):
        """``(jump, dropped, moved)`` of the step from ``current`` to ``candidate``: the
        trapezoid test's ``jump`` as it applies with contact objects (a step across a corner is
        taken only up to :data:`CORNER_STEP`; on steps up to that size the test is not applied:
        a grip's contact point crossing an edge of the object turns its normal within a step, a
        corner the pattern does not see, not another branch), infinite where an object dropped;
        the names of the objects that dropped and how far the farthest moved [m]."""
        step = candidate.lam - current.lam
        jump = 0.0 if step <= self.CORNER_STEP else (np.inf if corner else jump)
        dropped, moved = self.dropped(current, candidate)
        return (np.inf if dropped else jump), dropped, moved

    def dropped(self, a, b):
        """``(names, moved [m])`` of the contact objects whose position jumps between the
        points ``a`` and ``b``: by more than :data:`DROP` of their size and off the trapezoidal
        rule on their tangents (a kink where a grip or the support closes or opens moves them
        little over a small step; a grasp letting go moves them by their fall however small)."""
        names, moved = [], 0.0
        for body, index in zip(self.solver.robot.bodies, self.solver.nlp.pose_index):
            position = index[0:3]                          # scaled by the body's largest edge
            change = b.w[position] - a.w[position]
            size = float(np.max(np.abs(change)))
            if size <= DROP:
                continue
            error = change - 0.5 * (b.lam - a.lam) * (a.w_rate[position] + b.w_rate[position])
            if float(np.max(np.abs(error))) > DROP_INCONSISTENCY * size:
                names.append(body.name)
                moved = max(moved, float(np.linalg.norm(change)) * body.length_scale)
        return tuple(names), moved

    def stuck(self, follower, lam, trial, candidate):
        """The accepted point with the history carried from it (the grips closed there are
        anchored where they touch): the same state, linearised again if the history changed
        (``follower``'s path start takes the new history)."""
        from ..model.history import carried_history
        carried = carried_history(self.solver.robot, follower.P0, trial)
        if np.array_equal(carried, follower.P0):
            return candidate
        follower.P0 = carried
        return follower.point(lam, trial)


def _slack_pattern(solution):
    """Per ``tension_only`` actuator: slack, at the corner (taut with no tension: an
    unpressurised McKibben muscle, a tendon just taut) or taut; then, per contact candidate,
    which side of its complementarity's corner it is on. The branch has a corner where this
    changes."""
    actuators = tuple("slack" if a.slack else ("corner" if a.at_corner else "taut")
                      for a in solution.actuators.values() if a.tension_only)
    return actuators + tuple(solution.contact_pattern)


class ArclengthFollower:
    """Pseudo-arclength continuation of ``solver`` (a CollocationSolver) along
    ``P(lam) = P0 + lam delta``: ``(w, lam)`` advance together along the unit tangent of the
    bordered system ``[[J_w, J_P delta], [t^T]]``; Newton corrects on
    ``[g(w, P(lam)) = 0, t . (x - x_k) = ds]`` with sparse LU, so the branch is followed through
    folds (turning points in lam), also below the start value (down to half the range below it),
    until it reaches lam = 1."""

    def __init__(self, solver, P0, delta, tolerance):
        self.solver, self.tolerance = solver, tolerance
        self.branch = BranchFollower(solver, P0, delta)
        self.delta = self.branch.delta

    def params_at(self, lam):
        return self.branch.params_at(lam)

    def run(self, first, steps, min_step, max_points, record, where):
        """Follow the branch from ``first`` (a point with ``w``, ``w_rate``, ``solution``) with
        steps of about ``1 / (steps - 1)`` of the range (halved down to ``min_step`` of it) for
        at most ``max_points`` points. ``record(BranchPoint)`` keeps a point and returns what it
        kept (with ``values``); ``where(kept)`` describes a point for messages. Returns
        ``(completed, message)``."""
        tangent = _normalise(np.r_[first.w_rate, 1.0])
        ds = np.linalg.norm(np.r_[first.w_rate, 1.0]) / (steps - 1)
        ds_max, ds_min = 4 * ds, min_step * ds
        current = record(self.branch.point(0.0, first.solution, first.w, tangent))
        count = 1
        while count < max_points:
            corrected = self.correct(current, tangent, ds)
            if corrected is None:
                ds /= 2
                if ds < ds_min:
                    return False, (f"stopped at {where(current)}: the arclength corrector failed down "
                                   f"to a step of {ds_min:.2g}")
                continue
            w, lam, linear, iterations, elapsed = corrected
            tangent = self.tangent(linear, tangent)
            if lam > 1.0 and tangent[-1] > 0:
                return self._land(current, record, count)
            status = SolveStatus.judged("pseudo-arclength corrector", self.solver.max_residual(w, self.params_at(lam)),
                                        self.tolerance, nit=iterations, solve_time_s=elapsed)
            solution = self.solver.evaluate(w, self.params_at(lam), status)
            current, count = record(self.branch.point(lam, solution, w, tangent)), count + 1
            if lam < -0.5:
                return False, ("the branch turned back and left the swept range (below the start "
                               f"by half the range) after a fold; stopped at {where(current)}")
            ds = min(1.5 * ds, ds_max) if iterations <= 3 else ds
        return False, f"stopped after {max_points} points (max_points) before reaching the stop value"

    def _land(self, current, record, count):
        """Land exactly on lam = 1 from the last point before it."""
        final = self.solver.solve(self.params_at(1.0), current.solution)
        if not final.converged:
            return False, f"the last step to the stop value failed: {final.message}"
        tangent = np.r_[current.w_rate, current.lam_rate]
        tangent = self.tangent(self.solver.linearise(final.iterate.w, self.params_at(1.0)), tangent)
        record(self.branch.point(1.0, final, tangent=tangent))
        return True, f"reached the stop value in {count + 1} points (pseudo-arclength)"

    def correct(self, current, tangent, ds, max_iterations=12):
        """Newton on ``[g(w, P(lam)); t . ((w, lam) - (w_k, lam_k)) - ds]`` from the predictor.
        Returns ``(w, lam, linearisation, iterations, seconds)`` or None."""
        started = time.perf_counter()
        x = np.r_[current.w, current.lam] + ds * tangent
        anchor = np.r_[current.w, current.lam]
        square = self.solver.square
        for iteration in range(max_iterations + 1):
            g, J_w = square.evaluate(x[:-1], self.params_at(x[-1]))
            arc = tangent @ (x - anchor) - ds
            if np.max(np.abs(g)) <= self.tolerance and abs(arc) <= self.tolerance:
                if np.max(np.abs(x - anchor - ds * tangent)) > 0.5 * ds:      # left the branch
                    return None
                linear = self.solver.linearise(x[:-1], self.params_at(x[-1]))
                return x[:-1], x[-1], linear, iteration, time.perf_counter() - started
            if iteration == max_iterations:
                return None
            step = solve_bordered(J_w, self._lam_column(x), tangent, np.r_[g, arc])
            if step is None or not np.all(np.isfinite(step)) or np.max(np.abs(step)) > 10:
                return None
            x = x - step
        return None

    def _lam_column(self, x):
        """``dg/dlam = J_P delta`` at ``x = (w, lam)``."""
        return self.solver.square.parameter_rates(x[:-1], self.params_at(x[-1]), self.delta.reshape(-1, 1))[:, 0]

    def tangent(self, linear, previous):
        """Unit tangent of the branch at a point, oriented along ``previous``."""
        rhs = np.zeros(previous.size)
        rhs[-1] = 1.0
        tangent = solve_bordered(linear.J_w, linear.parameter_rates(self.delta), previous, rhs)
        if tangent is None:
            return previous
        return _normalise(tangent)


def solve_bordered(J_w, column, border, rhs):
    """Solve ``[[J_w, column], [border^T]] x = rhs`` (sparse LU); None if singular."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    column = sp.csc_matrix(np.asarray(column, float).reshape(-1, 1))
    matrix = sp.bmat([[J_w, column], [sp.csr_matrix(border[:-1].reshape(1, -1)),
                                      sp.csr_matrix(border[-1:].reshape(1, 1))]], format="csc")
    try:
        return spla.splu(matrix).solve(np.asarray(rhs, float))
    except RuntimeError:
        return None


def _normalise(vector):
    return vector / np.linalg.norm(vector)

"""Natural-parameter continuation along ``P(lam) = P0 + lam delta`` on the collocation NLP.

Each step predicts along the branch's tangent ``dw/dlam = -J_w^-1 J_P delta`` and corrects by
Newton on the square system, falling back to IPOPT (warm-started) when Newton fails. A step whose
end is inconsistent with the trapezoidal rule on the branch's tangents (more than
``jump_tolerance``: a jump to another branch, as seen on buckling problems when a step spans the
critical load), or where the sign of ``det J_w`` differs (the Jacobian is singular somewhere
between: a fold or a bifurcation), counts as a failed step and is halved. The trapezoid test is
skipped on a step where a tension-only actuator goes slack or taut: the branch has a corner
there.
Used by cold starts (from the unloaded reference state) and by sweeps.
"""
from dataclasses import dataclass, field

import numpy as np


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


class BranchFollower:
    """Follow the branch of ``solver`` (a CollocationSolver) along ``P0 + lam delta``."""

    def __init__(self, solver, P0, delta, jump_tolerance=0.15):
        self.solver, self.P0, self.delta = solver, np.asarray(P0, float), np.asarray(delta, float)
        self.jump_tolerance = float(jump_tolerance)
        self.iterations = 0

    def params_at(self, lam):
        return self.P0 + lam * self.delta

    def point(self, lam, solution, w=None, tangent=None):
        """A :class:`BranchPoint` with the linearisation at ``(w, P(lam))``."""
        w = solution.raw["w"] if w is None else np.asarray(w, float)
        linear = self.solver.linearise(w, self.params_at(lam))
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
        on a small step)."""
        predicted = current.w + (lam - current.lam) * current.w_rate
        trial = self.solver.solve_newton(self.params_at(lam), predicted)
        if not trial.converged and lam - current.lam <= self.IPOPT_STEP + 1e-12:
            trial = self.solver.solve_ipopt(self.params_at(lam), current.solution)
        self.iterations += trial.iterations
        return trial

    @staticmethod
    def inconsistency(a, b):
        """How far the step from point ``a`` to ``b`` is from the trapezoidal rule on the
        branch's tangents, ``|w_b - w_a - (lam_b - lam_a)(w'_a + w'_b)/2| / |w_b - w_a|`` (max
        norms). ``O(h^2)`` on one smooth branch; order one for a jump to another branch."""
        change = b.w - a.w
        size = float(np.max(np.abs(change)))
        if size == 0.0:
            return 0.0
        error = change - 0.5 * (b.lam - a.lam) * (a.w_rate + b.w_rate)
        return float(np.max(np.abs(error))) / size

    def advance(self, current, target, step, max_step, min_step):
        """Step from ``current`` to ``lam = target``, halving failed steps (growing good ones up
        to ``max_step``). Returns ``(point, step, substeps, failure)``; ``failure`` is a
        :class:`StepFailure` when the step fell below ``min_step`` (``point`` is then the last
        accepted one)."""
        substeps = 0
        while current.lam < target - 1e-12:
            lam = min(target, current.lam + step)
            trial = self.step(current, lam)
            jump, crossed = np.inf, False
            if trial.converged:
                candidate = self.point(lam, trial)
                # where a tension-only actuator goes slack or taut the branch has a corner: the
                # tangents on its two sides differ, so the trapezoid test does not apply
                corner = _slack_pattern(current.solution) != _slack_pattern(trial)
                jump = 0.0 if corner else self.inconsistency(current, candidate)
                crossed = candidate.det_sign * current.det_sign < 0
                if jump <= self.jump_tolerance and not crossed:
                    current, substeps = candidate, substeps + 1
                    step = min(2 * step, max_step)
                    continue
            step /= 2
            if step < min_step:
                return current, step, substeps, StepFailure(trial, jump, crossed)
        return current, step, substeps, None


def _slack_pattern(solution):
    return tuple(a.slack for a in solution.actuators.values() if a.tension_only)

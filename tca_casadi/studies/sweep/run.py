"""Continuation over parameters: the paper's Algorithm 1 as a study (``tca-casadi sweep``).

Several scalar parameters move together along ``P(lam) = P_start + lam (P_stop - P_start)``,
``lam`` from 0 to 1, on the collocation NLP built once.

* **Natural continuation** (default): ``lam`` on a uniform grid; each step predicts along the
  branch's tangent and corrects by Newton on the square system (IPOPT, warm-started, if Newton
  fails). A step that fails, or whose end is inconsistent with the branch's tangents (a jump to
  another branch, see :mod:`tca_casadi.solvers.continuation`), is halved, down to ``min_step``. Where no step succeeds the run stops and says why (near a fold the Jacobian
  becomes singular: it says so).
* **Pseudo-arclength** (``arclength=True``): ``(w, lam)`` advance together along the branch's
  tangent; Newton corrects on the bordered system ``[g(w, P(lam)) = 0, t . (x - x_k) = ds]``
  with sparse LU, so the branch is followed through folds (turning points in ``lam``), also
  below the start value (down to half the range below it), until it reaches the stop value.

Every accepted row carries the tip's derivative with respect to each swept parameter, from the
implicit function theorem on CasADi's exact Jacobians: ``dtip/dv = T_w (-J_w^-1 J_P d) + T_P d``.
"""
import logging
import time
from dataclasses import dataclass, field

import numpy as np

from ...errors import ScenarioError, flag
from ...solvers.continuation import ArclengthFollower, path_parameters, walk_branch
from ..parameters import check_range, resolve_parameters, shown_as_given
from .result import SweepResult, find_events

log = logging.getLogger(__name__)


@dataclass
class SweepPoint:
    """One accepted point of the branch (``w`` scaled NLP variables)."""
    lam: float
    values: np.ndarray            # (k,) swept parameter values
    solution: object              # Solution
    w: np.ndarray
    w_rate: np.ndarray            # dw/dlam (natural) or the tangent's w part (arclength)
    lam_rate: float               # 1 (natural) or the tangent's lam part (arclength)
    tip_derivative: np.ndarray    # (3, k) d tip / d value_j [m per unit]
    det_sign: int
    sigma_min: float
    substeps: int = 1
    #: the point's linearisation, kept on the newest point only (its LU starts the next step)
    linearisation: object = field(default=None, repr=False)


class Sweep:
    """Move ``paths`` together from ``start`` to ``stop`` (scalars, or one per path; numbers in
    the parameter's unit or strings with units) in ``steps`` points.

    >>> result = Sweep(sim, ["bending.tca2.temperature", "bending.tca3.temperature"],
    ...                25, 125, steps=51).run()
    """

    def __init__(self, sim, paths, start, stop, steps=51, arclength=False, min_step=1e-4,
                 max_points=None, jump_tolerance=0.15):
        if isinstance(paths, str):
            paths = [paths]
        if not paths:
            raise ScenarioError(f"a sweep needs at least one parameter ({flag('--param')} PATH)")
        if int(steps) < 2:
            raise ScenarioError(f"a sweep needs at least 2 steps, got {steps}")
        self.sim, self.steps, self.arclength = sim, int(steps), bool(arclength)
        self.min_step = float(min_step)
        self.max_points = int(max_points or 20 * self.steps)
        self.solver = sim.solver("collocation")
        self.parameters = resolve_parameters(sim.robot, sim.params, list(paths))
        self.start = self._values(start, "start")
        self.stop = self._values(stop, "stop")
        self.parameters = [shown_as_given(p, sim.scenario, a, b, values=[lo, hi]) for p, a, b, lo, hi in
                           zip(self.parameters, self._given(start), self._given(stop), self.start, self.stop)]
        for parameter, a, b in zip(self.parameters, self.start, self.stop):
            check_range(sim.robot, parameter, a, b, params=sim.params)
        base = sim.params.copy()
        for parameter, value in zip(self.parameters, self.start):
            base = parameter.with_value(base, value)
        self.P_start = base
        self.delta = sum(p.vector(base.size) * (b - a)
                         for p, a, b in zip(self.parameters, self.start, self.stop))
        self.directions = np.column_stack([p.vector(base.size) for p in self.parameters])
        if not np.any(self.delta):
            raise ScenarioError("the sweep's start and stop values are equal: nothing moves")
        self.tolerance = sim.scenario.solver.tolerance
        self.jump_tolerance = jump_tolerance
        self._path = path_parameters(self.solver.robot, self.P_start, self.delta)

    def _given(self, given):
        given = list(given) if isinstance(given, (list, tuple, np.ndarray)) else [given]
        return given * len(self.parameters) if len(given) == 1 else given

    def _values(self, given, what):
        given = self._given(given)
        if len(given) != len(self.parameters):
            raise ScenarioError(f"{len(given)} {what} values for {len(self.parameters)} parameters")
        return np.array([p.to_si(v, f"the {what} value") for p, v in zip(self.parameters, given)])

    def params_at(self, lam):
        """The parameter vector at ``lam`` of the swept path (grip anchors: the stop's)."""
        P0, delta = self._path
        return P0 + lam * delta

    def values_at(self, lam):
        return self.start + lam * (self.stop - self.start)

    # ------------------------------------------------------------------ running
    def run(self, progress=None):
        """Run the sweep; ``progress(fraction, text)`` is called after every accepted point.
        Returns a :class:`SweepResult` (``completed`` False, with the reason, if it stopped)."""
        started = time.perf_counter()
        first = self.sim.solve_at(self.P_start, method="collocation")
        if not first.converged:
            return self._result([], False, f"no equilibrium at the start: {first.message}", started)
        if self.arclength:
            completed, message = self._arclength(first, progress)
        else:
            completed, message = self._natural(first, progress)
        return self._result(self.points, completed, message, started)

    def _result(self, points, completed, message, started):
        return SweepResult(self.parameters, points, find_events(self.sim.robot, points, self.parameters),
                           completed, message, "arclength" if self.arclength else "natural",
                           time.perf_counter() - started)

    # ------------------------------------------------------------------ one point
    def _record(self, branch_point, substeps=1):
        """A :class:`SweepPoint`: sensitivities and fold indicators from the point's linearisation."""
        linear, lam = branch_point.linearisation, branch_point.lam
        try:
            tip_derivative = linear.tip_derivative(self.directions)
            det_sign, sigma = linear.determinant_sign(), linear.smallest_singular_value()
        except RuntimeError:                       # exactly singular: exactly at a fold
            tip_derivative = np.full((3, len(self.parameters)), np.nan)
            det_sign, sigma = 0, 0.0
        return SweepPoint(lam, self.values_at(lam), branch_point.solution, branch_point.w,
                          branch_point.w_rate, branch_point.lam_rate, tip_derivative, det_sign,
                          sigma, substeps, branch_point.linearisation)

    # ------------------------------------------------------------------ natural continuation
    def _natural(self, first, progress):
        spacing = 1.0 / (self.steps - 1)
        self.points = []

        def record(branch_point, substeps):
            if self.points:
                self.points[-1].linearisation = None         # only the newest point keeps its LU
            self.points.append(self._record(branch_point, max(substeps, 1)))
            _report(progress, self.points[-1], self)

        walk = walk_branch(self.solver, first, self.P_start, self.P_start + self.delta, first_step=spacing,
                           max_step=spacing, min_step=self.min_step, targets=spacing * np.arange(1, self.steps),
                           jump_tolerance=self.jump_tolerance, record=record)
        if not walk.completed:                          # the last point is the last accepted one
            return False, self._stalled(self.points[0], self.points[-1], walk.failure)
        return True, f"completed {self.steps} steps"

    def _stalled(self, first, last, failure):
        where = _describe(self.parameters, last.values)
        text = (f"stopped at {where}: no converged step down to a step of {self.min_step:g} "
                f"of the range")
        start_rate = np.max(np.abs(first.w_rate))
        rate = np.max(np.abs(last.w_rate)) / start_rate if start_rate > 0 else 1.0
        sigma = last.sigma_min / max(first.sigma_min, 1e-300)
        if failure.crossed or sigma < 0.1 or rate > 10:
            return (f"{text}. The Jacobian is (nearly) singular there (smallest singular value "
                    f"{last.sigma_min:.2e}, {sigma:.2g} x its value at the start; the branch's "
                    f"rate of change {rate:.3g} x"
                    + ("; its determinant changes sign within the step" if failure.crossed else "")
                    + f"): a fold (turning point) or a bifurcation. {flag('--arclength', 'arclength=True')} "
                      "follows the branch around a fold")
        if failure.trial.converged:
            return (f"{text}: the solver converged only off the branch (a jump to another branch; "
                    f"inconsistency with the branch's tangents {failure.jump:.2g})")
        return f"{text}: {failure.trial.message}"

    # ------------------------------------------------------------------ pseudo-arclength
    def _arclength(self, first, progress):
        follower = ArclengthFollower(self.solver, self.P_start, self.delta, self.tolerance)
        self.points = []

        def record(branch_point):
            self.points.append(self._record(branch_point))
            _report(progress, self.points[-1], self)
            return self.points[-1]

        start = self._record(follower.branch.point(0.0, first))
        return follower.run(start, self.steps, self.min_step, self.max_points, record,
                            lambda point: _describe(self.parameters, point.values))


def _describe(parameters, values):
    return ", ".join(p.describe(v) for p, v in zip(parameters, values))


def _report(progress, point, sweep):
    if progress is not None:
        progress(min(max(point.lam, 0.0), 1.0), _describe(sweep.parameters[:1], point.values[:1]))

"""Accuracy under control: an error estimate for a collocation solution, and refinement of the
intervals that carry the error until the tip and the tensions meet their tolerances.

**Estimate.** The same robot on the same mesh at degree ``d + 1`` is solved by Newton from the
degree-``d`` solution interpolated onto its nodes (two or three iterations). The higher degree
is far more accurate (the tip converges at order ``2d``), so the differences estimate the
degree-``d`` errors:

    tip error      = |p_tip(d+1) - p_tip(d)|                               [m]
    tension error  = max_k |F_k(d+1) - F_k(d)| / max(max_k |F_k|, 1 mN)    [-]

The solution's global balance residual (:mod:`tca_casadi.model.balance`) must also be at most
``BALANCE_TOLERANCE`` (1e-6 of the forces in play).

**Where.** Each interval gets a share of every unmet tolerance: the position difference it adds
(the change, across it, of ``p(d+1) - p(d)``) per tip tolerance, and, for each actuator, the
fraction of its path-length difference that falls in the interval times its tension error per
tension tolerance. Intervals with a share ``>= FLAG_FRACTION`` of the largest are bisected (every interval, when the last round did not
halve the largest estimate-to-tolerance ratio: the error then comes from where the indicator
does not point); the solution is carried onto the new mesh by interpolation and corrected by
Newton; repeat until both estimates meet their tolerances, or the
mesh reaches ``solver.max_intervals`` per module (a warning), or ``MAX_ROUNDS``.
"""
from dataclasses import dataclass, field

import numpy as np

from ..errors import PhysicsWarning
from .assemble import BALANCE_TOLERANCE

#: intervals whose indicator is at least this fraction of the largest are bisected
FLAG_FRACTION = 0.3
#: refinement rounds at most
MAX_ROUNDS = 8
#: tension differences are relative to the largest tension, but at least this [N]
TENSION_FLOOR = 1e-3


@dataclass
class AccuracyEstimate:
    """Estimated errors of a solution, the mesh it was found on, and how it was reached."""
    tip_error: float                 # [m]
    tension_error: float             # relative to the largest tension
    tip_tolerance: float
    tension_tolerance: float
    intervals: list = field(default_factory=list)     # per module
    refinements: int = 0
    limit_reached: bool = False
    balance: float = 0.0             # global balance residual, relative (model.balance)
    balance_tolerance: float = BALANCE_TOLERANCE

    @property
    def met(self):
        return (self.tip_error <= self.tip_tolerance and self.tension_error <= self.tension_tolerance
                and self.balance <= self.balance_tolerance)

    @property
    def excess(self):
        """The largest ratio of an estimate to its tolerance (met when at most 1)."""
        return max(self.tip_error / self.tip_tolerance, self.tension_error / self.tension_tolerance,
                   self.balance / self.balance_tolerance)

    def as_dict(self):
        return {"tip_error_estimate": self.tip_error, "tension_error_estimate": self.tension_error,
                "tip_tolerance": self.tip_tolerance, "tension_tolerance": self.tension_tolerance,
                "global_balance": self.balance, "balance_tolerance": self.balance_tolerance,
                "met": self.met, "intervals": list(self.intervals), "refinements": self.refinements,
                "mesh_limit_reached": self.limit_reached}

    def summary(self):
        state = "met" if self.met else "NOT met"
        return (f"accuracy {state}: tip error ~{self.tip_error:.1e} m (tolerance {self.tip_tolerance:.0e}), "
                f"tensions ~{self.tension_error:.1e} (tolerance {self.tension_tolerance:.0e}), "
                f"global balance {self.balance:.1e} (tolerance {self.balance_tolerance:.0e}); "
                f"{'+'.join(map(str, self.intervals))} intervals after {self.refinements} refinement(s)")


def interpolate(source, w, target, params):
    """Scaled variables of NLP ``target`` from the solution ``w`` of NLP ``source`` (same robot,
    or with contact candidates added; each target interval inside one source interval): the
    states' polynomials evaluated at the target's nodes, the tensions and the contact forces
    copied (a new candidate starts with none), the partial lengths recomputed."""
    out = np.zeros(target.scale.size)
    physical = np.asarray(w, float) * source.scale
    for m in range(len(source.meshes)):
        src_nodes = physical[source.state_index[m]]                  # (n_src, 13, d_src + 1)
        src_intervals = np.array(source.meshes[m].intervals)
        tgt_s = target.node_s(m)                                     # (n_tgt, d_tgt + 1)
        middles = tgt_s.mean(axis=1)
        owner = np.searchsorted(src_intervals[:, 1], middles)        # source interval of each target one
        owner = np.minimum(owner, len(src_intervals) - 1)
        s0, s1 = src_intervals[owner, 0], src_intervals[owner, 1]
        local = (tgt_s - s0[:, None]) / (s1 - s0)[:, None]           # (n_tgt, d_tgt + 1)
        basis = lagrange_basis(source.scheme.tau, local)                  # (n_tgt, d_tgt + 1, d_src + 1)
        values = np.einsum("tjr,tkr->tkj", basis, src_nodes[owner])  # (n_tgt, 13, d_tgt + 1)
        out[target.state_index[m]] = values
    out[target.tension_index] = physical[source.tension_index]
    forces = {(c.module, c.s, c.obstacle): physical[source.contact_index[c.index]] for c in source.robot.contacts}
    for c in target.robot.contacts:        # the same candidates, or (localisation) some added
        out[target.contact_index[c.index]] = forces.get((c.module, c.s, c.obstacle), 0.0)
    frictions = {(c.module, c.s, c.obstacle): physical[source.friction_index[c.index]]
                 for c in source.robot.contacts if c.index in source.friction_index}
    for c in target.robot.contacts:        # against obstacles with friction: f_t, slip
        if c.index in target.friction_index:
            out[target.friction_index[c.index]] = frictions.get((c.module, c.s, c.obstacle), 0.0)
    out[target.body_index] = physical[source.body_index]     # free bodies: grips, poses, supports
    out = out / target.scale
    partial = np.concatenate(target.partial_index) if target.partial_index else np.zeros(0, int)
    out[partial] = np.array(target.partials(out, params)).ravel()
    return out


def lagrange_basis(nodes, points):
    """Lagrange basis on ``nodes`` (k,) evaluated at ``points`` (..., ): shape (..., k)."""
    points = np.asarray(points)[..., None]
    out = np.ones(points.shape[:-1] + (nodes.size,))
    for j, node in enumerate(nodes):
        others = np.delete(nodes, j)
        out[..., j] = np.prod((points - others) / (node - others), axis=-1)
    return out


def estimate(solver, solution, params, higher):
    """``(tip error, tension error, indicators)`` of ``solution`` (by ``solver``, a
    CollocationSolver) against ``higher`` (the same meshes at degree d + 1); None if the
    higher-degree Newton solve fails. ``indicators`` (:class:`Indicators`) say where the
    differences arise."""
    w0 = interpolate(solver.nlp, solution.iterate.w, higher.nlp, params)
    better = higher.solve_newton(params, w0)
    if not better.converged:
        return None
    tip = float(np.linalg.norm(better.tip_position - solution.tip_position))
    tensions = np.array([a.tension for a in solution.actuators.values()])
    better_tensions = np.array([a.tension for a in better.actuators.values()])
    floor = max(float(np.max(np.abs(tensions), initial=0.0)), TENSION_FLOOR)
    errors = np.abs(better_tensions - tensions) / floor                 # per actuator, robot order
    indicators = Indicators(solver.nlp, solution.iterate.w, higher.nlp, better.iterate.w, errors)
    return tip, float(np.max(errors, initial=0.0)), indicators


class Indicators:
    """Where the two solutions' differences arise, per module and interval: the position
    difference each interval adds [m], and its share of each actuator's tension error (by the
    actuator's path-length difference over the interval)."""

    def __init__(self, nlp, w, higher, w_higher, tension_errors):
        self.position, self.tension = [], []
        robot = nlp.robot
        for m, module in enumerate(robot.modules):
            low, high = _interval_ends(nlp, w, m), _interval_ends(higher, w_higher, m)
            difference = high[:, :, 0:3] - low[:, :, 0:3]                    # (n_int, 2, 3)
            self.position.append(np.linalg.norm(difference[:, 1] - difference[:, 0], axis=1))
            length = np.abs(_partials(higher, w_higher, m) - _partials(nlp, w, m))   # (nA, n_int)
            error = np.array([tension_errors[robot.actuators.index(a)] for a in module.actuators])
            share = length / np.maximum(length.sum(axis=1, keepdims=True), 1e-300) * error[:, None]
            self.tension.append(share.max(axis=0) if module.actuators else np.zeros(length.shape[1]))

    def flags(self, found):
        """Intervals to bisect: those carrying at least ``FLAG_FRACTION`` of the largest share of
        an unmet tolerance: the position difference they add per tip tolerance, and their share
        of each actuator's tension error per tension tolerance (where only the balance is unmet,
        the position difference alone)."""
        tip_unmet = found.tip_error > found.tip_tolerance
        tension_unmet = found.tension_error > found.tension_tolerance
        shares = []
        for position, tension in zip(self.position, self.tension):
            share = position / found.tip_tolerance if tip_unmet or not tension_unmet else 0 * position
            if tension_unmet:
                share = np.maximum(share, tension / found.tension_tolerance)
            shares.append(share)
        largest = max((float(np.max(s)) for s in shares if s.size), default=0.0)
        return [s >= FLAG_FRACTION * largest if largest > 0 else np.zeros(s.size, bool) for s in shares]


def _partials(nlp, w, m):
    """(nA, n_int) partial path lengths [m] of module m's actuators over each interval."""
    module = nlp.robot.modules[m]
    if not module.actuators:
        return np.zeros((0, len(nlp.meshes[m].intervals)))
    running = (np.asarray(w, float)[nlp.partial_index[m]] * module.length).reshape(len(module.actuators), -1, order="F")
    return np.diff(running, axis=1, prepend=0.0)


def _interval_ends(nlp, w, m):
    """(n_int, 2, 13) physical deviation states at the start and end of every interval."""
    nodes = (np.asarray(w, float) * nlp.scale)[nlp.state_index[m]]      # (n_int, 13, d+1)
    end = np.einsum("kr,r->k", nodes.reshape(-1, nodes.shape[-1]), nlp.scheme.D).reshape(nodes.shape[:2])
    return np.stack([nodes[:, :, 0], end], axis=1)


def control(solver, solution, params, refine=True):
    """Estimate the accuracy of ``solution`` (by the CollocationSolver ``solver``) and, with
    ``refine`` (and ``solver.refine: auto``), bisect the intervals that carry the error until
    the estimate meets the tolerances. Returns ``(solver, solution, estimate)``: the solver of
    the final mesh (a new one when refined), its solution (with ``accuracy`` set and a warning
    when a tolerance is not met), the :class:`AccuracyEstimate` (None if unavailable)."""
    options, refinements, previous = solver.options, 0, None
    while True:
        result = estimate(solver, solution, params, solver.higher)
        if result is None:
            solution.warnings.append(PhysicsWarning(
                "accuracy", "no error estimate: the degree d+1 solve on the same mesh did not converge"))
            return solver, solution, None
        tip, tension, indicators = result
        found = AccuracyEstimate(tip, tension, options.tip_tolerance, options.tension_tolerance,
                                 [len(mesh.intervals) for mesh in solver.nlp.meshes], refinements,
                                 balance=solution.balance.relative)
        flags = indicators.flags(found)
        if previous is not None and found.excess > 0.5 * previous.excess:
            flags = [np.ones(f.size, bool) for f in flags]      # no progress where flagged: everywhere
        meshes = [mesh.bisected(f) for mesh, f in zip(solver.nlp.meshes, flags)]
        found.limit_reached = not found.met and any(len(m.intervals) > options.max_intervals for m in meshes)
        if found.met or not refine or options.refine == "off" or refinements >= MAX_ROUNDS or found.limit_reached:
            return solver, _attach(solution, found, refine and options.refine == "auto"), found
        finer = solver.finer(meshes)
        trial = finer.solve_newton(params, interpolate(solver.nlp, solution.iterate.w, finer.nlp, params))
        if not trial.converged:
            return solver, _attach(solution, found, True), found
        trial.result = solution.result.noted(f"mesh refined where the error was, Newton on the finer mesh "
                                             f"({refinements + 1}x)").replace(
            residual=trial.result.residual, nit=trial.iterations + solution.iterations,
            solve_time_s=trial.solve_time_s + solution.solve_time_s)
        solver.release_higher()                      # this mesh is left behind: its estimate is done
        if refinements:                              # an intermediate mesh: no solve starts on it again
            solver.release()
        solver, solution, refinements, previous = finer, trial, refinements + 1, found


def _attach(solution, found, refined):
    solution.accuracy = found
    if not found.met:
        why = ("the mesh limit was reached: raise solver.max_intervals" if found.limit_reached else
               "refinement is off (solver.refine)" if not refined else f"after {found.refinements} refinements")
        kind = "mesh_limit" if found.limit_reached else "accuracy"
        solution.warnings.append(PhysicsWarning(kind, f"{found.summary()}: {why}"))
    return solution

"""Localising contacts between candidates (issue 17, ``docs/contact.md`` section 3).

Contact is enforced at fixed candidate points. A point contact that falls between two of them
(a rod pressed by a ball) lets the body cut into the shape there; after a solve, the gap is
sampled finely along every module (the collocation polynomials) and, where the body cuts
deeper than ``contact.tolerance``, a candidate is added at the deepest point and the robot is
solved again: a structure change (a rebuilt NLP on the old mesh split there), warm-started from
the last answer, until no point penetrates or ``contact.localise`` rounds are spent. Later
rounds move the candidate they added (secant steps towards the point where the dip sits on the
candidate: there the gap is smallest and zero, ``g' = 0``), so the mesh keeps no needlessly
short intervals.
"""
import logging

import numpy as np

from ..discretisation.mesh import ModuleMesh
from ..model import Robot
from ..solution import Iterate
from . import accuracy
from .collocation import CollocationSolver

log = logging.getLogger(__name__)

#: a new candidate closer than this fraction of the module's length to a breakpoint is not added
#: (the remaining penetration, second order in that distance, is reported instead)
NEAREST = 1e-6
#: a moved candidate has settled when the next secant step is shorter than this fraction of L
SETTLED = 1e-7


def localise(strategy, solver, solution, params):
    """``(robot, solver, solution)``: ``solution`` (converged, by ``solver``, a
    CollocationSolver of ``strategy.robot``, at the parameter vector ``params``) with candidates
    added until no point of any rod penetrates an obstacle and each added one sits where the
    gap's slope vanishes, and the robot with those candidates. Returns the inputs unchanged
    when nothing needs adding or a new solve fails (its penetration warning stays).
    ``strategy``: the :class:`~tca_casadi.solvers.strategy.SolveStrategy` (its scenario, and
    its continuation from rest where a new candidate's solve needs it)."""
    scenario, robot, history = strategy.scenario, strategy.robot, {}
    for _ in range(scenario.contact.localise):
        added = _added_points(robot, solver.nlp.meshes, solution, history,
                              _slope_of(solver, solution.iterate.w, robot.at(params)))
        if added is None:
            break
        moved = Robot.from_scenario(scenario, added)
        meshes = [_split(mesh, robot.added_contacts.get(m, ()), added.get(m, ()))
                  for m, mesh in enumerate(solver.nlp.meshes)]
        candidate = CollocationSolver.shared(moved, scenario.solver, moved.structure_key(scenario), meshes,
                                             solver.degree)
        w0 = accuracy.interpolate(solver.nlp, solution.iterate.w, candidate.nlp, params)
        trial = candidate.solve_newton(params, w0, semismooth=True)
        if not trial.converged:
            trial = candidate.solve_ipopt(params, _warm(trial, w0))
        if not trial.converged:            # a contact far from the last one: from the reference state
            trial = strategy.continue_from_rest(candidate, params)
        if not trial.converged:
            log.info("contact localisation: the solve with candidates %s failed (%s)", added, trial.message)
            break
        log.info("contact localisation: candidates %s, penetration %.2e m", added, trial.penetration)
        robot, solver, solution = moved, candidate, trial
    return robot, solver, solution



def _slope_of(solver, w, placed):
    """``slope(m, name, s)``: d gap / d s [-] of module m against obstacle ``name`` at s, a
    central difference on the collocation polynomials either side of s (``placed``: the robot
    at the solve's parameters)."""
    from ..model.contact import gaps, outline_of
    shapes = {shape.name: shape for shape in placed.obstacles}

    def slope(m, name, s):
        module = placed.modules[m]
        step = 1e-7 * module.length
        ahead, behind = gaps(shapes[name], outline_of(module), *solver._poses_at(w, m, [s + step, s - step]))
        return (ahead - behind) / (2 * step)
    return slope


def _warm(trial, w0):
    """A Solution-like warm start from scaled variables ``w0`` for IPOPT."""
    return type("Warm", (), {"iterate": Iterate("collocation", w=np.asarray(w0, float))})()


def _added_points(robot, meshes, solution, history, slope):
    """``{module index: [s, ...]}``: the candidates localisation keeps with each obstacle's
    dip handled, or None when nothing moves. Where the body cuts an obstacle at ``s_d`` and no
    candidate added earlier bounds the mesh interval there, one is added at ``s_d``. An added
    candidate bounding that interval is moved: to ``s_d`` at first, then by secant steps on the
    gap's slope at the candidate (``slope(m, obstacle name, s)``, zero at the true contact
    point, where the dip sits on the candidate; ``history[(m, name)]`` the last ``(s, slope)``)
    until it moves by less than :data:`SETTLED` of the module's length."""
    added = {m: list(points) for m, points in robot.added_contacts.items()}
    names = [module.name for module in robot.modules]
    new = False
    obstacles = {shape.name for shape in robot.obstacles}
    for name, nearest in solution.clearance.items():
        if name not in obstacles:          # a free body: its grips are fixed candidates
            continue
        m, s_d = names.index(nearest["module"]), nearest["s"]
        penetrated, length = nearest["gap"] < -robot.contact_tolerance, robot.modules[m].length
        points = added.setdefault(m, [])
        a, b = next((a, b) for a, b in meshes[m].intervals if a - 1e-15 <= s_d <= b + 1e-15)
        moving = [p for p in points if abs(p - a) <= 1e-15 or abs(p - b) <= 1e-15]
        if moving:
            s_c = min(moving, key=lambda p: abs(p - s_d))
            slope_c, previous = slope(m, name, s_c), history.get((m, name))
            history[(m, name)] = (s_c, slope_c)
            target = s_d if penetrated else None
            if previous is not None and previous[0] != s_c and slope_c != previous[1]:
                target = s_c - slope_c * (s_c - previous[0]) / (slope_c - previous[1])
                target = min(max(target, a - (b - a)), b + (b - a))
            if target is None or abs(target - s_c) < SETTLED * length:
                continue
            points.remove(s_c)
        elif penetrated:
            target = s_d
        else:
            continue
        fixed = set(meshes[m].breakpoints) - set(robot.added_contacts.get(m, ()))
        if min(abs(target - p) for p in fixed) < NEAREST * length or not 0.0 < target < length:
            continue
        points.append(float(target))
        new = True
    return added if new else None


def _split(mesh, old, new):
    """``mesh`` with the breakpoints ``old`` removed (their two intervals merged) and cut at the
    points ``new``."""
    cuts = sorted({b for a, b in mesh.intervals[:-1] if not any(abs(b - p) <= 1e-15 for p in old)} | set(new))
    edges = [0.0] + [c for c in cuts if 0.0 < c < mesh.length] + [mesh.length]
    pieces = tuple((float(a), float(b)) for a, b in zip(edges[:-1], edges[1:]) if b > a)
    breakpoints = tuple(sorted((set(mesh.breakpoints) - set(old)) | set(new)))
    return ModuleMesh(mesh.length, breakpoints, pieces)


__all__ = ["localise"]

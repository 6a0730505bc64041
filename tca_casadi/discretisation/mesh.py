"""Collocation scheme (Legendre or Radau points) and per-module meshes whose breakpoints fall on
every actuator anchor, point load and distributed-load end (SPEC section 6)."""
from dataclasses import dataclass

import math

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class CollocationScheme:
    """Points ``tau`` (d+1, ``tau[0] = 0``) on [0, 1] and the matrices of the interpolating
    polynomial: ``C[r, j] = l_r'(tau_j)`` (derivative), ``D[r] = l_r(1)`` (end value) and
    ``weights`` (d,) the quadrature on the collocation points alone (Gauss or Radau)."""
    degree: int
    kind: str
    tau: np.ndarray
    C: np.ndarray
    D: np.ndarray
    weights: np.ndarray

    @classmethod
    def create(cls, degree, kind="legendre"):
        tau = np.append(0.0, ca.collocation_points(degree, kind))
        C = np.zeros((degree + 1, degree + 1))
        D = np.zeros(degree + 1)
        for r in range(degree + 1):
            basis = _lagrange(tau, r)
            D[r] = basis(1.0)
            C[r] = np.polyder(basis)(tau)
        weights = np.array([np.polyint(_lagrange(tau[1:], j))(1.0) for j in range(degree)])
        return cls(degree, kind, tau, C, D, weights)


def _lagrange(points, r):
    basis = np.poly1d([1.0])
    for k, point in enumerate(points):
        if k != r:
            basis *= np.poly1d([1.0, -point]) / (points[r] - point)
    return basis


@dataclass(frozen=True)
class ModuleMesh:
    """Intervals ``[(s0, s1), ...]`` [m] of one module, in order, covering [0, L]."""
    length: float
    breakpoints: tuple
    intervals: tuple

    def node_s(self, scheme):
        """Arc length of every node, shape (n_intervals, d+1)."""
        return np.array([s0 + scheme.tau * (s1 - s0) for s0, s1 in self.intervals])

    def bisected(self, flags):
        """A mesh with every interval whose flag is set cut in two (breakpoints kept)."""
        pieces = []
        for (s0, s1), flag in zip(self.intervals, flags):
            pieces += [(s0, 0.5 * (s0 + s1)), (0.5 * (s0 + s1), s1)] if flag else [(s0, s1)]
        return ModuleMesh(self.length, self.breakpoints, tuple(pieces))


def module_breakpoints(robot, index):
    """Sorted arc lengths [m] where the solution may jump in strain (anchors, loads, contact
    candidates, ends) or lose smoothness (a curve route's knots)."""
    module = robot.modules[index]
    points = {0.0, module.length}
    for actuator in module.actuators:
        points.update(actuator.route.span)
        points.update(actuator.route.smoothness_breaks)
    for load in robot.point_loads:
        if load.module == index:
            points.add(load.s)
    for load in robot.distributed_loads:
        if load.module == index:
            points.update(load.span)
    points.update(robot.contact_points(index))          # contact candidates (point forces)
    return _merge_close(sorted(points), 1e-12 * module.length)


def _merge_close(points, tolerance):
    merged = [points[0]]
    for point in points[1:]:
        if point - merged[-1] > tolerance:
            merged.append(point)
    return merged


#: the automatic mesh: intervals per module, plus per helix turn of its actuators (degree 4),
#: from the accuracy study (scripts/bench.py, README): against a 64-interval, degree-5 reference
#: the tip is within 1e-6 m on every shipped scenario from 2 intervals (the twisting module's 5
#: turns need 12, 15 below the bending module in the arm); 6 + 3 per turn keeps the whole
#: centerline, which ``check`` compares, within 1e-7 m (tips within 2e-7 m).
AUTO_BASE, AUTO_PER_TURN = 6, 3


def auto_intervals(robot, index):
    """Intervals for module ``index`` when ``solver.intervals`` is ``auto``."""
    turns = sum(abs(a.route.params.get("turns", 0.0)) for a in robot.modules[index].actuators)
    return AUTO_BASE + int(math.ceil(AUTO_PER_TURN * turns))


def build_mesh(robot, index, intervals):
    """A :class:`ModuleMesh` with about ``intervals`` intervals (an int, or ``"auto"``) spread
    by length over the segments between breakpoints (at least one per segment)."""
    if intervals == "auto":
        intervals = auto_intervals(robot, index)
    length = robot.modules[index].length
    breaks = module_breakpoints(robot, index)
    breaks[0], breaks[-1] = 0.0, length
    sizes = np.diff(breaks)
    counts = _allocate(sizes / length * intervals)
    pieces = []
    for (start, end), count in zip(zip(breaks[:-1], breaks[1:]), counts):
        edges = np.linspace(start, end, count + 1)
        pieces.extend(zip(edges[:-1], edges[1:]))
    return ModuleMesh(length, tuple(breaks), tuple((float(a), float(b)) for a, b in pieces))


def _allocate(shares):
    """Whole counts >= 1 close to ``shares`` whose sum is ``max(round(sum), len)``."""
    total = max(int(round(shares.sum())), len(shares))
    counts = np.maximum(1, np.floor(shares).astype(int))
    while counts.sum() < total:
        counts[np.argmax(shares - counts)] += 1
    return counts

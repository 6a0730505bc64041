"""Sample designs of a study (``tca-casadi study``): which values each varied path takes, and
the order the samples are solved in.

Every axis maps a coordinate ``u`` in [0, 1) to a value: a range ``[lo, hi]`` to
``lo + u (hi - lo)``, ``uniform: [lo, hi]`` the same, ``normal: {mean, std}`` to
``mean + std Phi^-1(u)`` (the inverse normal CDF), so one space-filling design in the unit cube
(``sobol``, ``latin``, ``random``; seeded) serves ranges and distributions alike: a Sobol design
with normal axes is quasi-Monte Carlo. ``grid`` takes ``N`` equally spaced values per range
axis, ends included, and crosses them. An explicit ``values: [...]`` axis is crossed with the
rest; ``rows`` (a table of paths) gives every sample outright.

**Order.** Each worker solves its samples warm-started from the previous one, so neighbours must
be next to each other: a grid is run in snake (boustrophedon) order, every other design in
greedy nearest-neighbour order in the unit cube (from the sample nearest its centre).
"""
from dataclasses import dataclass, field

import numpy as np

from ...errors import ScenarioError, flag

DESIGNS = ("grid", "sobol", "latin", "random")
#: values per axis of a grid when a range gives none
GRID_POINTS = 11
#: samples of a sampling design when none are asked for
SAMPLES = 256


@dataclass
class Axis:
    """One varied path: ``kind`` range | uniform | normal | values; bounds or moments in the
    path's unit (numbers; strings with units converted by the caller)."""
    path: str
    kind: str
    low: float = None
    high: float = None
    mean: float = None
    std: float = None
    points: int = None               # a grid's values on this axis
    values: list = field(default_factory=list)

    def __post_init__(self):
        where = f"vary {self.path}"
        if self.kind in ("range", "uniform"):
            if not (np.isfinite(self.low) and np.isfinite(self.high)) or not self.high > self.low:
                raise ScenarioError(f"{where}: the range [{self.low:g}, {self.high:g}] is empty "
                                    "(give low < high)")
            if self.points is not None and self.points < 1:
                raise ScenarioError(f"{where}: {self.points} points; give at least 1")
        elif self.kind == "normal":
            if not np.isfinite(self.mean) or not (np.isfinite(self.std) and self.std > 0):
                raise ScenarioError(f"{where}: normal with std {self.std:g}; give std > 0")
        elif self.kind == "values":
            if not self.values:
                raise ScenarioError(f"{where}: an empty list of values")
        else:
            raise ScenarioError(f"{where}: unknown kind {self.kind!r} (range, uniform, normal, values)")

    @property
    def distribution(self):
        """True for a Monte Carlo axis (normal, uniform)."""
        return self.kind in ("normal", "uniform")

    def value_at(self, u):
        """Values (k,) at unit coordinates ``u`` (k,)."""
        u = np.asarray(u, float)
        if self.kind in ("range", "uniform"):
            return self.low + u * (self.high - self.low)
        if self.kind == "normal":
            from scipy.stats import norm
            return self.mean + self.std * norm.ppf(np.clip(u, 1e-12, 1 - 1e-12))
        raise ValueError(self.kind)

    def describe(self):
        if self.kind == "range":
            return {"path": self.path, "range": [self.low, self.high], "points": self.points}
        if self.kind == "uniform":
            return {"path": self.path, "uniform": [self.low, self.high]}
        if self.kind == "normal":
            return {"path": self.path, "normal": {"mean": self.mean, "std": self.std}}
        return {"path": self.path, "values": list(self.values)}


@dataclass
class Design:
    """The samples of a study: ``values`` (n, k) in the axes' units, in the order they are
    solved (``ids``: each sample's number in the design's own order, (n,))."""
    paths: list
    values: np.ndarray
    ids: np.ndarray
    kind: str
    seed: int = 0

    @property
    def size(self):
        return len(self.ids)


def build_design(axes, kind=None, samples=None, seed=0):
    """The :class:`Design` of ``axes`` (list of :class:`Axis`): ``kind`` one of
    :data:`DESIGNS` (default ``grid``, or ``random`` when an axis is a distribution),
    ``samples`` the number of a sampling design's points (default :data:`SAMPLES`)."""
    if not axes:
        raise ScenarioError(f"study: nothing varies (give {flag('--vary')}, {flag('--monte-carlo')} or {flag('--rows')})")
    kind = kind or ("random" if any(a.distribution for a in axes) else "grid")
    if kind not in DESIGNS:
        raise ScenarioError(f"study: design {kind!r} is not one of {', '.join(DESIGNS)}")
    if samples is not None and samples < 1:
        raise ScenarioError(f"study: {samples} samples; give at least 1")
    listed = [a for a in axes if a.kind == "values"]
    drawn = [a for a in axes if a.kind != "values"]
    if kind == "grid":
        bad = [a.path for a in drawn if a.distribution]
        if bad:
            raise ScenarioError(f"study: a grid cannot sample the distribution of {', '.join(bad)}; "
                                f"use {flag('--design')} random, sobol or latin")
        unit = _grid([a.points or GRID_POINTS for a in drawn])
    else:
        unit = _sampled(kind, len(drawn), samples or SAMPLES, seed) if drawn else np.zeros((1, 0))
    values = np.column_stack([a.value_at(unit[:, j]) for j, a in enumerate(drawn)]) if drawn else np.zeros((1, 0))
    if listed:                                     # crossed with the drawn samples
        lists = [np.asarray(a.values, float) for a in listed]
        combos = np.array(np.meshgrid(*lists, indexing="ij")).reshape(len(lists), -1).T
        values = np.hstack([np.repeat(values, len(combos), axis=0), np.tile(combos, (len(values), 1))])
        unit = np.hstack([np.repeat(unit, len(combos), axis=0),
                          np.tile(_unit_of_lists(lists, combos), (len(unit), 1))])
    paths = [a.path for a in drawn] + [a.path for a in listed]
    order = snake_order([a.points or GRID_POINTS for a in drawn]) if kind == "grid" and not listed \
        else nearest_neighbour_order(unit)
    return Design(paths, values[order], np.asarray(order), kind, seed)


def rows_design(table, seed=0):
    """A :class:`Design` from explicit rows: ``table`` a dict path -> values (equal lengths),
    solved in nearest-neighbour order of the values scaled to their ranges."""
    paths = list(table)
    values = np.column_stack([np.asarray(table[p], float) for p in paths])
    if values.shape[0] == 0:
        raise ScenarioError("study: the rows table has no rows")
    if not np.all(np.isfinite(values)):
        row = int(np.flatnonzero(~np.all(np.isfinite(values), axis=1))[0])
        raise ScenarioError(f"study: row {row + 1} of the rows table is not a number in every column")
    span = np.ptp(values, axis=0)
    unit = (values - values.min(axis=0)) / np.where(span > 0, span, 1.0)
    order = nearest_neighbour_order(unit)
    return Design(paths, values[order], np.asarray(order), "rows", seed)


def _grid(points):
    """Unit coordinates (prod(points), k) of a grid, the last axis fastest."""
    axes = [np.linspace(0.0, 1.0, n) if n > 1 else np.array([0.5]) for n in points]
    return np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(points), -1).T


def _sampled(kind, dimensions, samples, seed):
    """``samples`` points (samples, dimensions) in [0, 1)."""
    from scipy.stats import qmc
    if kind == "sobol":                  # the first n of the next power of two (Sobol's balance)
        power = int(np.ceil(np.log2(max(samples, 1))))
        return qmc.Sobol(dimensions, scramble=True, seed=seed).random_base2(power)[:samples]
    if kind == "latin":
        return qmc.LatinHypercube(dimensions, seed=seed).random(samples)
    return np.random.default_rng(seed).random((samples, dimensions))


def _unit_of_lists(lists, combos):
    """Listed values' positions in their lists, scaled to [0, 1] (for the ordering)."""
    out = np.zeros(combos.shape)
    for j, values in enumerate(lists):
        rank = np.searchsorted(np.sort(values), combos[:, j])
        out[:, j] = rank / max(len(values) - 1, 1)
    return out


def snake_order(points):
    """Indices of a grid (C order, the last axis fastest) in snake order: every axis runs back
    and forth so that consecutive samples differ in one coordinate by one step."""
    index = np.arange(int(np.prod(points))).reshape(points)
    return _snake(index).ravel()


def _snake(block):
    if block.ndim == 1:
        return block
    rows = [_snake(block[i]) for i in range(block.shape[0])]
    return np.concatenate([r if i % 2 == 0 else r[::-1] for i, r in enumerate(rows)])


#: above this many samples the greedy tour (quadratic in n) gives way to a snake over cells
GREEDY_LIMIT = 4000


def nearest_neighbour_order(unit):
    """Greedy nearest-neighbour tour of the points ``unit`` (n, k), from the point nearest the
    centre of their box: each next sample is the closest one not yet taken. Above
    :data:`GREEDY_LIMIT` points: the cells of a coarse grid in snake order (about 8 points a
    cell), the points of a cell together."""
    unit = np.asarray(unit, float)
    n = unit.shape[0]
    if n <= 2 or unit.shape[1] == 0:
        return np.arange(n)
    if n > GREEDY_LIMIT:
        k = unit.shape[1]
        cells = max(2, int(round((n / 8) ** (1 / k))))
        index = np.minimum((unit * cells).astype(int), cells - 1)
        rank = np.empty(cells ** k, int)
        rank[snake_order([cells] * k)] = np.arange(cells ** k)
        return np.argsort(rank[np.ravel_multi_index(index.T, [cells] * k)], kind="stable")
    left = np.ones(n, bool)
    current = int(np.argmin(np.sum((unit - 0.5) ** 2, axis=1)))
    order = [current]
    left[current] = False
    remaining = unit.copy()
    for _ in range(n - 1):
        distance = np.sum((remaining - unit[current]) ** 2, axis=1)
        distance[~left] = np.inf
        current = int(np.argmin(distance))
        order.append(current)
        left[current] = False
    return np.array(order)

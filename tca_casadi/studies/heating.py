"""The robot's quasi-static motion while its TCAs heat and cool (issue 15).

The mechanics are quasi-static (a TCA robot's mechanical modes are 5-10 Hz, its thermal
response seconds): at every output time of a :class:`~tca_casadi.solvers.thermal.ThermalHistory`
the equilibrium at those temperatures is found by continuation from the previous output's
equilibrium (the branch is followed, never jumped), on the built collocation NLP.
"""
from dataclasses import dataclass, field

import numpy as np

from ..model.rotations import matrix_to_quaternion
from ..solvers.continuation import BranchFollower


@dataclass
class TimeSeries:
    """Solutions at the output times ``t`` [s] (n,), with the temperatures [degC] and electrical
    powers [W] (``nan`` where a TCA's temperature is set, not heated) of the TCAs ``keys``,
    arrays (n, len(keys))."""
    t: np.ndarray
    keys: list
    temperatures: np.ndarray
    powers: np.ndarray
    solutions: list = field(default_factory=list)
    message: str = ""

    @property
    def completed(self):
        return len(self.solutions) == len(self.t) and all(s.converged for s in self.solutions)

    def tip_positions(self):
        """(n, 3) [m] at the solved output times."""
        return np.array([s.tip_position for s in self.solutions])

    def header(self):
        columns = ["t [s]"]
        for key in self.keys:
            columns += [f"{key}.temperature [degC]", f"{key}.power [W]", f"{key}.tension [N]", f"{key}.stroke [m]"]
        return columns + ["tip_x [m]", "tip_y [m]", "tip_z [m]", "tip_qw", "tip_qx", "tip_qy", "tip_qz", "converged"]

    def rows(self):
        """``timeseries.csv`` rows: t, per TCA temperature, power (empty where not heated),
        tension, stroke; the tip position and quaternion; converged."""
        out = []
        for k, solution in enumerate(self.solutions):
            row = [f"{self.t[k]:.10g}"]
            for j, key in enumerate(self.keys):
                actuator = solution.actuators[key]
                power = "" if np.isnan(self.powers[k, j]) else f"{self.powers[k, j]:.10g}"
                row += [f"{self.temperatures[k, j]:.10g}", power, f"{actuator.tension:.10g}", f"{actuator.stroke:.10g}"]
            row += [f"{v:.10g}" for v in solution.tip_position]
            row += [f"{v:.10g}" for v in matrix_to_quaternion(solution.tip_rotation)]
            out.append(row + [int(solution.converged)])
        return out

    def to_csv(self, path):
        """Write ``timeseries.csv`` (atomically); return its path."""
        from ..output import write_csv
        return write_csv(path, self.header(), self.rows())


def follow_temperatures(sim, keys, history, progress=None):
    """The quasi-static shapes of ``sim``'s robot while the TCAs ``keys`` (``MODULE.TCA``) have
    the temperatures of ``history`` (a ThermalHistory whose columns are ``keys``); every other
    parameter stays at ``sim.params``. See :func:`follow_parameters`."""
    names = [f"{key}.temperature" for key in keys]
    missing = [name for name in names if name not in sim.robot.layout]
    if missing:
        raise KeyError(f"not TCA temperatures of this robot: {', '.join(missing)}")
    path = []
    for k in range(len(history.t)):
        params = sim.params.copy()
        for j, name in enumerate(names):
            params[sim.robot.layout[name]] = history.temperature[k, j]
        path.append(params)
    series = TimeSeries(np.asarray(history.t, float), list(keys), history.temperature, history.power)
    return follow_parameters(sim, series, path, progress)


def follow_parameters(sim, series, path, progress=None):
    """Fill ``series`` (a :class:`TimeSeries`) with the equilibria at the parameter vectors
    ``path`` (one per output time): the first solved from the reference state, each next one
    by continuation from the previous. Stops at the first output time whose parameters leave
    the model's range (e.g. a TCA above its type's max_temperature) or whose equilibrium
    cannot be followed (``completed`` is then False, ``message`` says why; the solutions up
    to there are kept). ``sim``'s parameters are left as they were."""
    base = sim.params.copy()
    solution = previous = linearisation = None
    try:
        for k, params in enumerate(path):
            problems = sim.robot.problems(params)
            if problems:
                series.message = f"stopped at t = {series.t[k]:g} s: " + "; ".join(problems)
                break
            if solution is None:
                sim.params = params.copy()
                solution = sim.solve(warn=False)
                if not solution.converged:
                    series.message = f"no equilibrium at t = {series.t[0]:g} s: {solution.message}"
                    break
            else:
                follower = BranchFollower(sim.solver("collocation"), previous, params - previous)
                start = follower.point(0.0, solution, linearisation=linearisation)   # the last one's, reused
                point, _, _, failure = follower.advance(start, 1.0, 1.0, 1.0, 1e-4)
                if failure is not None:
                    series.message = (f"stopped at t = {series.t[k]:g} s: the equilibrium could not be "
                                      f"followed from t = {series.t[k - 1]:g} s ({failure.trial.message})")
                    break
                solution, linearisation = point.solution, point.linearisation
            previous = params
            series.solutions.append(solution)
            if progress is not None:
                progress((k + 1) / len(path), f"t = {series.t[k]:.3g} s")
    finally:
        sim.params = base
        if solution is not None:
            sim.last = solution
    if series.completed:
        series.message = f"followed {len(series.t)} output times"
    return series

"""The robot's quasi-static motion while its TCAs heat and cool (issue 15).

The mechanics are quasi-static (a TCA robot's mechanical modes are 5-10 Hz, its thermal
response seconds): at every output time of a :class:`~tca_casadi.solvers.thermal.ThermalHistory`
the equilibrium at those temperatures is found by continuation from the previous output's
equilibrium (the branch is followed, never jumped), on the built collocation NLP.
"""
from dataclasses import dataclass, field

import numpy as np

from ..model.rotations import matrix_to_quaternion
from ..results import ResultAPI, status_of
from ..status import Status
from ..solvers.continuation import NOISE, _slack_pattern, walk_branch


@dataclass(repr=False)
class TimeSeries(ResultAPI):
    """Solutions at the output times ``t`` [s] (n,), with the temperatures [degC] and electrical
    powers [W] (``nan`` where a TCA's temperature is set, not heated) of the TCAs ``keys``,
    arrays (n, len(keys))."""
    t: np.ndarray
    keys: list
    temperatures: np.ndarray
    powers: np.ndarray
    solutions: list = field(default_factory=list)
    message: str = ""
    objects: list = field(default_factory=list)      # per solved output: {name: ObjectPose} (scenario objects)
    warnings: list = field(default_factory=list)     # PhysicsWarning s (e.g. a grasp not across the object)
    tip_velocities: np.ndarray = None                # a dynamic run's: (n, 3) [m/s]
    energies: np.ndarray = None                      # a dynamic run's: (n, 7) [J], motion.ENERGY_COLUMNS
    #: TCAs on voltage or current drives: {key: ("voltage" | "current", (n,) [V] or [A])} from
    #: the power and the fibre's resistance at its temperature (V = sqrt(P R(T)), I = sqrt(P / R(T)))
    electrical: dict = field(default_factory=dict)
    #: a dynamic run's per-output StepOutputs (its Solutions are built only when asked)
    views: list = None

    @property
    def outputs(self):
        """Per solved output, what its tables read (tip, actuators, contact columns): the
        Solutions, or a dynamic run's :attr:`views`."""
        return self.solutions if self.views is None else self.views

    @property
    def completed(self):
        return len(self.solutions) == len(self.t) and all(s.converged for s in self.outputs)

    def checked_balances(self):
        """The global balances (relative) of the outputs whose balance was checked."""
        built = self.solutions.checked() if hasattr(self.solutions, "checked") else self.solutions
        return [s.balance.relative for s in built if s.balance is not None]

    @property
    def result(self):
        """:class:`SolveStatus` of the run: success when every output time was solved."""
        return status_of(self.completed, "simulate", self.message, Status.STALLED, nit=len(self.solutions))

    def summary(self):
        """A few lines: the times run, the TCAs' peak temperatures, the tip at the end."""
        n = len(self.solutions)
        lines = [f"simulate {'completed' if self.completed else 'STOPPED'}: {n} of {len(self.t)} output times "
                 f"to {self.t[n - 1] if n else 0:g} s" + (f"; {self.message}" if self.message else "")]
        for k, key in enumerate(self.keys):
            lines.append(f"  {key:<24} temperature peak {np.nanmax(self.temperatures[:n, k]):.2f} degC")
        if n:
            lines.append("  tip at the end [mm]: " + " ".join(f"{v * 1e3:+.4f}" for v in self.outputs[-1].tip_position))
        return "\n".join(lines)

    def figure(self):
        """``timeseries.png``'s figure (events not marked: the scenario holds them)."""
        from ..plotting.timeseries import save_timeseries_png
        return save_timeseries_png(self, None)

    def tip_positions(self):
        """(n, 3) [m] at the solved output times."""
        return np.array([s.tip_position for s in self.outputs]).reshape(-1, 3)

    def header(self):
        columns = ["t [s]"]
        for key in self.keys:
            columns += [f"{key}.temperature [degC]", f"{key}.power [W]", f"{key}.tension [N]", f"{key}.stroke [m]"]
        columns += [f"{key}.{kind} [{'V' if kind == 'voltage' else 'A'}]" for key, (kind, _) in self.electrical.items()]
        columns += ["tip_x [m]", "tip_y [m]", "tip_z [m]", "tip_qw", "tip_qx", "tip_qy", "tip_qz"]
        if getattr(self, "energies", None) is not None:          # a dynamic run
            from .motion import ENERGY_COLUMNS
            columns += ["tip_vx [m/s]", "tip_vy [m/s]", "tip_vz [m/s]"] + [f"{name} [J]" for name in ENERGY_COLUMNS]
        free = self._free_bodies()
        for name in (self.objects[0] if self.objects else {}):          # a free body's centre is a contact column
            columns += [f"{name}.held"] + ([] if name in free else [f"{name}.x [m]", f"{name}.y [m]", f"{name}.z [m]"])
        columns += list(self.outputs[0].contact_columns()) if self.solutions else []
        return columns + ["converged"]

    def rows(self):
        """``timeseries.csv`` rows: t, per TCA temperature, power (empty where not heated),
        tension, stroke; the voltage or current of TCAs on such drives; the tip position and quaternion; each object's held flag and centre;
        each obstacle's normal force and clearance; converged."""
        out, free = [], self._free_bodies()
        for k, solution in enumerate(self.outputs):
            row = [f"{self.t[k]:.10g}"]
            for j, key in enumerate(self.keys):
                actuator = solution.actuators[key]
                power = "" if np.isnan(self.powers[k, j]) else f"{self.powers[k, j]:.10g}"
                row += [f"{self.temperatures[k, j]:.10g}", power, f"{actuator.tension:.10g}", f"{actuator.stroke:.10g}"]
            row += [f"{values[k]:.10g}" for _, values in self.electrical.values()]
            row += [f"{v:.10g}" for v in solution.tip_position]
            row += [f"{v:.10g}" for v in matrix_to_quaternion(solution.tip_rotation)]
            if getattr(self, "energies", None) is not None:
                row += [f"{v:.10g}" for v in self.tip_velocities[k]] + [f"{v:.10g}" for v in self.energies[k]]
            for name, pose in (self.objects[k].items() if self.objects else ()):
                row += [int(pose.held)] + ([] if name in free else [f"{v:.10g}" for v in pose.center])
            row += [f"{v:.10g}" for v in solution.contact_columns().values()]     # per obstacle
            out.append(row + [int(solution.converged)])
        return out

    def _free_bodies(self):
        """The names of the free bodies (contact objects), whose pose the contact columns hold."""
        return {body.name for body in getattr(self.outputs[0], "bodies", None) or []} if self.solutions else set()

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


#: in a time run, the outputs between branch checks: the quick steps between two checks are
#: accepted once the check at the end of their stretch passes (see :func:`follow_parameters`)
CHECK_EVERY = 10


@dataclass
class _Checked:
    """The last output whose branch was checked: its index, solution, parameters and the
    linearisation there (fresh)."""
    index: int
    solution: object
    params: np.ndarray
    linearisation: object


def follow_parameters(sim, series, path, progress=None, careful=None):
    """Fill ``series`` (a :class:`TimeSeries`) with the equilibria at the parameter vectors
    ``path`` (one per output time): the first solved from the reference state, each next one
    by continuation from the previous. Stops at the first output time whose parameters leave
    the model's range (e.g. a TCA above its type's max_temperature) or whose equilibrium
    cannot be followed (``completed`` is then False, ``message`` says why; the solutions up
    to there are kept). ``sim``'s parameters are left as they were.

    ``careful`` (bool per output, default all) marks outputs that take a full continuation
    step (:class:`BranchFollower`: a linearisation at the new point, the sign of det J_w and
    the trapezoid test on the tangents, halving on failure). Elsewhere a *quick step* is tried
    (:func:`quick_step`: the last checked point's tangent and LU, no linearisation), and every
    :data:`CHECK_EVERY` outputs the stretch of quick steps is checked at once: a linearisation
    at its end, the same sign of det J_w as at its start, and the trapezoid rule between its
    two ends (``w`` is a function of the parameters on a branch, so the test holds over a
    stretch as over one step). A stretch that fails is redone with full steps. A time run
    marks every output where parameters may step (events) careful."""
    base = sim.params.copy()
    careful = np.ones(len(path), bool) if careful is None else np.array(careful, bool)
    solution = previous = checked = None
    k = 0
    try:
        while k < len(path):
            params = path[k]
            problems = sim.robot.problems(params)
            if problems:
                series.message = f"stopped at t = {series.t[k]:g} s: " + "; ".join(problems)
                break
            quick = None
            if solution is not None and not careful[k] and checked is not None:
                quick = quick_step(sim.solver("collocation"), checked.linearisation, solution, previous, params)
            if solution is None:
                solution = sim.solve(warn=False, params=params)
                if not solution.converged:
                    series.message = f"no equilibrium at t = {series.t[0]:g} s: {solution.message}"
                    break
            elif quick is None:
                reuse = checked.linearisation if checked is not None and checked.index == k - 1 else None
                point, failure = _full_step(sim, solution, previous, params, reuse)
                if failure is not None:
                    series.message = (f"stopped at t = {series.t[k]:g} s: the equilibrium could not be "
                                      f"followed from t = {series.t[k - 1]:g} s ({failure.trial.message})")
                    break
                solution = point.solution
                checked = _Checked(k, solution, params, point.linearisation)
            else:
                solution = quick
                if k - checked.index >= CHECK_EVERY or k == len(path) - 1:
                    linearisation = sim.solver("collocation").linearise(solution.iterate.w, params)
                    if not _stretch_holds(checked, solution, params, linearisation):
                        del series.solutions[checked.index + 1:]          # redo it with full steps
                        careful[checked.index + 1:k + 1] = True
                        solution, previous, k = checked.solution, checked.params, checked.index + 1
                        continue
                    checked = _Checked(k, solution, params, linearisation)
            previous = params
            series.solutions.append(solution)
            if progress is not None:
                progress((k + 1) / len(path), f"t = {series.t[k]:.3g} s")
            k += 1
    finally:
        sim.params = base
        if solution is not None:
            sim.last = solution
    if series.completed:
        series.message = f"followed {len(series.t)} output times"
    return series


def _full_step(sim, solution, previous, params, linearisation=None):
    """One continuation step (halving on failure) from ``solution`` at ``previous`` to
    ``params``; ``linearisation``: the one at ``solution``, if known. ``(point, failure)``."""
    walk = walk_branch(sim.solver("collocation"), solution, previous, params, linearisation=linearisation)
    return walk.point, walk.failure


def _stretch_holds(checked, solution, params, linearisation, jump_tolerance=0.15):
    """Whether the quick steps from ``checked`` to ``solution`` (at ``params``, linearised
    there) stayed on one branch: det J_w has the same sign at both ends and the change in
    ``w`` meets the trapezoid rule on the two ends' tangents within ``jump_tolerance``
    (relative, as :meth:`BranchFollower.inconsistency`)."""
    try:
        if linearisation.determinant_sign() * checked.linearisation.determinant_sign() <= 0:
            return False
        delta = np.asarray(params, float) - checked.params
        change = solution.iterate.w - checked.solution.iterate.w
        rates = checked.linearisation.state_derivative(delta) + linearisation.state_derivative(delta)
    except RuntimeError:                    # singular: a fold at an end
        return False
    size = float(np.max(np.abs(change)))
    if size <= NOISE * max(1.0, float(np.max(np.abs(checked.solution.iterate.w)))):
        return True
    return float(np.max(np.abs(change - 0.5 * rates))) <= jump_tolerance * size


def quick_step(solver, linearisation, solution, previous, params, jump_tolerance=0.15):
    """The equilibrium at ``params`` from ``solution`` (at ``previous``) without a new
    linearisation: predicted along the tangent of ``linearisation`` (an earlier point's),
    corrected by Newton starting with chord steps on its LU. None when Newton does not converge,
    when its correction is more than ``jump_tolerance`` of the predicted change (it left the
    predicted branch), or when an actuator goes slack or taut (a corner of the branch): the
    caller then takes a full continuation step."""
    w = solution.iterate.w
    predicted = w + linearisation.state_derivative(np.asarray(params, float) - previous)
    trial = solver.solve_newton(params, predicted, lu=linearisation.lu)
    if not trial.converged or _slack_pattern(trial) != _slack_pattern(solution):
        return None
    change = float(np.max(np.abs(predicted - w)))
    correction = float(np.max(np.abs(trial.iterate.w - predicted)))
    floor = 1e-12 * max(1.0, float(np.max(np.abs(w))))
    return trial if correction <= jump_tolerance * change + floor else None

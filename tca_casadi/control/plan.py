"""Optimal heating schedules (``tca-casadi plan``, issue 32): which electrical powers, over time,
bring the tip to a target and keep it there, from the same model that ``simulate`` runs.

The formulation (``docs/control.md`` derives it):

* a time grid ``t_k = k h``, ``k = 0..N``, ``h = horizon / N``; the varied inputs ``u_k``
  (powers [W] of ``power`` drives) held constant on ``[t_k, t_{k+1})`` (zero-order hold: what
  a timeline of steps in ``simulate`` applies);
* the heated TCAs' temperatures from the exact discretisation of the lumped thermal model,
  ``T_{k+1} = Phi T_k + Gamma P_k + offset`` (:func:`~tca_casadi.solvers.thermal.zero_order_hold`),
  from the steady state of the scenario's drives at t = 0: ``T = T_free + M u``, linear in the
  inputs;
* at every node the robot's equilibrium at those temperatures (Newton on the built collocation
  system, warm from the last evaluation; continuation where Newton fails): every iterate is an
  equilibrium, and the tip's derivatives follow from the implicit function theorem
  (``dtip_k/du = dtip/dT (T_k) M_k``, one sparse LU per node);
* objectives: ``time``, least squares of the tip's error at every node from t = 0 with the
  inputs bounded (the error falls as fast as the bounds allow and then stays: for one heated
  TCA that is the bang-bang minimum-time input, full power then the holding power
  ``G (T* - T_amb)``); ``energy``, the least electrical energy ``sum_k h u_k`` with the error
  within the tolerance at every node from ``by`` on (scipy's SLSQP, started from the ``time``
  plan); ``track``, least squares of the tip's distance from a path ``p*(t)`` (given at times,
  linear in between) at every node. All keep every temperature at or below its type's
  ``max_temperature``.

``reached_at_s`` is the first node time from which the tip stays within the tolerance (of the
target, or of the path where it is at that time).
"""
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import ModelError, ScenarioError, SolverError, flag
from ..results import ResultAPI
from ..solvers.thermal import steady_state, zero_order_hold
from ..status import SolveStatus, Status

#: the drive kinds a plan varies and can hold: electrical ones whose power does not depend on the
#: temperature (a voltage or current drive with a constant resistance: P = V^2 / R, I^2 R)
PLANNED_KINDS = ("power", "voltage", "current")
#: the unit of each planned drive kind's value
DRIVE_UNIT = {"power": "W", "voltage": "V", "current": "A"}


def power_of(kind, resistance, value):
    """Electrical power [W] of a drive of ``kind`` and ``value`` (W, V or A) through a
    ``resistance`` [ohm] (unused for power)."""
    value = np.asarray(value, float)
    return {"power": value, "voltage": value ** 2 / resistance, "current": value ** 2 * resistance}[kind]


def value_of(kind, resistance, power):
    """The drive value (W, V or A) of ``kind`` that delivers ``power`` [W] (>= 0): the inverse
    of :func:`power_of`."""
    power = np.maximum(np.asarray(power, float), 0.0)
    return {"power": power, "voltage": np.sqrt(power * resistance), "current": np.sqrt(power / resistance)}[kind]
#: temperatures may exceed ``max_temperature`` by at most this much [K] in a converged plan
TEMPERATURE_SLACK = 1e-3
#: the total power may exceed ``--power-budget`` by at most this much [W] in a converged plan
POWER_SLACK = 1e-6
#: weight of the least-heating term that picks one plan where several reach the target equally
REGULARISATION = 1e-6
OBJECTIVES = ("time", "energy", "track")
#: the least-energy plan keeps the tip within this fraction of the tolerance (the optimum lies on
#: the boundary: a margin keeps it inside, whatever roundoff)
MARGIN = 0.98


@dataclass
class HeatingRecord:
    """What a plan and a closed loop both hold: times ``t`` [s], the varied inputs' electrical
    powers ``inputs`` [W] (``paths``), the heated TCAs' ``temperatures`` [degC] (``keys``) and their
    ``max_temperatures``, the tip ``tips`` [m] and its distance ``errors`` [m] from where it
    should be (what :func:`~tca_casadi.plotting.plan_plots.save_plan_png` draws)."""
    objective: str
    t: np.ndarray
    paths: list
    inputs: np.ndarray
    keys: list
    temperatures: np.ndarray
    max_temperatures: np.ndarray
    tips: np.ndarray
    errors: np.ndarray


@dataclass(repr=False)
class PlanResult(ResultAPI, HeatingRecord):
    """A plan: the node times ``t`` (N + 1,) [s], the varied inputs' powers ``inputs`` (N, k) [W]
    (``paths`` their scenario paths; :meth:`drive_values` in the drives' own units), the heated TCAs' ``temperatures`` (N + 1, n) [degC] (``keys``), the
    tip ``tips`` (N + 1, 3) [m] and its distance ``errors`` (N + 1,) [m] from ``targets`` (N + 1,
    3) [m]: the target at every node, or the tracked path there."""
    targets: np.ndarray
    tolerance: float
    result: SolveStatus
    energy_J: float
    reached_at_s: float = None
    by_s: float = None
    message: str = ""
    bounds: np.ndarray = None
    fixed_powers: dict = field(default_factory=dict)
    #: per varied input: its drive's kind (power, voltage, current) and resistance [ohm]
    kinds: list = None
    resistances: list = None
    #: the point aimed ('tip' or a module, whose end), and with a target direction: the point's
    #: tangent's angle from it [rad] at every node (N + 1,) and the angle counted as reached
    point: str = "tip"
    direction: np.ndarray = None
    angle_errors: np.ndarray = None
    angle_tolerance: float = None
    #: the limit [W] of the heated TCAs' total power at every step (None: no budget)
    power_budget: float = None

    @property
    def total_powers(self):
        """(N,) [W]: every heated TCA's power summed at each step (the fixed ones included)."""
        return np.sum(self.inputs, axis=1) + sum(self.fixed_powers.values())

    def drive_values(self):
        """(N, k): the planned inputs in their drives' units (W, V or A)."""
        kinds = self.kinds or ["power"] * len(self.paths)
        resistances = self.resistances or [np.nan] * len(self.paths)
        return np.column_stack([value_of(kind, r, self.inputs[:, j])
                                for j, (kind, r) in enumerate(zip(kinds, resistances))])

    @property
    def units(self):
        """Per varied input, its drive value's unit."""
        return [DRIVE_UNIT[kind] for kind in (self.kinds or ["power"] * len(self.paths))]

    @property
    def target(self):
        """(3,) [m]: the target (the path's end when tracking)."""
        return self.targets[-1]

    @property
    def converged(self):
        return self.result.success

    @property
    def reached(self):
        return self.reached_at_s is not None

    @property
    def success(self):
        """Converged and the target reached (held to the horizon's end)."""
        return bool(self.converged and self.reached)

    @property
    def status(self):
        return Status.CONVERGED if self.success else (self.result.status if not self.result.success
                                                      else Status.ABOVE_TOLERANCE)

    def figure(self):
        """``plan.png``'s figure."""
        from ..plotting.plan_plots import save_plan_png
        return save_plan_png(self, None)

    def timeline(self):
        """The schedule as ``simulate`` takes it: ``{duration, timeline: [{at, set}, ...]}`` (one
        event per node where an input changes, values in W)."""
        events, last = [], None
        for k, values in enumerate(self.drive_values()):
            current = [f"{v:.12g} {unit}" for v, unit in zip(values, self.units)]   # the same: one event
            if current != last:
                events.append({"at": f"{self.t[k]:.12g} s", "set": dict(zip(self.paths, current))})
                last = current
        return {"duration": f"{self.t[-1]:.12g} s", "timeline": events}

    def overrides(self):
        """``--set`` style overrides that replay the plan in ``simulate``."""
        import json
        schedule = self.timeline()
        return [f"duration={schedule['duration']}", f"timeline={json.dumps(schedule['timeline'])}"]

    def summary(self):
        state = "REACHED" if self.reached else "NOT REACHED"
        how = (f"{self.result.algorithm}, {self.result.nit} evaluations of the {len(self.t)} nodes, "
               f"{self.result.solve_time_s:.3g} s")
        lines = [f"plan ({self.objective}): {state}, " + (f"converged ({how})" if self.converged else
                                                          f"NOT CONVERGED ({how}): {self.result.message}"),
                 (f"  path of {len(self.targets)} nodes, RMS distance {self.rms_error * 1e3:.4g} mm, to "
                  if self.objective == "track" else "  target ")
                 + "[mm]: " + " ".join(f"{v * 1e3:+.4f}" for v in self.target)
                 + f", tolerance {self.tolerance * 1e3:.4g} mm" + ("" if self.point == "tip" else f" (the end of {self.point})")
                 + ("" if self.direction is None else
                    "; direction " + " ".join(f"{v:+.4f}" for v in self.direction)
                    + f" within {np.degrees(self.angle_tolerance):.3g} deg (at the end "
                    f"{np.degrees(self.angle_errors[-1]):.3g} deg)"),
                 (f"  within the tolerance of the path from {self.reached_at_s:.4g} s to {self.t[-1]:.4g} s"
                  if self.objective == "track" else
                  f"  reached at {self.reached_at_s:.4g} s and held to {self.t[-1]:.4g} s") if self.reached else
                 f"  not within the tolerance by {self.t[-1]:.4g} s: the closest is {np.min(self.errors) * 1e3:.4g} mm "
                 f"at {self.t[int(np.argmin(self.errors))]:.4g} s" + ("" if self.direction is None else
                                                                     f", the smallest angle {np.degrees(np.min(self.angle_errors)):.3g} deg"),
                 f"  electrical energy {self.energy_J:.4g} J over {self.t[-1]:.4g} s ({len(self.t) - 1} steps of "
                 f"{self.t[1] - self.t[0]:.4g} s)"]
        values = self.drive_values()
        for j, (path, unit) in enumerate(zip(self.paths, self.units)):
            lines.append(f"  {path:<28} {np.min(values[:, j]):.4g} to {np.max(values[:, j]):.4g} {unit}"
                         + ("" if unit == "W" else f" ({np.min(self.inputs[:, j]):.4g} to "
                                                    f"{np.max(self.inputs[:, j]):.4g} W)"))
        for j, key in enumerate(self.keys):
            lines.append(f"  {key + '.temperature':<28} peak {np.max(self.temperatures[:, j]):.2f} degC "
                         f"(max {self.max_temperatures[j]:g})")
        if self.power_budget is not None:
            lines.append(f"  {'total power':<28} peak {np.max(self.total_powers):.4g} W (budget {self.power_budget:.4g} W)")
        if self.message:
            lines.append(f"  {self.message}")
        return "\n".join(lines)

    @property
    def rms_error(self):
        """Root mean square of ``errors`` [m] over the nodes after t = 0."""
        return float(np.sqrt(np.mean(self.errors[1:] ** 2)))

    def header(self):
        powers = [f"{p.rsplit('.drive.value', 1)[0]}.power [W]" for p, unit in zip(self.paths, self.units)
                  if unit != "W"]
        return (["t [s]"] + [f"{p} [{unit}]" for p, unit in zip(self.paths, self.units)] + powers
                + [f"{k}.temperature [degC]" for k in self.keys]
                + ["tip_x [m]", "tip_y [m]", "tip_z [m]", "target_x [m]", "target_y [m]", "target_z [m]",
                   "tip_error [m]"] + ([] if self.direction is None else ["angle_error [rad]"]))

    def rows(self):
        """One row per node; an input is the value held from that node on (the last is held to the
        end)."""
        out, values = [], self.drive_values()
        electric = [j for j, unit in enumerate(self.units) if unit != "W"]
        for k, t in enumerate(self.t):
            step = min(k, len(self.inputs) - 1)
            held, power = values[step], self.inputs[step, electric]
            out.append([f"{t:.12g}"] + [f"{v:.12g}" for v in held] + [f"{v:.10g}" for v in power]
                       + [f"{v:.10g}" for v in self.temperatures[k]]
                       + [f"{v:.10g}" for v in self.tips[k]] + [f"{v:.10g}" for v in self.targets[k]]
                       + [f"{self.errors[k]:.10g}"]
                       + ([] if self.direction is None else [f"{self.angle_errors[k]:.10g}"]))
        return out

    def to_dict(self):
        return {"converged": self.converged, "objective": self.objective, "reached": self.reached,
                "reached_at_s": self.reached_at_s, "by_s": self.by_s, "energy_J": self.energy_J,
                "target_m": self.target.tolist(), "rms_error_m": self.rms_error, "tolerance_m": self.tolerance, "horizon_s": float(self.t[-1]),
                "nodes": len(self.t) - 1, "step_s": float(self.t[1] - self.t[0]), "inputs": self.paths,
                "input_units": self.units, "input_kinds": self.kinds or ["power"] * len(self.paths),
                "bounds_W": None if self.bounds is None else self.bounds.tolist(),
                "fixed_powers_W": self.fixed_powers,
                "peak_temperatures_degC": dict(zip(self.keys, np.max(self.temperatures, axis=0).tolist())),
                "max_temperatures_degC": dict(zip(self.keys, self.max_temperatures.tolist())),
                "final_error_m": float(self.errors[-1]), "status": self.result.as_dict(), "message": self.message,
                "point": self.point, "power_budget_W": self.power_budget,
                "peak_total_power_W": float(np.max(self.total_powers)),
                "target_direction": None if self.direction is None else self.direction.tolist(),
                "angle_tolerance_rad": self.angle_tolerance,
                "final_angle_error_rad": None if self.angle_errors is None else float(self.angle_errors[-1]),
                "timeline": self.timeline()}

    def save(self, directory, plot=True):
        """Write ``plan.csv``, ``plan.json``, ``plan_timeline.yaml`` and (``plot``) ``plan.png``
        into ``directory``; the paths written."""
        from pathlib import Path

        import yaml

        from ..output import write_csv, write_json, write_text
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        written = [write_csv(directory / "plan.csv", self.header(), self.rows()),
                   write_json(directory / "plan.json", self.to_dict()),
                   write_text(directory / "plan_timeline.yaml",
                              "# the plan's schedule: tca-casadi simulate SCENARIO --timeline plan_timeline.yaml\n"
                              + yaml.safe_dump(self.timeline(), sort_keys=False))]
        if plot:
            from ..plotting.plan_plots import save_plan_png
            written.append(save_plan_png(self, directory / "plan.png"))
        return written


class Plan:
    """An optimal heating schedule for ``sim``'s robot (module docstring).

    Parameters
    ----------
    sim : Simulation
        Its heated TCAs' drives (``power``) and the rest of its parameters; its timeline is not
        used (the plan is the timeline).
    target : array_like (3,), or a path ``(times (m,) [s], positions (m, 3) [m])``
        Target tip position [m] (global); for ``track``, the path (linear between its times,
        held before the first and after the last).
    objective : {"time", "energy", "track"}
    horizon : float
        [s] from t = 0.
    nodes : int
        Time steps N on the horizon.
    vary : list of str, optional
        ``MODULE.TCA.drive.value`` paths of the inputs (default every heated TCA's).
    bounds : (float or str, float or str), optional
        For every input, in its drive's unit (W, V or A; a string may carry its unit, "3 V";
        default 0 to the value that holds the TCA at its type's ``max_temperature``).
    tolerance : float
        Tip distance [m] within which the target counts as reached.
    by : float, optional
        ``energy``: the time [s] from which the tip must stay within the tolerance (default the
        horizon's end).
    initial_temperatures : array_like, optional
        The heated TCAs' temperatures [degC] at t = 0 (default the steady state of their drives;
        a controller plans from measured ones, :meth:`restart`).
    point : str
        'tip' or a module's name: the point (its end) brought to the target.
    direction : array_like (3,), optional
        Also aim the point's tangent ``R e_z`` along this direction (``time`` and ``energy``),
        reached within ``angle_tolerance`` [rad].
    power_budget : float, optional
        [W]: the heated TCAs' total electrical power at every step stays at or below it (the
        inputs not varied included).
    """

    def __init__(self, sim, target, objective="time", horizon=10.0, nodes=60, vary=None, bounds=None,
                 tolerance=1e-4, by=None, initial_temperatures=None, point="tip", direction=None,
                 angle_tolerance=np.radians(1.0), power_budget=None):
        from ..time_simulation.timeline import TimeSimulation
        if objective not in OBJECTIVES:
            raise ScenarioError(f"{flag('--objective')} {objective!r}: one of {', '.join(OBJECTIVES)}")
        if not horizon > 0 or not np.isfinite(horizon):
            raise ScenarioError(f"{flag('--horizon')} must be positive (got {horizon:g} s)")
        if int(nodes) < 1:
            raise ScenarioError(f"{flag('--nodes')} must be at least 1 (got {nodes})")
        if not tolerance > 0:
            raise ScenarioError(f"{flag('--tolerance')} must be positive (got {tolerance:g} m)")
        self.sim, self.objective, self.horizon, self.nodes = sim, objective, float(horizon), int(nodes)
        self.tolerance = float(tolerance)
        self.point, self.point_index = self._point(point)
        self.direction, self.angle_tolerance = self._direction(direction), float(angle_tolerance)
        if not self.angle_tolerance > 0:
            raise ScenarioError(f"{flag('--angle-tolerance')} must be positive (got {np.degrees(self.angle_tolerance):g} deg)")
        self.step = self.horizon / self.nodes
        self.targets = self._targets(target)
        self.by = self.horizon if by is None else float(by)
        if objective == "energy" and not 0 <= self.by <= self.horizon:
            raise ScenarioError(f"{flag('--by')} {self.by:g} s is outside the horizon (0 to {self.horizon:g} s)")
        last = max((e.at + (e.ramp or 0.0) for e in sim.scenario.timeline), default=0.0)
        timed = TimeSimulation(sim, duration=max(self.horizon, last), dt=self.step)
        self.heated, self.laws, self.coupling = timed.heated, timed.laws, timed.coupling
        if not self.heated:
            raise ScenarioError("plan: no TCA is heated electrically; give the TCAs to plan a drive "
                                "(e.g. drive: {kind: power, value: 0})")
        kinds = {a.key: TimeSimulation._drive(sim.scenario, a).kind for a in self.heated}
        other = {key: kind for key, kind in kinds.items() if kind not in PLANNED_KINDS}
        if other:
            raise ScenarioError("plan: power, voltage and current drives are planned; " + ", ".join(
                f"{key} has a {kind} drive" for key, kind in other.items()))
        for actuator, law in zip(self.heated, self.laws):
            if kinds[actuator.key] != "power" and law.resistance_coefficient != 0:
                raise ModelError(f"plan: {actuator.key} has a {kinds[actuator.key]} drive through a resistance that "
                                    "changes with temperature (its type's resistance_temperature_coefficient is "
                                    f"{law.resistance_coefficient:g} 1/K): its power is then not a function of its "
                                    "input alone; plan with a power drive, or set the coefficient to 0")
        self.keys = [a.key for a in self.heated]
        self.paths = self._varied(vary)
        self.kinds = [kinds[self._key_of(path)] for path in self.paths]
        self.resistances = [float(self.laws[self.keys.index(self._key_of(path))].resistance) for path in self.paths]
        self.ambient = float(sim.scenario.ambient_temperature)
        drives = timed.drives()
        self.powers0 = np.array([power_of(d.kind, law.resistance, d.schedule(0.0, left=True))
                                 for d, law in zip(drives, self.laws)], float)
        self.T0 = (steady_state(self.laws, drives, self.ambient, self.coupling)[:, 0] if initial_temperatures is None
                   else np.asarray(initial_temperatures, float).reshape(len(self.heated)))
        self.max_temperatures = np.array([a.law.max_temperature for a in self.heated], float)
        self.bounds = self._bounds(bounds)
        self._thermal_matrices()
        self.power_budget = self._budget(power_budget)
        self.temperature_index = [sim.robot.layout[a.parameter].start for a in self.heated]
        self._equilibria = None

    # ------------------------------------------------------------------ set-up
    def _targets(self, target):
        """(N + 1, 3) [m]: the target at every node (a path interpolated at the node times)."""
        times = np.arange(self.nodes + 1) * self.step
        if self.objective != "track":
            return np.tile(np.asarray(target, float).reshape(3), (self.nodes + 1, 1))
        path_times, positions = (np.asarray(part, float) for part in target)
        if path_times.ndim != 1 or positions.shape != (path_times.size, 3) or path_times.size < 1:
            raise ScenarioError(f"plan {flag('--path')}: give times (m,) and positions (m, 3)")
        if np.any(np.diff(path_times) <= 0):
            raise ScenarioError(f"plan {flag('--path')}: the times must increase from row to row")
        return np.column_stack([np.interp(times, path_times, positions[:, j]) for j in range(3)])

    def _point(self, point):
        """``(name, module index)`` of the point aimed: 'tip' or a module (its end)."""
        from ..scenario.sources import did_you_mean
        names = [module.name for module in self.sim.robot.modules]
        if point in (None, "tip"):
            return "tip", self.sim.robot.tip_index
        if point not in names:
            raise ScenarioError(f"{flag('--point')} {point!r} is not 'tip' or a module" + did_you_mean(point, names))
        return point, names.index(point)

    def _direction(self, direction):
        """The unit target direction (3,), or None."""
        if direction is None:
            return None
        if self.objective == "track":
            raise ScenarioError(f"plan {flag('--objective')} track follows positions; a {flag('--target-direction')} is for time and energy")
        from ..studies.inverse.targets import Target
        return Target.create(np.zeros(3), direction).direction

    @staticmethod
    def _key_of(path):
        """The TCA key of a varied drive path (``MODULE.TCA.drive.value`` -> ``MODULE.TCA``)."""
        return path.rsplit(".drive.value", 1)[0]

    def _varied(self, vary):
        from ..scenario.sources import did_you_mean
        known = {f"{key}.drive.value": key for key in self.keys}
        if not vary:
            return list(known)
        for path in vary:
            if path not in known:
                raise ScenarioError(f"{flag('--vary')} {path!r} is not a heated TCA's drive value"
                                    + did_you_mean(path, list(known)))
        return list(dict.fromkeys(vary))

    def _bounds(self, bounds):
        """(k, 2) [W]: the powers of the given bounds (each in its input's unit), or 0 to each
        varied TCA's holding power at ``max_temperature``."""
        from ..scenario.schema import DRIVE_UNITS
        from ..units import to_si
        rows = []
        for path, kind, resistance in zip(self.paths, self.kinds, self.resistances):
            j = self.keys.index(self._key_of(path))
            if bounds is None:
                rows.append((0.0, self.laws[j].conductance * (self.max_temperatures[j] - self.ambient)))
                continue
            try:
                values = [float(to_si(b, DRIVE_UNITS[kind])) for b in bounds]
            except (TypeError, ValueError) as exc:
                raise ScenarioError(f"{flag('--bounds')} for {path} (a {kind} drive, in {DRIVE_UNIT[kind]}): {exc}") from None
            if values[0] < 0 or values[1] <= values[0]:
                raise ScenarioError(f"{flag('--bounds')} {values[0]:g} {values[1]:g} {DRIVE_UNIT[kind]}: give 0 <= LO < HI "
                                    f"(a {kind} drive's value cannot be negative)")
            rows.append(tuple(float(power_of(kind, resistance, v)) for v in values))
        return np.array(rows, float)

    def _budget(self, budget):
        """The power budget [W] (None: none), checked against the inputs that are not varied, and
        each input's upper bound lowered to it (no single input may exceed it)."""
        if budget is None:
            return None
        budget, fixed = float(budget), float(np.sum(self._fixed))
        if not budget > 0 or not np.isfinite(budget):
            raise ScenarioError(f"{flag('--power-budget')} must be positive (got {budget:g} W)")
        if budget - fixed < self.bounds[:, 0].sum():
            raise ScenarioError(f"{flag('--power-budget')} {budget:g} W: the inputs that are not varied draw {fixed:g} W and the "
                                f"varied ones at least {self.bounds[:, 0].sum():g} W")
        self.bounds[:, 1] = np.minimum(self.bounds[:, 1], budget - fixed)
        if np.any(self.bounds[:, 1] <= self.bounds[:, 0]):
            raise ScenarioError(f"{flag('--power-budget')} {budget:g} W leaves an input no range above its lower bound")
        return budget

    def _budget_rows(self):
        """``(S (N, N k), headroom (N,))``: each step's sum of the varied inputs, and what the
        budget leaves them (inf without one)."""
        k = len(self.paths)
        S = np.kron(np.eye(self.nodes), np.ones((1, k)))
        room = np.inf if self.power_budget is None else self.power_budget - float(np.sum(self._fixed))
        return S, np.full(self.nodes, room)

    def _thermal_matrices(self):
        """``T_k = T_free[k] + M[k] u`` for k = 0..N (u: the inputs, node-major, (N k,)): the
        step (``zero_order_hold``) and ``M`` once, ``T_free`` from ``T0`` (:meth:`_free_response`)."""
        n, k, N = len(self.keys), len(self.paths), self.nodes
        self._hold = zero_order_hold(self.laws, self.ambient, self.step, self.coupling)
        Phi, Gamma, _ = self._hold
        E = np.zeros((n, k))
        for i, path in enumerate(self.paths):
            E[self.keys.index(self._key_of(path)), i] = 1.0
        self._fixed = self.powers0 * (1.0 - E.sum(axis=1))            # the inputs not varied keep their value
        self.fixed_powers = {key: float(p) for key, p in zip(self.keys, self._fixed)
                             if E[self.keys.index(key)].sum() == 0}
        self.M = np.zeros((N + 1, n, N * k))
        for step in range(N):
            self.M[step + 1] = Phi @ self.M[step]
            self.M[step + 1][:, step * k:(step + 1) * k] += Gamma @ E
        self._fixed_energy = float(np.sum(self._fixed)) * self.horizon
        self._free_response()

    def _free_response(self):
        """``T_free`` (N + 1, n) [degC]: the temperatures from ``T0`` with no varied input."""
        Phi, Gamma, offset = self._hold
        self.T_free = np.zeros((self.nodes + 1, len(self.keys)))
        self.T_free[0] = self.T0
        for step in range(self.nodes):
            self.T_free[step + 1] = Phi @ self.T_free[step] + Gamma @ self._fixed + offset

    def restart(self, initial_temperatures, target=None):
        """Plan again from ``initial_temperatures`` [degC] (and a new ``target``), keeping the
        built matrices and every node's last equilibrium as Newton's starts."""
        self.T0 = np.asarray(initial_temperatures, float).reshape(len(self.heated))
        if target is not None:
            self.targets = self._targets(target)
        self._free_response()

    def temperatures(self, u):
        """(N + 1, n) [degC] at the inputs ``u`` ((N k,) W)."""
        return self.T_free + self.M @ np.asarray(u, float)

    # ------------------------------------------------------------------ equilibria
    def _start(self):
        """The equilibrium at t = 0 (the scenario's parameters at the initial temperatures)."""
        sim = self.sim
        params = sim.params.copy()
        params[self.temperature_index] = self.T0
        first = sim.solve_at(params)
        if not first.converged:
            raise SolverError(f"plan: no equilibrium at t = 0: {first.message}")
        solver = sim.solver()
        return solver, [first.iterate.w] * (self.nodes + 1), [None] * (self.nodes + 1)

    def nodes_at(self, u, derivatives=False):
        """``(tips (N + 1, 3) [m], dtips (N + 1, 3, N k) or None)`` at the inputs ``u``: the
        aimed point's position at every node (:meth:`poses_at`)."""
        poses, dposes = self.poses_at(u, derivatives)
        return poses[:, 0:3], None if dposes is None else dposes[:, 0:3]

    def _pose_function(self):
        """``(w, P) -> (y, dy/dw, dy/dP)``: the aimed point's position and tangent ``y = [p; R
        e_z]`` (6,) and their derivatives (buffered; patterns to wrap them as sparse matrices)."""
        if getattr(self, "_pose", None) is None:
            import casadi as ca

            from ..model.rotations import rotation_matrix
            from ..buffers import BufferedFunction, CscPattern
            nlp = self._equilibria[0].nlp
            w, P = ca.SX.sym("w", nlp.w.numel()), ca.SX.sym("P", nlp.P.numel())
            ends = nlp.outputs.expand()(w, P)[1]
            m = self.point_index
            y = ca.vertcat(ends[0:3, m], rotation_matrix(ends[3:7, m])[:, 2])
            function = ca.Function("pose", [w, P], [y, ca.jacobian(y, w), ca.jacobian(y, P)])
            self._pose = (BufferedFunction(function), [CscPattern(function.sparsity_out(k)) for k in (1, 2)])
        return self._pose

    def poses_at(self, u, derivatives=False):
        """``(poses (N + 1, 6), dposes (N + 1, 6, N k) or None)`` at the inputs ``u``: the aimed
        point's position [m] and tangent at every node's equilibrium (warm Newton from the last
        evaluation's, continuation where that fails) and their derivatives by the implicit
        function theorem."""
        if self._equilibria is None:
            self._equilibria = self._start()
        solver, ws, lus = self._equilibria
        pose, patterns = self._pose_function()
        T = self.temperatures(u)
        tips = np.zeros((self.nodes + 1, 6))
        dtips = np.zeros((self.nodes + 1, 6, self.M.shape[2])) if derivatives else None
        selector = np.zeros((self.sim.params.size, len(self.keys)))
        selector[self.temperature_index, np.arange(len(self.keys))] = 1.0
        tolerance = self.sim.scenario.solver.tolerance
        for k in range(self.nodes + 1):
            params = self.sim.params.copy()
            params[self.temperature_index] = T[k]
            w, status = solver.square.newton(ws[k], params, tolerance, lu=lus[k])
            if not status.success:
                solution = self.sim.solve_at(params)
                if not solution.converged:
                    raise _NoEquilibrium(k, self.step * k, solution.message)
                w = solution.iterate.w
            ws[k], lus[k] = w, solver.square.last_lu
            y, y_w, y_P = pose(w, params)
            tips[k] = y
            if derivatives and k > 0:             # (node 0's temperatures are measured or given: M_0 = 0)
                rates, lus[k] = solver.square.state_derivative(w, params, selector)
                by_w, by_P = (pattern.matrix(values) for pattern, values in zip(patterns, (y_w, y_P)))
                dtips[k] = (by_w @ rates + by_P @ selector) @ self.M[k]
        return tips, dtips

    def solutions(self, plan):
        """One :class:`~tca_casadi.solution.Solution` per node of ``plan`` (this planner's
        result): the robot's equilibrium at the node's planned temperatures (Newton from the
        node's last equilibrium; the frames of ``plan --animation``)."""
        out = []
        for k, temperatures in enumerate(plan.temperatures):
            params = self.sim.params.copy()
            params[self.temperature_index] = temperatures
            start = self._equilibria[1][k] if self._equilibria is not None else None
            solution = (self.sim.solver().solve_newton(params, start) if start is not None else None)
            if solution is None or not solution.converged:
                solution = self.sim.solve_at(params)
            out.append(solution)
        return out

    # ------------------------------------------------------------------ objectives
    def solve(self, progress=None, start=None):
        """The plan (:class:`PlanResult`); ``progress(fraction, text)`` after each phase;
        ``start``: the inputs (N k,) [W] to start from (default the holding powers of the
        inverse-statics answer, :meth:`initial_inputs`)."""
        started = time.perf_counter()
        try:
            u, status, evaluations = self._fastest(start)
            if self.objective == "energy":
                if progress:
                    progress(0.5, "least energy")
                u, status, more = self._least_energy(u)
                evaluations += more
        except _NoEquilibrium as exc:
            u = getattr(self, "_last_u", np.zeros(self.M.shape[2]))
            status = SolveStatus(Status.NO_EQUILIBRIUM, "plan", detail=str(exc))
            evaluations = 0
        return self._result(u, status, evaluations, time.perf_counter() - started)

    def initial_inputs(self):
        """(N k,) [W]: for each varied TCA, the bang-bang way to the temperature ``T*`` that
        inverse statics finds for the target (its nearest pose if unreachable): the bound towards
        ``T*`` while a whole step does not pass it, the power that lands on it, then its holding
        power ``G (T* - T_amb)``, from the TCA's own thermal step (coupling ignored). For one TCA
        that is the minimum-time plan itself, so least squares starts next to its answer."""
        from ..studies.inverse.statics import InverseStatics
        from ..studies.inverse.targets import Target
        varied = [self.keys.index(self._key_of(path)) for path in self.paths]
        conductance = np.array([self.laws[j].conductance for j in varied])
        low = float(np.max(self.ambient + self.bounds[:, 0] / conductance))
        high = float(np.min(self.ambient + self.bounds[:, 1] / conductance))
        inverse = InverseStatics(self.sim, vary=[f"{self.keys[j]}.temperature" for j in varied],
                                 bounds=(low, max(high, low + 1e-3)), tolerance=self.tolerance,
                                 angle_tolerance=self.angle_tolerance)
        answer = inverse.solve(Target.create(self.targets[-1], self.direction, point=self.point))
        hold = np.array([answer.temperatures[f"{self.keys[j]}.temperature"] for j in varied])
        inputs = np.empty((self.nodes, len(varied)))
        for i, j in enumerate(varied):
            law = self.laws[j]
            decay = np.exp(-self.step * law.conductance / law.heat_capacity)      # T' = a T + (1 - a)(T_amb + P/G)
            temperature = self.T0[j]
            for step in range(self.nodes):
                landing = law.conductance * ((hold[i] - decay * temperature) / (1 - decay) - self.ambient)
                inputs[step, i] = np.clip(landing, self.bounds[i, 0], self.bounds[i, 1])
                temperature = decay * temperature + (1 - decay) * (self.ambient + inputs[step, i] / law.conductance)
        return inputs.ravel()

    def _scaled(self):
        lo = np.tile(self.bounds[:, 0], self.nodes)
        hi = np.tile(self.bounds[:, 1], self.nodes)
        return lo, hi

    def _fastest(self, start=None):
        """Least squares of the tip error at every node (the ``time`` and ``track`` objectives),
        from the inputs ``start`` (default :meth:`initial_inputs`)."""
        from scipy.optimize import least_squares
        lo, hi = self._scaled()
        span = hi - lo
        weight = np.sqrt(REGULARISATION)
        T_max = np.tile(self.max_temperatures, self.nodes + 1)
        cache = {}

        def evaluate(x, derivatives=False):
            """``(u, tips, dtips)`` at x; the derivatives only when asked (trial points that
            least squares rejects need none)."""
            key = x.tobytes()
            if key not in cache or (derivatives and cache[key][2] is None):
                cache.clear()
                u = lo + span * x
                self._last_u = u
                cache[key] = (u, *self.poses_at(u, derivatives=derivatives))
            return cache[key]

        goal, scale = self._goal()
        S, room = self._budget_rows()

        def residuals(x):
            u, poses, _ = evaluate(x)
            over = np.maximum(self.temperatures(u).ravel() - T_max, 0.0) / TEMPERATURE_SLACK
            spent = np.maximum(S @ u - room, 0.0) / POWER_SLACK
            return np.concatenate([((poses[:, :goal.shape[1]] - goal) / scale).ravel(), weight * x, over, spent])

        def jacobian(x):
            u, _, dposes = evaluate(x, derivatives=True)
            hot = (self.temperatures(u).ravel() - T_max > 0)[:, None]
            dT = self.M.reshape(-1, self.M.shape[2]) * span / TEMPERATURE_SLACK
            rates = dposes[:, :goal.shape[1]] / scale[:, None]
            spending = np.where((S @ u - room > 0)[:, None], S * span / POWER_SLACK, 0.0)
            return np.vstack([rates.reshape(-1, dposes.shape[2]) * span, weight * np.eye(x.size), np.where(hot, dT, 0.0),
                              spending])

        x0 = np.clip(((self.initial_inputs() if start is None else np.asarray(start, float)) - lo) / span, 0.0, 1.0)
        found = least_squares(residuals, x0, jac=jacobian, bounds=(0.0, 1.0), method="trf", xtol=1e-10,
                              ftol=1e-12, gtol=1e-10, max_nfev=200)
        u = lo + span * found.x
        failure = None if found.status > 0 else Status.MAX_ITERATIONS if found.status == 0 else Status.ALGORITHM_FAILED
        residual = self._limit_violation(u)
        status = SolveStatus.judged("least squares (trf)", residual, 1.0, failure, nit=int(found.nfev),
                                    detail=f"least squares: {found.message}")
        return u, status, int(found.nfev)

    def _limit_violation(self, u):
        """How far ``u`` passes the limits, in their slacks (<= 1: within): the temperatures above
        ``max_temperature`` over :data:`TEMPERATURE_SLACK`, the total power above the budget over
        :data:`POWER_SLACK`."""
        S, room = self._budget_rows()
        hot = float(np.max(self.temperatures(u) - self.max_temperatures)) / TEMPERATURE_SLACK
        spent = float(np.max(S @ u - room)) / POWER_SLACK if S.size else 0.0
        return max(hot, spent, 0.0)

    def _goal(self):
        """``(goal (N + 1, 3 or 6), scale (3 or 6,))``: what the aimed point's pose should be at
        every node (its position; with a direction, its tangent too) and the error that costs 1
        (the tolerances)."""
        if self.direction is None:
            return self.targets, np.full(3, self.tolerance)
        return (np.hstack([self.targets, np.tile(self.direction, (self.nodes + 1, 1))]),
                np.r_[np.full(3, self.tolerance), np.full(3, self.angle_tolerance)])

    def _least_energy(self, u0):
        """The least electrical energy with the tip within the tolerance from ``by`` on (SLSQP)."""
        from scipy.optimize import minimize
        lo, hi = self._scaled()
        span = hi - lo
        late = np.flatnonzero(np.arange(self.nodes + 1) * self.step >= self.by - 1e-9 * self.step)
        T_max = self.max_temperatures
        M = self.M.reshape(-1, self.M.shape[2])
        cache, count = {}, [0]

        def evaluate(x):
            key = x.tobytes()
            if key not in cache:
                cache.clear()
                count[0] += 1
                u = lo + span * x
                self._last_u = u
                cache[key] = self.poses_at(u, derivatives=True)
            return cache[key]

        goal, scale = self._goal()
        box = MARGIN * scale / np.sqrt(3.0)            # per coordinate: the box inside the tolerance's ball

        def reach(x):                      # >= 0: each coordinate within the tolerance box from ``by`` on
            poses, _ = evaluate(x)
            error = ((poses[late, :goal.shape[1]] - goal[late]) / box).ravel()
            return np.concatenate([1.0 - error, 1.0 + error])

        def reach_jacobian(x):
            _, dposes = evaluate(x)
            rate = (dposes[late, :goal.shape[1]] / box[:, None]).reshape(-1, dposes.shape[2]) * span
            return np.vstack([-rate, rate])

        cool = {"type": "ineq", "fun": lambda x: (np.tile(T_max, self.nodes + 1) - (self.T_free.ravel() + M @ (lo + span * x))),
                "jac": lambda x: -M * span}
        S, room = self._budget_rows()
        limits = [cool] if self.power_budget is None else [
            cool, {"type": "ineq", "fun": lambda x: room - S @ (lo + span * x), "jac": lambda x: -S * span}]
        energy = self.step * span / np.sum(span)                       # scaled: the energy per full range
        found = minimize(lambda x: float(energy @ x), (u0 - lo) / span, jac=lambda x: energy, method="SLSQP",
                         bounds=[(0.0, 1.0)] * lo.size,
                         constraints=[{"type": "ineq", "fun": reach, "jac": reach_jacobian}] + limits,
                         options={"maxiter": 200, "ftol": 1e-9})
        x = np.clip(found.x, 0.0, 1.0)
        u = lo + span * x
        # in units of what is allowed: 1e-6 of the reach box, the limits' slacks (<= 1: within)
        violation = max(float(-np.min(reach(x))) / 1e-6, self._limit_violation(u), 0.0)
        failure = None if found.success else Status.ALGORITHM_FAILED
        status = SolveStatus.judged("SLSQP", violation, 1.0, failure, nit=int(found.nit),
                                    detail=f"SLSQP: {found.message}")
        return u, status, count[0]

    # ------------------------------------------------------------------ the result
    def _result(self, u, status, evaluations, seconds):
        poses = self.poses_at(u)[0] if status.status != Status.NO_EQUILIBRIUM else np.full((self.nodes + 1, 6), np.nan)
        tips = poses[:, 0:3]
        errors = np.linalg.norm(tips - self.targets, axis=1)
        angles = None
        worst = errors / self.tolerance
        if self.direction is not None:
            angles = np.arccos(np.clip(poses[:, 3:6] @ self.direction / np.linalg.norm(poses[:, 3:6], axis=1), -1.0, 1.0))
            worst = np.maximum(worst, angles / self.angle_tolerance)
        reached = held_from(np.arange(self.nodes + 1) * self.step, worst, 1.0)
        message = ""
        if self.objective == "energy" and (reached is None or reached > self.by + 1e-9):
            status = status.replace(status=Status.ABOVE_TOLERANCE) if status.success else status
            message = (f"the target cannot be held from {self.by:g} s within these bounds"
                       + (f" (the fastest plan holds it from {reached:g} s)" if reached is not None else ""))
        elif reached is None and self.objective == "track" and status.status != Status.NO_EQUILIBRIUM:
            message = (f"the tip is not within the tolerance of the path at the horizon's end ({errors[-1] * 1e3:.4g} mm "
                       f"away; RMS distance {np.sqrt(np.mean(errors[1:] ** 2)) * 1e3:.4g} mm)")
        elif reached is None and status.status != Status.NO_EQUILIBRIUM:
            closest = int(np.argmin(worst))
            message = (f"the target is not reached within the horizon: the closest pose is "
                       f"{errors[closest] * 1e3:.4g} mm away" + ("" if angles is None else
                                                               f" and {np.degrees(angles[closest]):.3g} deg off the direction")
                       + f" (raise {flag('--horizon')} or the {flag('--bounds')}, or move the target)")
        u = np.asarray(u, float).reshape(self.nodes, len(self.paths))
        energy = float(np.sum(u) * self.step) + self._fixed_energy
        status = status.replace(solve_time_s=seconds, nit=evaluations)
        t = np.arange(self.nodes + 1) * self.step
        return PlanResult(self.objective, t, list(self.paths), u, list(self.keys), self.temperatures(u.ravel()),
                          self.max_temperatures, tips, errors, self.targets, self.tolerance, status, energy, reached,
                          self.by if self.objective == "energy" else None, message, self.bounds, self.fixed_powers,
                          list(self.kinds), list(self.resistances), self.point, self.direction, angles,
                          self.angle_tolerance if self.direction is not None else None, self.power_budget)


def held_from(t, errors, tolerance):
    """The first of the times ``t`` from which ``errors`` stay within ``tolerance`` to the end
    (None when the last is not within it)."""
    within = np.asarray(errors) <= tolerance
    if not within[-1]:
        return None
    k = len(within) - 1
    while k > 0 and within[k - 1]:
        k -= 1
    return float(t[k])


def read_path(path, label=f"plan {flag('--path')}"):
    """``(times (m,) [s], positions (m, 3) [m])`` of a CSV with columns ``t``, ``x``, ``y``,
    ``z`` (units in the header: ``t [s]``, ``x [mm]``; none: SI), times increasing. Read by
    :func:`tca_casadi.tables.read_table` (one-line errors for any bad file, naming ``label``)."""
    from ..tables import name_of, read_table
    table = read_table(path, label, "tip path", required=("t", "x", "y", "z"))
    columns = {name_of(name).lower(): k for k, name in enumerate(table.header)}
    times = np.array([table.quantity(k, columns["t"], "time") for k in range(len(table.rows))])
    positions = np.array([[table.quantity(k, columns[c], "length") for c in "xyz"] for k in range(len(table.rows))])
    if not len(times):
        raise ScenarioError(f"{label}: {path}: no rows (a header t, x, y, z, then one row per point)")
    later = np.flatnonzero(np.diff(times) <= 0)
    if later.size:
        raise ScenarioError(f"{table.where(int(later[0]) + 1)}: the times must increase from row to row")
    return times, positions


class _NoEquilibrium(Exception):
    def __init__(self, node, t, message):
        super().__init__(f"no equilibrium at node {node} (t = {t:g} s): {message}")

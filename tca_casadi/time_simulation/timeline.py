"""``tca-casadi simulate``: a scenario's ``timeline`` run in time (issue 15).

The scenario at t = 0 is the state before the first event. Each event sets values by dotted
path (drive values, temperatures, tensions, loads, the base pose, an object's ``held``), at once
or linearly over its ramp; the values between events follow from the scenario after each event.
TCAs with a ``power``, ``voltage`` or ``current`` drive get their temperatures from the thermal
model (:mod:`tca_casadi.solvers.thermal`), starting from the steady state of their drive at
t = 0; every other parameter follows the timeline. At every output time the quasi-static
equilibrium is followed from the previous one (:func:`~tca_casadi.time_simulation.heating.follow_parameters`).
"""
import copy

import numpy as np

from ..errors import ScenarioError, flag
from ..catalogue import thermal_kinds
from ..scenario.loader import validate
from ..scenario.overrides import apply_overrides, without_set
from ..solvers.thermal import Drive, Schedule, integrate, steady_state
from .heating import TimeSeries, follow_parameters
from ..text import signed

#: drive kinds the thermal model heats (``temperature`` sets the temperature directly)
HEATED = ("power", "voltage", "current", "setpoint")


def step_response(t, y, start, end):
    """10-90 % rise time and 2 % settling time [s] of the signal ``y`` (at times ``t``) after
    an event at ``start``, the window ending at ``end`` (the next event or the end of the run):
    measured from ``start`` against the change from ``y(start)`` to ``y(end)`` (crossings
    interpolated linearly between output times). ``{"change", "rise_time", "settling_time"}``;
    the times are None when the signal does not change."""
    inside = (t >= start - 1e-12) & (t <= end + 1e-12)
    t, y = np.asarray(t, float)[inside], np.asarray(y, float)[inside]
    change = float(y[-1] - y[0]) if y.size else 0.0
    if y.size < 2 or abs(change) <= 1e-12 * max(1.0, float(np.max(np.abs(y)))):
        return {"change": change, "rise_time": None, "settling_time": None}
    progress = (y - y[0]) / change

    def crossing(level):
        k = int(np.argmax(progress >= level))
        if k == 0:
            return float(t[0])
        return float(t[k - 1] + (level - progress[k - 1]) / (progress[k] - progress[k - 1]) * (t[k] - t[k - 1]))

    outside = np.flatnonzero(np.abs(progress - 1.0) > 0.02)
    if outside.size == 0:
        settled = float(t[0])
    else:
        k = outside[-1]              # the last output outside the band; it enters between k and k + 1
        excess = abs(progress[k] - 1.0) - 0.02
        after = abs(progress[k + 1] - 1.0) - 0.02
        settled = float(t[k] + excess / (excess - after) * (t[k + 1] - t[k]))
    return {"change": change, "rise_time": crossing(0.9) - crossing(0.1), "settling_time": settled - float(t[0])}


#: output times (time steps, with dynamics) a run may have at most: each is an equilibrium kept
#: in memory and a row of timeseries.csv
MAX_OUTPUT_TIMES = 1_000_000
#: memory kept per output time: bytes per node of the robot's mesh (states, rotations, internal
#: forces, actuator paths: measured 700-900 on the shipped robots) and per output
BYTES_PER_NODE, BYTES_PER_OUTPUT = 1000, 4000


def check_run_size(sim, duration, dt, events=0):
    """ScenarioError (one line: the number and the limit) before a run of ``duration`` [s] at
    ``dt`` [s] starts, when it has more output times than :data:`MAX_OUTPUT_TIMES` or they
    would need more memory than the machine has available."""
    from ..resources import available_memory, readable_bytes
    count = duration / dt + 1 + 2 * events
    what = "time steps" if sim.scenario.dynamics.enabled else "output times"
    asked = f"{flag('--duration')} {duration:g} s at {flag('--dt')} {dt:g} s"
    if not count <= MAX_OUTPUT_TIMES:
        number = f"{count:,.0f}" if count < 1e12 else f"{count:.3g}"
        raise ScenarioError(f"simulate: {asked} is {number} {what}; at most {MAX_OUTPUT_TIMES:,} are kept: "
                            f"raise {flag('--dt')} or shorten the duration")
    need = count * (BYTES_PER_OUTPUT + BYTES_PER_NODE * _mesh_nodes(sim))
    available = available_memory()
    if available is not None and need > 0.8 * available:
        raise ScenarioError(f"simulate: {asked} is {count:,.0f} {what} of this robot, about {readable_bytes(need)} to "
                            f"keep, more than the {readable_bytes(available)} available: raise {flag('--dt')} or shorten the duration")


def _mesh_nodes(sim):
    """Nodes of the robot's starting mesh (before any refinement): intervals (d + 1) + 1 per module."""
    from ..discretisation.mesh import build_mesh
    options = sim.scenario.solver
    return sum(len(build_mesh(sim.robot, m, options.intervals).intervals) * (options.degree + 1) + 1
               for m in range(len(sim.robot.modules)))


class _TemperatureDrive:
    """The default drive: the scenario's temperature, set directly."""
    kind = "temperature"

    def __init__(self, value):
        self.value = value


def mpc_drives(scenario):
    """``[(MODULE.TCA, drive)]`` of the scenario's ``kind: mpc`` drives (run by
    :class:`tca_casadi.control.ClosedLoop`, not by the open-loop timeline)."""
    return [(f"{module.name}.{actuator.name}", actuator.drive) for module in scenario.modules
            for actuator in module.actuators
            if getattr(actuator, "drive", None) is not None and actuator.drive.kind == "mpc"]


class TimeSimulation:
    """A :class:`~tca_casadi.simulation.Simulation`'s timeline, ready to run.

    Parameters
    ----------
    sim : Simulation
        Its scenario holds ``duration``, ``timeline`` and the TCAs' ``drive`` s.
    duration : float, optional
        [s]; default the scenario's ``duration``, else the last event plus its ramp.
    dt : float
        Output step [s]; event times and ramp ends are output times too.
    """

    def __init__(self, sim, duration=None, dt=0.1):
        self.sim = sim
        scenario = sim.scenario
        if mpc_drives(scenario):
            raise ScenarioError(f"{', '.join(k for k, _ in mpc_drives(scenario))}: an mpc drive runs in the closed loop "
                                "(tca_casadi.control.ClosedLoop; tca-casadi simulate runs it)")
        events = scenario.timeline
        ends = [e.at + (e.ramp or 0.0) for e in events]
        self.duration = float(duration or scenario.duration or (max(ends) if ends else 0.0))
        if not self.duration > 0:
            raise ScenarioError(f"simulate needs a duration (the scenario's duration, {flag('--duration')}, or a timeline)")
        if not dt > 0:
            raise ScenarioError(f"{flag('--dt')} must be positive (got {dt:g})")
        if ends and max(e.at for e in events) > self.duration:
            raise ScenarioError(f"the timeline's last event ({max(e.at for e in events):g} s) is after the "
                                f"duration ({self.duration:g} s)")
        self.dt = float(dt)
        check_run_size(sim, self.duration, self.dt, len(events))
        if scenario.dynamics.enabled:
            from .motion import check_dynamics
            check_dynamics(sim, self.dt)
        self._parameter_schedule = None
        self.states = self._states_after_events()
        self.heated = [a for a in sim.robot.thermal_actuators if self._drive(scenario, a).kind in HEATED]
        self.laws = [a.thermal_law(scenario) for a in self.heated]
        for actuator, law in zip(self.heated, self.laws):
            kind = self._drive(scenario, actuator).kind
            if kind in ("voltage", "current") and not law.resistance > 0:
                raise ScenarioError(f"{actuator.key}: a {kind} drive needs {actuator.type_path}.resistance")
            if kind == "setpoint":
                highest = max(self._drive(state, actuator).value for state, _ in self.states)
                limit = actuator.law.max_temperature
                if highest > limit:
                    raise ScenarioError(f"{actuator.key}: setpoint {highest:g} degC is above "
                                        f"{actuator.type_path}.max_temperature ({limit:g} degC)")
        self.coupling = self._coupling()

    def _coupling(self):
        """The (heated, heated) conductances [W/K] of the modules' ``thermal_coupling`` (None
        when there is none). A coupling needs both TCAs heated: a TCA whose temperature is set
        has no heat balance to take the heat."""
        keys = [a.key for a in self.heated]
        matrix = np.zeros((len(keys), len(keys)))
        for module in self.sim.scenario.modules:
            coupling = module.thermal_coupling
            if coupling is None:
                continue
            names = [a.name for a in module.actuators if a.kind in thermal_kinds()]
            pairs = coupling.between or [(a, b) for i, a in enumerate(names) for b in names[i + 1:]]
            for pair in pairs:
                for name in pair:
                    if f"{module.name}.{name}" not in keys:
                        raise ScenarioError(f"{module.name}.thermal_coupling: {module.name}.{name} has its temperature "
                                            "set (no power, voltage, current or setpoint drive): give it a drive "
                                            "(e.g. {kind: power, value: 0}) so it can exchange heat")
                i, j = (keys.index(f"{module.name}.{name}") for name in pair)
                matrix[i, j] = matrix[j, i] = coupling.conductance
        return matrix if np.any(matrix) else None

    # ------------------------------------------------------------------ the timeline
    @staticmethod
    def _drive(scenario, actuator):
        config = next(a for a in scenario.modules[actuator.module].actuators if a.name == actuator.name)
        return config.drive or _TemperatureDrive(config.temperature)

    def _states_after_events(self):
        """``[(scenario, params)]``: at t = 0 and after each event (cumulative)."""
        sim = self.sim
        raw, sources = sim.scenario._raw, copy.deepcopy(sim.scenario._sources)   # the events' origins stay here
        if raw is None:
            raw, sources = sim.scenario.model_dump(mode="json"), None
        structure = sim.robot.structure_key(sim.scenario)
        states = [(sim.scenario, sim.params.copy())]
        if self.start_steps:            # the run starts where the sequence's steps took it
            for step in self.start_steps:
                raw = apply_overrides(raw, step.set, sources, label=f"sequence step {step.name!r}:")
            scenario = validate(raw, sources) if sources is not None else type(sim.scenario).model_validate(raw)
            states = [(scenario, sim.robot.parameter_vector(scenario))]
        for k, event in enumerate(sim.scenario.timeline):
            try:
                raw = apply_overrides(raw, event.set, sources)
                scenario = validate(raw, sources) if sources is not None else type(sim.scenario).model_validate(raw)
            except ScenarioError as exc:
                raise ScenarioError(f"timeline[{k}] (at {event.at:g} s): {without_set(str(exc))}") from None
            if sim.robot.structure_key(scenario) != structure:
                raise ScenarioError(f"timeline[{k}] (at {event.at:g} s): {', '.join(event.set)} changes the robot's "
                                    "structure; a timeline may only set parameters and drive values")
            states.append((scenario, self._with_set_temperatures(scenario, sim.robot.parameter_vector(scenario))))
        states[0] = (states[0][0], self._with_set_temperatures(states[0][0], states[0][1]))
        return states

    @property
    def start_steps(self):
        """The sequence steps a dynamic run starts after (``dynamics.start_after``): the
        scenario's ``sequence`` up to that step, or none."""
        scenario = self.sim.scenario
        start = scenario.dynamics.start_after if scenario.dynamics.enabled else None
        if start is None:
            return []
        names = [step.name for step in scenario.sequence]
        return list(scenario.sequence[:names.index(start) + 1])

    def _with_set_temperatures(self, scenario, params):
        """``params`` with each ``kind: temperature`` drive's value as its TCA's temperature."""
        params = params.copy()
        for actuator in self.sim.robot.thermal_actuators:
            config = next(a for a in scenario.modules[actuator.module].actuators if a.name == actuator.name)
            if config.drive is not None and config.drive.kind == "temperature":
                params[self.sim.robot.layout[actuator.parameter]] = config.drive.value
        return params

    def output_times(self):
        """``0, dt, 2 dt, ...`` up to the duration, with every event time and ramp end."""
        grid = np.arange(0.0, self.duration + 0.5 * self.dt, self.dt)
        marks = [t for e in self.sim.scenario.timeline for t in (e.at, e.at + (e.ramp or 0.0))]
        times = np.union1d(np.round(grid, 12), np.round([t for t in marks if t <= self.duration], 12))
        times = times[times <= self.duration + 1e-12]
        return times[np.r_[True, np.diff(times) > 1e-9]]         # a mark within 1 ns of a grid time is that time

    def _knots(self):
        """Knot times and the state index on each side: values are linear between knots."""
        knots = [(0.0, 0)]
        for k, event in enumerate(self.sim.scenario.timeline, start=1):
            knots += [(event.at, k - 1), (event.at + (event.ramp or 0.0), k)]
        return knots

    def parameters_at(self, t, left=False):
        """The parameter vector the timeline gives at ``t`` [s] (heated TCAs' temperatures aside;
        ``left``: before an event at ``t``)."""
        if self._parameter_schedule is None:
            knots = self._knots()
            self._parameter_schedule = Schedule(tuple(t for t, _ in knots), tuple(self.states[k][1] for _, k in knots))
        return self._parameter_schedule(t, left)

    def drives(self):
        """One :class:`Drive` per heated TCA: its value's schedule from the timeline."""
        out = []
        for actuator in self.heated:
            knots = self._knots()
            values = [float(self._drive(self.states[k][0], actuator).value) for _, k in knots]
            config = self._drive(self.sim.scenario, actuator)
            pi = {} if config.kind != "setpoint" else {"proportional": config.gains.proportional,
                                                       "integral": config.gains.integral,
                                                       "max_power": config.max_power}
            out.append(Drive(config.kind, Schedule(tuple(t for t, _ in knots), tuple(values)), **pi))
        return out

    # ------------------------------------------------------------------ running
    def run(self, progress=None):
        """Temperatures in time, then the equilibrium at every output time. Returns a
        :class:`TimeSeries` (``completed`` False and a ``message`` if it stopped)."""
        times = self.output_times()
        ambient = self.sim.scenario.ambient_temperature
        drives = self.drives()
        history = None
        if self.heated:
            initial = steady_state(self.laws, drives, ambient, self.coupling)      # before any event
            history = integrate(self.laws, drives, ambient, initial, times, self.coupling)
        layout, tcas = self.sim.robot.layout, self.sim.robot.thermal_actuators
        powers = np.full((times.size, len(tcas)), np.nan)
        path = []
        for k, t in enumerate(times):
            params = self.parameters_at(t)
            for j, actuator in enumerate(self.heated):
                params[layout[actuator.parameter]] = history.temperature[k, j]
                powers[k, tcas.index(actuator)] = history.power[k, j]
            path.append(params)
        temperatures = np.array([[p[layout[a.parameter]][0] for a in tcas] for p in path]).reshape(times.size, len(tcas))
        series = TimeSeries(times, [a.key for a in tcas], temperatures, powers)
        series.history = history
        for j, (actuator, law, drive) in enumerate(zip(self.heated, self.laws, drives)):
            if drive.kind in ("voltage", "current"):
                resistance = law.resistance_at(history.temperature[:, j])
                ratio = resistance if drive.kind == "voltage" else 1.0 / resistance
                series.electrical[actuator.key] = (drive.kind, np.sqrt(np.maximum(history.power[:, j], 0.0) * ratio))
        if self.sim.scenario.dynamics.enabled:
            from .motion import follow_dynamics
            initial = self.parameters_at(times[0], left=True)       # at rest before any event at t = 0
            for j, actuator in enumerate(self.heated):
                initial[layout[actuator.parameter]] = history.temperature[0, j]
            start = self._sequence_start(series) if self.start_steps else None
            if not self.start_steps or start is not None:
                follow_dynamics(self.sim, series, path, progress, initial, start=start)
        else:
            follow_parameters(self.sim, series, path, progress, careful=self._careful(times))
        self._track_objects(series)
        return series

    def _sequence_start(self, series):
        """The Solution the sequence reaches at ``dynamics.start_after`` (its steps solved in
        order on a copy of the simulation's parameters), or None with ``series.message`` saying
        which step did not converge."""
        from ..studies.sequence import run_sequence
        base = self.sim.params.copy()
        try:
            result = run_sequence(self.sim, self.start_steps)
        finally:
            self.sim.params = base
        for name, solution in zip(result.names, result.solutions):
            if not solution.converged:
                series.message = f"no start: sequence step {name!r} did not converge ({solution.message})"
                return None
        return result.solutions[-1]

    def _careful(self, times):
        """Outputs that take a full continuation step: the first one at or after each event
        (where its values may step) and the one after."""
        careful = np.zeros(times.size, bool)
        for event in self.sim.scenario.timeline:
            k = int(np.searchsorted(times, event.at - 1e-12))
            careful[k:k + 2] = True
        return careful

    def _track_objects(self, series):
        """Each object's pose at every solved output (picked when its ``held`` is set: the
        grasp checked as in ``sequence``; carried; put down). A grasp outside the object stops
        the run there; one not across the object's long axis is a warning."""
        from ..errors import PhysicsWarning
        from ..studies.sequence.objects import ObjectTracker
        from ..studies.sequence.steps import GRIP_ANGLE_TOLERANCE
        if not self.sim.scenario.objects:
            return
        tracker = ObjectTracker(self.sim.scenario, self.sim.robot)
        for k, solution in enumerate(series.outputs):           # a dynamic run's step outputs
            picked = [n for n in tracker.names if tracker.held_in(solution, n) and not tracker.poses[n].held]
            try:
                series.objects.append(tracker.advance(solution, f"t = {series.t[k]:g} s"))
            except ScenarioError as exc:
                del series.solutions[k:]
                if series.views is not None:
                    del series.views[k:]
                series.message = f"stopped at t = {series.t[k]:g} s: {str(exc).split(': ', 1)[1]}"
                return
            for name in picked:
                if name in tracker.free:            # a free body's grasp is solved for: it holds or slips
                    continue
                angle = tracker.grip_angle(solution, name)
                if angle is not None and abs(angle - 90.0) > GRIP_ANGLE_TOLERANCE:
                    series.warnings.append(PhysicsWarning("grasp", f"t = {series.t[k]:g} s: the gripper closes on "
                                                          f"{name!r} at {angle:.1f} deg to its long axis, not across it"))


    # ------------------------------------------------------------------ reporting
    def report(self, series):
        """``simulation.json``: status, the events, per TCA its drive, peak temperature and
        the electrical energy used [J] (heated TCAs), the heat balance's worst residual; up to
        the last solved output time (the first, if none was)."""
        history = getattr(series, "history", None)
        reached = max(len(series.solutions), 1)
        tcas = {}
        for j, actuator in enumerate(self.sim.robot.thermal_actuators):
            entry = {"drive": self._drive(self.sim.scenario, actuator).kind,
                     "peak_temperature": float(np.max(series.temperatures[:reached, j]))}
            if actuator in self.heated:
                i = self.heated.index(actuator)
                balance = history.heat_balance_residual()[:reached, i]
                entry.update(energy=float(history.energy_in[reached - 1, i]), time_constant=self.laws[i].time_constant,
                             heat_to_neighbours=float(history.energy_exchanged[reached - 1, i]),
                             heat_balance_residual=float(np.max(np.abs(balance))))
            tcas[actuator.key] = entry
        responses = self._responses(series, reached)
        for key, entry in tcas.items():
            entry["responses"] = responses[key]
        solved_until = float(series.t[len(series.solutions) - 1]) if series.solutions else None
        return {"completed": series.completed, "message": series.message, "duration": self.duration,
                "dt": self.dt, "outputs": int(len(series.t)), "planned_outputs": int(len(series.t)),
                "solved": len(series.solutions), "solved_until_s": solved_until,
                "ambient_temperature": self.sim.scenario.ambient_temperature,
                "events": [{"at": e.at, "set": {k: str(v) for k, v in e.set.items()}, "ramp": e.ramp}
                           for e in self.sim.scenario.timeline],
                "tcas": tcas, "tip_responses": responses["tip"], "objects": self._object_report(series),
                "dynamics": self._dynamics_report(series),
                "warnings": [str(w) for w in series.warnings]}

    def _dynamics_report(self, series):
        """The integrator, the peak tip speed [m/s], the energy balance's worst residual [J]
        (and relative to the largest stored energy) and the global balance's worst relative
        residual over the steps where it was checked (``dynamics.balance_every``), or None for
        a quasi-static run."""
        config = self.sim.scenario.dynamics
        if not config.enabled or getattr(series, "energies", None) is None or not len(series.energies):
            return None
        from .motion import ENERGY_COLUMNS
        energies = series.energies
        # the energy in play: stored (kinetic and elastic; the change of gravitational) and moved (work)
        moved = [ENERGY_COLUMNS.index(name) for name in ("actuator_work", "load_work", "dissipated_energy", "impact_loss",
                                                         "friction_work")]
        stored = float(np.max(energies[:, 0] + energies[:, 1]) + np.max(np.abs(energies[:, 2] - energies[0, 2]))
                       + np.max(np.abs(energies[:, moved])))
        worst = float(np.max(np.abs(energies[:, ENERGY_COLUMNS.index("energy_balance")])))
        checked = series.checked_balances()
        return {"compiled_residual": bool(getattr(series, "compiled", False)),
                "global_balance_checked": len(checked), "global_balance_every": config.balance_every,
                "global_balance_worst": float(max(checked)) if checked else None,
"integrator": config.integrator, "damping": None if config.damping is None else
                config.damping.model_dump(), "peak_tip_speed": float(np.max(np.linalg.norm(series.tip_velocities, axis=1))),
                "energy_balance_residual": worst, "energy_balance_relative": worst / stored if stored > 0 else 0.0,
                "final": {name: float(energies[-1, k]) for k, name in enumerate(ENERGY_COLUMNS)}}

    @staticmethod
    def _object_report(series):
        """Per object: when it was picked and put down [s], when a grip of a free body started
        sliding over it (``slides_at`` [s]: Coulomb's law, dynamics) and where it ended [m]."""
        out = {}
        for name in (series.objects[0] if series.objects else {}):
            held = [poses[name].held for poses in series.objects]
            changes = [k for k in range(1, len(held)) if held[k] != held[k - 1]]
            sliding = [any(c.sliding for b in (getattr(view, "bodies", None) or []) if b.name == name for c in b.grips)
                       for view in (series.views or [])[:len(held)]]
            out[name] = {"picked_at": [float(series.t[k]) for k in changes if held[k]],
                         "put_down_at": [float(series.t[k]) for k in changes if not held[k]],
                         "slides_at": [float(series.t[k]) for k in range(len(sliding))
                                       if sliding[k] and (k == 0 or not sliding[k - 1])],
                         "final_center": series.objects[-1][name].center.tolist(), "held_at_end": held[-1],
                         "held_at_start": held[0]}
        return out

    def _responses(self, series, reached):
        """Per event: the step response of each TCA's temperature and of the tip's distance
        from where it was at the event (:func:`step_response`), over the solved outputs."""
        t = series.t[:reached]
        tips = series.tip_positions() if series.solutions else np.zeros((0, 3))
        events = self.sim.scenario.timeline
        out = {key: [] for key in series.keys} | {"tip": []}
        for k, event in enumerate(events):
            end = events[k + 1].at if k + 1 < len(events) else self.duration
            if event.at > t[-1] if t.size else True:
                break
            for j, key in enumerate(series.keys):
                out[key].append({"at": event.at, **step_response(t, series.temperatures[:reached, j], event.at, end)})
            if tips.shape[0]:
                at = int(np.argmin(np.abs(t - event.at)))
                distance = np.linalg.norm(tips - tips[at], axis=1)
                out["tip"].append({"at": event.at, **step_response(t, distance, event.at, end)})
        return out

    def summary(self, series):
        events = f"{len(self.sim.scenario.timeline)} event(s)"
        if series.completed:
            done = f"{self.duration:g} s, {len(series.t)} output times, {events}"
        else:
            reached = f"up to t = {series.t[len(series.solutions) - 1]:g} s" if series.solutions else "nothing"
            done = (f"solved {reached} of {self.duration:g} s: {len(series.solutions)} of {len(series.t)} "
                    f"output times, {events}")
        state = "completed" if series.completed else "STOPPED"
        lines = [f"{self.sim.scenario.name}: simulate {state} ({series.message}); {done}"]
        report = self.report(series)
        for key, entry in report["tcas"].items():
            extra = (f", energy {entry['energy']:.4g} J, tau {entry['time_constant']:.3g} s" if "energy" in entry else "")
            lines.append(f"  {key:<24} {entry['drive']:<11} peak {entry['peak_temperature']:.2f} degC{extra}")
        if series.solutions:
            tip = series.outputs[-1].tip_position * 1e3
            lines.append("  tip at the end [mm]: " + " ".join(signed(v) for v in tip))
        for name, entry in report["objects"].items():
            picked = ", ".join(f"{t:g}" for t in entry["picked_at"]) or ("held from the start" if entry["held_at_start"]
                                                                       else "never")
            down = ", ".join(f"{t:g}" for t in entry["put_down_at"])
            down = f"put down at {down} s" if down else "never put down"
            centre = " ".join(signed(v * 1e3, 2) for v in entry["final_center"])
            picked = picked if picked.startswith("held") or picked == "never" else f"picked at {picked} s"
            slides = ", ".join(f"{t:g}" for t in entry["slides_at"])
            slides = f", SLIDES in its grip from {slides} s" if slides else ""
            lines.append(f"  {name}: {picked}{slides}, {down}; ends at [{centre}] mm")
        if report["dynamics"] is not None:
            motion = report["dynamics"]
            lines.append(f"  dynamics ({motion['integrator']}): peak tip speed {motion['peak_tip_speed'] * 1e3:.4g} mm/s, "
                         f"energy balance {motion['energy_balance_relative']:.1e} of the energy in play"
                         + ("; residual and Newton's chord steps compiled (solver.jit)" if motion["compiled_residual"] else ""))
            if motion["global_balance_checked"]:
                lines.append(f"  global balance checked at {motion['global_balance_checked']} of "
                             f"{len(series.solutions)} outputs (the start, the first step, every "
                             f"{motion['global_balance_every']}th and the last; dynamics.balance_every): worst {motion['global_balance_worst']:.1e} of the "
                             "forces in play")
        lines += [f"  warning: {w}" for w in report["warnings"]]
        return "\n".join(lines)


def simulate(sim, duration=None, dt=0.1, progress=None):
    """Run ``sim``'s timeline (:class:`TimeSimulation`): the :class:`TimeSeries` of
    ``duration`` [s] (default the scenario's) at output step ``dt`` [s]; ``progress(fraction,
    text)`` is called after each output time."""
    return TimeSimulation(sim, duration=duration, dt=dt).run(progress)

"""Model-predictive control of the tip (``drive: {kind: mpc, mpc: {...}}`` in ``simulate``,
issue 32): a receding-horizon loop around the minimum-time plan of :mod:`.plan`.

Every ``period`` ``T_c``, at ``t_p = p T_c``:

1. measure the plant: its TCAs' temperatures ``T_p`` and its tip ``y_p`` (its equilibrium);
2. estimate what the plant does differently from the model and aim the model at ``p* - d``,
   ``d = e + i``: the output disturbance ``e``, the measured tip less the model's tip at the
   measured temperatures, filtered (``e <- e + f (y_p - y_model(T_p) - e)``, ``f`` =
   ``disturbance_gain``; zero when plant and model agree, the whole mechanical mismatch, a
   stiffer body, in steady state), and the integral ``i <- i + g (y_p - p*)`` of the tip error
   (``integral_gain`` ``g`` per period, only within :data:`INTEGRATION_WINDOW` tolerances of the
   target, so that the approach does not wind it up), which removes what ``e`` cannot see (a
   larger conductance: the plant settles a little cooler than the model predicts);
3. plan over the horizon from ``T_p`` (the ``time`` objective: least squares of the tip error
   at every node, inputs bounded, temperatures under their maxima), warm-started from the last
   plan shifted by one period;
4. apply the plan's first input to the plant for one period: its temperatures by the exact
   zero-order-hold step of the plant's own thermal model, its equilibrium at the period's end.

The plant is the scenario with ``plant_overrides`` (``--plant-set``) applied, the controller's
model the scenario as given; both with the mpc drives as power drives.
"""
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ScenarioError, SolverError, flag
from ..results import ResultAPI, status_of
from ..time_simulation.timeline import mpc_drives  # noqa: F401  (re-exported)
from .plan import HeatingRecord, Plan, _NoEquilibrium, held_from, read_path

#: the tip error is integrated only within this many tolerances of the target (anti-windup)
INTEGRATION_WINDOW = 3.0


@dataclass(repr=False)
class ClosedLoopResult(ResultAPI, HeatingRecord):
    """A closed-loop run: the period times ``t`` (n,) [s], the applied ``inputs`` (n, k) [W]
    (``paths``; the last row repeats the one before: nothing is applied after the end), the
    plant's ``temperatures`` (n, m) [degC] (``keys``), ``tips`` (n, 3) [m], ``errors`` (n,) [m]
    from ``target``, the integral term ``offsets`` (n, 3) [m], the controller's ``solve_times``
    (n,) [s] (NaN at the end) and whether each plan ``converged`` (n,)."""
    offsets: np.ndarray
    solve_times: np.ndarray
    plans_converged: np.ndarray
    target: np.ndarray
    tolerance: float
    settings: dict
    plant_overrides: list
    message: str = ""
    #: (n, 3) [m]: where the tip should be at each period time (the target, or the path there)
    targets: np.ndarray = None
    #: the followed path's CSV file (None: a fixed target)
    path: str = None

    @property
    def reached_at_s(self):
        """The first period time from which the tip stays within the tolerance (None if it
        does not end within it)."""
        return held_from(self.t, self.errors, self.tolerance)

    @property
    def reached(self):
        return self.reached_at_s is not None

    @property
    def result(self):
        """:class:`SolveStatus` of the run: success when every plan converged and the tip ends
        within the tolerance."""
        return status_of(self.completed and self.reached, "mpc (closed loop)", self.message,
                         nit=len(self.t) - 1, solve_time_s=float(np.nansum(self.solve_times)))

    def figure(self):
        """``timeseries.png``'s figure of a closed loop."""
        from ..plotting.plan_plots import save_plan_png
        return save_plan_png(self, None)

    @property
    def completed(self):
        return bool(np.all(self.plans_converged[:-1])) and not self.message

    @property
    def energy_J(self):
        return float(np.sum(self.inputs[:-1]) * self.settings["period_s"])

    def header(self):
        return (["t [s]"] + [f"{p} [W]" for p in self.paths] + [f"{k}.temperature [degC]" for k in self.keys]
                + ["tip_x [m]", "tip_y [m]", "tip_z [m]", "tip_error [m]", "offset_x [m]", "offset_y [m]",
                   "offset_z [m]", "controller_solve_time [s]", "converged"]
                + ([] if self.path is None else ["target_x [m]", "target_y [m]", "target_z [m]"]))

    def rows(self):
        out = []
        for k, t in enumerate(self.t):
            solve = "" if np.isnan(self.solve_times[k]) else f"{self.solve_times[k]:.6g}"
            out.append([f"{t:.12g}"] + [f"{v:.10g}" for v in self.inputs[k]]
                       + [f"{v:.10g}" for v in self.temperatures[k]] + [f"{v:.10g}" for v in self.tips[k]]
                       + [f"{self.errors[k]:.10g}"] + [f"{v:.10g}" for v in self.offsets[k]]
                       + [solve, int(self.plans_converged[k])]
                       + ([] if self.path is None else [f"{v:.10g}" for v in self.targets[k]]))
        return out

    def report(self):
        times = self.solve_times[~np.isnan(self.solve_times)]
        return {"controller": "mpc", "completed": self.completed, "reached": self.reached,
                "reached_at_s": self.reached_at_s, "final_error_m": float(self.errors[-1]),
                "target_m": self.target.tolist(), "path": self.path, "tolerance_m": self.tolerance,
                "rms_error_m": float(np.sqrt(np.mean(self.errors[1:] ** 2))) if len(self.errors) > 1 else 0.0,
                "energy_J": self.energy_J,
                "settings": self.settings, "plant_overrides": self.plant_overrides,
                "solve_time_median_s": float(np.median(times)) if times.size else None,
                "solve_time_max_s": float(np.max(times)) if times.size else None,
                "solve_time_fraction_of_period": float(np.max(times) / self.settings["period_s"]) if times.size else None,
                "plans_converged": int(np.sum(self.plans_converged[:-1])), "periods": len(self.t) - 1,
                "peak_temperatures_degC": dict(zip(self.keys, np.max(self.temperatures, axis=0).tolist())),
                "message": self.message}

    def summary(self):
        report = self.report()
        what = "the path" if self.path is not None else ""
        state = (f"held within {self.tolerance * 1e3:.4g} mm{' of ' + what if what else ''} from "
                 f"{self.reached_at_s:.4g} s" if self.reached else
                 f"NOT within {self.tolerance * 1e3:.4g} mm{' of ' + what if what else ''} at the end "
                 f"({self.errors[-1] * 1e3:.4g} mm away)")
        lines = [f"closed loop (mpc): {state}; {report['plans_converged']} of {report['periods']} plans converged",
                 ("  target [mm]: " if self.path is None else
                  f"  path {Path(self.path).name} (RMS distance {report['rms_error_m'] * 1e3:.4g} mm), to [mm]: ")
                 + " ".join(f"{v * 1e3:+.4f}" for v in self.target)
                 + "; tip at the end [mm]: " + " ".join(f"{v * 1e3:+.4f}" for v in self.tips[-1]),
                 f"  controller solve time per period: median {report['solve_time_median_s'] * 1e3:.0f} ms, "
                 f"max {report['solve_time_max_s'] * 1e3:.0f} ms ({report['solve_time_fraction_of_period']:.0%} of the "
                 f"{self.settings['period_s']:g} s period)",
                 "  mismatch estimate at the end (disturbance + integral) [mm]: " + " ".join(f"{v * 1e3:+.4f}" for v in self.offsets[-1])
                 + f"; electrical energy {self.energy_J:.4g} J"]
        if self.plant_overrides:
            lines.append("  plant differs from the model: " + ", ".join(self.plant_overrides))
        if self.message:
            lines.append(f"  {self.message}")
        return "\n".join(lines)

    def to_csv(self, path):
        from ..output import write_csv
        return write_csv(path, self.header(), self.rows())


class ClosedLoop:
    """The closed loop of a scenario whose TCAs have ``kind: mpc`` drives (module docstring).

    Parameters
    ----------
    source : path or dict
        The scenario.
    overrides : list of str
        ``--set`` overrides for both the model and the plant.
    plant_overrides : list of str
        Further overrides that make the simulated plant differ from the controller's model.
    duration : float, optional
        [s]; default the scenario's ``duration``.
    """

    def __init__(self, source, overrides=(), plant_overrides=(), duration=None, allow_code=False):
        from ..simulation import Simulation
        scenario = Simulation.from_file(source, overrides, allow_code=allow_code).scenario
        drives = mpc_drives(scenario)
        if not drives:
            raise ScenarioError("closed loop: no TCA has an mpc drive (drive: {kind: mpc, mpc: {target: ...}})")
        settings = drives[0][1].mpc
        if any(d.mpc != settings for _, d in drives[1:]):
            raise ScenarioError("closed loop: every mpc drive must have the same mpc settings (one controller "
                                f"drives {', '.join(k for k, _ in drives)})")
        self.settings = settings
        self.duration = float(duration or scenario.duration or 0.0)
        if not self.duration > 0:
            raise ScenarioError(f"simulate with an mpc drive needs a duration (the scenario's or {flag('--duration')})")
        as_power = [f"{key}.drive={{kind: power, value: {d.value!r}}}" for key, d in drives]
        self.model = Simulation.from_file(source, list(overrides) + as_power, allow_code=allow_code)
        self.plant = Simulation.from_file(source, list(overrides) + list(plant_overrides) + as_power,
                                          allow_code=allow_code)
        self.plant_overrides = list(plant_overrides)
        for override in self.plant_overrides:
            self._check_changes(source, list(overrides) + as_power, override, allow_code)
        self.paths = [f"{key}.drive.value" for key, _ in drives]
        self.path = None if settings.path is None else read_path(settings.path, f"{drives[0][0]}.drive.mpc.path")
        self.target = np.asarray(settings.target if self.path is None else self.path[1][-1], float)
        bounds = [d.max_power for _, d in drives]
        self.bounds = None if all(b is None for b in bounds) else (0.0, min(b for b in bounds if b is not None))
        self.periods = int(np.floor(self.duration / settings.period + 1e-9))
        if self.periods < 1:
            raise ScenarioError(f"the duration ({self.duration:g} s) is shorter than the mpc period "
                                f"({settings.period:g} s)")
        steps = max(1, int(round(settings.horizon / settings.period)))
        self.controller = Plan(self.model, self._goal(0.0, np.zeros(3)), objective="time" if self.path is None else "track",
                               horizon=steps * settings.period, nodes=settings.nodes, vary=self.paths, bounds=self.bounds,
                               tolerance=settings.tolerance)
        self.step = Plan(self.plant, self.target, horizon=settings.period, nodes=1, vary=self.paths,
                         bounds=self.bounds, tolerance=settings.tolerance)

    def _check_changes(self, source, overrides, override, allow_code):
        """A ScenarioError if the plant override ``override`` changes neither a parameter of the
        robot nor a TCA's thermal constants (a key the robot does not use: a typo)."""
        from ..scenario.sources import did_you_mean
        from ..simulation import Simulation
        changed = Simulation.from_file(source, overrides + [override], allow_code=allow_code)
        def constants(sim):
            return np.array([[getattr(a.thermal_law(sim.scenario), name) for name in
                              ("heat_capacity", "conductance", "resistance", "resistance_coefficient")]
                             for a in sim.robot.thermal_actuators], float)
        same_laws = np.array_equal(constants(changed), constants(self.model), equal_nan=True)
        if same_laws and np.array_equal(changed.params, self.model.params):
            path = override.partition("=")[0].strip()
            raise ScenarioError(f"{flag('--plant-set')} {override!r} changes nothing the robot uses"
                                + did_you_mean(path, self.model.robot.layout.names()))

    def target_at(self, t):
        """(3,) [m]: where the tip should be at time ``t`` [s] (the target, or the path there:
        linear between its rows, held before the first and after the last)."""
        if self.path is None:
            return self.target
        times, positions = self.path
        return np.array([np.interp(t, times, positions[:, j]) for j in range(3)])

    def _goal(self, t, offset):
        """What the controller plans towards from time ``t``, less the mismatch estimate
        ``offset`` (3,): the target, or the path with its times from ``t`` on."""
        if self.path is None:
            return self.target - offset
        times, positions = self.path
        return times - t, positions - offset

    def _shifted(self, inputs):
        """The next period's start: the plan's inputs (N, k) one period later in time (the last
        held), whatever the ratio of the period to the plan's step."""
        shift = self.settings.period / self.controller.step
        index = np.minimum(np.floor(np.arange(len(inputs)) + shift + 1e-9).astype(int), len(inputs) - 1)
        return inputs[index].ravel()

    def run(self, progress=None):
        """The :class:`ClosedLoopResult`; ``progress(fraction, text)`` after each period."""
        settings, k = self.settings, len(self.paths)
        T = self.step.T0.copy()
        disturbance, integral = np.zeros(3), np.zeros(3)
        rows, start, message = [], None, ""
        for p in range(self.periods + 1):
            self.step.restart(T)
            applied = np.zeros(k) if p == self.periods else None
            offset = disturbance + integral
            if applied is None:
                self.controller.restart(T, self._goal(p * settings.period, offset))
                started = time.perf_counter()
                plan = self.controller.solve(start=start)
                seconds = time.perf_counter() - started
                model_tip = plan.tips[0]                    # the model's tip at the measured temperatures
                applied = plan.inputs[0]
                start = self._shifted(plan.inputs)
                converged = plan.converged
            else:
                seconds, converged = float("nan"), True
            try:
                tips, _ = self.step.nodes_at(np.asarray(applied, float))
            except _NoEquilibrium as exc:          # the run stops here; what came before is kept
                if not rows:
                    raise SolverError(f"closed loop: the plant has no equilibrium at t = 0 ({exc})") from None
                message = f"stopped at t = {p * settings.period:g} s: the plant has no equilibrium ({exc})"
                break
            tip = tips[0]
            rows.append((p * settings.period, applied, T.copy(), tip, offset.copy(), seconds, converged,
                         self.target_at(p * settings.period)))
            if p < self.periods:
                disturbance = disturbance + settings.disturbance_gain * (tip - model_tip - disturbance)
                # the plant's tip at the period's end (the next measurement) from where it should be then
                error = tips[1] - self.target_at((p + 1) * settings.period)
                if np.linalg.norm(error) <= INTEGRATION_WINDOW * settings.tolerance:
                    integral = integral + settings.integral_gain * error
                T = self.step.temperatures(applied)[1]
            if progress is not None:
                progress((p + 1) / (self.periods + 1), f"t = {p * settings.period:.4g} s")
        t = np.array([r[0] for r in rows])
        inputs = np.array([r[1] for r in rows])
        if not message and len(inputs) > 1:          # nothing is applied after the end: the last held
            inputs[-1] = inputs[-2]
        tips, targets = np.array([r[3] for r in rows]), np.array([r[7] for r in rows])
        return ClosedLoopResult(
            "mpc (closed loop)", t, list(self.paths), inputs, list(self.step.keys), np.array([r[2] for r in rows]),
            self.step.max_temperatures, tips, np.linalg.norm(tips - targets, axis=1),
            np.array([r[4] for r in rows]), np.array([r[5] for r in rows]), np.array([r[6] for r in rows]),
            self.target, settings.tolerance,
            {"period_s": settings.period, "horizon_s": self.controller.horizon, "nodes": settings.nodes,
             "integral_gain": settings.integral_gain, "disturbance_gain": settings.disturbance_gain, "bounds_W": self.controller.bounds.tolist()},
            self.plant_overrides, message, targets, settings.path)

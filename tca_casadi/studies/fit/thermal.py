"""Calibration in time: a TCA type's thermal constants from a heating curve.

A measurement file with a ``t [s]`` column is a time series of the scenario's own timeline
(its drives and events, as ``simulate`` runs them): each row a time, the measured columns TCA
temperatures, ``ACTUATOR.temperature [degC]`` (or ``[K]``), with optional ``sigma_`` columns
(default ``temperature=0.5`` K, ``--sigma temperature=...``). The fitted parameters are the lumped
thermal model's constants, ``tca_types.TYPE.thermal.heat_capacity`` [J/K] and
``.conductance`` [W/K] (their nominal values the scenario's, or those derived from the fibre);
the time constant is ``tau = C / G``. Every prediction integrates the thermal model
(:func:`~tca_casadi.solvers.thermal.integrate`, rtol 1e-11) at the data's times; the Jacobian is
by central differences of relative step :data:`STEP` (the thermal ODE is not part of the
collocation NLP, so there is no implicit-function derivative to take; the integrator's
tolerance keeps the differences to about 1e-6).
"""
from dataclasses import dataclass

import numpy as np

from ...errors import ScenarioError, flag
from ...units import ureg
from ...tables import name_of, unit_of

#: relative step of the central differences
STEP = 1e-5
#: default standard deviation of a measured temperature [K]
TEMPERATURE_SIGMA = 0.5
THERMAL_KEYS = ("heat_capacity", "conductance")
UNITS = {"heat_capacity": "J/K", "conductance": "W/K"}


def is_time_series(path):
    """True if a measurement CSV has a time column ``t`` (ScenarioError if it cannot be read)."""
    from ...tables import name_of, read_table
    return any(name_of(text) == "t" for text in read_table(path, f"fit {flag('--data')}", "measurements file").header)


@dataclass
class HeatingCurve:
    """Measured TCA temperatures in time: ``times`` (n,) [s], ``names`` (``ACTUATOR.temperature``),
    ``values`` and ``sigmas`` (n, q) [degC, K]."""
    times: np.ndarray
    names: list
    values: np.ndarray
    sigmas: np.ndarray
    source: str = "<data>"
    inputs: tuple = ()

    @property
    def size(self):
        return self.times.size


def read_heating_curve(path, robot, sigma=None):
    """A :class:`HeatingCurve` from a CSV (read by :func:`tca_casadi.tables.read_table`);
    one-line ScenarioErrors naming the column or line."""
    from ...tables import read_table
    table = read_table(path, f"fit {flag('--data')}", "heating curve")
    header, n = table.header, len(table.rows)
    if not n:
        raise ScenarioError(f"fit {flag('--data')}: {path} has a header but no rows")
    keys = [a.key for a in robot.thermal_actuators]
    time_column, measured, sigmas = None, [], {}
    for column, text in enumerate(header):
        name, unit = name_of(text), unit_of(text)
        if name == "t":
            time_column = (column, unit or "s")
        elif name.startswith("sigma_"):
            sigmas[name[len("sigma_"):]] = (column, unit)
        elif name.endswith(".temperature") and name.rsplit(".", 1)[0] in keys:
            measured.append((name, column, unit))
        else:
            raise ScenarioError(f"fit {flag('--data')}: column {text!r} of a time series (it has a t column) must be a TCA's "
                                f"temperature ({', '.join(k + '.temperature' for k in keys)}) or its sigma_")
    if not measured:
        raise ScenarioError(f"fit {flag('--data')}: {path} has a t column but no measured temperature column")
    times = np.array([_value(table, k, time_column[0], time_column[1], "s") for k in range(n)])
    if np.any(np.diff(times) <= 0) or times[0] < 0:
        raise ScenarioError(f"fit {flag('--data')}: the t column of {path} must start at 0 or later and increase")
    values = np.column_stack([[_value(table, k, column, unit or "degC", "degC") for k in range(n)]
                              for _, column, unit in measured])
    spread = np.full(values.shape, float(sigma or TEMPERATURE_SIGMA))
    for j, (name, *_) in enumerate(measured):
        if name in sigmas:
            column, unit = sigmas[name]
            spread[:, j] = [_value(table, k, column, unit or "K", "K", difference=True) for k in range(n)]
    if not np.all(spread > 0):
        raise ScenarioError(f"fit {flag('--data')}: every sigma must be positive")
    return HeatingCurve(times, [m[0] for m in measured], values, spread, str(path))


def _value(table, k, column, unit, target, difference=False):
    """Row ``k``, ``column`` of ``table`` in the unit ``target``."""
    value = table.number(k, column)
    try:
        if difference:                  # a temperature difference: K and degC steps alike
            unit = {"degC": "K", "°C": "K"}.get(unit, unit)
        return float(ureg.Quantity(value, unit).to(target).magnitude)
    except Exception:
        raise ScenarioError(f"fit {flag('--data')}: column {table.header[column]!r}: [{unit}] is not a unit of {target}") from None


@dataclass
class ThermalParameter:
    """A fitted thermal constant: ``tca_types.TYPE.thermal.KEY`` (or an SMA wire's,
    ``muscle_types.TYPE.thermal.KEY``)."""
    path: str
    tca_type: str
    key: str

    @property
    def type_path(self):
        """``tca_types.TYPE`` or ``muscle_types.TYPE``."""
        return self.path.rsplit(".", 2)[0]

    @property
    def unit(self):
        return UNITS[self.key]

    @property
    def name(self):
        return self.path

    @property
    def label(self):
        return f"{self.path} [{self.unit}]"

    def to_si(self, value, what="value"):
        from ...units import to_si
        try:
            return to_si(value, "heat_capacity" if self.key == "heat_capacity" else "thermal_conductance")
        except ValueError as exc:
            raise ScenarioError(f"{what} for {self.path}: {exc}") from None


def thermal_parameter(scenario, path):
    """The :class:`ThermalParameter` of ``path``; ScenarioError naming what a time-series fit takes."""
    from ...catalogue import thermal_kinds
    heated = {f"tca_types.{t}" for t in scenario.tca_types} | {
        f"muscle_types.{t}" for t, config in scenario.muscle_types.items() if config.kind in thermal_kinds()}
    parts = path.split(".")
    if len(parts) == 4 and f"{parts[0]}.{parts[1]}" in heated and parts[2] == "thermal" and parts[3] in THERMAL_KEYS:
        return ThermalParameter(path, parts[1], parts[3])
    types = ", ".join(f"{t}.thermal.{k}" for t in sorted(heated) for k in THERMAL_KEYS)
    raise ScenarioError(f"fit {flag('--param')} {path}: a time-series fit takes a TCA type's (or an SMA type's) "
                        f"thermal constants ({types})")


class ThermalFitModel:
    """Predicted temperatures of a heating curve at thermal constants ``theta`` (same interface
    as :class:`~tca_casadi.studies.fit.least_squares.FitModel`)."""

    def __init__(self, sim, data, parameters):
        from ...time_simulation.timeline import TimeSimulation
        self.sim, self.data, self.parameters = sim, data, parameters
        self.timed = TimeSimulation(sim, duration=max(float(data.times[-1]), 1e-9))     # built once
        keys = [a.key for a in self.timed.heated]
        for name in data.names:
            key = name.rsplit(".", 1)[0]
            if key not in keys:
                raise ScenarioError(f"fit {flag('--data')}: {name} is measured, but {key} has no power, voltage, current or "
                                    "setpoint drive in the scenario: its temperature is set, not predicted")
        self.columns = [keys.index(name.rsplit(".", 1)[0]) for name in data.names]
        self.nominal = np.array([self._nominal(p) for p in parameters])
        self._cache = (None, None)

    def _nominal(self, parameter):
        """The constant's value in the scenario: that of the first heated TCA of its type."""
        index = next((k for k, a in enumerate(self.timed.heated) if a.type_path == parameter.type_path), None)
        if index is None:
            raise ScenarioError(f"fit {flag('--param')} {parameter.path}: no heated TCA (with a power, voltage, current or "
                                f"setpoint drive) is of type {parameter.tca_type}")
        return getattr(self.timed.laws[index], parameter.key)

    def laws_at(self, theta):
        """The heated TCAs' thermal laws with the constants ``theta`` for their types."""
        from dataclasses import replace
        laws = list(self.timed.laws)
        for parameter, value in zip(self.parameters, theta):
            laws = [replace(law, **{parameter.key: float(value)}) if actuator.type_path == parameter.type_path else law
                    for actuator, law in zip(self.timed.heated, laws)]
        return laws

    def predictions(self, theta, rows=None):
        """Temperatures (n, q) [degC] at the data's times."""
        key = np.asarray(theta, float).tobytes()
        if self._cache[0] != key:
            self._cache = (key, self._run(theta))
        out = self._cache[1]
        return out if rows is None else out[np.asarray(rows, int)]

    def _run(self, theta):
        from ...solvers.thermal import integrate, steady_state
        if not np.all(np.asarray(theta) > 0):
            from ...errors import TcaError
            raise TcaError("a thermal constant reached zero")
        laws, timed = self.laws_at(theta), self.timed
        ambient = self.sim.scenario.ambient_temperature
        drives = timed.drives()
        initial = steady_state(laws, drives, ambient, timed.coupling)
        history = integrate(laws, drives, ambient, initial, self.data.times, timed.coupling)
        return history.temperature[:, self.columns]

    def residuals(self, theta, rows):
        rows = np.asarray(rows, int)
        if rows.size == 0:
            return np.zeros(0)
        return ((self.data.values[rows] - self.predictions(theta, rows)) / self.data.sigmas[rows]).ravel()

    def jacobian(self, theta, rows):
        """Central differences of the weighted residuals (relative step :data:`STEP`)."""
        theta = np.asarray(theta, float)
        columns = []
        for j in range(theta.size):
            step = STEP * abs(theta[j])
            plus, minus = theta.copy(), theta.copy()
            plus[j] += step
            minus[j] -= step
            columns.append((self.residuals(plus, rows) - self.residuals(minus, rows)) / (2 * step))
        return np.column_stack(columns)


def synthetic_heating_curve(sim, truth, names, times, noise, seed=0):
    """A heating curve made by the model at the thermal constants ``truth`` (``{path: value}``)
    with Gaussian noise ``noise`` [K] (seeded): a :class:`HeatingCurve`."""
    curve = HeatingCurve(np.asarray(times, float), list(names), np.zeros((len(times), len(names))),
                         np.full((len(times), len(names)), float(noise)), "<synthetic>")
    parameters = [thermal_parameter(sim.scenario, path) for path in truth]
    model = ThermalFitModel(sim, curve, parameters)
    clean = model.predictions(np.array(list(truth.values()), float))
    curve.values = clean + noise * np.random.default_rng(seed).standard_normal(clean.shape)
    return curve


def write_heating_curve(path, curve, comments=()):
    from ...output import write_csv
    header = ["t [s]"] + [f"{n} [degC]" for n in curve.names] + [f"sigma_{n} [K]" for n in curve.names]
    rows = [[f"{t:.10g}"] + [f"{v:.10g}" for v in values] + [f"{s:.6g}" for s in sigma]
            for t, values, sigma in zip(curve.times, curve.values, curve.sigmas)]
    return write_csv(path, header, rows, comments=comments)

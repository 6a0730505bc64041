"""Calibration (``tca-casadi fit``, ``tc.Fit``): a robot's parameters from measurements, with
their uncertainty.

**Data.** A CSV, one row per experiment: input columns named by scenario path with a unit in
brackets (``bending.tca2.temperature [degC]``), measured columns named by a measurable quantity
(:mod:`tca_casadi.discretisation.measurements`: ``tip_x [mm]``, ``bending.tca1.stroke [m]``,
``bending.tca1.tension [mN]``) and optional ``sigma_NAME`` columns (the measurement's standard
deviation, same units rules); where a sigma column is absent, ``sigmas={kind: value}`` (or
``--sigma``) gives one per kind of quantity (default 0.1 mm for lengths, 1 mN for forces).

**Estimator.** Weighted least squares ``min sum_ij ((y_ij - m_j(P_i(theta))) / sigma_ij)^2``
over the chosen parameters ``theta`` (any scalar NLP parameter), scaled by their nominal values
(``x = theta / |theta_0|``), within optional bounds (scipy's trust-region reflective
``least_squares``). Every residual evaluation solves each experiment's equilibrium by Newton
from its last solution (the first time in nearest-neighbour order of the inputs, each from the
one before), and the Jacobian is exact: ``dm/dtheta = m_w dw/dtheta + m_P dP/dtheta`` with
``dw/dtheta = -J_w^-1 J_P dP/dtheta`` (the implicit function theorem on the collocation
system, one sparse LU per experiment).

**Uncertainty.** With ``J`` the Jacobian of the weighted residuals at the optimum (n residuals,
p parameters) and ``s^2 = 2 cost / (n - p)``: ``Cov = s^2 (J^T J)^-1`` (``absolute_sigma``: the
sigmas are trusted, ``s = 1``), standard errors its diagonal's roots, 95 % intervals
``theta +- t_{0.975, n-p} SE``, correlations ``Cov_ij / (SE_i SE_j)``. ``J^T J`` is the Fisher
information; when its condition number exceeds :data:`~tca_casadi.studies.fit.result.CONDITION_LIMIT` the parameters with a
large share in its weakest direction cannot be told apart from the data: they are named, and
the parameters in an exactly singular direction get no interval at all.
"""
import time
from dataclasses import dataclass

import numpy as np

from ...discretisation.measurements import measurable_names, measurement_function, quantity_kind
from ...errors import ScenarioError, TcaError, flag
from ...scenario.checks import closest
from ..batch.design import nearest_neighbour_order
from ..parameters import resolve_parameter, shown_as_given

#: default standard deviations of the measurements, per kind [m, N]
DEFAULT_SIGMAS = {"length": 1e-4, "force": 1e-3}


@dataclass
class Measurements:
    """Experiments read from a file: ``inputs`` (StudyParameter per input column) and their
    values (n, k) in the parameters' units; measured ``names`` with ``values`` and ``sigmas``
    (n, q) in SI; ``columns``: the file's header, for messages."""
    inputs: list
    input_values: np.ndarray
    names: list
    values: np.ndarray
    sigmas: np.ndarray
    source: str = "<data>"

    @property
    def size(self):
        return self.values.shape[0]

    def subset(self, rows):
        rows = np.asarray(rows, int)
        return Measurements(self.inputs, self.input_values[rows], self.names, self.values[rows],
                            self.sigmas[rows], self.source)


def read_measurements(path, robot, params, sigmas=None):
    """:class:`Measurements` of a CSV (module docstring; read by :func:`tca_casadi.tables.read_table`);
    one-line ScenarioErrors naming the column or line for a column that is neither, a unit that
    does not match, a value that is not a finite number."""
    from ...tables import read_table
    table = read_table(path, f"fit {flag('--data')}", "measurements file")
    if not table.rows:
        raise ScenarioError(f"fit {flag('--data')}: {path} has no experiments (a header row and one row per experiment)")
    defaults = dict(DEFAULT_SIGMAS, **(sigmas or {}))
    inputs, input_columns, measured, measured_columns, sigma_columns = [], [], [], [], {}
    for column, text in enumerate(table.header):
        name, unit = _split_unit(text)
        if name.startswith("sigma_"):
            sigma_columns[name[len("sigma_"):]] = (column, unit)
        elif quantity_kind(robot, name) is not None:
            measured.append(name)
            measured_columns.append((column, unit))
        else:
            try:
                parameter = resolve_parameter(robot, params, name)
            except ScenarioError:
                raise ScenarioError(f"fit {flag('--data')}: column {text!r} is neither a scenario parameter nor a measured "
                                    f"quantity{closest(name, measurable_names(robot) + robot.layout.names())}") from None
            inputs.append(parameter)
            input_columns.append((column, unit))
    if not measured:
        raise ScenarioError(f"fit {flag('--data')}: {path} has no measured column (e.g. tip_x [m]; measurable: "
                            f"{', '.join(measurable_names(robot)[:8])}, ...)")
    for name in sigma_columns:
        if name not in measured:
            raise ScenarioError(f"fit {flag('--data')}: column sigma_{name} has no measured column {name}")
    n = len(table.rows)
    values = np.empty((n, len(measured)))
    spread = np.empty((n, len(measured)))
    for j, ((column, unit), name) in enumerate(zip(measured_columns, measured)):
        kind = quantity_kind(robot, name)
        values[:, j] = [_number(table, k, column, unit, kind) for k in range(n)]
        if name in sigma_columns:
            s_column, s_unit = sigma_columns[name]
            spread[:, j] = [_number(table, k, s_column, s_unit, kind) for k in range(n)]
        else:
            spread[:, j] = defaults[kind]
        bad = np.flatnonzero(~(spread[:, j] > 0))
        if bad.size:
            raise ScenarioError(f"{table.where(int(bad[0]))}: sigma of {name} is {spread[bad[0], j]:g}; give sigma > 0")
    given = np.empty((n, len(inputs)))
    for j, ((column, unit), parameter) in enumerate(zip(input_columns, inputs)):
        for k in range(n):
            given[k, j] = _input(table, k, column, unit, parameter)
    return Measurements(inputs, given, measured, values, spread, str(path))


def _split_unit(text):
    text = text.strip()
    if text.endswith("]") and "[" in text:
        name, unit = text[:-1].split("[", 1)
        return name.strip(), unit.strip()
    return text, None


def _number(table, k, column, unit, kind):
    """A measured value in SI (m or N) from row ``k``, ``column`` of ``table`` in the column's
    unit (:meth:`~tca_casadi.tables.Table.quantity`)."""
    return table.quantity(k, column, kind)


def _input(table, k, column, unit, parameter):
    """An input value in its parameter's unit from row ``k``, ``column`` of ``table``."""
    value = table.number(k, column)
    if unit is None:
        return value
    try:
        return float(parameter.to_si(f"{value!r} {unit}", f"column {table.header[column]!r}"))
    except ScenarioError as exc:
        raise ScenarioError(f"fit {flag('--data')}: {exc}") from None


class Fit:
    """Calibration of ``sim``'s parameters ``params`` (paths) to ``data`` (a CSV path or
    :class:`Measurements`).

    Parameters
    ----------
    bounds : dict, optional
        ``{path: (lo, hi)}`` in the path's unit (strings with units allowed); must contain the
        nominal value.
    sigmas : dict, optional
        ``{"length": m, "force": N}``: the standard deviation of measurements without a sigma
        column.
    absolute_sigma : bool
        Trust the sigmas (covariance not scaled by the residual variance).
    starts : int
        Starting points (more than one: a Sobol set in the bounds, the best kept).
    holdout : float, optional
        Fraction of the experiments (seeded) left out of the fit and predicted after it.
    """

    def __init__(self, sim, data, params, bounds=None, sigmas=None, absolute_sigma=False, starts=1,
                 holdout=None, seed=0):
        from .thermal import HeatingCurve, ThermalFitModel, is_time_series, read_heating_curve, thermal_parameter
        self.sim, self._model = sim, None
        if not params:
            raise ScenarioError(f"fit: no parameter to fit (give {flag('--param')} PATH)")
        self.time_series = isinstance(data, HeatingCurve) or (not isinstance(data, Measurements) and is_time_series(data))
        if self.time_series:                         # a heating curve: the thermal constants
            self.data = data if isinstance(data, HeatingCurve) else \
                read_heating_curve(data, sim.robot, (sigmas or {}).get("temperature"))
            self.parameters = [thermal_parameter(sim.scenario, path) for path in params]
            self._model = ThermalFitModel(sim, self.data, self.parameters)
            nominal = self._model.nominal
        else:
            if sim.solver().has_square_system is False:
                raise ScenarioError("fit needs the collocation solver (solver.method: collocation)")
            self.data = data if isinstance(data, Measurements) else read_measurements(data, sim.robot, sim.params, sigmas)
            self.parameters = [self._parameter(path) for path in params]
            inputs = {p.name for p in self.data.inputs}
            for p in self.parameters:
                if p.name in inputs:
                    raise ScenarioError(f"fit {flag('--param')} {p.path}: it is an input column of the data too")
            nominal = np.array([p.value(sim.params) for p in self.parameters])
        self.nominal, self.scale = nominal, np.where(nominal != 0, np.abs(nominal), 1.0)
        self.bounds = self._bounds(bounds or {})
        if not self.time_series:              # shown in the unit the bounds were given in, else a readable one
            self.parameters = [shown_as_given(p, sim.scenario, *(bounds or {}).get(p.path, ()), values=[v])
                               for p, v in zip(self.parameters, nominal)]
        self.absolute_sigma, self.starts, self.seed = absolute_sigma, int(starts), int(seed)
        if self.starts < 1:
            raise ScenarioError(f"fit {flag('--starts')} {starts}: give at least 1")
        if self.starts > 1 and not np.all(np.isfinite(self.bounds)):
            raise ScenarioError(f"fit {flag('--starts')} needs {flag('--bounds')} on every parameter (the starts are spread in them)")
        self.train, self.test = self._split(holdout)
        residuals = len(self.train) * len(self.data.names)
        if residuals < len(self.parameters):
            raise ScenarioError(f"fit: {residuals} measured values for {len(self.parameters)} parameters; "
                                "give at least as many measurements as parameters")

    def quantity_kind(self, name):
        """``length``, ``force`` or ``temperature``: the kind of a measured quantity."""
        return "temperature" if self.time_series else quantity_kind(self.sim.robot, name)

    def fitted_overrides(self, values):
        """``{scenario path: value}`` that write fitted ``values`` into the scenario (a
        parameter-vector entry in full, SI; temperatures degC)."""
        if self.time_series:
            return {p.path: float(v) for p, v in zip(self.parameters, values)}
        params = self.sim.params.copy()
        for parameter, value in zip(self.parameters, values):
            params = parameter.with_value(params, value)
        out = {}
        for parameter in self.parameters:
            entry = params[parameter.slice]
            out[parameter.name] = float(entry[0]) if entry.size == 1 else [float(v) for v in entry]
        return out

    def _parameter(self, path):
        try:
            return resolve_parameter(self.sim.robot, self.sim.params, path)
        except ScenarioError:
            raise ScenarioError(f"fit {flag('--param')} {path}: not a parameter (structure cannot be fitted); parameters: "
                                f"{', '.join(self.sim.robot.layout.names())}{closest(path, self.sim.robot.layout.names())}") from None

    def _bounds(self, given):
        out = np.array([[-np.inf, np.inf]] * len(self.parameters))
        paths = [p.path for p in self.parameters]
        for path, (low, high) in given.items():
            if path not in paths:
                raise ScenarioError(f"fit {flag('--bounds')} {path}: not one of the fitted parameters ({', '.join(paths)})")
            j = paths.index(path)
            parameter = self.parameters[j]
            low, high = parameter.to_si(low, "low bound"), parameter.to_si(high, "high bound")
            if not low < high:
                raise ScenarioError(f"fit {flag('--bounds')} {path}: [{low:g}, {high:g}] is empty")
            if not low <= self.nominal[j] <= high:
                raise ScenarioError(f"fit {flag('--bounds')} {path}: [{low:g}, {high:g}] {parameter.unit} excludes the nominal "
                                    f"value {self.nominal[j]:g} {parameter.unit}")
            out[j] = low, high
        return out

    def _split(self, holdout):
        n = self.data.size
        if holdout is None or holdout == 0:
            return np.arange(n), np.arange(0)
        if not 0 < holdout < 1:
            raise ScenarioError(f"fit {flag('--holdout')} {holdout}: give a fraction between 0 and 1")
        count = int(round(holdout * n))
        if count < 1 or count >= n:
            raise ScenarioError(f"fit {flag('--holdout')} {holdout}: leaves {count} of {n} experiments out; give a fraction "
                                "that keeps at least one on each side")
        test = np.sort(np.random.default_rng(self.seed).choice(n, count, replace=False))
        return np.setdiff1d(np.arange(n), test), test

    # ------------------------------------------------------------------ run
    @property
    def model(self):
        if self._model is None:
            self._model = FitModel(self.sim, self.data, self.parameters)
        return self._model

    def run(self, progress=None):
        """Fit; a :class:`~tca_casadi.studies.fit.result.FitResult`."""
        from scipy.optimize import least_squares
        started = time.perf_counter()
        model, train = self.model, self.train
        x0 = self.nominal / self.scale
        lower, upper = self.bounds[:, 0] / self.scale, self.bounds[:, 1] / self.scale
        before = model.residuals(self.nominal, train)

        def residuals(x):
            return model.residuals(x * self.scale, train)

        def jacobian(x):
            return model.jacobian(x * self.scale, train) * self.scale[None, :]

        best, failed = None, []
        for start in self._starts(x0, lower, upper):
            try:
                fitted = least_squares(residuals, start, jac=jacobian, bounds=(lower, upper), method="trf",
                                       x_scale=1.0, xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200)
            except TcaError as exc:
                if start is x0:
                    raise TcaError(f"fit: {exc}") from None
                failed.append(str(exc))            # said in the result's warnings
                continue
            if best is None or fitted.cost < best.cost:
                best = fitted
            if progress is not None:
                progress(1.0, f"start cost {fitted.cost:.4g}")
        theta = best.x * self.scale
        after = model.residuals(theta, train)
        J = model.jacobian(theta, train)                       # d r / d theta (r weighted)
        test = model.residuals(theta, self.test) if self.test.size else None
        from .result import FitResult
        result = FitResult.build(self, theta, best, before, after, J, test, time.perf_counter() - started)
        if failed:
            result.warnings.append(f"{len(failed)} of {self.starts} starts failed (the first: {failed[0]})")
        return result

    def profile(self, result, path, points=9, span=3.0):
        """The profile likelihood of one fitted parameter: at ``points`` values within ``span``
        standard errors of the estimate, the others refitted; ``{"path", "values", "statistic",
        "interval_95"}`` where the statistic is ``2 (cost - cost_min) / s^2`` and the interval is
        where it stays below 3.84 (chi-squared, one degree of freedom, 95 %; None on a side it
        does not cross), to compare with the Wald interval ``theta +- t SE``."""
        from scipy.optimize import least_squares
        paths = [p.path for p in self.parameters]
        if path not in paths:
            raise ScenarioError(f"fit {flag('--profile')} {path}: not one of the fitted parameters ({', '.join(paths)})")
        j = paths.index(path)
        fitted = result.parameters[j]
        if not fitted.identifiable:
            raise ScenarioError(f"fit {flag('--profile')} {path}: it cannot be identified from these data")
        theta_hat = np.array([q.value for q in result.parameters])
        free = np.array([k != j for k in range(len(paths))])
        values = fitted.value + fitted.standard_error * np.linspace(-span, span, points)
        costs = []
        for value in values:
            def full(x, value=value):
                theta = theta_hat.copy()
                theta[free], theta[j] = x * self.scale[free], value
                return theta
            if free.any():
                least = least_squares(lambda x: self.model.residuals(full(x), self.train), theta_hat[free] / self.scale[free],
                                      jac=lambda x: self.model.jacobian(full(x), self.train)[:, free] * self.scale[free],
                                      bounds=(self.bounds[free, 0] / self.scale[free], self.bounds[free, 1] / self.scale[free]),
                                      method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12)
                costs.append(float(least.cost))
            else:
                r = self.model.residuals(full(np.zeros(0)), self.train)
                costs.append(0.5 * float(r @ r))
        statistic = 2 * (np.array(costs) - result.cost) / result.residual_scale ** 2
        middle = points // 2
        return {"path": path, "values": values.tolist(), "statistic": statistic.tolist(),
                "interval_95": [_crossing(values[:middle + 1][::-1], statistic[:middle + 1][::-1]),
                                _crossing(values[middle:], statistic[middle:])],
                "wald_interval_95": [fitted.low, fitted.high]}

    def _starts(self, x0, lower, upper):
        yield x0
        if self.starts > 1:
            from scipy.stats import qmc
            unit = qmc.Sobol(len(x0), scramble=True, seed=self.seed).random(int(2 ** np.ceil(np.log2(self.starts))))
            for u in unit[:self.starts - 1]:
                yield lower + u * (upper - lower)


def _crossing(values, statistic, level=3.84):
    """Where ``statistic`` (rising along ``values``) first reaches ``level`` (linear
    interpolation), None if it does not."""
    for k in range(1, len(values)):
        if statistic[k] >= level > statistic[k - 1]:
            fraction = (level - statistic[k - 1]) / (statistic[k] - statistic[k - 1])
            return float(values[k - 1] + fraction * (values[k] - values[k - 1]))
    return None


class FitModel:
    """The experiments' predictions and their exact Jacobian at parameter values ``theta``
    (the fitted parameters' units), each experiment's equilibrium warm-started from its last."""

    def __init__(self, sim, data, parameters):
        from ...simulation import Simulation
        self.sim = Simulation(sim.scenario)                  # its own: the user's keeps its state
        self.sim.params = sim.params.copy()
        self.nominal = self.sim.solve(warn=False)            # fixes the mesh (accuracy control), as solve does
        self.solver = self.sim.solver()
        self.data, self.parameters = data, parameters
        from ...buffers import BufferedFunction, CscPattern
        function = measurement_function(self.solver.nlp, data.names)
        self.measure = BufferedFunction(function)
        self.patterns = (CscPattern(function.sparsity_out(1)), CscPattern(function.sparsity_out(2)))
        size = sim.params.size
        self.directions = np.column_stack([p.vector(size) for p in parameters])
        base = sim.params.copy()
        self.bases = []
        for row in data.input_values:
            params = base.copy()
            for parameter, value in zip(data.inputs, row):
                params = parameter.with_value(params, value)
            self.bases.append(params)
        span = np.ptp(data.input_values, axis=0) if data.input_values.size else np.zeros(0)
        unit = (data.input_values - data.input_values.min(axis=0)) / np.where(span > 0, span, 1.0) \
            if data.input_values.size else np.zeros((data.size, 0))
        self.order = nearest_neighbour_order(unit)
        self.solutions = [None] * data.size
        self._cache = (None, None)
        self.solves = 0

    def params_at(self, theta, k):
        params = self.bases[k].copy()
        for parameter, value in zip(self.parameters, theta):
            params = parameter.with_value(params, value)
        return params

    def solve(self, theta):
        """Every experiment's Solution at ``theta`` (cached for the last theta)."""
        key = np.asarray(theta, float).tobytes()
        if self._cache[0] == key:
            return self._cache[1]
        previous = None
        out = [None] * self.data.size
        for k in self.order:
            start = self.solutions[k] if self.solutions[k] is not None else previous
            try:
                solution = self.sim.solve_near(start, self.params_at(theta, k))
            except TcaError as error:
                raise TcaError(f"experiment {k + 1} at {self._describe(theta)}: {error}") from None
            self.solves += 1
            if not solution.converged:
                raise TcaError(f"experiment {k + 1} did not converge at {self._describe(theta)}: {solution.message}")
            out[k] = previous = solution
        self.solutions = out
        self._cache = (key, out)
        return out

    def _describe(self, theta):
        return ", ".join(f"{p.path} = {v:.6g} {p.unit}" for p, v in zip(self.parameters, theta))

    def predictions(self, theta, rows=None):
        """Predicted measurements (n, q) in SI."""
        solutions = self.solve(theta)
        rows = range(self.data.size) if rows is None else rows
        return np.array([self.measure(solutions[k].iterate.w, self.params_at(theta, k))[0].copy() for k in rows])

    def residuals(self, theta, rows):
        """Weighted residuals ``(y - m) / sigma`` of the experiments ``rows``, flattened (n q,)."""
        rows = np.asarray(rows, int)
        if rows.size == 0:
            return np.zeros(0)
        predicted = self.predictions(theta, rows)
        return ((self.data.values[rows] - predicted) / self.data.sigmas[rows]).ravel()

    def jacobian(self, theta, rows):
        """``d residuals / d theta`` (n q, p): minus the measurements' exact derivatives over sigma."""
        solutions = self.solve(theta)
        q = len(self.data.names)
        pattern = self.patterns
        out = np.zeros((len(rows) * q, len(self.parameters)))
        for i, k in enumerate(rows):
            w, params = solutions[k].iterate.w, self.params_at(theta, k)
            _, y_w, y_P = self.measure(w, params)
            linear = self.solver.linearise(w, params)
            dw = linear.state_derivative(self.directions)                    # (n_w, p)
            dy = pattern[0].matrix(y_w) @ dw + pattern[1].matrix(y_P) @ self.directions
            out[i * q:(i + 1) * q] = -dy / self.data.sigmas[k][:, None]
        return out


def synthetic_measurements(sim, truth, inputs, names, noise, seed=0):
    """Measurements made by the model itself: the quantities ``names`` of ``sim``'s robot at the
    parameter values ``truth`` (``{path: value}``) for the experiments ``inputs`` (``{path:
    values (n,)}``), plus Gaussian noise of standard deviation ``noise`` (``{kind: sigma}``,
    SI, seeded). A :class:`Measurements` whose sigmas are the noise's."""
    from ...simulation import Simulation
    model_sim = Simulation(sim.scenario)
    model_sim.solve(warn=False)                  # the mesh a fit of these data uses (accuracy control)
    params = model_sim.params.copy()
    for path, value in truth.items():
        params = resolve_parameter(model_sim.robot, params, path).with_value(params, value)
    columns = [resolve_parameter(model_sim.robot, params, path) for path in inputs]
    given = np.column_stack([np.asarray(v, float) for v in inputs.values()])
    function = measurement_function(model_sim.solver().nlp, names)
    kinds = [quantity_kind(model_sim.robot, name) for name in names]
    sigmas = np.array([noise[k] for k in kinds])
    rng = np.random.default_rng(seed)
    values, previous = np.empty((len(given), len(names))), None
    for k, row in enumerate(given):
        point = params.copy()
        for parameter, value in zip(columns, row):
            point = parameter.with_value(point, value)
        solution = model_sim.solve_near(previous, point)
        if not solution.converged:
            raise TcaError(f"synthetic experiment {k + 1} did not converge: {solution.message}")
        previous = solution
        values[k] = np.array(function(solution.iterate.w, point)[0]).ravel() + sigmas * rng.standard_normal(len(names))
    return Measurements(columns, given, list(names), values, np.tile(sigmas, (len(given), 1)), "<synthetic>")


def write_measurements(path, data, comments=()):
    """``data`` as a measurement CSV (inputs in their units, measurements and their sigmas in
    mm or mN), ``comments`` as ``#`` lines first."""
    from ...output import write_csv
    header = [p.si_label for p in data.inputs]
    scale = [(1e3, "mN") if name.endswith(".tension") else (1e3, "mm") for name in data.names]
    header += [f"{name} [{unit}]" for name, (_, unit) in zip(data.names, scale)]
    header += [f"sigma_{name} [{unit}]" for name, (_, unit) in zip(data.names, scale)]
    factors = np.array([f for f, _ in scale])
    rows = [[f"{v:.10g}" for v in given] + [f"{v:.10g}" for v in values * factors] + [f"{v:.6g}" for v in sigma * factors]
            for given, values, sigma in zip(data.input_values, data.values, data.sigmas)]
    return write_csv(path, header, rows, comments=comments)

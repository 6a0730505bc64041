"""The result of a calibration: the fitted values with their standard errors, 95 % intervals and
correlations, the identifiability diagnosis, the residuals before and after, and the files
(``fit.json``, ``fitted.yaml``, ``fit.png``, ``fit_parameters.png``)."""
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...output import atomic_path, write_json
from ...results import ResultAPI, status_of
from ...status import Status
from ...errors import flag

#: Fisher information condition numbers above this are reported (parameters not told apart)
CONDITION_LIMIT = 1e10
#: a direction whose singular value is below this fraction of the largest is unidentifiable
SINGULAR = 1e-9
#: a parameter whose share of the weakest direction is at least this is named in the warning
SHARE = 0.3
#: a parameter with at least this share of a singular direction has no finite variance
NULL_SHARE = 0.01


@dataclass
class FittedParameter:
    path: str
    unit: str
    nominal: float
    value: float
    standard_error: float = None      # None: not identifiable from the data
    low: float = None                 # 95 % interval
    high: float = None
    shown_as: object = None           # the StudyParameter that says the unit values are shown in (None: SI)

    @property
    def identifiable(self):
        return self.standard_error is not None

    @property
    def shown_unit(self):
        return self.shown_as.shown_unit if self.shown_as is not None else self.unit

    def shown(self, value):
        """``value`` (SI) in :attr:`shown_unit`."""
        return self.shown_as.shown(value) if self.shown_as is not None else value

    def as_dict(self):
        return {"path": self.path, "unit": self.unit, "nominal": self.nominal, "value": self.value,
                "standard_error": self.standard_error, "interval_95": None if self.low is None else [self.low, self.high],
                "identifiable": self.identifiable}


@dataclass(repr=False)
class FitResult(ResultAPI):
    """``parameters`` (FittedParameter), ``correlation`` (p, p; NaN where not identifiable),
    ``covariance`` (p, p) in the parameters' units, ``condition`` (of the Fisher information
    ``J^T J`` in scaled parameters), ``warnings`` (texts), residual statistics and status."""
    parameters: list
    covariance: np.ndarray
    correlation: np.ndarray
    condition: float
    warnings: list
    converged: bool
    message: str
    evaluations: int
    cost: float
    residual_scale: float            # s: the residuals' RMS in units of sigma
    rms: dict                        # before/after (and held out): per kind
    residuals: np.ndarray            # (n_train, q) after, SI
    predicted: np.ndarray            # (n, q) after, SI (every experiment)
    predicted_before: np.ndarray     # (n, q) at the nominal values
    names: list
    train: np.ndarray
    test: np.ndarray
    wall_time_s: float
    data_source: str
    fit: object = field(default=None, repr=False)
    profile: dict = None              # Fit.profile of one parameter, on request
    measured_scale: float = None      # the residuals' RMS in units of sigma, even with absolute sigmas

    @classmethod
    def build(cls, fit, theta, optimum, before, after, J, test_residuals, wall_time):
        model, data = fit.model, fit.data
        n, p = J.shape
        scaled = J * fit.scale[None, :]
        _, singular, vectors = np.linalg.svd(scaled, full_matrices=False)
        condition = float((singular[0] / singular[-1]) ** 2) if singular[-1] > 0 else float("inf")
        dof = max(n - p, 1)
        s2 = 1.0 if fit.absolute_sigma else float(after @ after) / dof
        weak = singular <= SINGULAR * singular[0]          # all of them when J is zero
        unidentifiable = set()
        for k in np.flatnonzero(weak):
            unidentifiable |= {j for j in range(p) if abs(vectors[k, j]) >= NULL_SHARE}
        inverse = np.zeros(p)
        inverse[~weak] = 1.0 / singular[~weak] ** 2
        covariance_x = (vectors.T * inverse) @ vectors * s2
        covariance = covariance_x * np.outer(fit.scale, fit.scale)
        from scipy.stats import t as student
        quantile = float(student.ppf(0.975, dof))
        parameters = []
        for j, parameter in enumerate(fit.parameters):
            nominal = float(fit.nominal[j])
            if j in unidentifiable:
                parameters.append(FittedParameter(parameter.path, parameter.unit, nominal, float(theta[j]),
                                                  shown_as=_shown(parameter)))
                continue
            error = float(np.sqrt(max(covariance[j, j], 0.0)))
            parameters.append(FittedParameter(parameter.path, parameter.unit, nominal, float(theta[j]), error,
                                              float(theta[j] - quantile * error), float(theta[j] + quantile * error),
                                              _shown(parameter)))
        errors = np.array([q.standard_error if q.identifiable and q.standard_error > 0 else np.nan for q in parameters])
        with np.errstate(invalid="ignore", divide="ignore"):
            correlation = covariance / np.outer(errors, errors)
        warnings = []
        if unidentifiable:
            names = [fit.parameters[j].path for j in sorted(unidentifiable)]
            warnings.append(("cannot be identified from these data: " + " and ".join(names) +
                             (" (they change the measurements only in a fixed combination)" if len(names) > 1
                              else " (the measurements do not depend on it)") +
                             f"; Fisher information condition number {condition:.3g}; no interval given"))
        elif condition > CONDITION_LIMIT:
            k = int(np.argmin(singular))
            names = [fit.parameters[j].path for j in range(p) if abs(vectors[k, j]) >= SHARE]
            warnings.append(f"hard to tell apart: {' and '.join(names)} (Fisher information condition number "
                            f"{condition:.3g}); their intervals are wide and strongly correlated")
        for i in range(p):
            for j in range(i + 1, p):
                if np.isfinite(correlation[i, j]) and abs(correlation[i, j]) > 0.99:
                    warnings.append(f"{fit.parameters[i].path} and {fit.parameters[j].path} are correlated "
                                    f"{correlation[i, j]:+.4f}: the data hardly tell them apart")
        measured = float(np.sqrt(float(after @ after) / dof))
        warnings.extend(misfit_warnings(measured, dof, fit.absolute_sigma))
        q = len(data.names)
        predicted = model.predictions(theta)
        predicted_before = _nominal_predictions(fit)
        rms = {"before": _rms(fit, data.values[fit.train] - predicted_before[fit.train]),
               "after": _rms(fit, data.values[fit.train] - predicted[fit.train])}
        if fit.test.size:
            rms["held_out"] = _rms(fit, data.values[fit.test] - predicted[fit.test])
        return cls(parameters, covariance, correlation, condition, warnings, bool(optimum.success),
                   str(optimum.message), int(optimum.nfev), float(optimum.cost), float(np.sqrt(s2)),
                   rms, (data.values[fit.train] - predicted[fit.train]).reshape(-1, q), predicted,
                   predicted_before, list(data.names), fit.train, fit.test, wall_time, data.source, fit,
                   measured_scale=measured)

    # ------------------------------------------------------------------ text and files
    @property
    def result(self):
        """:class:`SolveStatus` of the least squares."""
        return status_of(self.converged, "least squares (fit)", self.message, Status.ALGORITHM_FAILED,
                         nit=self.evaluations, solve_time_s=self.wall_time_s)

    def figure(self):
        """``fit.png``'s figure: measured against predicted, the residuals."""
        from ...plotting.fit_plots import plot_fit
        return plot_fit(self, None)

    def summary(self):
        what = (f"a time series of {len(self.train)} samples" if self.fit.time_series
                else f"{len(self.train)} experiment(s)")
        lines = [f"fit of {len(self.parameters)} parameter(s) to {what} "
                 f"({len(self.names)} quantit{'y' if len(self.names) == 1 else 'ies'} each): "
                 f"{'converged' if self.converged else 'NOT CONVERGED'} "
                 f"in {self.evaluations} evaluations, {self.wall_time_s:.2f} s"]
        for q in self.parameters:
            interval = (f"+- {q.shown(q.standard_error):.3g} (95 %: {q.shown(q.low):.6g} to {q.shown(q.high):.6g})"
                        if q.identifiable else "not identifiable")
            lines.append(f"  {q.path} = {q.shown(q.value):.6g} {q.shown_unit} {interval}; "
                         f"nominal {q.shown(q.nominal):.6g}")
        for when in ("before", "after", "held_out"):
            r = self.rms.get(when, {})
            parts = []
            if "length_mm" in r:
                parts.append(f"{r['length_mm']:.4g} mm ({r['length_percent']:.3g} % of the robot's length)")
            if "force_mN" in r:
                parts.append(f"{r['force_mN']:.4g} mN")
            if "temperature_K" in r:
                parts.append(f"{r['temperature_K']:.4g} K")
            if parts:
                lines.append(f"  RMS {when.replace('_', ' ')}: " + ", ".join(parts))
        if self.fit.time_series:
            by_type = {}
            for q, p in zip(self.parameters, self.fit.parameters):
                by_type.setdefault(p.tca_type, {})[p.key] = q.value
            for name, values in by_type.items():
                if len(values) == 2:
                    lines.append(f"  tca_types.{name}: time constant C/G = {values['heat_capacity'] / values['conductance']:.4g} s")
        lines.append(f"  residual scale {self.measured_scale:.3g} sigma"
                     + (" (intervals from the sigmas as given)" if self.fit.absolute_sigma else "")
                     + f"; Fisher condition number {self.condition:.3g}")
        if self.profile is not None:
            low, high = self.profile["interval_95"]
            wald = self.profile["wald_interval_95"]
            show = lambda v: "beyond the profiled range" if v is None else f"{v:.6g}"     # noqa: E731
            lines.append(f"  profile likelihood of {self.profile['path']}: 95 % from {show(low)} to {show(high)} "
                         f"(Wald: {wald[0]:.6g} to {wald[1]:.6g})")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self):
        return {"converged": self.converged, "message": self.message, "evaluations": self.evaluations,
                "wall_time_s": self.wall_time_s, "data": self.data_source,
                "experiments": {"fitted": len(self.train), "held_out": len(self.test)},
                "measured": self.names, "parameters": [q.as_dict() for q in self.parameters],
                "correlation": _nan_to_none(self.correlation), "covariance": _nan_to_none(self.covariance),
                "fisher_condition_number": self.condition, "residual_scale_sigma": self.residual_scale,
                "residual_scale_measured": self.measured_scale,
                "rms": self.rms, "warnings": self.warnings, "profile": self.profile,
                "residuals": [dict(zip(self.names, map(float, row)), experiment=int(k) + 1)
                              for k, row in zip(self.train, self.residuals)]}

    def fitted_scenario(self):
        """The scenario's raw mapping with the fitted values written in (every fitted layout
        entry in full, SI numbers; temperatures in degC)."""
        from ...scenario.overrides import apply_overrides
        sim = self.fit.sim
        raw = sim.scenario._raw if sim.scenario._raw is not None else sim.scenario.model_dump(mode="json")
        return apply_overrides(raw, self.fit.fitted_overrides([q.value for q in self.parameters]))

    def save(self, directory, plots=True):
        """Write fit.json, fitted.yaml and (``plots``) fit.png and fit_parameters.png."""
        import yaml
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        written = [write_json(directory / "fit.json", self.to_dict())]
        header = ("# written by tca-casadi fit: the scenario with the fitted values (SI; temperatures degC)\n# "
                  + "\n# ".join(f"{q.path} = {q.value:.8g} {q.unit}" + (f" +- {q.standard_error:.3g}" if q.identifiable
                                                                         else " (not identifiable)")
                                for q in self.parameters) + "\n")
        with atomic_path(directory / "fitted.yaml") as temporary:
            temporary.write_text(header + yaml.safe_dump(self.fitted_scenario(), sort_keys=False))
        written.append(directory / "fitted.yaml")
        if plots:
            from ...plotting.fit_plots import plot_fit, plot_fit_parameters
            written += [plot_fit(self, directory / "fit.png"), plot_fit_parameters(self, directory / "fit_parameters.png")]
        return written


def _nominal_predictions(fit):
    return fit.model.predictions(fit.nominal)


#: a residual scale outside the central 1 - MISFIT_LEVEL of chance (chi-square) is warned about
MISFIT_LEVEL = 1e-3


def misfit_warnings(scale, dof, absolute_sigma):
    """Warnings (texts) when the residuals' RMS in units of their sigmas (``scale``) is more, or
    less, than chance allows at ``dof`` degrees of freedom if the model and the sigmas were right
    (the chi-square test at :data:`MISFIT_LEVEL` each side)."""
    from scipy.stats import chi2
    high = float(np.sqrt(chi2.ppf(1 - MISFIT_LEVEL, dof) / dof))
    low = float(np.sqrt(chi2.ppf(MISFIT_LEVEL, dof) / dof))
    if scale > high:
        effect = (f"the intervals assume the sigmas ({flag('--absolute-sigma')}) and are too narrow" if absolute_sigma
                  else "the intervals are widened by it")
        return [f"the residuals are {scale:.3g} times their sigmas, more than chance allows ({high:.3g} at most, "
                f"{dof} degrees of freedom): the model does not fit these data or the sigmas are too small; {effect}"]
    if scale < low:
        effect = (f"the intervals assume the sigmas ({flag('--absolute-sigma')}) and are too wide" if absolute_sigma
                  else "the intervals are narrowed by it")
        return [f"the residuals are {scale:.3g} of their sigmas, less than chance allows ({low:.3g} at least, "
                f"{dof} degrees of freedom): the sigmas are larger than the scatter of these data; {effect}"]
    return []


def _rms(fit, difference):
    """RMS of the differences (n, q) per kind: lengths in mm and % of the robot's length, forces
    in mN, temperatures in K."""
    robot = fit.sim.robot
    kinds = [fit.quantity_kind(name) for name in fit.data.names]
    out = {}
    temperatures = difference[:, [k == "temperature" for k in kinds]]
    if temperatures.size:
        out["temperature_K"] = float(np.sqrt(np.mean(temperatures ** 2)))
    lengths = difference[:, [k == "length" for k in kinds]]
    if lengths.size:
        value = float(np.sqrt(np.mean(lengths ** 2)))
        out.update({"length_mm": value * 1e3, "length_percent": 100 * value / robot_length(robot)})
    forces = difference[:, [k == "force" for k in kinds]]
    if forces.size:
        out["force_mN"] = float(np.sqrt(np.mean(forces ** 2))) * 1e3
    return out


def robot_length(robot):
    """The length [m] of the modules from the base to the tip."""
    total, m = 0.0, robot.tip_index
    while m is not None:
        total += robot.modules[m].length
        m = robot.modules[m].parent
    return total


def _nan_to_none(matrix):
    return [[None if not np.isfinite(v) else float(v) for v in row] for row in np.asarray(matrix)]


def _shown(parameter):
    """The fitted parameter's :class:`StudyParameter` where it has one (it knows its shown unit)."""
    return parameter if hasattr(parameter, "shown_unit") else None

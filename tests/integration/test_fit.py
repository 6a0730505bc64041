"""Calibration (``tc.Fit``, ``tca-casadi fit``): the exact Jacobian against central
differences, recovery of known values from synthetic data (coverage of the 95 % intervals),
unidentifiable parameters reported as such, the files, bad input."""
import json
import subprocess
import sys

import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

import tca_casadi as tc
from tca_casadi.cli import main
from tca_casadi.studies.fit.least_squares import Fit, synthetic_measurements, write_measurements

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
E = "materials.ecoflex30.youngs_modulus"
FIBER = "tca_types.nylon.fiber_radius"
TIP = ["tip_x", "tip_y", "tip_z"]


@pytest.fixture
def sim(scenarios):
    return tc.Simulation.from_file(scenarios / "bending_module.yaml")


def _temperatures(count, seed):
    rng = np.random.default_rng(seed)
    return {f"bending.tca{k}.temperature": np.round(rng.uniform(25, 125, count), 1) for k in (1, 2, 3)}


def test_exact_jacobian_equals_central_differences(sim):
    """Every kind of measured quantity (the tip, a module's end, a stroke, a tension) against four
    parameters (a modulus, the TCA geometry, a route's radius: it moves the reference length
    too, a fit coefficient): to 1e-6 of each column's largest entry. Fourth-order central
    differences with steps of 1e-3 of each value: their truncation (~1e-12) and Newton's
    tolerance over the step (1e-10 / 1e-3) both stay well below the bound."""
    names = TIP + ["bending.tip_x", "bending.tca1.stroke", "bending.tca2.tension", "bending.tca3.length"]
    params = [E, FIBER, "bending.tca1.route.radius", "tca_types.nylon.untwist.c1"]
    data = synthetic_measurements(sim, {}, _temperatures(4, 1), names, {"length": 1e-4, "force": 1e-3})
    fit = Fit(sim, data, params)
    model, theta = fit.model, fit.nominal * np.array([1.05, 0.97, 1.02, 1.01])
    exact = model.jacobian(theta, fit.train)
    for j in range(len(params)):
        step = 1e-3 * fit.scale[j]

        def at(k):
            moved = theta.copy()
            moved[j] += k * step
            return model.residuals(moved, fit.train)
        central = (at(-2) - 8 * at(-1) + 8 * at(1) - at(2)) / (12 * step)
        assert_allclose(exact[:, j], central, rtol=0, atol=1e-6 * np.max(np.abs(central)))
        assert np.max(np.abs(central)) > 0


def test_recovery_and_coverage(sim):
    """Synthetic data at known values of two parameters with 0.05 mm noise
    (``scripts/fit_coverage.py``, whose full run of 100 repetitions the README quotes): over 8
    seeded repetitions the 95 % intervals hold the true values about 15 times of 16 (at least 13
    asserted: fewer has probability below 1 % for honest intervals); the residuals' RMS equals
    the noise (mean residual scale within 0.15 of 1 sigma; every fit's within 0.5 to 1.6 for its
    30 residuals)."""
    sys.path.insert(0, str(ROOT / "scripts"))
    from fit_coverage import coverage
    inside, total, scales = coverage(sim, 8)
    assert total == 16 and inside >= 13, inside
    assert_allclose(np.mean(scales), 1.0, rtol=0, atol=0.15)
    assert all(0.5 < s < 1.6 for s in scales)


def test_unidentifiable_parameters_are_reported(sim):
    """With every heated TCA at one temperature, the untwist fit's c1 and c2 change the data only
    through c2 (T^2 - T0^2) + c1 (T - T0): a pair that cannot be told apart. c0 cancels in the
    law altogether. Neither gets an interval, and the warning names them."""
    inputs = {"bending.tca2.temperature": np.full(6, 100.0), "bending.tca3.temperature": np.full(6, 100.0),
              "tip_force.force.x": np.linspace(-2e-3, 2e-3, 6)}
    data = synthetic_measurements(sim, {}, inputs, TIP, {"length": 5e-5}, 3)
    result = Fit(sim, data, ["tca_types.nylon.untwist.c1", "tca_types.nylon.untwist.c2", E]).run()
    by_path = {q.path: q for q in result.parameters}
    assert not by_path["tca_types.nylon.untwist.c1"].identifiable
    assert not by_path["tca_types.nylon.untwist.c2"].identifiable
    assert by_path[E].identifiable
    assert any("tca_types.nylon.untwist.c1 and tca_types.nylon.untwist.c2" in w for w in result.warnings)
    alone = Fit(sim, data, ["tca_types.nylon.untwist.c0"]).run()
    assert not alone.parameters[0].identifiable
    assert "do not depend on it" in alone.warnings[0]


def test_cli_on_the_shipped_example(tmp_path, capsys):
    """The shipped dataset: four parameters recovered within their intervals; the fitted
    scenario reproduces the fitted predictions; the held-out error is reported."""
    out = tmp_path / "fit"
    code = main(["fit", str(ROOT / "scenarios" / "bending_module.yaml"), "--data",
                 str(ROOT / "data" / "bending_module_measurements.csv"), "--param", E, "--param", FIBER,
                 "--param", "bending.tca1.route.radius", "--param", "tca_types.nylon.untwist.c1",
                 "--holdout", "0.2", "-o", str(out), "--quiet"])
    assert code == 0
    text = capsys.readouterr().out
    assert "fit of 4 parameter(s) to 40 experiment(s)" in text and "RMS held out" in text
    report = json.loads((out / "fit.json").read_text())
    sys.path.insert(0, str(ROOT / "scripts"))
    from make_fit_data import NOISE_MM, TRUTH
    for entry in report["parameters"]:
        low, high = entry["interval_95"]
        assert low <= TRUTH[entry["path"]] <= high, entry
    assert_allclose(report["rms"]["after"]["length_mm"], NOISE_MM, rtol=0.25)
    assert report["rms"]["before"]["length_mm"] > 5 * report["rms"]["after"]["length_mm"]   # 0.27 -> 0.045 mm
    fitted = yaml.safe_load((out / "fitted.yaml").read_text())
    assert fitted["materials"]["ecoflex30"]["youngs_modulus"] == pytest.approx(report["parameters"][0]["value"], rel=1e-12)
    first = report["residuals"][0]["experiment"]
    header = [line for line in (ROOT / "data" / "bending_module_measurements.csv").read_text().splitlines()
              if not line.startswith("#")]
    row = dict(zip(header[0].split(","), header[first].split(",")))
    again = tc.Simulation.from_file(out / "fitted.yaml", [
        f"bending.tca{k}.temperature={row[f'bending.tca{k}.temperature [degC]']}" for k in (1, 2, 3)]).solve(warn=False)
    measured = np.array([float(row[f"{a} [mm]"]) for a in TIP]) * 1e-3
    residual = np.array([report["residuals"][0][a] for a in TIP])
    assert_allclose(measured - again.tip_position, residual, rtol=0, atol=1e-9)
    for name in ("fit.png", "fit_parameters.png"):
        assert (out / name).stat().st_size > 10000


def test_shipped_dataset_is_what_the_script_makes(tmp_path):
    """The shipped datasets are the output of scripts/make_fit_data.py: the same comments,
    columns and inputs, and the same measurements to 1e-8 of their units (mm: 1e-11 m, below
    what the solver's tolerance fixes; they are written with 10 digits)."""
    for options, shipped in (([], "bending_module_measurements.csv"), (["--heating"], "bending_module_heating_curve.csv")):
        made = tmp_path / shipped
        run = subprocess.run([sys.executable, str(ROOT / "scripts" / "make_fit_data.py"), *options, "-o", str(made)],
                             capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        made_text, made_numbers = _text_and_numbers(made)
        shipped_text, shipped_numbers = _text_and_numbers(ROOT / "data" / shipped)
        assert made_text == shipped_text
        assert_allclose(made_numbers, shipped_numbers, rtol=0, atol=1e-8)


def _text_and_numbers(path):
    """A CSV's comment and header lines, and its rows of numbers (k, columns)."""
    text, numbers = [], []
    for line in path.read_text().splitlines():
        try:
            numbers.append([float(value) for value in line.split(",")])
        except ValueError:
            text.append(line)
    return text, np.array(numbers)


@pytest.fixture
def data_file(sim, tmp_path):
    data = synthetic_measurements(sim, {}, _temperatures(3, 0), TIP, {"length": 1e-4})
    return write_measurements(tmp_path / "data.csv", data)


def _edit(path, old, new):
    path.write_text(path.read_text().replace(old, new, 1))
    return path


@pytest.mark.parametrize("change, args, message", [
    (("tip_x [mm]", "tip_w [mm]"), [], "column 'tip_w [mm]' is neither a scenario parameter nor a measured quantity"),
    (("tip_x [mm]", "tip_x [N]"), [], "column 'tip_x [N]': [N] is not a unit of length"),
    (("bending.tca1.temperature [degC]", "bending.tca1.temperature [mm]"), [], "bending.tca1.temperature"),
    (None, ["--param", "bending.length"], "structure cannot be fitted"),
    (None, ["--bounds", f"{E}=0.2MPa:0.3MPa"], "excludes the nominal value"),
    (None, ["--param", FIBER, "--param", "bending.tca1.route.radius", "--param", "bending.tca2.route.radius",
            "--param", "bending.tca3.route.radius", "--param", "tca_types.nylon.coil_radius",
            "--param", "tca_types.nylon.untwist.c1", "--param", "tca_types.nylon.untwist.c2",
            "--param", "tca_types.nylon.shear_modulus.a0"], "9 measured values for 10 parameters"),
    (None, ["--sigma", "length=-1mm"], "positive"),
    (None, ["--holdout", "1.5"], "holdout"),
])
def test_bad_input_is_one_line_exit_2(data_file, tmp_path, capsys, change, args, message):
    if change is not None:
        _edit(data_file, *change)
    code = main(["fit", str(ROOT / "scenarios" / "bending_module.yaml"), "--data", str(data_file), "--param", E,
                 "--param", "tca_types.nylon.pitch_angle"] + args + ["-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err


def test_missing_data_file_is_exit_2(tmp_path, capsys):
    code = main(["fit", str(ROOT / "scenarios" / "bending_module.yaml"), "--data", str(tmp_path / "none.csv"),
                 "--param", E, "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "none.csv: no such file" in err and err.count("\n") == 1, err


def test_nan_row_names_its_row(data_file, tmp_path, capsys):
    lines = data_file.read_text().splitlines()
    cells = lines[2].split(",")
    cells[-4] = "nan"
    lines[2] = ",".join(cells)
    data_file.write_text("\n".join(lines) + "\n")
    code = main(["fit", str(ROOT / "scenarios" / "bending_module.yaml"), "--data", str(data_file), "--param", E,
                 "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "line 3, column" in err and "NaN" in err, err


def test_profile_likelihood_agrees_with_the_wald_interval(sim):
    """For a nearly linear problem (the modulus alone, 20 synthetic experiments) the profile
    likelihood's 95 % interval equals the Wald interval within 5 % of its width, its statistic
    is 0 at the estimate and rises on both sides; with a second fitted parameter refitted at
    each point it is at least as wide as with it held (profiling never narrows)."""
    data = synthetic_measurements(sim, {E: 0.14e6}, _temperatures(20, 4), TIP, {"length": 5e-5}, 4)
    fit = Fit(sim, data, [E])
    result = fit.run()
    profile = fit.profile(result, E)
    width = result.parameters[0].high - result.parameters[0].low
    assert_allclose(profile["interval_95"], profile["wald_interval_95"], rtol=0, atol=0.05 * width)
    statistic = np.array(profile["statistic"])
    assert abs(statistic[4]) < 1e-6 and np.all(np.diff(statistic[:5]) < 0) and np.all(np.diff(statistic[4:]) > 0)
    both = Fit(sim, data, [E, FIBER])
    joint = both.run()
    profiled = both.profile(joint, E)
    assert profiled["interval_95"][1] - profiled["interval_95"][0] >= 0.99 * width


HEATING = ROOT / "scenarios" / "bending_module_heating.yaml"
C, G = "tca_types.nylon.thermal.heat_capacity", "tca_types.nylon.thermal.conductance"


def test_heating_curve_model_is_the_closed_form():
    """The time-series model at constants (C, G): a 0.3 W step from ambient at 1 s, off at 40 s,
    follows T_amb + P/G (1 - exp(-(t - 1) G/C)) and then decays exponentially, to 1e-6 K."""
    from tca_casadi.studies.fit.thermal import synthetic_heating_curve
    sim = tc.Simulation.from_file(HEATING)
    times = np.arange(0.0, 80.5, 2.0)
    curve = synthetic_heating_curve(sim, {C: 0.16, G: 0.0065}, ["bending.tca2.temperature"], times, 1e-30)
    tau, rise = 0.16 / 0.0065, 0.3 / 0.0065
    heating = 25 + rise * (1 - np.exp(-np.clip(times - 1, 0, None) / tau))
    peak = 25 + rise * (1 - np.exp(-39 / tau))
    expected = np.where(times <= 40, heating, 25 + (peak - 25) * np.exp(-(times - 40) / tau))
    assert_allclose(curve.values[:, 0], expected, rtol=0, atol=1e-6)


def test_heating_curve_recovery_and_coverage():
    """Twenty seeded heating curves (0.3 K noise): the 95 % intervals of C and G hold the truth
    at least 34 times of 40 (about 38 expected; 36 here), the fitted values' errors in units of
    their standard errors have mean within 0.5 of 0 and spread within 0.7-1.4."""
    from tca_casadi.studies.fit.thermal import synthetic_heating_curve
    sim = tc.Simulation.from_file(HEATING)
    truth = {C: 0.16, G: 0.0065}
    inside, z = 0, []
    for seed in range(20):
        curve = synthetic_heating_curve(sim, truth, ["bending.tca2.temperature"], np.arange(0.0, 80.5, 1.0), 0.3, seed)
        result = Fit(sim, curve, list(truth), absolute_sigma=True).run()
        for q, value in zip(result.parameters, truth.values()):
            inside += q.low <= value <= q.high
            z.append((q.value - value) / q.standard_error)
    assert inside >= 34, inside
    assert abs(np.mean(z)) < 0.5 and 0.7 < np.std(z) < 1.4


def test_cli_fits_the_shipped_heating_curve(tmp_path, capsys):
    out = tmp_path / "heating"
    code = main(["fit", str(HEATING), "--data", str(ROOT / "data" / "bending_module_heating_curve.csv"),
                 "--param", C, "--param", G, "-o", str(out), "--quiet"])
    assert code == 0
    text = capsys.readouterr().out
    assert "a time series of 81 samples (1 quantity each)" in text and "time constant C/G" in text
    report = json.loads((out / "fit.json").read_text())
    for entry, value in zip(report["parameters"], (0.16, 0.0065)):
        assert abs(entry["value"] - value) < 3 * entry["standard_error"], entry     # C is 2.5 SE off: chance
    assert_allclose(report["rms"]["after"]["temperature_K"], 0.3, rtol=0.2)
    fitted = yaml.safe_load((out / "fitted.yaml").read_text())
    assert fitted["tca_types"]["nylon"]["thermal"]["conductance"] == pytest.approx(report["parameters"][1]["value"], rel=1e-9)


@pytest.mark.parametrize("args, message", [
    (["--param", "materials.ecoflex30.youngs_modulus"], "a time-series fit takes a TCA type's (or an SMA type's) thermal constants"),
    (["--param", C, "--sigma", "temperature=-1"], "positive"),
])
def test_heating_bad_input(tmp_path, capsys, args, message):
    code = main(["fit", str(HEATING), "--data", str(ROOT / "data" / "bending_module_heating_curve.csv")] + args
                + ["-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1, err


def test_heating_curve_column_that_is_not_a_temperature(tmp_path, capsys):
    bad = tmp_path / "curve.csv"
    bad.write_text("t [s],tip_x [mm]\n0,1\n1,2\n")
    code = main(["fit", str(HEATING), "--data", str(bad), "--param", C, "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and "column 'tip_x [mm]' of a time series" in err, err


def test_a_fit_that_does_not_fit_says_so(sim):
    """The README's own example (two of the four parameters that made the data): residuals 4.2
    times their 0.1 mm sigma, which chance does not allow for 148 degrees of freedom."""
    fit = Fit(sim, str(ROOT / "data" / "bending_module_measurements.csv"), [E, "tca_types.nylon.untwist.c1"],
              bounds={E: ("0.05 MPa", "0.5 MPa")})
    result = fit.run()
    assert result.converged
    assert 4.0 < result.measured_scale < 4.4
    misfit = [w for w in result.warnings if "times their sigmas" in w]
    assert len(misfit) == 1 and "the model does not fit these data or the sigmas are too small" in misfit[0]
    assert json.loads(json.dumps(result.to_dict()))["residual_scale_measured"] == result.measured_scale      # JSON keeps floats exactly


@pytest.mark.parametrize("noise, sigma, words", [
    (0.05e-3, 0.05e-3, None),                       # honest sigmas: no warning
    (0.05e-3, 0.5e-3, "less than chance allows"),   # sigmas ten times the scatter
    (0.05e-3, 0.005e-3, "more than chance allows"),  # a tenth of it
])
def test_the_residual_scale_is_judged_against_chance(sim, noise, sigma, words):
    from tca_casadi.studies.fit.least_squares import synthetic_measurements
    truth = {E: 0.14e6}
    data = synthetic_measurements(sim, truth, _temperatures(12, 3), TIP, {"length": noise}, seed=4)
    data.sigmas[:] = sigma
    result = Fit(sim, data, [E]).run()
    found = [w for w in result.warnings if "chance allows" in w]
    assert (found == []) if words is None else (len(found) == 1 and words in found[0]), result.warnings
    absolute = Fit(sim, data, [E], absolute_sigma=True).run()
    assert absolute.residual_scale == 1.0 and absolute.measured_scale == pytest.approx(result.measured_scale, rel=1e-6)

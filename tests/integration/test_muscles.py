"""Other muscles (issue 20): SMA wires (Liang-Rogers), McKibben muscles (Tondu-Lopez /
Chou-Hannaford) and user laws against closed forms written here independently of
:mod:`tca_casadi.model.laws`, and both solvers on the example robots.

The closed forms: a muscle on the centerline of a straight rod without gravity keeps the rod
straight and compresses it axially, ``nu_3 = 1 - F / (E A)`` exactly (the linear constitutive
law), so its path length is ``L (1 - F / (E A))`` and its tension is the root of one scalar
equation, found here by bisection (scipy's brentq)."""
import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.optimize import brentq

import tca_casadi as tc
from tca_casadi.studies.compare import check

LENGTH, DIAMETER, YOUNGS = 0.1, 0.01, 1e9
AREA = math.pi * DIAMETER ** 2 / 4


def centerline_robot(muscle_type, actuator, youngs=YOUNGS):
    """A straight 100 mm rod (10 mm across, E = 1 GPa) with one muscle on its centerline."""
    return tc.Simulation(tc.load_scenario({
        "name": "centerline", "gravity": [0, 0, 0],
        "materials": {"stiff": {"youngs_modulus": youngs, "poisson_ratio": 0.5}},
        "muscle_types": {"m": muscle_type},
        "modules": [{"name": "rod", "length": LENGTH, "material": "stiff",
                     "cross_section": {"shape": "circle", "diameter": DIAMETER},
                     "actuators": [dict({"name": "a", "type": "m",
                                         "route": {"kind": "straight", "radius": 0}}, **actuator)]}],
        "solver": {"intervals": 4}}))


# ----------------------------------------------------------------------------- SMA
def liang_rogers_fraction(T, sigma, A_s=68.0, A_f=78.0, C_A=13.8e6):
    """Heating branch, Liang and Rogers (1990): xi = xi_M / 2 (cos(a_A (T - A_s - sigma/C_A)) + 1)
    inside the band, 1 below it, 0 above it (xi_M = 1)."""
    low, high = A_s + sigma / C_A, A_f + sigma / C_A
    if T <= low:
        return 1.0
    if T >= high:
        return 0.0
    return 0.5 * (math.cos(math.pi / (A_f - A_s) * (T - low)) + 1.0)


def sma_tension(T, d=0.15e-3, E_A=83e9, E_M=28e9, eps_L=0.04, T_ref=25.0):
    """The wire's tension on the centerline rod: the wire is stress free at T_ref in the
    reference shape (installed strain eps_L xi(T_ref, 0)); at F its strain is
    (1 + eps_0)(1 - F / (E A)) - 1 and sigma = E(xi) (eps - eps_L xi), E(xi) = E_A + xi (E_M - E_A)."""
    A = math.pi * d * d / 4
    eps_0 = eps_L * liang_rogers_fraction(T_ref, 0.0)

    def residual(F):
        xi = liang_rogers_fraction(T, F / A)
        eps = (1 + eps_0) * (1 - F / (YOUNGS * AREA)) - 1
        return A * (E_A + xi * (E_M - E_A)) * (eps - eps_L * xi) - F
    return brentq(residual, 0.0, 50.0, xtol=1e-15, rtol=1e-15)


@pytest.mark.parametrize("temperature", [25.0, 60.0, 70.0, 73.0, 76.0, 80.0, 95.0, 150.0])
def test_sma_wire_on_a_stiff_rod_pulls_with_the_liang_rogers_force(temperature):
    sim = centerline_robot({"kind": "sma"}, {"kind": "sma", "temperature": temperature})
    solution = sim.solve()
    assert solution.converged
    force = solution.actuators["rod.a"].tension
    expected = sma_tension(temperature)
    assert_allclose(force, expected, rtol=1e-8, atol=1e-12)
    # the rod stays straight and shortens by F L / (E A)
    assert_allclose(solution.tip_position, [0, 0, LENGTH * (1 - expected / (YOUNGS * AREA))], rtol=0, atol=1e-12)
    if temperature < 68:
        assert force < 1e-9          # martensite at rest: nothing happens below A_s


def test_sma_free_stroke_and_martensite_fraction_closed_forms():
    law = tc.Simulation(tc.load_scenario("scenarios/bending_module_sma.yaml")).robot.actuators[0].law
    for T in (25.0, 68.0, 70.0, 73.0, 77.5, 78.0, 120.0):
        for sigma in (0.0, 50e6, 200e6):
            assert_allclose(float(law.martensite_fraction(T, sigma)), liang_rogers_fraction(T, sigma),
                            rtol=0, atol=1e-14)
    l_star = law.reference_length
    austenite_length = l_star / 1.04                 # installed fully detwinned: eps_0 = eps_L = 4 %
    for T in (25.0, 70.0, 73.0, 90.0):
        expected = austenite_length * (1 + 0.04 * liang_rogers_fraction(T, 0.0)) - l_star
        assert_allclose(law.free_stroke(T), expected, rtol=0, atol=1e-15)
    assert_allclose(law.free_stroke(90.0), -l_star * 0.04 / 1.04, rtol=1e-14)


def test_sma_cooling_branch_lags_the_heating_branch():
    """Inside the hysteresis (between M_s and A_s) a wire on the cooling branch is still
    austenite (it pulls), one on the heating branch still martensite (it does not)."""
    heating = centerline_robot({"kind": "sma"}, {"kind": "sma", "temperature": 60.0}).solve()
    cooling = centerline_robot({"kind": "sma", "branch": "cooling", "reference_temperature": 25},
                               {"kind": "sma", "temperature": 60.0}).solve()
    assert heating.actuators["rod.a"].tension < 1e-9
    assert cooling.actuators["rod.a"].tension > 1.0


def test_sma_thermal_model_is_the_wire_s():
    """C = rho c A l*, G = h pi d l*, R = rho_e l* / A (the defaults: NiTi in still air)."""
    sim = tc.Simulation.from_file("scenarios/bending_module_sma.yaml")
    actuator = sim.robot.actuators[0]
    law = actuator.thermal_law(sim.scenario)
    d, length = 0.15e-3, actuator.reference_length
    area = math.pi * d * d / 4
    assert_allclose(law.heat_capacity, 6450 * 837 * area * length, rtol=1e-14)
    assert_allclose(law.conductance, 25 * math.pi * d * length, rtol=1e-14)
    assert_allclose(law.resistance, 80e-8 * length / area, rtol=1e-14)


def test_a_current_heats_the_wire_to_its_steady_state(tmp_path):
    """Under a constant current the wire settles at T_amb + I^2 R / G; its heat balance holds."""
    sim = tc.Simulation.from_file("scenarios/bending_module_sma.yaml",
                                  ["timeline=[]", "duration=60", "bending.sma1.drive.value=0.12"])
    series = tc.TimeSimulation(sim, dt=2.0).run()
    assert series.completed, series.message
    law = sim.robot.actuators[0].thermal_law(sim.scenario)
    steady = 25.0 + 0.12 ** 2 * law.resistance / law.conductance
    history = series.history
    assert_allclose(history.temperature[-1, 0], steady, rtol=0, atol=0.02)   # 60 s = 7.4 time constants
    assert np.max(np.abs(history.heat_balance_residual())) < 1e-6
    # the wire pulls once above A_s (plus its stress's shift) and the module bends toward it
    assert series.solutions[-1].tip_position[0] > 1e-3


# ----------------------------------------------------------------------------- McKibben
def chou_hannaford_force(P, eps, r0=2e-3, alpha=math.radians(20), k=1.0):
    """Tondu and Lopez: F = pi r0^2 P (3 (1 - k eps)^2 / tan^2(alpha) - 1 / sin^2(alpha))."""
    return math.pi * r0 ** 2 * P * (3 * (1 - k * eps) ** 2 / math.tan(alpha) ** 2 - 1 / math.sin(alpha) ** 2)


@pytest.mark.parametrize("correction", [1.0, 1.25])
@pytest.mark.parametrize("pressure", [0.0, 50e3, 200e3, 600e3])
def test_mckibben_on_a_stiff_rod_pulls_with_the_law_s_force(pressure, correction):
    sim = centerline_robot({"kind": "mckibben", "correction": correction}, {"kind": "mckibben", "pressure": pressure})
    solution = sim.solve()
    assert solution.converged
    force = solution.actuators["rod.a"].tension
    # the rod shortens by F / (E A): the muscle contracts by eps = F / (E A)
    expected = brentq(lambda F: chou_hannaford_force(pressure, F / (YOUNGS * AREA), k=correction) - F,
                      -1.0, 1e3, xtol=1e-14, rtol=1e-15) if pressure else 0.0
    assert_allclose(force, expected, rtol=1e-8, atol=1e-12)
    # the blocked force pi r0^2 P (a - b), less the rod's small compliance to first order in
    # eps = F / (E A): F / F_blocked - 1 = -2 a k eps / (a - b) + O(eps^2)
    a, b = 3 / math.tan(math.radians(20)) ** 2, 1 / math.sin(math.radians(20)) ** 2
    blocked = math.pi * 4e-6 * pressure * (a - b)
    assert_allclose(sim.robot.actuators[0].law.blocked_force(pressure), blocked, rtol=1e-14)
    if pressure:
        eps = force / (YOUNGS * AREA)
        assert abs(force / blocked - 1 + 2 * a * correction * eps / (a - b)) < 10 * eps ** 2 * a / (a - b)


@pytest.mark.parametrize("correction", [1.0, 1.25])
def test_mckibben_free_contraction_is_the_closed_form(correction):
    """A muscle whose rest length exceeds its path by more than its free contraction is slack
    (tension_only): its slack length is l0 (1 - eps_max) - l*, eps_max = (1 - 1/(sqrt 3 cos a0)) / k."""
    eps_max = (1 - 1 / (math.sqrt(3) * math.cos(math.radians(20)))) / correction
    rest = LENGTH / (1 - eps_max) * 1.01
    sim = centerline_robot({"kind": "mckibben", "correction": correction, "rest_length": rest},
                           {"kind": "mckibben", "pressure": 200e3, "tension_only": True})
    solution = sim.solve()
    result = solution.actuators["rod.a"]
    assert result.tension < 1e-6 and result.slack
    # pressurised and slack: a surprise, so a warning (a passive slack tendon gives none)
    assert any("rod.a is active but slack" in w for w in solution.warning_texts("slack"))
    assert_allclose(result.slack_length, rest * (1 - eps_max) - LENGTH, rtol=1e-9)
    assert_allclose(result.free_stroke, rest * (1 - eps_max) - LENGTH, rtol=1e-12)


# ----------------------------------------------------------------------------- user laws
CHOU_HANNAFORD = '''
import casadi

def chou_hannaford(stroke, force, input, reference_length, radius, angle):
    eps = -stroke / reference_length
    a, b = 3 / casadi.tan(angle) ** 2, 1 / casadi.sin(angle) ** 2
    return 3.141592653589793 * radius ** 2 * input * (a * (1 - eps) ** 2 - b) - force

def wrong_shape(stroke, force, input, reference_length):
    return casadi.vertcat(stroke, force)

def not_casadi(stroke, force, input, reference_length):
    return "r"
'''


def test_a_user_law_reproduces_the_built_in_mckibben_law(tmp_path):
    """The entry point (found beside the scenario) writes Chou-Hannaford's law; the robot solves
    as with the built-in law, to the solver's precision."""
    (tmp_path / "my_laws.py").write_text(CHOU_HANNAFORD)
    text = Path("scenarios/bending_module_mckibben.yaml").read_text()
    built_in = tc.Simulation.from_file("scenarios/bending_module_mckibben.yaml").solve()
    custom = text.replace("thin: {kind: mckibben, radius: \"2 mm\", braid_angle: \"20 deg\", correction: 1.0, "
                          "max_pressure: \"400 kPa\"}",
                          "thin: {kind: custom, entry_point: 'my_laws:chou_hannaford', scale: 50, "
                          "parameters: {radius: 0.002, angle: 0.3490658503988659}, min_input: 0, max_input: 4e5}")
    custom = custom.replace("kind: mckibben,", "kind: custom,").replace('pressure: "200 kPa"', "input: 2e5")
    custom = custom.replace("pressure: 0", "input: 0")
    (tmp_path / "custom.yaml").write_text(custom)
    solution = tc.Simulation.from_file(tmp_path / "custom.yaml", allow_code=True).solve()
    assert solution.converged
    assert_allclose(solution.tip_position, built_in.tip_position, rtol=0, atol=1e-11)
    for k in ("pam1", "pam2", "pam3"):       # atol: the slack muscles' smoothing residue (~1e-8 N)
        assert_allclose(solution.actuators[f"segment.{k}"].tension, built_in.actuators[f"segment.{k}"].tension,
                        rtol=1e-9, atol=2e-8)


def test_the_shipped_user_law_against_its_closed_form():
    """linear_muscle: F = k (delta + g u l*) on each muscle, at the solved stroke."""
    solution = tc.Simulation.from_file("scenarios/bending_module_custom.yaml", allow_code=True).solve()
    for key, u in (("bending.m1", 1.0), ("bending.m2", 0.0)):
        a = solution.actuators[key]
        assert_allclose(a.tension, 200.0 * (a.stroke + 0.05 * u * a.reference_length), rtol=1e-9, atol=1e-12)
        assert a.input == u


# ----------------------------------------------------------------------------- both solvers
@pytest.mark.parametrize("scenario", ["bending_module_sma", "bending_module_mckibben", "bending_module_custom"])
@pytest.mark.parametrize("setting", [None, "low", "high"])
def test_collocation_and_shooting_agree_on_the_example_robots(scenario, setting):
    overrides = {"bending_module_sma": {"low": ["bending.sma1.temperature=72"], "high": ["bending.sma1.temperature=150"]},
                 "bending_module_mckibben": {"low": ["segment.pam1.pressure=20 kPa"],
                                             "high": ["segment.pam1.pressure=400 kPa", "segment.pam2.pressure=100 kPa"]},
                 "bending_module_custom": {"low": ["bending.m1.input=0.1"], "high": ["bending.m2.input=2"]}}
    sim = tc.Simulation.from_file(f"scenarios/{scenario}.yaml", overrides[scenario].get(setting, []),
                                 allow_code=scenario == "bending_module_custom")
    report, collocation, shooting = check(sim)
    assert collocation.converged and shooting.converged
    assert_allclose(collocation.tip_position, shooting.tip_position, rtol=0, atol=1e-6)
    for key, a in collocation.actuators.items():
        b = shooting.actuators[key]
        assert abs(a.tension - b.tension) <= 1e-5 * max(1.0, abs(a.tension)), key
    assert collocation.balance.relative < 1e-8


def test_muscle_constants_are_parameters_no_rebuild_needed():
    """Setting an SMA constant on a built model equals building the model with it."""
    sim = tc.Simulation.from_file("scenarios/bending_module_sma.yaml", ["bending.sma1.temperature=74"])
    structure = sim.robot.structure_key(sim.scenario)
    sim.set("muscle_types.flexinol.A_f", 76.0)
    sim.set("muscle_types.flexinol.E_A", 70e9)
    moved = sim.solve()
    assert sim.robot.structure_key(sim.scenario) == structure
    fresh = tc.Simulation.from_file("scenarios/bending_module_sma.yaml",
                                    ["bending.sma1.temperature=74", "muscle_types.flexinol.A_f=76",
                                     "muscle_types.flexinol.E_A=70e9"]).solve()
    assert_allclose(moved.tip_position, fresh.tip_position, rtol=0, atol=1e-12)
    assert abs(moved.tip_position[0] - tc.Simulation.from_file(
        "scenarios/bending_module_sma.yaml", ["bending.sma1.temperature=74"]).solve().tip_position[0]) > 1e-4


def test_an_sma_wire_s_thermal_constants_fit_from_its_heating_curve():
    """Calibration sees the thermal muscles through the same interface: a noiseless heating curve
    of wire 1 (140 mA for 40 s, then cooling) at C = 6e-3 J/K, G = 9e-4 W/K gives them back."""
    from tca_casadi.studies.fit.thermal import synthetic_heating_curve
    sim = tc.Simulation.from_file("scenarios/bending_module_sma.yaml")
    truth = {"muscle_types.flexinol.thermal.heat_capacity": 6e-3, "muscle_types.flexinol.thermal.conductance": 9e-4}
    curve = synthetic_heating_curve(sim, truth, ["bending.sma1.temperature"], np.arange(0.0, 80.5, 2.0), 1e-30)
    # I^2 R / G: the steady rise of a constant current, reached before the current stops
    law = sim.robot.actuators[0].thermal_law(sim.scenario)
    assert_allclose(curve.values[20, 0], 25 + 0.14 ** 2 * law.resistance / 9e-4, rtol=0, atol=0.5)
    result = tc.Fit(sim, curve, list(truth)).run()
    assert result.converged, result.message
    for q, value in zip(result.parameters, truth.values()):
        assert_allclose(q.value, value, rtol=1e-6)


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("scenario, override, message", [
    ("sma", "muscle_types.flexinol.M_s=90", "transformation temperatures out of order: need M_s < A_f"),
    ("sma", "muscle_types.flexinol.A_s=80", "need A_s < A_f"),
    ("sma", "muscle_types.flexinol.E_A=-1", "muscle_types.flexinol.E_A: input should be greater than 0"),
    ("sma", "muscle_types.flexinol.wire_diameter=0", "wire_diameter: input should be greater than 0"),
    ("sma", "bending.sma1.temperature=200", "200 degC is outside the sma law's range [0, 150] degC"),
    ("sma", "bending.sma1.type=nope", "unknown sma type 'nope'"),
    ("sma", ["muscle_types.pam={kind: mckibben}", "bending.sma1.type=pam"], "muscle_types.pam is a mckibben type, not a sma one"),
    ("mckibben", "muscle_types.thin.radius=0", "muscle_types.thin.radius: input should be greater than 0"),
    ("mckibben", "muscle_types.thin.braid_angle=60 deg", "braid_angle 60 deg must be below 54.7 deg"),
    ("mckibben", "segment.pam1.pressure=1 MPa", "outside the mckibben law's range [0, 400000] Pa"),
    ("mckibben", "segment.pam1.pressure=-1 kPa", "outside the mckibben law's range"),
    ("custom", "muscle_types.linear.entry_point=no_such_module:f", "entry_point: cannot import 'no_such_module'"),
    ("custom", "muscle_types.linear.entry_point=muscle_laws:nothing", "module 'muscle_laws' has no function 'nothing'"),
    ("custom", "muscle_types.linear.entry_point=muscle_laws", "must read 'module:function'"),
    ("custom", "bending.m1.input=5", "5 is outside the custom law's range [0, 2]"),
])
def test_bad_muscle_input_is_one_line_exit_2(capsys, scenario, override, message):
    from tca_casadi import cli
    overrides = [override] if isinstance(override, str) else override
    code = cli.main(["solve", f"scenarios/bending_module_{scenario}.yaml", "--no-plot", "-o", "/nonexistent-never-written",
                     "--allow-code"]
                    + [word for o in overrides for word in ("--set", o)])
    err = capsys.readouterr().err
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], err


@pytest.mark.parametrize("function, message", [
    ("wrong_shape", "returned shape (2, 1), expected a scalar (1, 1)"),
    ("not_casadi", "returned str, not a CasADi expression"),
])
def test_an_entry_point_that_builds_no_scalar_expression_is_refused(tmp_path, capsys, function, message):
    from tca_casadi import cli
    (tmp_path / "my_laws.py").write_text(CHOU_HANNAFORD)
    text = Path("scenarios/bending_module_custom.yaml").read_text()
    text = text.replace('"muscle_laws:linear_muscle", parameters: {stiffness: 200.0, gain: 0.05}',
                        f'"my_laws:{function}", parameters: {{}}')
    (tmp_path / "bad.yaml").write_text(text)
    code = cli.main(["solve", str(tmp_path / "bad.yaml"), "--no-plot", "-o", str(tmp_path / "out"), "--allow-code"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("seed", range(4))
def test_random_robots_with_muscles_balance_and_both_solvers_agree(seed):
    """Random chains and trees with SMA wires and McKibben muscles on straight, helical and spline
    routes: the global force and moment balance holds and shooting agrees with collocation."""
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from random_robots import random_muscle_robot
    scenario = random_muscle_robot(seed)
    scenario["solver"] = {"intervals": 32, "refine": "off"}      # the balance, not the refinement
    sim = tc.Simulation(tc.load_scenario(scenario))
    report, collocation, shooting = check(sim)
    assert collocation.converged and shooting.converged, (collocation.message, shooting.message)
    assert collocation.balance.relative < 1e-8
    assert_allclose(collocation.tip_position, shooting.tip_position, rtol=0, atol=1e-6)
    for key, a in collocation.actuators.items():
        assert abs(a.tension - shooting.actuators[key].tension) <= 1e-5 * max(1e-3, abs(a.tension)), key


def test_a_mckibben_muscle_s_geometry_fits_from_tip_measurements():
    """Calibration reaches a muscle's constants as NLP parameters: noiseless tip positions of the
    McKibben segment at six pressures, made at r0 = 2.2 mm and alpha0 = 22 deg, give them back."""
    from tca_casadi.studies.fit.least_squares import synthetic_measurements
    sim = tc.Simulation.from_file("scenarios/bending_module_mckibben.yaml")
    truth = {"muscle_types.thin.radius": 2.2e-3, "muscle_types.thin.braid_angle": math.radians(22)}
    inputs = {"segment.pam1.pressure": np.linspace(50e3, 300e3, 6)}
    data = synthetic_measurements(sim, truth, inputs, ["tip_x", "tip_z"], {"length": 1e-12})
    result = tc.Fit(sim, data, list(truth)).run()
    assert result.converged, result.message
    for q, value in zip(result.parameters, truth.values()):
        assert_allclose(q.value, value, rtol=1e-6)


def test_a_user_law_travels_to_study_workers(tmp_path, capsys):
    """Worker processes rebuild the scenario from a mapping: the law's folder (the scenario
    file's, written down absolute by the loader) goes with it."""
    from tca_casadi import cli
    code = cli.main(["study", str(Path("scenarios/bending_module_custom.yaml").resolve()),
                     "--vary", "bending.m1.input=0:2:3", "--vary", "bending.m2.input=0:2:2", "--workers", "2",
                     "--no-plot", "--quiet", "-o", str(tmp_path / "study"), "--allow-code"])
    assert code == 0, capsys.readouterr().err
    import json
    report = json.loads((tmp_path / "study" / "study.json").read_text())
    assert report["converged"] == 6 and report["failed"] == 0, report


def test_a_monte_carlo_over_sma_constants_converges_everywhere(tmp_path, capsys):
    """Each sample starts from the reference state, where the tension-only wires sit at the
    corner of their complementarity (taut, no tension): continuation must take that corner."""
    from tca_casadi import cli
    code = cli.main(["study", "scenarios/bending_module_sma.yaml", "--set", "bending.sma1.temperature=74",
                     "--monte-carlo", "muscle_types.flexinol.A_f=normal:78:1",
                     "--monte-carlo", "muscle_types.flexinol.E_A=uniform:70e9:90e9", "--samples", "12",
                     "--no-plot", "--quiet", "-o", str(tmp_path / "mc")])
    assert code == 0, capsys.readouterr().err
    import json
    report = json.loads((tmp_path / "mc" / "study.json").read_text())
    assert report["converged"] == 12, report


# ----------------------------------------------------------------------------- code is opt-in
MARKER_LAW = """
import pathlib
pathlib.Path(__file__).with_name("ran.txt").write_text("imported")


def linear_muscle(stroke, force, input, reference_length, stiffness, gain):
    return force - stiffness * (stroke + gain * input * reference_length)
"""


def _dropped_law_scenario(tmp_path):
    """The shipped custom scenario beside a law module that leaves a file behind when imported."""
    (tmp_path / "muscle_laws.py").write_text(MARKER_LAW)
    (tmp_path / "robot.yaml").write_text(Path("scenarios/bending_module_custom.yaml").read_text())
    return tmp_path / "robot.yaml"


@pytest.mark.parametrize("command", ["validate", "solve", "check"])
def test_a_scenario_that_would_run_code_is_refused_without_importing_it(tmp_path, command):
    """In a fresh process, as a user opening someone else's scenario: one line naming the module
    and the file it would import, exit 2, and the module never ran."""
    import subprocess
    import sys
    scenario = _dropped_law_scenario(tmp_path)
    output = [] if command == "validate" else ["-o", str(tmp_path / "out")]
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", command, str(scenario), *output],
                         capture_output=True, text=True, cwd="/")
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1, run.stderr
    assert "muscle_types.linear.entry_point: this scenario runs Python code" in lines[0]
    assert f"module 'muscle_laws' ({tmp_path / 'muscle_laws.py'})" in lines[0] and "--allow-code" in lines[0]
    assert not (tmp_path / "ran.txt").exists() and not (tmp_path / "out").exists()


def test_allowed_code_runs(tmp_path):
    import subprocess
    import sys
    scenario = _dropped_law_scenario(tmp_path)
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "validate", str(scenario), "--allow-code"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "ran.txt").read_text() == "imported"


def test_python_callers_allow_code_explicitly(tmp_path):
    scenario = _dropped_law_scenario(tmp_path)
    with pytest.raises(tc.ScenarioError, match="allow_code=True"):
        tc.Simulation.from_file(scenario)
    with pytest.raises(tc.ScenarioError, match="runs Python code"):       # --set cannot smuggle one in
        tc.Simulation.from_file("scenarios/bending_module_sma.yaml",
                                ["muscle_types.mine={kind: custom, entry_point: 'muscle_laws:linear_muscle'}"])
    assert not (tmp_path / "ran.txt").exists()
    assert tc.Simulation.from_file(scenario, allow_code=True).solve(warn=False).converged

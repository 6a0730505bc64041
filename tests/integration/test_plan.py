"""Optimal heating schedules (``tca-casadi plan``, issue 32): the minimum-time plan of one heated
TCA against its closed form, the plan replayed through ``simulate``, the least-energy plan
against the fastest and against a constant input, bad input."""
import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.cli import main
from tca_casadi.control import Plan
from tca_casadi.errors import ModelError
from tca_casadi.time_simulation.timeline import TimeSimulation

HEATING = SCENARIOS / "bending_module_heating.yaml"
#: TCA 2 at 60 degC in steady state puts the tip here
TARGET_TEMPERATURE = 60.0


@pytest.fixture(scope="module")
def target():
    return Simulation.from_file(HEATING, [f"bending.tca2.temperature={TARGET_TEMPERATURE}"]).solve(warn=False).tip_position


@pytest.fixture(scope="module")
def fastest(target):
    return Plan(Simulation.from_file(HEATING), target, objective="time", horizon=24.0, nodes=12).solve()


def test_minimum_time_is_bang_bang_and_follows_the_closed_form(fastest):
    """One heated TCA, power bounded by P_max (the default: the power that holds 150 degC): full
    power until the temperature that puts the tip on target, T* = 60 degC, then the holding power
    G (T* - T_amb). Reached at t* = (C/G) ln((P_max/G) / (P_max/G - (T* - T_amb))) (6.37 s) to
    the grid's resolution (2 s steps); the temperatures on the way follow the heating curve
    T_amb + (P_max/G)(1 - exp(-t G/C)) to 1e-9 K."""
    plan = fastest
    assert plan.converged and plan.reached, plan.summary()
    law = Plan(Simulation.from_file(HEATING), plan.target, horizon=24.0, nodes=12).laws[0]
    C, G, ambient = law.heat_capacity, law.conductance, 25.0
    p_max = plan.bounds[0, 1]
    assert p_max == pytest.approx(G * (150.0 - ambient), rel=1e-12)
    rise = TARGET_TEMPERATURE - ambient
    t_star = (C / G) * np.log((p_max / G) / (p_max / G - rise))
    h = plan.t[1]
    assert t_star <= plan.reached_at_s <= t_star + h
    full = plan.t[:-1] + h <= t_star                       # steps that end before t*
    hold = plan.t[:-1] >= plan.reached_at_s
    assert_allclose(plan.inputs[full, 0], p_max, rtol=1e-6, atol=0)
    assert_allclose(plan.inputs[hold, 0], G * rise, rtol=1e-6, atol=0)
    on_the_way = plan.t <= t_star
    curve = ambient + (p_max / G) * (1 - np.exp(-plan.t[on_the_way] * G / C))
    assert_allclose(plan.temperatures[on_the_way, 0], curve, rtol=0, atol=1e-9)
    assert np.all(plan.errors[plan.t >= plan.reached_at_s] <= plan.tolerance)


def test_a_power_budget_below_full_power_is_the_bang_bang_of_the_budget(target, fastest):
    """A 0.6 W budget on the one heated TCA (full power 0.884 W): the same closed form with
    P_max = 0.6 W (t* = 10.8 s instead of 6.4 s), the budget held to the slack while heating, and
    the total power never above it; one line for a budget below what the fixed inputs draw."""
    plan = Plan(Simulation.from_file(HEATING), target, objective="time", horizon=24.0, nodes=24,
                power_budget=0.6).solve()
    assert plan.converged and plan.reached, plan.summary()
    law = Plan(Simulation.from_file(HEATING), target, horizon=24.0, nodes=24).laws[0]
    C, G = law.heat_capacity, law.conductance
    t_star = (C / G) * np.log((0.6 / G) / (0.6 / G - (TARGET_TEMPERATURE - 25.0)))
    assert t_star <= plan.reached_at_s <= t_star + plan.t[1] and plan.reached_at_s > fastest.reached_at_s
    full = plan.t[:-1] + plan.t[1] <= t_star
    assert_allclose(plan.inputs[full, 0], 0.6, rtol=0, atol=1e-6)
    assert np.max(plan.total_powers) <= 0.6 + 1e-6 and plan.to_dict()["power_budget_W"] == 0.6


def test_a_power_budget_shared_by_three_tcas_on_the_arm():
    """The arm's bending module (three TCAs by power) to where TCA 1 at 65 degC and the others at
    42.5 degC put the tip: its fastest plan in 6 s steps draws 1.34 W at once; with a 0.9 W budget
    the total stays within it (to 1e-6 W) at every step and the tip comes slower to the target."""
    drives = [f"bending.tca{k}.drive={{kind: power, value: 0}}" for k in (1, 2, 3)]
    arm = SCENARIOS / "arm.yaml"
    goal = Simulation.from_file(arm, drives + ["bending.tca1.temperature=65", "bending.tca2.temperature=42.5",
                                               "bending.tca3.temperature=42.5"]).solve(warn=False).tip_position
    free = Plan(Simulation.from_file(arm, drives), goal, horizon=30.0, nodes=5).solve()
    held = Plan(Simulation.from_file(arm, drives), goal, horizon=30.0, nodes=5, power_budget=0.9).solve()
    assert free.reached and np.max(free.total_powers) > 1.2, free.summary()
    assert held.converged and held.reached, held.summary()
    assert np.max(held.total_powers) <= 0.9 + 1e-6 and held.reached_at_s >= free.reached_at_s
    assert held.errors[2] > 1e-5 > free.errors[2]          # at 12 s: 0.099 mm with it, 1.6e-8 mm without


def test_the_plan_replayed_in_simulate_gives_the_planned_temperatures_and_tips(fastest):
    """The schedule (``PlanResult.overrides``, what ``plan_timeline.yaml`` holds) run through the
    quasi-static ``simulate`` at the plan's step: the same temperatures to 1e-6 K and the same tip
    to 1e-6 m at every node (measured 1e-8 K and 1e-11 m: the thermal integrator's tolerance)."""
    series = TimeSimulation(Simulation.from_file(HEATING, fastest.overrides()), dt=fastest.t[1]).run()
    assert series.completed, series.message
    assert_allclose(series.t, fastest.t, rtol=0, atol=1e-12)
    column = series.keys.index("bending.tca2")
    assert_allclose(series.temperatures[:, column], fastest.temperatures[:, 0], rtol=0, atol=1e-6)
    assert_allclose(series.tip_positions(), fastest.tips, rtol=0, atol=1e-6)


VOLTAGE = ["timeline=[]", "bending.tca2.drive={kind: voltage, value: 0}", "tca_types.nylon.resistance=20 ohm"]


def test_a_voltage_drive_is_planned_in_volts_and_replays(target, fastest):
    """The same TCA driven by a voltage through a constant 20 ohm: the same powers as the power
    plan (the model is linear in P = V^2 / R), the drive values V = sqrt(P R) in the CSV header's
    unit and the timeline, and the schedule replayed through ``simulate`` gives the planned
    temperatures to 1e-6 K and tips to 1e-6 m."""
    plan = Plan(Simulation.from_file(HEATING, VOLTAGE), target, horizon=24.0, nodes=12).solve()
    assert plan.converged and plan.reached_at_s == fastest.reached_at_s, plan.summary()
    assert_allclose(plan.inputs, fastest.inputs, rtol=1e-9, atol=1e-12)
    assert_allclose(plan.drive_values(), np.sqrt(fastest.inputs * 20.0), rtol=1e-9, atol=1e-12)
    assert plan.header()[1:3] == ["bending.tca2.drive.value [V]", "bending.tca2.power [W]"]
    assert plan.timeline()["timeline"][0]["set"]["bending.tca2.drive.value"].endswith(" V")
    series = TimeSimulation(Simulation.from_file(HEATING, VOLTAGE + plan.overrides()), dt=plan.t[1]).run()
    assert series.completed, series.message
    column = series.keys.index("bending.tca2")
    assert_allclose(series.temperatures[:, column], plan.temperatures[:, 0], rtol=0, atol=1e-6)
    assert_allclose(series.tip_positions(), plan.tips, rtol=0, atol=1e-6)


def test_voltage_bounds_are_in_volts_and_a_temperature_dependent_resistance_is_refused(target):
    sim = Simulation.from_file(HEATING, VOLTAGE)
    planner = Plan(sim, target, horizon=24.0, nodes=4, bounds=["0 V", "3 V"])
    assert_allclose(planner.bounds, [[0.0, 9.0 / 20.0]], rtol=1e-12, atol=0)
    with pytest.raises(Exception, match=r"^bounds for bending.tca2.drive.value \(a voltage drive, in V\): "
                                        r"'3 W' is not a voltage"):
        Plan(sim, target, horizon=24.0, nodes=4, bounds=["0", "3 W"])
    varying = Simulation.from_file(HEATING, VOLTAGE + ["tca_types.nylon.resistance_temperature_coefficient=0.001"])
    with pytest.raises(ModelError, match="resistance that changes with temperature"):
        Plan(varying, target, horizon=24.0, nodes=4)


def test_an_sma_on_a_current_drive_is_planned_in_amperes():
    """A shape-memory wire heated by a current (``bending_module_sma.yaml``): the plan to the pose
    that 80 degC gives reaches it, in A, and its schedule replays through ``simulate``."""
    sma = SCENARIOS / "bending_module_sma.yaml"
    goal = Simulation.from_file(sma, ["bending.sma1.temperature=80"]).solve(warn=False).tip_position
    plan = Plan(Simulation.from_file(sma), goal, horizon=30.0, nodes=10).solve()
    assert plan.converged and plan.reached, plan.summary()
    assert plan.units == ["A"] and "bending.sma1.drive.value [A]" in plan.header()
    series = TimeSimulation(Simulation.from_file(sma, plan.overrides()), dt=plan.t[1]).run()
    assert series.completed, series.message
    assert_allclose(series.tip_positions(), plan.tips, rtol=0, atol=1e-6)


def test_a_target_direction_consistent_with_the_pose_is_reached_with_it(fastest):
    """The tip's tangent at 60 degC as a target direction besides its position: the same plan
    (reached at the same node, the same inputs), the angle at the end under 1e-6 rad (the forward
    solve's own tangent); the vertical instead, which no temperature of TCA 2 gives with that
    position: not reached, and the message says how far off in angle."""
    pose = Simulation.from_file(HEATING, [f"bending.tca2.temperature={TARGET_TEMPERATURE}"]).solve(warn=False)
    tangent = pose.modules[-1].R[:, 2, -1]
    plan = Plan(Simulation.from_file(HEATING), pose.tip_position, horizon=24.0, nodes=12, direction=tangent).solve()
    assert plan.converged and plan.reached_at_s == fastest.reached_at_s, plan.summary()
    assert_allclose(plan.inputs, fastest.inputs, rtol=1e-6, atol=0)
    assert plan.angle_errors[-1] < 1e-6 and plan.header()[-1] == "angle_error [rad]"
    assert np.all(plan.angle_errors[plan.t >= plan.reached_at_s] <= np.radians(1.0))
    off = Plan(Simulation.from_file(HEATING), pose.tip_position, horizon=24.0, nodes=12, direction=[0, 0, -1]).solve()
    assert not off.reached and "deg off the direction" in off.message, off.summary()


def test_a_module_s_end_as_the_point_on_the_arm():
    """``point='bending'`` on the arm (its bending module's TCAs by power): the plan brings that
    module's end, not the tip, to where TCA 2 at 60 degC puts it; a forward solve at the plan's
    last temperatures puts the module's end where the plan says, to 1e-9 m."""
    drives = [f"bending.tca{k}.drive={{kind: power, value: 0}}" for k in (1, 2, 3)] + \
             [f"bending.tca{k}.temperature=25" for k in (1, 2, 3)]
    arm = SCENARIOS / "arm.yaml"
    goal = Simulation.from_file(arm, drives + ["bending.tca2.temperature=60"]).solve(warn=False).modules[0].p[:, -1]
    plan = Plan(Simulation.from_file(arm, drives), goal, horizon=24.0, nodes=6, point="bending").solve()
    assert plan.converged and plan.reached, plan.summary()
    final = Simulation.from_file(arm, drives + [f"{key}.temperature={float(T)!r}" for key, T in
                                                zip(plan.keys, plan.temperatures[-1])]).solve(warn=False)
    assert_allclose(final.modules[0].p[:, -1], plan.tips[-1], rtol=0, atol=1e-9)
    assert np.linalg.norm(final.tip_position - plan.tips[-1]) > 0.01          # the tip is elsewhere


def test_least_energy_uses_less_than_the_fastest_plan_and_a_constant_input(target, fastest):
    """Held from 16 s on: less electrical energy than the minimum-time plan over the horizon, and
    up to 16 s less than the constant input that brings the TCA to the same temperature at 16 s,
    G (T(16 s) - T_amb) / (1 - exp(-16 s G/C)) (heating late loses less to the air)."""
    planner = Plan(Simulation.from_file(HEATING), target, objective="energy", horizon=24.0, nodes=12, by=16.0)
    plan = planner.solve()
    assert plan.converged and plan.reached and plan.reached_at_s <= 16.0, plan.summary()
    assert np.all(plan.errors[plan.t >= 16.0] <= plan.tolerance)
    assert plan.energy_J < fastest.energy_J
    law, h = planner.laws[0], plan.t[1]
    before = plan.t[:-1] < 16.0
    used = float(np.sum(plan.inputs[before, 0]) * h)
    reached = plan.temperatures[plan.t == 16.0, 0][0]
    constant = law.conductance * (reached - 25.0) / (1 - np.exp(-16.0 * law.conductance / law.heat_capacity))
    assert used < constant * 16.0
    assert np.max(plan.temperatures) <= 150.0


def test_cli_plan_writes_its_files_and_simulate_replays_its_timeline(tmp_path, target, capsys):
    position = [f"{v * 1e3:.9f} mm" for v in target]
    assert main(["plan", str(HEATING), "--target-position", *position, "--horizon", "24 s", "--nodes", "12",
                 "-o", str(tmp_path / "plan"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "plan (time): REACHED" in out
    report = json.loads((tmp_path / "plan" / "plan.json").read_text())
    assert report["converged"] and report["reached_at_s"] == 8.0 and report["nodes"] == 12
    data = np.genfromtxt(tmp_path / "plan" / "plan.csv", delimiter=",", names=True)
    assert data.dtype.names[:3] == ("t_s", "bendingtca2drivevalue_W", "bendingtca2temperature_degC")
    assert (tmp_path / "plan" / "plan.png").stat().st_size > 10_000
    assert main(["simulate", str(HEATING), "--timeline", str(tmp_path / "plan" / "plan_timeline.yaml"), "--dt", "2",
                 "-o", str(tmp_path / "replay"), "--quiet", "--no-animation", "--no-plot"]) == 0
    replay = np.genfromtxt(tmp_path / "replay" / "timeseries.csv", delimiter=",", names=True)
    assert_allclose(replay["tip_x_m"], data["tip_x_m"], rtol=0, atol=1e-6)
    assert_allclose(replay["bendingtca2temperature_degC"], data["bendingtca2temperature_degC"], rtol=0, atol=1e-6)


def test_plan_animation_draws_every_node_s_equilibrium(tmp_path, target, capsys):
    """``--animation``: plan.gif beside the other files; the frames' robots are the plan's
    equilibria (each node's solution puts the tip where plan.csv says, to 1e-9 m)."""
    position = [f"{v * 1e3:.9f} mm" for v in target]
    assert main(["plan", str(HEATING), "--target-position", *position, "--horizon", "24 s", "--nodes", "4",
                 "-o", str(tmp_path), "--quiet", "--no-plot", "--animation"]) == 0
    assert "animation at" in capsys.readouterr().out and (tmp_path / "plan.gif").stat().st_size > 10_000
    planner = Plan(Simulation.from_file(HEATING), target, horizon=24.0, nodes=4)
    plan = planner.solve()
    solutions = planner.solutions(plan)
    assert len(solutions) == 5 and all(s.converged for s in solutions)
    assert_allclose([s.tip_position for s in solutions], plan.tips, rtol=0, atol=1e-9)


def test_an_unreachable_target_says_how_close_and_writes_its_files(tmp_path, capsys):
    """A target 10 cm away: the plan gets as close as the bounds allow, says how close, exit 1."""
    assert main(["plan", str(HEATING), "--target-position", "0.1", "0", "0", "--horizon", "10", "--nodes", "5",
                 "-o", str(tmp_path), "--quiet", "--no-plot"]) == 1
    out = capsys.readouterr().out
    assert "NOT REACHED" in out and "the target is not reached within the horizon: the closest pose is" in out
    assert not json.loads((tmp_path / "plan.json").read_text())["reached"]


@pytest.mark.parametrize("arguments, message", [
    (["--vary", "bending.tca2.drive.valu"], "--vary 'bending.tca2.drive.valu' is not a heated TCA's drive value "
                                            "(did you mean 'bending.tca2.drive.value'?)"),
    (["--bounds", "0.5", "0.1"], "--bounds 0.5 0.1 W: give 0 <= LO < HI"),
    (["--objective", "energy", "--by", "40"], "--by 40 s is outside the horizon (0 to 30 s)"),
    (["--horizon", "-1"], "--horizon must be positive"),
    (["--point", "bendng"], "--point 'bendng' is not 'tip' or a module (did you mean 'bending'?)"),
    (["--target-direction", "0", "0", "0"], "target direction must not be zero"),
    (["--target-direction", "0", "0", "1", "--angle-tolerance", "0"], "--angle-tolerance must be positive"),
    (["--bounds", "0", "3 V"], "--bounds for bending.tca2.drive.value (a power drive, in W): '3 V' is not a power"),
    (["--power-budget", "0 W"], "--power-budget must be positive (got 0 W)"),
    (["--power-budget", "2 V"], "--power-budget: '2 V' is not a power"),
])
def test_bad_plan_input_is_one_line(arguments, message, tmp_path, capsys):
    assert main(["plan", str(HEATING), "--target-position", "0", "0", "-0.04", *arguments,
                 "-o", str(tmp_path), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err


def test_a_robot_without_heated_tcas_has_nothing_to_plan(tmp_path, capsys):
    assert main(["plan", str(SCENARIOS / "bending_module.yaml"), "--target-position", "0", "0", "-0.04",
                 "-o", str(tmp_path), "--quiet"]) == 2
    assert "plan: no TCA is heated electrically" in capsys.readouterr().err


def test_a_timeline_file_without_a_timeline_is_refused(tmp_path, capsys):
    bad = tmp_path / "timeline.yaml"
    bad.write_text("events: []\n")
    assert main(["simulate", str(HEATING), "--timeline", str(bad), "-o", str(tmp_path / "out"), "--quiet"]) == 2
    assert "expected a mapping with a 'timeline' list" in capsys.readouterr().err


def test_tracking_a_plan_s_own_tips_recovers_its_inputs(fastest):
    """A path that some schedule follows exactly (the fastest plan's tips at its nodes) is
    tracked to roundoff, and with one heated TCA (tip and temperature one to one) the tracking
    plan's powers are that schedule's (measured: 7e-12 m, 2e-8 relative, 3e-8 K)."""
    plan = Plan(Simulation.from_file(HEATING), (fastest.t, fastest.tips), objective="track", horizon=24.0,
                nodes=12).solve()
    assert plan.converged and plan.reached and plan.reached_at_s == 0.0
    assert np.max(plan.errors) < 1e-9
    assert_allclose(plan.inputs, fastest.inputs, rtol=1e-6, atol=0)
    assert_allclose(plan.temperatures, fastest.temperatures, rtol=0, atol=1e-5)


def test_cli_track_reads_a_path_in_any_unit(tmp_path, fastest, capsys):
    path = tmp_path / "path.csv"
    rows = "\n".join(f"{t:.12g},{x * 1e3:.12g},{y * 1e3:.12g},{z * 1e3:.12g}" for t, (x, y, z) in zip(fastest.t, fastest.tips))
    path.write_text("t [s],x [mm],y [mm],z [mm]\n" + rows + "\n")
    assert main(["plan", str(HEATING), "--objective", "track", "--path", str(path), "--horizon", "24", "--nodes", "12",
                 "-o", str(tmp_path / "out"), "--quiet", "--no-plot"]) == 0
    assert "plan (track): REACHED" in capsys.readouterr().out
    report = json.loads((tmp_path / "out" / "plan.json").read_text())
    assert report["rms_error_m"] < 1e-9
    path.write_text("t [s],x [mm],y [mm],z [mm]\n1,0,0,-40\n1,0,0,-41\n")
    assert main(["plan", str(HEATING), "--objective", "track", "--path", str(path), "-o", str(tmp_path / "bad"),
                 "--quiet"]) == 2
    assert "line 3: the times must increase from row to row" in capsys.readouterr().err
    assert main(["plan", str(HEATING), "--objective", "track", "--target-position", "0", "0", "-0.04",
                 "-o", str(tmp_path / "bad"), "--quiet"]) == 2
    assert "plan --objective track follows a --path CSV" in capsys.readouterr().err


# ---------------------------------------------------------------------------------- closed loop
MPC = SCENARIOS / "bending_module_mpc.yaml"
#: the plant of the issue: the body 10 % stiffer, the TCAs' conductance 20 % larger
PLANT = ["materials.ecoflex30.youngs_modulus=0.1375 MPa", "tca_types.nylon.thermal.conductance=0.0084823 W/K"]


def test_mpc_with_the_exact_model_applies_the_open_loop_plan():
    """Plant = model: every period's plan starts where the last one said it would, so the loop
    applies the minimum-time plan itself (the same powers to 1e-6, reached at 7 s) and holds the
    target with no correction: its disturbance estimate is 0 and its integral holds only the 6 nm
    by which the one-TCA reach misses the target (given to 1e-5 mm), a few times over."""
    from tca_casadi.control import ClosedLoop
    result = ClosedLoop(MPC, ["duration=15"]).run()
    assert result.completed and result.reached and result.reached_at_s == 7.0, result.summary()
    open_loop = Plan(Simulation.from_file(HEATING), result.target, horizon=15.0, nodes=15).solve()
    assert_allclose(result.inputs[:-1, 0], open_loop.inputs[:, 0], rtol=1e-6, atol=0)
    assert np.all(result.errors[result.t >= 7.0] <= result.tolerance)
    assert np.max(np.abs(result.offsets)) < 1e-7
    assert np.all(np.isfinite(result.solve_times[:-1])) and np.isnan(result.solve_times[-1])


def test_mpc_settles_on_a_plant_that_differs_from_its_model():
    """The body 10 % stiffer and the conductance 20 % larger: with the disturbance and integral
    terms the tip settles within the tolerance and ends 0.005 mm from the target (the closest
    the plant's one-TCA reach passes); without them it ends 0.093 mm away."""
    from tca_casadi.control import ClosedLoop
    corrected = ClosedLoop(MPC, ["duration=25"], PLANT).run()
    assert corrected.completed and corrected.reached and corrected.reached_at_s <= 10.0, corrected.summary()
    assert corrected.errors[-1] < 0.01e-3
    blind = ClosedLoop(MPC, ["duration=15", "bending.tca2.drive.mpc.integral_gain=0",
                             "bending.tca2.drive.mpc.disturbance_gain=0"], PLANT).run()
    assert blind.errors[-1] > 10 * corrected.errors[-1]


FOLLOW = "bending.tca2.drive.mpc={path: bending_module_mpc_path.csv, period: 1 s, horizon: 10 s, nodes: 10}"


def test_mpc_follows_a_path_with_the_model_and_with_a_plant_that_differs():
    """``mpc: {path: CSV}`` (``scenarios/bending_module_mpc_path.csv``: the tip's poses as TCA 2
    heats to 50 degC in 20 s and cools to 40 degC in 20 more, every 2 s): with the exact model the
    tip stays within 1e-3 mm of the path (linear between its rows) at every period (measured
    4e-4 mm), and with the body 10 % stiffer and the conductance 20 % larger within 0.02 mm
    (measured 0.012); the path's target at each period is in timeseries' target columns."""
    from tca_casadi.control import ClosedLoop
    from tca_casadi.control.plan import read_path
    exact = ClosedLoop(MPC, ["duration=40", FOLLOW]).run()
    assert exact.completed and exact.reached_at_s == 0.0, exact.summary()
    assert np.max(exact.errors) < 1e-6
    times, positions = read_path(SCENARIOS / "bending_module_mpc_path.csv")
    assert_allclose(exact.targets[::2], positions, rtol=0, atol=1e-12)
    assert exact.header()[-3:] == ["target_x [m]", "target_y [m]", "target_z [m]"]
    robust = ClosedLoop(MPC, ["duration=40", FOLLOW], PLANT).run()
    assert robust.completed and np.max(robust.errors) < 2e-5, robust.summary()


def test_cli_simulate_runs_the_closed_loop_and_reports_its_solve_times(tmp_path, capsys):
    assert main(["simulate", str(MPC), "--set", "duration=8", "--plant-set", PLANT[0], "-o", str(tmp_path),
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "closed loop (mpc): held within 0.1 mm from 7 s" in out and "plant differs from the model" in out
    data = np.genfromtxt(tmp_path / "timeseries.csv", delimiter=",", names=True)
    assert len(data) == 9 and np.all(data["controller_solve_time_s"][:-1] > 0)
    report = json.loads((tmp_path / "simulation.json").read_text())
    assert report["controller"] == "mpc" and report["periods"] == 8 and report["plant_overrides"] == [PLANT[0]]
    assert (tmp_path / "timeseries.png").exists()


def test_closed_loop_bad_input(tmp_path, capsys):
    assert main(["simulate", str(HEATING), "--plant-set", PLANT[0], "-o", str(tmp_path), "--quiet"]) == 2
    assert "--plant-set makes the plant of a closed loop differ from its model" in capsys.readouterr().err
    assert main(["simulate", str(MPC), "--plant-set", "materials.ecoflex.youngs_modulus=1 MPa", "-o", str(tmp_path),
                 "--quiet"]) == 2
    assert ("--plant-set 'materials.ecoflex.youngs_modulus=1 MPa' changes nothing the robot uses (did you mean "
            "'materials.ecoflex30.youngs_modulus'?)") in capsys.readouterr().err
    assert main(["simulate", str(MPC), "--set", "bending.tca2.drive.mpc.horizon=0.5 s", "-o", str(tmp_path),
                 "--quiet"]) == 2
    assert "the horizon (0.5 s) is shorter than the period (1 s)" in capsys.readouterr().err
    assert main(["validate", str(HEATING), "--set", "bending.tca2.drive.kind=mpc"]) == 2
    assert "an mpc drive needs its controller's settings" in capsys.readouterr().err
    assert main(["simulate", str(MPC), "--set", "bending.tca2.drive.mpc.path=ramp.csv", "-o", str(tmp_path),
                 "--quiet"]) == 2
    assert "follows a target: [x, y, z] or a path: CSV file (one of them)" in capsys.readouterr().err
    assert main(["simulate", str(MPC), "--set", "bending.tca2.drive.mpc={path: nothere.csv}", "-o", str(tmp_path),
                 "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: bending.tca2.drive.mpc.path: ") and err.endswith("nothere.csv: no such file"), err
    with pytest.raises(Exception, match="an mpc drive runs in the closed loop"):
        TimeSimulation(Simulation.from_file(MPC), dt=1.0)


def test_a_plant_without_equilibrium_stops_the_loop_and_keeps_what_came_before(monkeypatch):
    """The plant's equilibrium made to fail from the third period's solve on: the run stops there,
    says why, keeps the periods before and is not complete."""
    from tca_casadi.control import ClosedLoop
    from tca_casadi.control.plan import _NoEquilibrium
    loop = ClosedLoop(MPC, ["duration=4"])
    real, calls = loop.step.nodes_at, []

    def failing(u, derivatives=False):
        calls.append(1)
        if len(calls) > 2:
            raise _NoEquilibrium(1, 1.0, "made to fail")
        return real(u, derivatives)

    monkeypatch.setattr(loop.step, "nodes_at", failing)
    result = loop.run()
    assert not result.completed and len(result.t) == 2
    assert result.message.startswith("stopped at t = 2 s: the plant has no equilibrium")
    assert result.inputs[-1, 0] > 0                   # the input applied there, not a copy of the one before
    assert "stopped at t = 2 s" in result.summary()


def test_the_arm_bends_to_a_pose_then_tracks_a_circle(tmp_path):
    """``scripts/arm_circle.py --quick`` (docs/control.md's worked example, 10 s steps): the arm
    bends to the circle's first point by 10 s, and the tracking plan of its three TCAs follows the
    circle (poses the arm holds statically, slow enough for the TCAs' cooling) from 10 s on to
    1e-6 m (measured 1e-11 m); the path file it writes reads back as the poses it solved."""
    import sys

    from conftest import ROOT
    from tca_casadi.control.plan import read_path
    sys.path.insert(0, str(ROOT / "scripts"))
    from arm_circle import main as arm_circle
    results = arm_circle(["--quick", "-o", str(tmp_path)])
    bend, track = results["bend"], results["track"]
    assert bend.converged and bend.reached_at_s <= 10.0, bend.summary()
    assert track.converged and track.reached_at_s <= 10.0, track.summary()
    assert np.max(track.errors[track.t >= 10.0]) < 1e-6
    times, positions = read_path(tmp_path / "circle.csv")
    assert_allclose(positions[0], bend.target, rtol=0, atol=1e-12)
    assert np.ptp(positions[:, 0]) > 4e-3 and np.ptp(positions[:, 1]) > 4e-3        # it goes round
    assert (tmp_path / "track" / "plan.csv").exists()

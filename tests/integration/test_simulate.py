"""``tca-casadi simulate``: a heating and cooling cycle against the closed form, a ramped load
event against independent solves, the files, and bad input."""
import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.cli import main
from tca_casadi.time_simulation.timeline import TimeSimulation

BENDING = str(SCENARIOS / "bending_module.yaml")
CYCLE = ["bending.tca2.drive={kind: power, value: 0}", "bending.tca3.drive={kind: power, value: 0}", "duration=40",
         "timeline=[{at: 1 s, set: {bending.tca2.drive.value: 0.5 W, bending.tca3.drive.value: 0.5 W}},"
         " {at: 20 s, set: {bending.tca2.drive.value: 0, bending.tca3.drive.value: 0}},"
         " {at: 25 s, set: {tip_force.force: [0.002, 0, 0]}, ramp: 4 s}]"]


def _sets(items):
    return [arg for item in items for arg in ("--set", item)]


def test_heating_cycle_files_and_closed_form(tmp_path, capsys):
    assert main(["simulate", BENDING, *_sets(CYCLE), "--dt", "2", "-o", str(tmp_path), "--quiet"]) == 0
    assert "simulate completed" in capsys.readouterr().out
    report = json.loads((tmp_path / "simulation.json").read_text())
    assert report["completed"] and report["outputs"] == report["solved"]
    tca2 = report["tcas"]["bending.tca2"]
    assert_allclose(tca2["energy"], 0.5 * 19.0, rtol=1e-9, atol=0)        # 0.5 W from 1 s to 20 s
    assert tca2["heat_balance_residual"] <= 1e-9 * tca2["energy"]
    assert [r["at"] for r in tca2["responses"]] == [1.0, 20.0, 25.0]          # one per event
    heating, cooling = tca2["responses"][:2]
    assert heating["change"] > 0 and cooling["change"] < 0 and heating["rise_time"] > 0
    assert report["tcas"]["bending.tca1"]["responses"][0]["rise_time"] is None   # never heated
    assert len(report["tip_responses"]) == 3 and report["tip_responses"][2]["rise_time"] > 0
    data = np.genfromtxt(tmp_path / "timeseries.csv", delimiter=",", names=True)
    t, T = data["t_s"], data["bendingtca2temperature_degC"]
    sim = Simulation.from_file(BENDING, CYCLE)
    law = TimeSimulation(sim).laws[0]
    rise = 0.5 / law.conductance
    heating = (t > 1) & (t <= 20)
    expected = 25.0 + rise * (1 - np.exp(-(t[heating] - 1.0) / law.time_constant))
    assert_allclose(T[heating], expected, rtol=0, atol=1e-6 * rise)
    T20 = 25.0 + rise * (1 - np.exp(-19.0 / law.time_constant))
    cooling = t >= 20
    assert_allclose(T[cooling], 25.0 + (T20 - 25.0) * np.exp(-(t[cooling] - 20.0) / law.time_constant),
                    rtol=0, atol=1e-6 * rise)
    assert {1.0, 20.0, 25.0, 29.0} <= set(t.tolist())                      # event times and the ramp's end
    for name in ("timeseries.csv", "simulation.json", "timeseries.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_a_ramped_event_is_linear_and_each_output_is_an_independent_solve():
    sim = Simulation.from_file(BENDING, CYCLE)
    timed = TimeSimulation(sim, duration=30.0, dt=1.0)
    series = timed.run()
    assert series.completed, series.message
    for t, fraction in ((25.0, 0.0), (26.0, 0.25), (27.0, 0.5), (30.0, 1.0)):
        k = int(np.flatnonzero(series.t == t)[0])
        assert_allclose(timed.parameters_at(t)[sim.robot.layout["tip_force.force"]], [0.002 * fraction, 0, 0],
                        rtol=0, atol=1e-15)
        alone = Simulation.from_file(BENDING, [f"tip_force.force=[{0.002 * fraction}, 0, 0]"])
        for j, key in enumerate(series.keys):
            alone.set_parameter(f"{key}.temperature", series.temperatures[k, j])
        assert_allclose(series.solutions[k].tip_position, alone.solve(warn=False).tip_position, rtol=0, atol=1e-9)


@pytest.mark.parametrize("settings, words", [
    (["duration=10", "timeline=[{at: 12 s}]"], "after the duration"),
    (["duration=10", "timeline=[{at: 2 s}, {at: 1 s}]"], "must be in time order"),
    (["duration=10", "timeline=[{at: 2 s, ramp: 3 s}, {at: 4 s}]"], "ends after the next event"),
    (["duration=10", "timeline=[{at: 2 s, set: {bending.tca2.temprature: 50}}]"], "timeline[0] (at 2 s)"),
    (["duration=10", "timeline=[{at: 2 s, set: {bending.length: 40 mm}}]"], "changes the robot's structure"),
    (["bending.tca2.drive={kind: voltage, value: 3 V}", "duration=10"], "needs tca_types.nylon.resistance"),
    (["bending.tca2.drive={kind: power, value: -1 W}"], "must not be negative"),
    (["bending.tca2.drive={kind: setpoint, value: 160, gains: {proportional: 0.05, integral: 0.005}, max_power: 1}",
      "duration=10"], "setpoint 160 degC is above tca_types.nylon.max_temperature"),
    (["bending.tca2.drive={kind: setpoint, value: 60}"], "needs gains"),
    (["bending.thermal_coupling={conductance: 2 mW/K, between: [[tca1, tca4]]}"], "not a TCA of module 'bending'"),
    (["bending.thermal_coupling={conductance: 2 mW/K, between: [[tca1, tca1]]}"], "coupled to itself"),
    (["bending.thermal_coupling={conductance: -2 mW/K}"], "greater than or equal to 0"),
    (["bending.tca2.drive={kind: power, value: 1 W}", "bending.thermal_coupling={conductance: 2 mW/K}",
      "duration=10"], "bending.tca1 has its temperature set"),
])
def test_bad_timelines_are_one_line(tmp_path, capsys, settings, words):
    assert main(["simulate", BENDING, *_sets(settings), "-o", str(tmp_path), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err


def test_a_setpoint_drive_holds_its_temperature_within_its_power():
    settings = ["bending.tca2.drive={kind: setpoint, value: 25, gains: {proportional: 0.05 W/K, "
                "integral: 0.005 W/K/s}, max_power: 1 W}", "duration=200",
                "timeline=[{at: 1 s, set: {bending.tca2.drive.value: 80}}]"]
    sim = Simulation.from_file(BENDING, settings)
    series = TimeSimulation(sim, dt=4.0).run()
    assert series.completed, series.message
    j = series.keys.index("bending.tca2")
    assert np.nanmax(series.powers[:, j]) <= 1.0 and series.powers[1, j] == 1.0   # saturated while far
    assert_allclose(series.temperatures[-1, j], 80.0, rtol=0, atol=1e-6)
    assert series.temperatures[:, j].max() <= 80.0 + 1e-6


def test_coupled_tcas_of_a_module_share_heat_as_the_closed_form_says():
    """The bending module's three TCAs coupled pairwise by Gc through the body, TCA 2 heated by
    P from t = 1 s: the mean rise relaxes with G/C and the differences with (G + 3 Gc)/C, so
    T2 - T_amb = (P/3G)(1 - e^(-tG/C)) + (2P/3(G + 3Gc))(1 - e^(-t(G + 3Gc)/C)) and TCAs 1 and 3
    (symmetric) stay equal; each TCA's heat balance holds and the exchanges cancel."""
    P, Gc = 0.4, 0.002
    settings = [f"bending.tca{k}.drive={{kind: power, value: 0}}" for k in (1, 2, 3)] + [
        f"bending.thermal_coupling={{conductance: {Gc} W/K}}", "duration=30",
        f"timeline=[{{at: 1 s, set: {{bending.tca2.drive.value: {P} W}}}}]"]
    sim = Simulation.from_file(BENDING, settings)
    timed = TimeSimulation(sim, dt=1.0)
    series = timed.run()
    assert series.completed, series.message
    C, G = timed.laws[0].heat_capacity, timed.laws[0].conductance
    t = np.clip(series.t - 1.0, 0.0, None)
    mean = P / (3 * G) * (1 - np.exp(-t * G / C))
    spread = P / (G + 3 * Gc) * (1 - np.exp(-t * (G + 3 * Gc) / C))
    T = series.temperatures
    assert_allclose(T[:, 1], 25.0 + mean + 2 * spread / 3, rtol=0, atol=1e-6 * P / G)
    assert_allclose(T[:, 0], 25.0 + mean - spread / 3, rtol=0, atol=1e-6 * P / G)
    assert_allclose(T[:, 0], T[:, 2], rtol=0, atol=1e-9)
    report = timed.report(series)
    exchanged = [report["tcas"][f"bending.tca{k}"]["heat_to_neighbours"] for k in (1, 2, 3)]
    assert exchanged[1] > 0.5 and exchanged[0] < 0                      # from the heated one to the others
    assert_allclose(sum(exchanged), 0.0, rtol=0, atol=1e-9)
    assert all(report["tcas"][k]["heat_balance_residual"] <= 1e-9 * P * 29 for k in report["tcas"])


def test_the_animation_has_a_clock_at_a_stated_speed_up(tmp_path, capsys):
    from PIL import Image

    from tca_casadi.plotting.animation import animation_speed_up, frame_indices
    assert [animation_speed_up(d, 10, 150) for d in (15.0, 15.1, 60.0, 130.0, 1e4)] == [1, 2, 5, 10, 1000]
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2.2])
    assert frame_indices(t, fps=1, speed_up=1).tolist() == [0, 2, 4, 5]        # frames at 0, 1, 2 s, then the end
    settings = CYCLE[:2] + ["duration=4", "timeline=[{at: 1 s, set: {bending.tca2.drive.value: 0.5 W}}]"]
    assert main(["simulate", BENDING, *_sets(settings), "--dt", "0.5", "-o", str(tmp_path), "--quiet"]) == 0
    assert "animation at real time" in capsys.readouterr().out
    with Image.open(tmp_path / "simulate.gif") as gif:                         # 41 frames of 0.1 s (0 to 4 s),
        durations = []                                                         # identical ones merged by the writer
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.append(gif.info["duration"])
    assert gif.n_frames == 9 and sum(durations) == 4100                        # the 9 outputs: plays in real time
    assert main(["simulate", BENDING, *_sets(settings), "--dt", "0.5", "-o", str(tmp_path), "--quiet",
                 "--no-animation"]) == 0
    assert not (tmp_path / "simulate.gif").exists()                            # a stale one is removed


def test_holding_an_object_the_gripper_is_not_on_stops_the_run(tmp_path, capsys):
    timed = str(SCENARIOS / "arm_pick_and_place_timed.yaml")
    settings = ["duration=3", "timeline=[{at: 1 s, set: {bar.held: true}}]"]
    assert main(["simulate", timed, *_sets(settings), "--dt", "1", "-o", str(tmp_path), "--quiet",
                 "--no-animation"]) == 1
    out = capsys.readouterr().out
    assert "simulate STOPPED (stopped at t = 1 s: holds 'bar' but the grasp point is 9.59 mm from its centre" in out
    rows = (tmp_path / "timeseries.csv").read_text().strip().splitlines()
    assert len(rows) == 2 and rows[0].split(",")[-5:] == ["bar.held", "bar.x [m]", "bar.y [m]", "bar.z [m]",
                                                          "converged"]


def test_a_run_that_stops_early_says_what_was_done(tmp_path, capsys):
    """TCA 2 heated at 1.5 W from t = 1 s passes its max_temperature near 18 s: the summary and
    simulation.json say how much was solved, not the planned 30 s and 301 output times."""
    settings = ["bending.tca2.drive={kind: power, value: 0}", "duration=30",
                "timeline=[{at: 1 s, set: {bending.tca2.drive.value: 1.5 W}}]"]
    code = main(["simulate", BENDING, *_sets(settings), "--dt", "0.1", "-o", str(tmp_path), "--quiet",
                 "--no-plot", "--no-animation"])
    out = capsys.readouterr().out
    report = json.loads((tmp_path / "simulation.json").read_text())
    assert code == 1 and report["completed"] is False
    assert 150 < report["solved"] < 200 and report["planned_outputs"] == 301
    assert report["solved_until_s"] == pytest.approx(0.1 * (report["solved"] - 1), abs=1e-9)
    assert f"solved up to t = {report['solved_until_s']:g} s of 30 s: {report['solved']} of 301 output times" in out
    assert "max_temperature" in report["message"]
    assert (tmp_path / "timeseries.csv").read_text().count("\n") == report["solved"] + 1


@pytest.mark.parametrize("duration, dt, words", [
    ("1e9", "1e-9", "is 1e+18 output times; at most 1,000,000 are kept"),
    ("100", "1e-4", "is 1,000,001 output times; at most 1,000,000 are kept"),
])
def test_runs_too_large_to_keep_are_refused_before_they_start(tmp_path, capsys, duration, dt, words):
    code = main(["simulate", BENDING, "--duration", duration, "--dt", dt, "-o", str(tmp_path), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0], err


def test_a_run_beyond_the_memory_is_refused_with_the_need(tmp_path, capsys, monkeypatch):
    from tca_casadi import resources
    monkeypatch.setattr(resources, "available_memory", lambda: 200e6)
    code = main(["simulate", BENDING, "--duration", "1000", "--dt", "0.01", "-o", str(tmp_path), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1, err
    assert "100,001 output times of this robot, about" in err[0] and "more than the 200 MB available" in err[0]


def test_a_long_run_says_how_long_it_will_take(tmp_path):
    """From its first steps, in a fresh process without a terminal: one line with the time to
    go (the run is then interrupted; its global balance checked at every step, so that it has
    minutes to go)."""
    import signal
    import subprocess
    import sys
    import time
    process = subprocess.Popen([sys.executable, "-m", "tca_casadi.cli", "simulate", BENDING,
                                "--set", "dynamics={enabled: true, balance_every: 1}", "--set", "solver.jit=false",
                                "--duration", "400",
                                "--dt", "0.002", "-o", str(tmp_path), "--no-plot", "--no-animation"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline, line = time.monotonic() + 120, ""
    while time.monotonic() < deadline and "to go" not in line:
        line = process.stderr.readline()
        if not line and process.poll() is not None:
            break
    process.send_signal(signal.SIGINT)
    process.communicate(timeout=60)
    assert line.startswith("simulate: ") and "% done; about " in line and "to go at this pace" in line, line

"""``simulate`` with ``dynamics: {enabled: true}`` (issue 16): the files and the energy account,
the tip velocity against the motion of the tip, a TCA step that rings at the module's first
mode, slow heating against the quasi-static answer, bad input."""
import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.cli import main
from tca_casadi.time_simulation.spectrum import dominant_frequencies
from tca_casadi.time_simulation.timeline import TimeSimulation
from tca_casadi.status import Status

CANTILEVER = str(SCENARIOS / "analytic" / "released_cantilever.yaml")
BENDING = str(SCENARIOS / "bending_module.yaml")
RELEASE = ["dynamics={enabled: true, integrator: midpoint}", "duration=2",
           "timeline=[{at: 0 s, set: {hold.force: [0, 0, 0]}}]"]
COLD = ["bending.tca2.temperature=25", "bending.tca3.temperature=25"]


def _sets(items):
    return [arg for item in items for arg in ("--set", item)]


def test_release_files_and_energy_account(tmp_path, capsys):
    assert main(["simulate", CANTILEVER, *_sets(RELEASE), "--dt", "0.005", "-o", str(tmp_path), "--quiet",
                 "--no-animation"]) == 0
    out = capsys.readouterr().out
    assert "dynamics, midpoint" in out
    assert "global balance checked at 18 of 401 outputs (the start, the first step, every 25th and the last" in out
    report = json.loads((tmp_path / "simulation.json").read_text())["dynamics"]
    assert report["integrator"] == "midpoint" and report["energy_balance_relative"] < 1e-8
    # the static start and 400 steps: the balance there and at steps 1, 25, 50, ..., 400 (the last)
    assert report["global_balance_checked"] == 18 and report["global_balance_worst"] < 1e-8
    data = np.genfromtxt(tmp_path / "timeseries.csv", delimiter=",", names=True)
    assert data["tip_x_m"][0] == pytest.approx(0.8695e-3, rel=1e-3) and data["tip_vx_ms"][0] == 0.0   # held, at rest
    total = data["kinetic_energy_J"] + data["elastic_energy_J"]
    assert_allclose(total, total[0], rtol=1e-8, atol=0)                         # undamped, no work done
    assert np.max(data["kinetic_energy_J"]) > 0.9 * total[0]
    assert np.all(data["dissipated_energy_J"] == 0) and np.all(data["actuator_work_J"] == 0)


@pytest.mark.parametrize("integrator, within", [("bdf2", 0.005), ("midpoint", 0.02)])
def test_the_tip_velocity_is_the_rate_of_the_tip_position(integrator, within):
    """The tip velocity ``R q`` from the velocity states against central differences of the tip
    positions at 2.5 ms steps (the first two steps, after the release's jump in acceleration,
    aside): BDF2 to 0.5 % of the peak speed (0.23 % measured), the midpoint rule's (extrapolated
    from its solved midpoint states) to 2 % (1.5 %)."""
    series = TimeSimulation(Simulation.from_file(CANTILEVER, [RELEASE[0].replace("midpoint", integrator)] + RELEASE[1:]),
                            dt=0.0025).run()
    t, x, v = series.t, series.tip_positions()[:, 0], series.tip_velocities[:, 0]
    rate = (x[2:] - x[:-2]) / (t[2:] - t[:-2])
    assert_allclose(v[3:-1], rate[2:], rtol=0, atol=within * np.max(np.abs(v)))


def test_a_temperature_step_rings_at_the_first_mode_and_overshoots():
    """TCA 2 stepped from 25 to 35 degC at t = 0 (midpoint, 2 ms): the tip rings at the frequency
    of the same module released from a small tip force at 35 degC (within 1 %: 5.17 against
    5.14 Hz) and, undamped, overshoots to about twice the quasi-static displacement."""
    base = ["dynamics={enabled: true, integrator: midpoint}", "duration=1.5", *COLD]
    ring = TimeSimulation(Simulation.from_file(BENDING, base + [
        "timeline=[{at: 0 s, set: {bending.tca2.temperature: 35}}]"]), dt=0.002).run()
    free = TimeSimulation(Simulation.from_file(BENDING, base[:2] + [
        "bending.tca2.temperature=35", "bending.tca3.temperature=25", "tip_force.force=[0.5 mN, 0, 0]",
        "timeline=[{at: 0 s, set: {tip_force.force: [0, 0, 0]}}]"]), dt=0.002).run()
    assert ring.completed and free.completed, (ring.message, free.message)
    ringing = dominant_frequencies(ring.t, ring.tip_positions()[:, 1], count=1)[0]
    released = dominant_frequencies(free.t, free.tip_positions()[:, 0], count=1)[0]
    assert abs(ringing / released - 1) < 0.01 and 4.0 < released < 7.0, (ringing, released)
    static = Simulation.from_file(BENDING, ["bending.tca2.temperature=35", "bending.tca3.temperature=25"]).solve(warn=False)
    start = ring.tip_positions()[0]
    peak = np.max(np.linalg.norm(ring.tip_positions() - start, axis=1))
    assert 1.8 < peak / np.linalg.norm(static.tip_position - start) < 2.1


def test_slow_heating_stays_on_the_quasi_static_shape():
    """TCA 2 ramped from 25 to 60 degC over 3 s (much slower than the 5 Hz mode), 5 % damping,
    BDF2 at 10 ms: the tip stays within 3 um of the quasi-static solve (the tip moves 3.6 mm)."""
    settings = ["dynamics={enabled: true, integrator: bdf2, damping: {ratio: 0.05, frequency: 5.1 Hz}}",
                "duration=3", *COLD, "timeline=[{at: 0 s, set: {bending.tca2.temperature: 60}, ramp: 3 s}]"]
    series = TimeSimulation(Simulation.from_file(BENDING, settings), dt=0.01).run()
    assert series.completed, series.message
    for t in (0.5, 1.5, 3.0):
        k = int(np.flatnonzero(np.isclose(series.t, t))[0])
        static = Simulation.from_file(BENDING, ["bending.tca3.temperature=25",
                                                f"bending.tca2.temperature={25 + 35 * t / 3}"]).solve(warn=False)
        assert_allclose(series.solutions[k].tip_position, static.tip_position, rtol=0, atol=3e-6)


@pytest.mark.parametrize("settings, words", [
    (["dynamics={enabled: true}", "materials.ecoflex30.density=0", "duration=1"], "has no mass"),
    (["dynamics={enabled: true, damping: {viscosity: -1 Pa s}}"], "greater than or equal to 0"),
    (["dynamics={enabled: true, damping: {ratio: 0.05}}"], "needs the frequency"),
    (["dynamics={enabled: true, damping: {ratio: 0.05, frequency: 5 Hz, viscosity: 10 Pa s}}"], "either viscosity"),
    (["dynamics={enabled: true, integrator: rk4}"], "integrator"),
    (["dynamics={enabled: true}", "duration=1", "--dt=0.5"], "outside the range"),
])
def test_bad_dynamics_input_is_one_line(tmp_path, capsys, settings, words):
    dt = [s.split("=", 1)[1] for s in settings if s.startswith("--dt=")]
    sets = [s for s in settings if not s.startswith("--dt=")]
    assert main(["simulate", BENDING, *_sets(sets), "--dt", dt[0] if dt else "0.01", "-o", str(tmp_path),
                 "--quiet", "--no-animation"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err


def test_a_realistic_power_step_does_not_ring():
    """1 W on TCA 2 from 0.5 s (tau = 19.4 s: the heating takes seconds), 5 % damping, BDF2 at
    10 ms: the dynamic tip stays within 10 um of the quasi-static run at every output (6.1 um
    at most, just after the step in heating rate) while it moves 2.6 mm in 5 s."""
    base = ["bending.tca2.drive={kind: power, value: 0}", "bending.tca3.temperature=25", "duration=5",
            "timeline=[{at: 0.5 s, set: {bending.tca2.drive.value: 1 W}}]"]
    moving = TimeSimulation(Simulation.from_file(BENDING, base + [
        "dynamics={enabled: true, integrator: bdf2, damping: {ratio: 0.05, frequency: 5.1 Hz}}"]), dt=0.01).run()
    still = TimeSimulation(Simulation.from_file(BENDING, base), dt=0.01).run()
    assert moving.completed and still.completed
    assert_allclose(moving.tip_positions(), still.tip_positions(), rtol=0, atol=10e-6)
    assert np.max(np.linalg.norm(still.tip_positions() - still.tip_positions()[0], axis=1)) > 2.5e-3


def test_a_step_that_fails_is_halved_and_a_run_that_cannot_go_on_says_why(monkeypatch):
    """Steps longer than 4 ms made to fail: every 10 ms output is reached in four 2.5 ms steps
    (halved twice), the same motion as 2.5 ms steps throughout; steps that always fail stop the
    run at the first output with the reason."""
    from tca_casadi.solvers.dynamics import RodDynamics
    real = RodDynamics.advance
    taken = []

    def fragile(self, params, h):
        taken.append(h)
        state = real(self, params, h)
        return None if h > 0.004 else state

    settings = [RELEASE[0].replace("midpoint", "bdf2"), "duration=0.05", RELEASE[2]]
    monkeypatch.setattr(RodDynamics, "advance", fragile)
    halved = TimeSimulation(Simulation.from_file(CANTILEVER, settings), dt=0.01).run()
    assert halved.completed and np.unique(np.round(taken, 12)).tolist() == [0.0025, 0.005, 0.01]
    monkeypatch.setattr(RodDynamics, "advance", real)
    fine = TimeSimulation(Simulation.from_file(CANTILEVER, settings), dt=0.0025).run()
    assert_allclose(halved.tip_positions(), fine.tip_positions()[::4], rtol=0, atol=1e-12)
    monkeypatch.setattr(RodDynamics, "advance", lambda self, params, h: real(self, params, h) and None)
    stuck = TimeSimulation(Simulation.from_file(CANTILEVER, settings), dt=0.01).run()
    assert not stuck.completed and len(stuck.solutions) == 1
    assert "did not converge even halved 6 times" in stuck.message


@pytest.mark.parametrize("integrator", ["bdf2", "midpoint"])
def test_solutions_are_built_only_when_asked_and_equal_those_built_at_every_step(integrator):
    """Issue 36: a run keeps each step's state and builds the Solutions of its balance checks
    only (the start, the first step, the last); one built later on request, and the per-step
    values the tables and the energy account read, equal those of the same run with every
    Solution built as it goes (``balance_every: 1``) to the last bit."""
    damped = f"dynamics={{enabled: true, integrator: {integrator}, damping: {{ratio: 0.05, frequency: 5}}"
    settings = ["duration=0.1", *COLD, "timeline=[{at: 0 s, set: {bending.tca2.temperature: 45}}]"]
    lazy = TimeSimulation(Simulation.from_file(BENDING, [damped + "}"] + settings), dt=0.005).run()
    eager = TimeSimulation(Simulation.from_file(BENDING, [damped + ", balance_every: 1}"] + settings), dt=0.005).run()
    assert lazy.completed and eager.completed and len(lazy.solutions) == len(eager.solutions) == 21
    assert len(lazy.solutions.checked()) == 3 and len(eager.solutions.checked()) == 21
    assert np.array_equal(lazy.energies, eager.energies) and np.array_equal(lazy.tip_velocities, eager.tip_velocities)
    assert lazy.rows() == eager.rows()
    assert np.max(np.abs(lazy.energies[:, 3])) > 0                         # the TCA did work
    for k in (2, 11, 20):
        built, reference, view = lazy.solutions[k], eager.solutions[k], lazy.views[k]
        assert built.balance is None if k != 20 else built.balance is not None
        for m, module in enumerate(built.modules):
            assert_allclose(module.p, reference.modules[m].p, rtol=0, atol=0)
            assert_allclose(module.force, reference.modules[m].force, rtol=0, atol=0)
            assert_allclose(view.modules[m].p, module.p, rtol=0, atol=0)
            assert_allclose(view.modules[m].R, module.R, rtol=0, atol=1e-15)
        for key, actuator in built.actuators.items():
            assert actuator.tension == reference.actuators[key].tension == view.actuators[key].tension
            assert_allclose(view.actuators[key].stroke, actuator.stroke, rtol=0, atol=1e-16)
    assert lazy.solutions[-1].tip_position.tolist() == lazy.views[-1].tip_position.tolist()


def test_an_event_newton_cannot_take_at_once_is_taken_by_continuation_within_the_step(monkeypatch):
    """TCA 2 stepped from 25 to 60 degC at t = 0 stopped BDF2's first step (Newton from the
    state at rest cannot take the jump, and no halving splits a jump at the step's start): the
    step's equations are now solved along the way from the start's parameters. The run completes with its global balance; and
    where Newton takes the jump at once (to 45 degC), forcing the way along lands on the same
    motion to 1e-12 m."""
    from tca_casadi.solvers.dynamics import RodDynamics
    damped = "dynamics={enabled: true, integrator: bdf2, damping: {ratio: 0.05, frequency: 5}}"

    def run(temperature):
        settings = [damped, "duration=0.05", *COLD, f"timeline=[{{at: 0 s, set: {{bending.tca2.temperature: {temperature}}}}}]"]
        return TimeSimulation(Simulation.from_file(BENDING, settings), dt=0.005).run()

    hot = run(60)
    assert hot.completed, hot.message
    assert hot.checked_balances() and max(hot.checked_balances()) < 1e-8
    tension = [out.actuators["bending.tca2"].tension for out in hot.outputs]
    assert tension[-1] > 10 * tension[0] > 0                                 # it pulls harder
    direct = run(45)
    real, forced = RodDynamics._newton, []

    def first_fails(self, guess, full, lu=None, contact=False):
        w, status = real(self, guess, full, lu, contact)
        if not forced:                          # the first step's first attempt, at the jump
            forced.append(True)
            return w, status.replace(status=Status.NO_DESCENT)
        return w, status

    monkeypatch.setattr(RodDynamics, "_newton", first_fails)
    along = run(45)
    assert forced and along.completed
    assert_allclose(along.tip_positions(), direct.tip_positions(), rtol=0, atol=1e-12)

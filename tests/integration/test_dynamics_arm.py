"""The arm lets go of its bar (issue 16's example: the release of Fig. 6): with the bar's rigid
inertia and weight gone at once, the arm springs back, overshoots and settles on the static shape
without it."""
import numpy as np
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.time_simulation.timeline import TimeSimulation

PICK = SCENARIOS / "arm_pick_and_place.yaml"
HOLDING = ["base.position=[0, 0, -10 mm]", "twisting.tca.temperature=90", "bar.held=true"]


def test_the_arm_springs_back_when_it_lets_go_of_the_bar():
    settings = HOLDING + ["dynamics={enabled: true, integrator: bdf2, damping: {ratio: 0.05, frequency: 5 Hz}}",
                          "duration=0.6", "timeline=[{at: 0.1 s, set: {bar.held: false}}]"]
    timed = TimeSimulation(Simulation.from_file(PICK, settings), dt=0.002)
    series = timed.run()
    assert series.completed, series.message
    report = timed.report(series)
    assert report["objects"]["bar"]["put_down_at"] == [0.1] and report["objects"]["bar"]["held_at_start"]
    assert report["dynamics"]["energy_balance_relative"] < 1e-3      # BDF2's own dissipation and the steps
    holding = Simulation.from_file(PICK, HOLDING).solve(warn=False).tip_position
    released = Simulation.from_file(PICK, HOLDING[:2]).solve(warn=False).tip_position
    tips = series.tip_positions()
    assert_allclose(tips[0], holding, rtol=0, atol=1e-9)                 # at rest, holding, before the event
    # the vertical spring-back (20 Hz, damped at 20 % there) has settled without it; a slow lateral
    # sway (5 Hz, 5 %) of a few um is still decaying at 0.6 s
    assert_allclose(tips[-1, 2], released[2], rtol=0, atol=1e-6)
    assert np.all(np.abs(tips[-1, :2] - released[:2]) < 10e-6)
    jump = np.linalg.norm(released - holding)
    assert jump > 0.1e-3 and np.max(np.linalg.norm(tips - holding, axis=1)) > 1.3 * jump   # it overshoots

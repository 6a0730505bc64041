"""The paper's pick-and-place in real time (``scenarios/arm_pick_and_place_timed.yaml``): the
arm heated by electrical power through Fig. 6's steps, checked against the closed-form energy,
independent solves at the same parameters and the story of the figure."""
import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.studies.sequence.objects import ObjectTracker
from tca_casadi.studies.sequence.steps import tip_yaw
from tca_casadi.time_simulation.timeline import TimeSimulation

TIMED = SCENARIOS / "arm_pick_and_place_timed.yaml"
PICK = SCENARIOS / "arm_pick_and_place.yaml"


@pytest.fixture(scope="module")
def run():
    sim = Simulation.from_file(TIMED)
    timed = TimeSimulation(sim, dt=1.0)
    return sim, timed, timed.run()


def _without_drives(doc):
    for module in doc["modules"]:
        for actuator in module["actuators"]:
            actuator.pop("drive", None)
    return doc


def test_the_timed_file_holds_the_same_arm_and_object():
    timed, pick = (_without_drives(yaml.safe_load(path.read_text())) for path in (TIMED, PICK))
    for key in ("gravity", "base", "materials", "tca_types", "modules", "solver", "objects"):
        assert timed[key] == pick[key], key
    assert all(a["drive"]["kind"] == "power" for m in yaml.safe_load(TIMED.read_text())["modules"]
               for a in m["actuators"])


def test_it_runs_through_fig6_in_130_s(run):
    sim, timed, series = run
    assert series.completed, series.message
    report = timed.report(series)
    assert report["duration"] == 130.0 and not report["warnings"]
    at = {t: k for k, t in enumerate(series.t)}
    tracker = ObjectTracker(sim.scenario, sim.robot)
    keys = series.keys
    # (b) the twisting TCA boosted then held near 90 degC turns the gripper by about 90 deg
    assert_allclose(series.temperatures[at[54.0], keys.index("twisting.tca")], 89.7, rtol=0, atol=0.1)
    assert tip_yaw(series.solutions[at[54.0]]) == pytest.approx(90.2, abs=0.3)
    # (c) the fingers near 100 degC open the gripper to about 23 mm; cooled, it closes to under 5 mm
    assert tracker.opening(series.solutions[at[22.0]], "bar") == pytest.approx(23.0e-3, abs=0.2e-3)
    assert tracker.opening(series.solutions[at[53.0]], "bar") < 5e-3          # before it is held
    # the bar is picked when the fingers have closed and put down after they opened again, to +x
    objects = report["objects"]["bar"]
    assert objects["picked_at"] == [54.0] and objects["put_down_at"] == [118.0] and not objects["held_at_end"]
    assert objects["final_center"][0] > 10e-3 and objects["final_center"][2] == pytest.approx(-93.3e-3, abs=1e-12)
    # (f) back to a yaw of about 1 deg by 104 s; (g) the arm bends to +x
    assert abs(tip_yaw(series.solutions[at[104.0]])) < 1.5
    assert series.solutions[-1].tip_position[0] > 10e-3


def test_energy_is_the_integral_of_the_power_steps_and_heat_balances(run):
    _, timed, series = run
    report = timed.report(series)["tcas"]
    expected = {"twisting.tca": 3.4 * 7.8 + 1.13 * 51.2, "finger_a.tca": 1.27 * 7.8 * 2 + 0.42 * (5.2 + 7.2),
                "bending.tca1": 1.59 * 7.8 + 0.53 * 17.2, "bending.tca2": 0.0}
    for key, energy in expected.items():
        assert_allclose(report[key]["energy"], energy, rtol=1e-9, atol=1e-12)
        assert report[key]["heat_balance_residual"] <= 1e-8 * max(energy, 1.0)


@pytest.mark.parametrize("t", [40.0, 80.0, 120.0])
def test_the_shape_at_an_output_time_is_an_independent_solve(run, t):
    """The untimed pick-and-place, solved cold at the parameters (temperatures from the thermal
    model, base position, held) the timed run had at ``t``: the same tip to 1e-9 m."""
    _, _, series = run
    k = int(np.flatnonzero(series.t == t)[0])
    solution = series.solutions[k]
    alone = Simulation.from_file(PICK)
    assert alone.robot.layout.names() == Simulation.from_file(TIMED).robot.layout.names()
    alone.params = np.array(solution.parameters, float)
    assert_allclose(alone.solve(warn=False).tip_position, solution.tip_position, rtol=0, atol=1e-9)

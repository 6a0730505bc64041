"""The paper's soft robotic arm and its pick-and-place sequence (Fig. 6; SPEC section 9)."""
import numpy as np
import pytest
import yaml

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.errors import ScenarioError
from tca_casadi.studies.sequence.steps import run_sequence, tip_yaw

STEPS = ["straight", "twist", "open", "grasp", "lift", "untwist", "place"]
BAR_MASS = 0.5e-3


@pytest.fixture(scope="module")
def pick_and_place():
    sim = Simulation.from_file(SCENARIOS / "arm_pick_and_place.yaml")
    return sim, run_sequence(sim)


def step(result, name):
    return result.solutions[STEPS.index(name)]


def test_the_two_arm_files_describe_the_same_arm(scenarios):
    arm = yaml.safe_load((scenarios / "arm.yaml").read_text())
    pick = yaml.safe_load((scenarios / "arm_pick_and_place.yaml").read_text())
    for key in ("gravity", "base", "materials", "tca_types", "modules", "solver"):
        assert arm[key] == pick[key], key


def test_every_step_converges_and_the_story_of_fig6_holds(pick_and_place):
    _, result = pick_and_place
    assert result.converged and len(result.solutions) == 7
    # (b) the heated helical TCA (90 degC) turns the gripper about the arm's axis by about 90 deg
    assert tip_yaw(step(result, "straight")) == pytest.approx(0.0, abs=0.1)
    assert tip_yaw(step(result, "twist")) == pytest.approx(91.2, abs=0.5)
    # (c) the gripper opens when its TCAs are heated, (d) closes again when they cool
    closed, opened, holding = (result.openings[STEPS.index(n)] for n in ("straight", "open", "grasp"))
    assert closed == pytest.approx(4.57e-3, abs=0.05e-3)
    assert opened > 4 * closed
    assert holding < 5.5e-3                                  # back on the 5 mm bar
    # (f) the twisting module cooled: the gripper turns back
    assert tip_yaw(step(result, "untwist")) == pytest.approx(0.0, abs=0.2)
    # (g) the bending module bends the arm towards +x
    assert step(result, "place").tip_position[0] > 10e-3
    assert abs(step(result, "place").tip_position[1]) < 1e-6
    # the bar is picked in (d), carried through (f), and put down elsewhere in (g)
    held = [result.objects[k]["bar"].held for k in range(7)]
    assert held == [False, False, False, True, True, True, False]
    start, end = result.objects[0]["bar"].center, result.objects[-1]["bar"].center
    assert end[2] == pytest.approx(start[2], rel=0, abs=1e-7) and end[0] - start[0] > 10e-3
    assert result.objects[4]["bar"].center[2] - result.objects[3]["bar"].center[2] == pytest.approx(0.01, abs=2e-4)
    assert not result.warnings


def test_the_bar_weighs_on_the_arm_only_while_held(pick_and_place):
    """Statics: the base carries the arm's weight, plus the bar's exactly while it is held."""
    sim, result = pick_and_place
    arm = sum(m.weight_density * m.length for m in sim.robot.modules)
    arm += sum(m.connector.mass for m in sim.robot.modules if m.connector is not None)
    for k, name in enumerate(STEPS):
        mass = arm + (BAR_MASS if result.objects[k]["bar"].held else 0.0)
        reaction = result.solutions[k].modules[0].base_reaction["force"]
        assert reaction == pytest.approx([0, 0, mass * 9.81], abs=1e-7), name   # discretisation ~1e-8 N; bar 4.9e-3 N


def test_jointly_solved_and_decoupled_gripper(scenarios, pick_and_place):
    """The paper's decoupled gripper neglects the gripper's moment on the arm: same answer while
    the gripper hangs on the axis, a larger bend in (g) where its weight is off the axis."""
    _, joint = pick_and_place
    sim = Simulation.from_file(scenarios / "arm_pick_and_place.yaml",
                               ["finger_a.decoupled=true", "finger_b.decoupled=true"])
    decoupled = run_sequence(sim, steps=sim.scenario.sequence)
    assert decoupled.converged
    straight = np.linalg.norm(step(decoupled, "straight").tip_position - step(joint, "straight").tip_position)
    assert straight < 1e-7          # the helix tilts the tip by ~1e-9 rad: a tiny moment
    extra_bend = step(decoupled, "place").tip_position[0] - step(joint, "place").tip_position[0]
    assert 0.5e-3 < extra_bend < 2e-3


def test_arm_step_agrees_with_shooting(scenarios):
    """Collocation against shooting with the bar held in the twisted arm (step (d)), on the tree."""
    from tca_casadi.studies.compare import compare_solutions
    sim = Simulation.from_file(scenarios / "arm_pick_and_place.yaml")
    run = run_sequence(sim, steps=sim.scenario.sequence[:4])
    collocation = run.solutions[-1]
    shooting = sim.solver("shooting")
    shooting.sample_s = [m.s for m in collocation.modules]
    shot = shooting.solve(sim.params, initial=collocation)
    report = compare_solutions(collocation, shot)
    assert report.agree, report.summary()
    assert report.max_centerline_distance < 1e-7


def test_holding_an_object_out_of_reach_is_an_error(scenarios):
    sim = Simulation.from_file(scenarios / "arm_pick_and_place.yaml")
    with pytest.raises(ScenarioError, match=r"step 'grab': holds 'bar' but the grasp point is 9\.\d+ mm from its centre"):
        run_sequence(sim, steps=[{"name": "grab", "set": {"bar.held": True}}])

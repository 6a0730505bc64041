"""Trees (several fingers on one parent) and decoupled modules (SPEC section 5), checked against
mirror symmetry, an equivalent chain, statics, an independent solve and the shooting solver."""
import numpy as np
import pytest

from builders import robot, rod, tca
from tca_casadi import Simulation
from tca_casadi.model.rotations import matrix_to_quaternion
from tca_casadi.studies.compare import check

UPRIGHT = {"position": [0, 0, 0], "orientation": {"quaternion": [1, 0, 0, 0]}}


def finger(name, tilt_deg, actuators=(), **extra):
    connector = {"offset": [0, 0, 0.002], "rotation": {"axis": [0, 1, 0], "angle": f"{tilt_deg} deg"},
                 "mass": "0.5 g"}
    return rod(name, "25 mm", actuators, parent="trunk", connector=connector, **extra)


def y_tree(**finger_extra):
    """An upright trunk carrying two mirrored fingers tilted +-40 deg, each with a heated TCA."""
    scenario = robot([rod("trunk", "30 mm", [tca("t", "90 deg", 25)]),
                      finger("left", 40, [tca("a", "0 deg", 70)], **finger_extra),
                      finger("right", -40, [tca("b", "180 deg", 70)], **finger_extra)])
    scenario["base"] = UPRIGHT
    return scenario


@pytest.fixture(scope="module")
def tree():
    return Simulation.from_file(y_tree()).solve().raise_if_failed()


def test_tree_is_mirror_symmetric_and_balances_the_weight(tree):
    left, right = tree.modules[1], tree.modules[2]
    mirror = np.diag([-1.0, 1.0, 1.0])
    assert np.max(np.abs(mirror @ left.p - right.p)) < 1e-10
    assert tree.actuators["left.a"].tension == pytest.approx(tree.actuators["right.b"].tension, rel=1e-8)
    assert tree.actuators["left.a"].tension > 1e-3                      # the TCAs do pull
    # the fingers bend away from the heated side: the tips move outwards more than the rest shape
    assert abs(left.tip_position[0]) > 0.025 * np.sin(np.radians(40)) + 1e-3
    # statics: the base carries the total weight, and by symmetry no moment about y
    sim = Simulation.from_file(y_tree())
    mass = sum(m.weight_density * m.length for m in sim.robot.modules) + 2 * 0.5e-3
    reaction = tree.modules[0].base_reaction
    assert reaction["force"] == pytest.approx([0, 0, mass * 9.81], abs=1e-12)
    assert abs(reaction["moment"][1]) < 1e-12
    assert tree.tip_module == 0                                          # the tip is the trunk's


def test_two_coincident_fingers_equal_one_finger_twice_as_stiff_and_heavy():
    fingers = robot([rod("trunk", "30 mm"), finger("f1", 30), finger("f2", 30)])
    single = robot([rod("trunk", "30 mm"), finger("f1", 30)])
    single["materials"]["double"] = {"youngs_modulus": "0.25 MPa", "density": "2140 kg/m^3"}
    single["modules"][1]["material"] = "double"
    single["modules"][1]["connector"]["mass"] = "1 g"
    for scenario in (fingers, single):
        scenario["base"] = UPRIGHT
        scenario["gravity"] = [-9.81, 0, 0]                               # bends everything sideways
    two = Simulation.from_file(fingers).solve().raise_if_failed()
    one = Simulation.from_file(single).solve().raise_if_failed()
    assert np.max(np.abs(two.modules[0].p - one.modules[0].p)) < 1e-10
    assert np.max(np.abs(two.modules[1].p - one.modules[1].p)) < 1e-10
    assert np.max(np.abs(two.modules[2].p - two.modules[1].p)) < 1e-12
    assert np.max(np.abs(two.modules[0].p[0])) > 1e-3                    # it did bend


def test_tree_collocation_agrees_with_shooting():
    report = check(Simulation.from_file(y_tree()))[0]
    assert report.agree
    assert report.max_centerline_distance < 1e-8 and report.worst_relative_tension < 1e-7


def decoupled_arm(decoupled=True):
    """A hanging two-module chain with a pre-curved, heated finger on its tip."""
    gripper = rod("gripper", "20 mm", [tca("g", "90 deg", 60)], precurvature=["40 1/m", 0, 0],
                  connector={"offset": [0, 0, 0.001], "mass": "0.4 g"}, decoupled=decoupled)
    return robot([rod("bend", "30 mm", [tca("a", "0 deg", 80)]), rod("twist", "16 mm"), gripper],
                 loads=[{"name": "object", "kind": "mass", "module": "gripper", "mass": "2 g"}])


def test_decoupled_module_loads_its_parent_with_its_weight_only():
    coupled_sim = Simulation.from_file(decoupled_arm())
    arm = coupled_sim.solve().raise_if_failed()
    assert arm.tip_module == 1
    weight = coupled_sim.robot.modules[2].weight_density * 0.02 + 0.4e-3 + 2e-3
    chain = decoupled_arm()
    chain["modules"].pop()
    chain["loads"] = [{"name": "gripper_weight", "kind": "mass", "module": "twist", "mass": weight}]
    reference = Simulation.from_file(chain).solve().raise_if_failed()
    for m in (0, 1):
        assert np.max(np.abs(arm.modules[m].p - reference.modules[m].p)) < 1e-12
    assert arm.actuators["bend.a"].tension == pytest.approx(reference.actuators["bend.a"].tension, rel=1e-9)
    # the gripper itself equals a gripper solved on its own from the chain tip's frame
    alone = decoupled_arm()
    alone["modules"] = [dict(alone["modules"][2], decoupled=False)]
    alone["modules"][0].pop("connector")
    alone["modules"][0].pop("decoupled")
    R = arm.modules[1].tip_rotation
    position = arm.modules[1].tip_position + R @ [0, 0, 0.001]
    alone["base"] = {"position": position.tolist(),
                     "orientation": {"quaternion": matrix_to_quaternion(R).tolist()}}
    solo = Simulation.from_file(alone).solve().raise_if_failed()
    assert np.max(np.abs(solo.modules[0].p - arm.modules[2].p)) < 1e-10
    assert solo.actuators["gripper.g"].tension == pytest.approx(arm.actuators["gripper.g"].tension, rel=1e-8)


def test_decoupled_and_coupled_grippers_differ_by_the_neglected_moment():
    decoupled = Simulation.from_file(decoupled_arm(True)).solve().raise_if_failed()
    coupled = Simulation.from_file(decoupled_arm(False)).solve().raise_if_failed()
    gap = np.linalg.norm(decoupled.tip_position - coupled.modules[1].tip_position)
    assert 1e-6 < gap < 5e-3            # the gripper's off-axis weight bends the coupled chain a bit
    assert coupled.tip_module == 2


def test_decoupled_collocation_agrees_with_shooting():
    report = check(Simulation.from_file(decoupled_arm()))[0]
    assert report.agree and report.max_centerline_distance < 1e-8


def test_parent_errors_name_the_key():
    from tca_casadi.errors import ScenarioError
    bad = y_tree()
    bad["modules"][1]["parent"] = "trunc"
    with pytest.raises(ScenarioError, match=r"modules\[left\]\.parent.*did you mean 'trunk'"):
        Simulation.from_file(bad)
    later = y_tree()
    later["modules"][1]["parent"] = "right"
    with pytest.raises(ScenarioError, match="must come before"):
        Simulation.from_file(later)
    first = y_tree()
    first["modules"][0]["decoupled"] = True
    with pytest.raises(ScenarioError, match="no parent"):
        Simulation.from_file(first)

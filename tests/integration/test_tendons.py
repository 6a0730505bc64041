"""Tendon-driven robots: displacement control, compliance, slack (tension_only), tendons ending
part-way, and agreement with the shooting solver."""
import numpy as np
import pytest

from conftest import SCENARIOS
from tca_casadi import ScenarioError, Simulation, Sweep
from tca_casadi.model.rotations import rotation_angle
from tca_casadi.studies import bending_angle, check

ROBOT = SCENARIOS / "tendon_robot.yaml"
TWO_SEGMENTS = SCENARIOS / "tendon_robot_two_segments.yaml"


@pytest.fixture(scope="module")
def four_tendons():
    sim = Simulation.from_file(ROBOT)
    return sim, sim.solve()


def test_pulling_one_tendon_bends_towards_it_and_the_opposite_goes_slack(four_tendons):
    sim, solution = four_tendons
    t1, t3 = solution.actuators["body.t1"], solution.actuators["body.t3"]
    assert solution.converged
    assert solution.tip_position[0] > 0.02                # towards tendon 1 (body and global +x)
    assert t1.tension > 0.1 and t1.slack_length == 0.0
    assert abs(t3.tension) < 1e-9 * t1.tension and t3.slack_length > 1e-4
    # the length conditions: taut t1 exactly, slack t3 by its reported slack length
    law = sim.robot.actuators[0].law
    assert t1.stroke + t1.displacement == pytest.approx(law.reference_length * law.compliance * t1.tension, abs=1e-12)
    assert t3.slack_length == pytest.approx(-(t3.stroke + t3.displacement), abs=1e-9)
    # slack is a state of a passive tendon, not a warning (issue 35): it is in the table
    assert not solution.warning_texts("slack") and solution.actuators["body.t3"].slack


@pytest.mark.parametrize("path", [ROBOT, TWO_SEGMENTS], ids=["four_tendons", "two_segments"])
def test_collocation_and_shooting_agree_on_tensions_and_slack(path):
    report, collocation, shooting = check(Simulation.from_file(path))
    assert report.agree, report.summary()
    assert report.tip_position_difference < 1e-6 and report.worst_relative_tension < 1e-5
    assert max(report.slack_differences.values()) < 1e-6
    assert any(a.slack_length for a in collocation.actuators.values())


def test_sweep_to_ninety_degrees_without_a_failed_step():
    sim = Simulation.from_file(ROBOT)
    result = Sweep(sim, ["body.t1.displacement", "body.t3.displacement"], [0, 0],
                   ["16 mm", "-16 mm"], steps=33).run()
    assert result.completed
    assert all(point.substeps == 1 for point in result.points[1:])        # no step was halved
    angles = np.degrees([bending_angle(s) for s in result.solutions])
    assert angles[-1] > 90 and np.all(np.diff(angles) > 0)
    slack = {e["message"].split()[0] for e in result.events if e["kind"] == "slack"}
    assert {"body.t2", "body.t3", "body.t4"} <= slack


def test_converges_from_a_straight_initial_guess():
    """No continuation: Newton (then IPOPT) straight from the reference shape."""
    direct = Simulation.from_file(ROBOT, ["solver.continuation=never"]).solve()
    assert direct.converged
    assert np.max(np.abs(direct.tip_position - Simulation.from_file(ROBOT).solve().tip_position)) < 1e-9


def single_tendon(**tendon):
    base = {"name": "t", "kind": "tendon", "route": {"kind": "straight", "radius": "3 mm"}}
    return {"name": "rod", "gravity": [0, 0, 0],
            "materials": {"m": {"youngs_modulus": "1 MPa", "poisson_ratio": 0.5}},
            "modules": [{"name": "rod", "length": "80 mm", "material": "m",
                         "cross_section": {"shape": "circle", "diameter": "8 mm"},
                         "actuators": [dict(base, **tendon)]}]}


def test_displacement_control_is_the_tension_control_of_its_tension():
    """Pulling by q gives a tension F; prescribing that F reproduces the same arc."""
    pulled = Simulation.from_file(single_tendon(control="displacement", displacement="2 mm",
                                                compliance="0.01 1/N")).solve()
    force = pulled.actuators["rod.t"].tension
    given = Simulation.from_file(single_tendon(tension=force)).solve()
    assert force > 0
    assert np.max(np.abs(pulled.modules[0].p - given.modules[0].p)) < 1e-9
    curvature = pulled.modules[0].u[1]
    assert np.ptp(curvature) < 1e-9 * abs(curvature.mean())                # a constant-curvature arc


@pytest.mark.parametrize("turns", [2.0, -2.0])
def test_helical_tendon_twists_against_its_winding(turns):
    """Tension shortens a helical tendon's path by unwinding it: a right-handed helix (turns > 0)
    twists the tip negatively about the axis, a left-handed one positively, by the same angle."""
    route = {"kind": "helix", "radius": "3 mm", "turns": turns}
    solution = Simulation.from_file(single_tendon(tension="0.05 N", route=route)).solve()
    mirror = Simulation.from_file(single_tendon(tension="0.05 N", route=dict(route, turns=-turns))).solve()
    twist = solution.modules[0].u[2].mean()
    assert np.sign(twist) == -np.sign(turns)
    assert twist == pytest.approx(-mirror.modules[0].u[2].mean(), rel=1e-9)
    assert solution.actuators["rod.t"].stroke < 0                         # the path got shorter
    angle = rotation_angle(solution.modules[0].R[:, :, 0], solution.tip_rotation)
    assert angle > np.radians(1)


@pytest.mark.parametrize("tendon, message", [
    ({"tension": 0.1, "displacement": 0.001}, "need control: displacement"),
    ({"control": "displacement", "tension": 0.1}, "remove 'tension'"),
    ({"control": "displacement", "compliance": 0.01, "stiffness": 50}, "not both"),
    ({"control": "displacement", "compliance": "2 mm"}, "compliance"),
])
def test_bad_tendon_input_is_named(tendon, message):
    with pytest.raises(ScenarioError, match=message):
        Simulation.from_file(single_tendon(**tendon))

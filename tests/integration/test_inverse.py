"""Inverse statics: round trips from forward solves, the arm's pose with rotation, unreachable
targets, path tracking, bad input."""
import csv

import numpy as np
import pytest
import yaml

from conftest import SCENARIOS
from tca_casadi import InverseStatics, ScenarioError, Simulation, Target
from tca_casadi.cli import main
from tca_casadi.model.rotations import matrix_to_quaternion, rotation_angle

BENDING = SCENARIOS / "bending_module.yaml"


def set_temperatures(sim, paths, values, refine=True):
    for path, value in zip(paths, values):
        sim.set_parameter(path, value)
    return sim.solve(refine=refine)


@pytest.fixture(scope="module", params=["ipopt", "reduced"])
def bending(request):
    """The bending module's inverse problem, by the full-space NLP (IPOPT) and the reduced path."""
    sim = Simulation.from_file(BENDING)
    return sim, InverseStatics(sim, bounds=(25, 125), method=request.param)


def test_round_trip_from_random_temperatures(bending):
    """50 random temperature sets (seed 0): forward tip -> inverse from a cold start."""
    _, inverse = bending
    forward = Simulation.from_file(BENDING)
    paths = [p.name for p in inverse.parameters]
    rng, reached, times = np.random.default_rng(0), 0, []
    for _ in range(50):
        truth = set_temperatures(forward, paths, rng.uniform(25, 125, 3))
        assert truth.converged
        answer = inverse.solve(Target.create(truth.tip_position))
        reached += answer.reachable and answer.position_error <= 1e-4
        assert answer.verification_difference <= 1e-6          # the forward check agrees
        assert answer.forward.converged
        if answer.reachable:                                    # its optimiser's status says why
            assert answer.result.success and answer.result.residual <= forward.scenario.solver.tolerance
            assert answer.result.algorithm == {"ipopt": "IPOPT", "reduced": "least squares (dogbox)"}[inverse.method]
        times.append(answer.solve_time_s)
    assert reached >= 48                                        # >= 95 %


def test_unreachable_target_gives_the_closest_pose(bending):
    sim, inverse = bending
    target = Target.create([-0.06, 0.0, -0.04])
    answer = inverse.solve(target)
    assert not answer.reachable and "unreachable" in answer.message
    assert answer.position_error == pytest.approx(np.linalg.norm(answer.position - target.position), rel=1e-12)
    assert answer.verified
    # no corner or centre of the temperature box comes closer than the reported closest pose
    forward = Simulation.from_file(BENDING)
    for corner in [(25, 125, 125), (125, 125, 125), (25, 100, 100), (75, 75, 75), (25, 125, 25)]:
        tip = set_temperatures(forward, [p.name for p in inverse.parameters], corner).tip_position
        assert np.linalg.norm(tip - target.position) >= answer.position_error - 1e-9


def test_tracking_a_path_warm_starts(bending, tmp_path):
    _, inverse = bending
    forward = Simulation.from_file(BENDING)
    paths = [p.name for p in inverse.parameters]
    targets = [Target.create(set_temperatures(forward, paths, (30, t, t)).tip_position)
               for t in np.linspace(60, 100, 5)]
    results = inverse.track(targets)
    assert all(r.reachable and r.verified for r in results)
    assert all(r.starts == 1 for r in results[1:])               # warm: no multi-start needed
    for r, t in zip(results, np.linspace(60, 100, 5)):             # recovers the heating path
        assert r.temperatures[paths[1]] == pytest.approx(t, abs=0.05)


def arm(intervals=20):
    """The bending module with the twisting module below it: 4 TCAs."""
    bending_raw, twisting_raw = (yaml.safe_load((SCENARIOS / f"{n}.yaml").read_text())
                                 for n in ("bending_module", "twisting_module"))
    raw = dict(bending_raw, name="arm", loads=[])
    raw.pop("inverse")
    raw["modules"] = bending_raw["modules"] + twisting_raw["modules"]
    raw["solver"] = {"intervals": intervals, "degree": 4}
    return Simulation.from_file(raw)


@pytest.mark.parametrize("method, intervals", [("ipopt", 12), ("reduced", 20)])
def test_arm_position_and_rotation_about_its_axis(method, intervals):
    """Both methods on the arm (IPOPT on a coarser mesh: its full-space iterations are slow on
    this robot, which is why the reduced method is the default)."""
    sim = arm(intervals)
    paths = [a.parameter for a in sim.robot.tcas]
    assert len(paths) == 4
    # the truth on the mesh the inverse works on (a round trip of one discretisation)
    truth = set_temperatures(arm(intervals), paths, (40, 70, 70, 110), refine=False)
    twist = rotation_angle(truth.modules[0].tip_rotation, truth.tip_rotation)
    assert twist > np.radians(60)                        # the twisting module turns the tip
    target = Target.create(truth.tip_position, orientation=matrix_to_quaternion(truth.tip_rotation))
    answer = InverseStatics(sim, bounds=(25, 125), method=method).solve(target)
    assert answer.reachable and answer.verified
    assert answer.position_error <= 1e-4 and answer.angle_error <= np.radians(1.0)
    assert answer.temperatures["twisting.tca.temperature"] == pytest.approx(110, abs=1.0)


@pytest.mark.parametrize("make, message", [
    (lambda: Target.create([0, float("nan"), 0]), "not finite"),
    (lambda: Target.create([0, 0]), "expected 3 numbers"),
    (lambda: Target.create([0, 0, 0], direction=[0, 0, 0]), "must not be zero"),
    (lambda: Target.create([0, 0, 0], [0, 0, 1], [1, 0, 0, 0]), "not both"),
])
def test_bad_targets_are_named(make, message):
    with pytest.raises(ScenarioError, match=message):
        make()


@pytest.mark.parametrize("options, message", [
    ({"bounds": (100, 50)}, "inverted"),
    ({"bounds": (20, 125)}, r"range \[25, 150\]"),
    ({"bounds": (25, 200)}, r"range \[25, 150\]"),
    ({"vary": ["tip_force.force.x"]}, "not one"),
    ({"vary": ["bending.tca4.temperature"]}, "did you mean"),
    ({"method": "newton"}, "unknown inverse method"),
])
def test_bad_options_are_named(bending, options, message):
    sim, _ = bending
    with pytest.raises(ScenarioError, match=message):
        InverseStatics(sim, **options)


def test_unknown_point_is_named(bending):
    _, inverse = bending
    with pytest.raises(ScenarioError, match="did you mean 'bending'"):
        inverse.solve(Target.create([0, 0, -0.04], point="bendng"))


def test_inverse_command_from_the_scenario_section(tmp_path, capsys):
    assert main(["inverse", str(BENDING), "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "REACHED" in out and "verified" in out
    data = (tmp_path / "inverse.json").read_text()
    assert '"reachable": true' in data
    for name in ("solution.json", "arrays.npz", "inverse.png"):
        assert (tmp_path / name).exists()


def test_inverse_command_path_and_errors(tmp_path, capsys):
    targets = tmp_path / "targets.csv"
    targets.write_text("x [m],y [m],z [m]\n-0.010,0,-0.040\n-0.012,0.001,-0.039\n-0.08,0,0\n")
    code = main(["inverse", str(BENDING), "--path", str(targets), "-o", str(tmp_path), "--quiet",
                 "--method", "reduced"])
    assert code == 1                                            # the last target is out of reach
    with (tmp_path / "inverse_path.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [r["reachable"] for r in rows] == ["1", "1", "0"]
    assert float(rows[0]["position_error [m]"]) < 1e-4
    capsys.readouterr()
    assert main(["inverse", str(BENDING), "--target-position", "nan", "0", "0"]) == 2
    assert "finite" in capsys.readouterr().err
    assert main(["inverse", str(BENDING), "--bounds", "125", "25"]) == 2
    assert "inverted" in capsys.readouterr().err

"""Sequences: cumulative steps solved by continuation from the previous one, agreement with
independent solves and with shooting, the CLI's table, PNGs and animation."""
import csv

import numpy as np
import pytest
from PIL import Image

from conftest import SCENARIOS
from tca_casadi import ScenarioError, Simulation
from tca_casadi.cli import main
from tca_casadi.studies.compare import compare_solutions
from tca_casadi.studies.sequence.steps import run_sequence

BENDING = SCENARIOS / "bending_module.yaml"
CUMULATIVE = [{}, {"bending.tca1.temperature": 100},
              {"bending.tca1.temperature": 100, "bending.tca2.temperature": 25, "bending.tca3.temperature": 25},
              {"bending.tca1.temperature": 25, "bending.tca2.temperature": 25, "bending.tca3.temperature": 25}]


@pytest.fixture(scope="module")
def sequence():
    return run_sequence(Simulation.from_file(BENDING))


def test_steps_equal_independent_solves_of_their_cumulative_settings(sequence):
    assert sequence.converged and len(sequence.solutions) == 4
    for solution, settings in zip(sequence.solutions, CUMULATIVE):
        alone = Simulation.from_file(BENDING, [f"{k}={v}" for k, v in settings.items()]).solve()
        assert np.max(np.abs(solution.tip_position - alone.tip_position)) < 1e-9
    tips = np.array([s.tip_position for s in sequence.solutions])
    assert tips[1][0] == pytest.approx(0.0, abs=1e-9)           # all three heated: straight
    assert tips[2][0] > 0.01                                   # only TCA 1: bends towards it (+x)
    assert tips[0][0] < -0.01                                  # TCA 2 and 3: away from TCA 1


def test_every_step_agrees_with_shooting(sequence):
    sim = Simulation.from_file(BENDING)
    shooting = sim.solver("shooting")
    for solution in sequence.solutions:
        shooting.sample_s = [m.s for m in solution.modules]
        report = compare_solutions(solution, shooting.solve(solution.parameters, solution))
        assert report.agree, report.summary()


def test_sequence_command_writes_table_pngs_and_animation(tmp_path, capsys):
    assert main(["sequence", str(BENDING), "-o", str(tmp_path), "--frames", "2", "--quiet"]) == 0
    with (tmp_path / "sequence.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [r["name"] for r in rows] == ["TCA 2 and 3 heated", "TCA 1 heated too", "only TCA 1 heated", "all cool"]
    assert float(rows[2]["bending.tca1.temperature [degC]"]) == 100.0
    assert len(list(tmp_path.glob("step_*.png"))) == 4
    with Image.open(tmp_path / "sequence.gif") as gif:       # identical frames are merged, durations add
        durations = []
        for index in range(gif.n_frames):
            gif.seek(index)
            durations.append(gif.info["duration"])
    # 4 steps held 3 frames each, 2 frames in each of the 4 transitions, at 8 frames per second
    assert sum(durations) == pytest.approx((4 * 3 + 4 * 2) * 125, rel=0.05)   # GIF stores centiseconds
    assert len(durations) >= 4 + 3 * 2                          # every step and moving frame is there
    assert "all converged" in capsys.readouterr().out


def test_with_ffmpeg_the_animation_is_an_mp4_too(sequence, tmp_path, monkeypatch):
    """With an ``ffmpeg`` on the PATH (imageio-ffmpeg's, a test dependency), ``save_animation``
    writes ``sequence.mp4`` beside the GIF from the same rendering: one video frame per
    animation frame (every transition frame and each step held 3 frames), at 8 frames per
    second, its middle frame the GIF's within the video's compression (mean difference below 3
    of 255)."""
    import re
    import subprocess
    from tca_casadi.plotting.animation import save_animation
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    folder = tmp_path / "bin"
    folder.mkdir()
    (folder / "ffmpeg").symlink_to(imageio_ffmpeg.get_ffmpeg_exe())
    monkeypatch.setenv("PATH", f"{folder}:{__import__('os').environ['PATH']}")
    paths = save_animation(sequence, tmp_path)
    assert [p.name for p in paths] == ["sequence.gif", "sequence.mp4"]
    count = sum(len(transition) + 3 for transition in sequence.transitions)
    middle = tmp_path / "middle.png"
    run = subprocess.run([str(folder / "ffmpeg"), "-i", str(paths[1]), "-vf", f"select=eq(n\\,{count // 2})",
                          "-frames:v", "1", str(middle)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert re.search(r"(\d+(?:\.\d+)?) fps", run.stderr).group(1) == "8"
    decoded = subprocess.run([str(folder / "ffmpeg"), "-i", str(paths[1]), "-f", "null", "-"], capture_output=True,
                             text=True, timeout=60).stderr
    assert int(re.findall(r"frame=\s*(\d+)", decoded)[-1]) == count
    with Image.open(paths[0]) as gif:                         # the GIF's frame at the same time
        shown, elapsed = None, 0
        for index in range(gif.n_frames):
            gif.seek(index)
            if elapsed <= (count // 2) * 125 < elapsed + gif.info["duration"]:
                shown = np.asarray(gif.convert("RGB"), float)
            elapsed += gif.info["duration"]
    with Image.open(middle) as frame:
        assert np.mean(np.abs(np.asarray(frame.convert("RGB"), float) - shown)) < 3.0


def test_missing_sequence_and_bad_paths_are_named(tmp_path, capsys):
    assert main(["sequence", str(SCENARIOS / "twisting_module.yaml"), "-o", str(tmp_path)]) == 2
    assert "no sequence" in capsys.readouterr().err
    with pytest.raises(ScenarioError, match="tca7"):
        run_sequence(Simulation.from_file(BENDING), steps=[{"name": "bad", "set": {"bending.tca7.temperature": 50}}])


def small_gripper():
    """A short hanging trunk with two pre-curved fingers (a tree) and heated-to-open TCAs."""
    from builders import robot, rod, tca
    fingers = [rod(name, "20 mm", [dict(tca("t", angle, 25), tension_only=True)], parent="trunk",
                   precurvature=[0, curl, 0],
                   connector={"offset": [0, 0, 0.002], "rotation": {"axis": [0, 1, 0], "angle": tilt}})
               for name, angle, curl, tilt in (("fa", "0 deg", "-100 1/m", "90 deg"),
                                               ("fb", "180 deg", "100 1/m", "-90 deg"))]
    return robot([rod("trunk", "20 mm")] + fingers)


def test_pick_and_place_command_checks_every_step_and_moves_the_object(tmp_path, capsys):
    import yaml
    scenario = small_gripper()
    rest = Simulation.from_file(scenario).solve()
    grasp = (rest.modules[1].tip_position + rest.modules[2].tip_position) / 2
    scenario["objects"] = [{"name": "cube", "mass": "0.2 g", "size": ["4 mm"] * 3,
                            "position": (grasp - [0, 0, 0.005]).tolist(), "held_by": ["fa", "fb"]}]
    heat = {"fa.t.temperature": 100, "fb.t.temperature": 100}
    cool = {"fa.t.temperature": 25, "fb.t.temperature": 25}
    scenario["sequence"] = [{"name": "open", "set": heat},
                            {"name": "lower and close", "set": dict(cool, **{"base.position": [0, 0, "-5 mm"],
                                                                             "cube.held": True})},
                            {"name": "lift and swing", "set": {"base.position": ["8 mm", 0, 0]}},
                            {"name": "release", "set": dict(heat, **{"cube.held": False})}]
    path = tmp_path / "gripper.yaml"
    path.write_text(yaml.safe_dump(scenario))
    assert main(["sequence", str(path), "-o", str(tmp_path), "--frames", "1", "--check", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "shooting AGREES on every step" in out
    with (tmp_path / "sequence.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    opening = [float(r["gripper_opening [m]"]) for r in rows]
    assert opening[0] > opening[1] + 5e-3 and opening[3] > opening[2] + 5e-3   # heated opens, cooled closes
    assert [int(r["cube.held"]) for r in rows] == [0, 1, 1, 0]
    assert float(rows[3]["cube.x [m]"]) == pytest.approx(0.008, abs=1e-4)      # put down 8 mm away
    assert float(rows[3]["cube.z [m]"]) == pytest.approx(scenario["objects"][0]["position"][2], rel=1e-9)
    for row in rows:
        assert float(row["shooting_centerline_difference [m]"]) < 1e-7
    import json
    checks = json.loads((tmp_path / "sequence_check.json").read_text())
    assert all(report["agree"] for report in checks.values()) and len(checks) == 4
    assert len(list(tmp_path.glob("step_*.png"))) == 4 and (tmp_path / "sequence.gif").exists()


def test_picking_and_putting_down_move_the_object_not_at_all():
    """The pick-and-place: the bar held in (d) is where it rested (the grasp keeps its offset
    from the grasp point: it was 0.3 mm below the rest pose when the grasp point was taken as
    the centre), rises with the base's 10 mm lift in (e), and is let go at its support height."""
    result = run_sequence(Simulation.from_file(SCENARIOS / "arm_pick_and_place.yaml"))
    bar = [step["bar"] for step in result.objects]
    assert not bar[2].held and bar[3].held and not bar[6].held
    np.testing.assert_allclose(bar[3].center, bar[2].center, rtol=0, atol=1e-12)
    np.testing.assert_allclose(bar[4].center - bar[3].center, [0, 0, 0.010], rtol=0, atol=1e-4)
    assert bar[6].center[2] == bar[0].center[2] and bar[6].center[0] > 0.015

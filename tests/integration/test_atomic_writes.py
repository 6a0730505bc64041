"""A run killed at any moment leaves its output directory with one run's complete set of files:
the previous run's or the new one's, never a mix (issue 34, item 6), and every file complete.
Each file is written atomically into a hidden sibling directory, which is then exchanged with the
output directory in one step; ``run_<command>.json`` names the run and its files. What else the
directory holds (notes, other commands' results) survives."""
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import SCENARIOS

PNG_END = b"IEND\xaeB`\x82"
BENDING = str(SCENARIOS / "bending_module.yaml")
DATA = str(SCENARIOS.parent / "data" / "bending_module_measurements.csv")
HEATING = ["--set", "bending.tca2.drive={kind: power, value: 0}", "--set", "duration=8",
           "--set", "timeline=[{at: 1 s, set: {bending.tca2.drive.value: 0.3 W}}]", "--dt", "0.5", "--quiet"]
#: per command: its arguments, a first run's and a second (different) run's
COMMANDS = {
    "solve": ([BENDING], [], ["--no-plot", "--set", "bending.tca2.temperature=90"]),
    "sweep": ([BENDING, "--param", "bending.tca2.temperature", "--from", "25", "--quiet"],
              ["--to", "60", "--steps", "6"], ["--to", "70", "--steps", "5", "--no-plot"]),
    "simulate": ([BENDING, *HEATING, "--no-animation"], [], ["--no-plot", "--set", "bending.tca3.temperature=60"]),
    "study": ([BENDING, "--vary", "bending.tca2.temperature=25:125:4", "--quiet"],
              ["--vary", "bending.tca3.temperature=25:125:3"], ["--vary", "bending.tca3.temperature=25:125:4", "--no-plot"]),
    "fit": ([BENDING, "--data", DATA, "--param", "materials.ecoflex30.youngs_modulus", "--quiet"],
            [], ["--param", "tca_types.nylon.untwist.c1", "--no-plot"]),
}
#: runs killed at random moments per command: every command writes through the same
#: ``output.ResultSet``, so the longer runs are killed once, the quick ones twice
KILLS = {"solve": 2, "sweep": 2, "simulate": 1, "study": 1, "fit": 1}


def complete(path):
    """True if ``path`` parses completely as what its suffix says."""
    if path.suffix == ".json":
        json.loads(path.read_text())
    elif path.suffix == ".npz":
        with np.load(path) as data:
            [data[key] for key in data.files]
    elif path.suffix == ".csv":
        lines = path.read_text().splitlines()
        assert lines and all(line.count(",") == lines[0].count(",") for line in lines if not line.startswith("#"))
    elif path.suffix == ".png":
        data = path.read_bytes()
        assert data.startswith(b"\x89PNG") and data.endswith(PNG_END)
    elif path.suffix == ".parquet":
        assert path.read_bytes()[-4:] == b"PAR1"
    return True


def result_set(directory, command):
    """``(run id, {name: bytes})`` of the command's set in ``directory``: exactly the files its
    ``run_<command>.json`` lists, each complete (asserted)."""
    manifest = json.loads((directory / f"run_{command}.json").read_text())
    present = {p.name for p in directory.iterdir() if p.is_file() and not p.name.startswith(".")}
    present -= {f"run_{command}.json", "notes.txt", "study_rows.jsonl"}
    assert present == set(manifest["files"]), (present, manifest["files"])
    for name in present:
        assert complete(directory / name), name
    return manifest["run_id"], {name: (directory / name).read_bytes() for name in present}


def _cli(command, *args):
    return [sys.executable, "-m", "tca_casadi.cli", command, *args]


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_killed_run_leaves_one_runs_complete_set(tmp_path, command):
    common, first, second = COMMANDS[command]
    directory = tmp_path / "out"
    output = ["-o", str(directory)]
    started = time.perf_counter()
    done = subprocess.run(_cli(command, *common, *first, *output), capture_output=True, text=True)
    duration = time.perf_counter() - started
    assert done.returncode in (0, 1), done.stderr
    (directory / "notes.txt").write_text("the user's own notes")
    (directory / "sub").mkdir()
    (directory / "sub" / "kept.txt").write_text("kept")
    sets = [result_set(directory, command)]
    rng = np.random.default_rng(sorted(COMMANDS).index(command))
    for moment in rng.uniform(0.3 * duration, 1.1 * duration, KILLS[command]):
        process = subprocess.Popen(_cli(command, *common, *second, *output), stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        time.sleep(moment)
        process.send_signal(signal.SIGKILL)
        process.wait()
        run_id, files = result_set(directory, command)
        if run_id == sets[-1][0]:
            assert files == sets[-1][1]                     # the set from before, byte for byte
        else:
            sets.append((run_id, files))                    # the new run's, complete
        assert (directory / "notes.txt").read_text() == "the user's own notes"
        assert (directory / "sub" / "kept.txt").read_text() == "kept"
    finished = subprocess.run(_cli(command, *common, *second, *output), capture_output=True, text=True)
    assert finished.returncode in (0, 1), finished.stderr
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".out")] == []     # a killed run's staging goes
    assert result_set(directory, command)[0] not in [run_id for run_id, _ in sets]


def test_a_killed_study_resumes_to_the_uninterrupted_rows(tmp_path):
    """Killed once it has written some rows, ``--resume`` solves the rest; the rows equal a run
    that was never killed."""
    import pandas
    args = [BENDING, "--vary", "bending.tca2.temperature=25:125:6", "--vary", "bending.tca3.temperature=25:125:5",
            "--quiet", "--no-plot"]
    whole = subprocess.run(_cli("study", *args, "-o", str(tmp_path / "whole")), capture_output=True, text=True)
    assert whole.returncode == 0, whole.stderr
    directory = tmp_path / "killed"
    process = subprocess.Popen(_cli("study", *args, "-o", str(directory)), stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    journal = directory / "study_rows.jsonl"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and (not journal.exists() or journal.read_text().count("\n") < 8):
        time.sleep(0.05)
    process.send_signal(signal.SIGKILL)
    process.wait()
    kept = journal.read_text().count("\n") - 1
    assert 7 <= kept < 30 and not (directory / "study.csv").exists()
    resumed = subprocess.run(_cli("study", *args, "-o", str(directory), "--resume"), capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    info = json.loads((directory / "study.json").read_text())
    assert info["resumed_samples"] >= kept - 1          # a row cut short by the kill is solved again
    a = pandas.read_parquet(tmp_path / "whole" / "study.parquet").sort_values("sample")
    b = pandas.read_parquet(directory / "study.parquet").sort_values("sample")
    columns = [c for c in a.columns if c.endswith(("[m]", "[N]"))]
    assert list(a["sample"]) == list(b["sample"]) == list(range(30))
    np.testing.assert_allclose(b[columns].to_numpy(float), a[columns].to_numpy(float), rtol=0, atol=1e-9)
    assert not journal.exists()

"""A process killed at any moment never leaves a truncated result: every result file is either
absent, the previous complete one, or the new complete one (writes go to a temporary file in the
same directory, then are renamed over the target)."""
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest


PNG_END = b"IEND\xaeB`\x82"


def complete(path):
    """True if ``path`` parses completely as what its suffix says."""
    if path.suffix == ".json":
        json.loads(path.read_text())
    elif path.suffix == ".npz":
        with np.load(path) as data:
            [data[key] for key in data.files]
    elif path.suffix == ".csv":
        lines = path.read_text().splitlines()
        assert lines and all(line.count(",") == lines[0].count(",") for line in lines)
    elif path.suffix == ".png":
        data = path.read_bytes()
        assert data.startswith(b"\x89PNG") and data.endswith(PNG_END)
    return True


def _kill_runs(command, directory, seed, runs=3):
    """Start ``command`` ``runs`` times, killing it (SIGKILL) at random moments of its second
    half (where the files are written; before, nothing is open); after each, every visible file
    in ``directory`` must be complete."""
    rng = np.random.default_rng(seed)
    subprocess.run(command, check=True, capture_output=True)        # a first complete run
    first = {p.name for p in directory.iterdir() if not p.name.startswith(".")}
    started = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    duration = time.perf_counter() - started
    for moment in rng.uniform(0.5 * duration, 1.05 * duration, runs):
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(moment)
        process.send_signal(signal.SIGKILL)
        process.wait()
        visible = [p for p in directory.iterdir() if not p.name.startswith(".")]
        assert {p.name for p in visible} == first
        for path in visible:
            assert complete(path), path


@pytest.mark.parametrize("command, seed", [
    (["solve", "scenarios/bending_module.yaml"], 0),
    (["sweep", "scenarios/bending_module.yaml", "--param", "bending.tca2.temperature", "--from", "25",
      "--to", "60", "--steps", "6", "--quiet"], 1)])
def test_killed_runs_leave_complete_files(tmp_path, command, seed):
    directory = tmp_path / "out"
    _kill_runs([sys.executable, "-m", "tca_casadi.cli", *command, "-o", str(directory)], directory, seed)

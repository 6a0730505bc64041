"""The output stage: atomic writes, prepared directories, safe names."""
import json
import os

import pytest

from tca_casadi.output import atomic_path, prepare_directory, safe_name, write_text


@pytest.mark.parametrize("name, expected", [("../../escaped", "escaped"), ("/etc/passwd", "etc_passwd"),
                                            ("..", "scenario"), ("arm pick&place", "arm_pick_place"),
                                            ("a" * 100, "a" * 64)])
def test_safe_name(name, expected):
    assert safe_name(name) == expected


def test_a_failed_write_keeps_the_previous_file(tmp_path):
    target = write_text(tmp_path / "result.json", '{"run": 1}')
    with pytest.raises(RuntimeError):
        with atomic_path(target) as temporary:
            temporary.write_text('{"run": 2, "trunc')
            raise RuntimeError("killed while writing")
    assert json.loads(target.read_text()) == {"run": 1}
    assert sorted(os.listdir(tmp_path)) == ["result.json"]


def test_leftovers_of_a_killed_run_are_removed(tmp_path):
    (tmp_path / ".solution.abc123.json").write_text("{")
    (tmp_path / "robot.png").write_bytes(b"old")
    prepare_directory(tmp_path, ["solution.json", "robot.png"], stale=["robot.png"])
    assert os.listdir(tmp_path) == []


# ----------------------------------------------------------------------------- result sets
from tca_casadi.output import SWAPPED, ResultSet, _exchange, recover  # noqa: E402


def _run(directory, files, stale=(), command="solve"):
    with ResultSet(directory, command, list(files), list(stale)) as run:
        for name, text in files.items():
            write_text(run.staging / name, text)
    return run


def test_a_result_set_replaces_the_old_one_and_keeps_the_rest(tmp_path):
    out = tmp_path / "out"
    _run(out, {"solution.json": "1", "robot.png": "old"})
    (out / "notes.txt").write_text("mine")
    (out / "sweep").mkdir()
    run = _run(out, {"solution.json": "2"}, stale=["robot.png"])
    assert sorted(os.listdir(out)) == ["notes.txt", "run_solve.json", "solution.json", "sweep"]
    assert (out / "solution.json").read_text() == "2"
    manifest = json.loads((out / "run_solve.json").read_text())
    assert manifest["files"] == ["solution.json"] and manifest["run_id"] == run.run_id
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_an_exception_leaves_the_old_set(tmp_path):
    out = tmp_path / "out"
    _run(out, {"solution.json": "1"})
    with pytest.raises(KeyboardInterrupt):
        with ResultSet(out, "solve", ["solution.json"]) as run:
            write_text(run.staging / "solution.json", "2")
            raise KeyboardInterrupt
    assert (out / "solution.json").read_text() == "1" and [p.name for p in tmp_path.iterdir()] == ["out"]


def test_exchange_is_one_step(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "x").write_text("a")
    (tmp_path / "b" / "y").write_text("b")
    _exchange(tmp_path / "a", tmp_path / "b")
    assert os.listdir(tmp_path / "b") == ["x"] and os.listdir(tmp_path / "a") == ["y"]


def test_a_run_killed_between_the_exchange_and_the_move_back_is_finished_by_the_next(tmp_path):
    """The old directory, swapped out, still holds the user's files: the next run (any command)
    moves them back before it starts."""
    out = tmp_path / "out"
    _run(out, {"solution.json": "1"})
    (out / "notes.txt").write_text("mine")
    run = ResultSet(out, "solve", ["solution.json"])
    run.prepare()
    write_text(run.staging / "solution.json", "2")
    write_text(run.staging / "run_solve.json", "{}")
    write_text(out / SWAPPED, json.dumps(["solution.json", "run_solve.json"]))
    _exchange(run.staging, out)                      # ... and the process is killed here
    assert sorted(os.listdir(out)) == ["run_solve.json", "solution.json"]
    recover(out)
    assert sorted(os.listdir(out)) == ["notes.txt", "run_solve.json", "solution.json"]
    assert (out / "solution.json").read_text() == "2" and [p.name for p in tmp_path.iterdir()] == ["out"]


def test_the_working_directory_is_written_in_place(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "robot.png").write_bytes(b"old")
    run = _run(tmp_path, {"solution.json": "1"}, stale=["robot.png"])
    assert run.in_place and sorted(os.listdir(tmp_path)) == ["run_solve.json", "solution.json"]
    assert json.loads((tmp_path / "run_solve.json").read_text())["files"] == ["solution.json"]

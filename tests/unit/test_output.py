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

"""The command line as a user meets it: files written, exit codes, one-line errors."""
import json
import subprocess
import sys

import numpy as np
from numpy.testing import assert_allclose
import pytest

from tca_casadi.cli import main

SPEC_KEYS = {"converged", "method", "max_residual", "solve_time_s", "tip", "modules", "actuators", "warnings"}
ACTUATOR_KEYS = {"temperature", "tension", "length", "reference_length", "stroke", "free_stroke"}


def test_solve_writes_json_npz_and_png(tmp_path, scenarios, capsys):
    code = main(["solve", str(scenarios / "bending_module.yaml"), "-o", str(tmp_path)])
    assert code == 0
    data = json.loads((tmp_path / "solution.json").read_text())
    assert SPEC_KEYS <= set(data)
    assert data["converged"] is True and data["method"] == "collocation"
    assert set(data["tip"]) == {"position", "quaternion", "rotation_matrix"}
    assert ACTUATOR_KEYS <= set(data["actuators"]["bending.tca1"])
    assert set(data["modules"]["bending"]) == {"tip", "base_reaction"}
    arrays = np.load(tmp_path / "arrays.npz")
    assert arrays["bending/p"].shape[0] == 3
    assert_allclose(arrays["bending/p"][:, -1], data["tip"]["position"], rtol=0, atol=0)   # the same numbers
    assert (tmp_path / "robot.png").stat().st_size > 10_000
    out = capsys.readouterr().out
    assert "converged" in out and "bending.tca2" in out


def test_solve_json_to_stdout_with_override(tmp_path, scenarios, capsys):
    code = main(["solve", str(scenarios / "bending_module.yaml"), "-o", str(tmp_path), "--json", "--no-plot",
                 "--set", "bending.tca2.temperature=60", "--set", "bending.tca3.temperature=60"])
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert data["actuators"]["bending.tca2"]["temperature"] == 60
    assert not (tmp_path / "robot.png").exists()


@pytest.mark.parametrize("override, fragment", [
    ("bending.lenght=3", "did you mean 'length'"),
    ("bending.tca1.route.radius=6 mm", "outside the body"),
    ("bending.tca1.temperature=hot", "temperature"),
])
def test_bad_input_is_one_line_and_exit_2(scenarios, capsys, override, fragment):
    code = main(["solve", str(scenarios / "bending_module.yaml"), "--set", override])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("error: ") and fragment in err


def test_unconverged_solve_exits_1(tmp_path, scenarios, capsys):
    code = main(["solve", str(scenarios / "bending_module.yaml"), "-o", str(tmp_path), "--no-plot",
                 "--set", "solver.max_iterations=1", "--set", "solver.continuation=never"])
    assert code == 1
    assert json.loads((tmp_path / "solution.json").read_text())["converged"] is False
    assert "NOT CONVERGED" in capsys.readouterr().out


def test_validate_lists_parameters(scenarios, capsys):
    assert main(["validate", str(scenarios / "twisting_module.yaml")]) == 0
    assert "twisting.tca.temperature" in capsys.readouterr().out


def test_console_script_has_no_traceback_on_bad_file(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nmodules: [\n")
    result = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "solve", str(bad)],
                            capture_output=True, text=True)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and "malformed YAML" in result.stderr


def _subcommands():
    from tca_casadi.cli import build_parser
    action = next(a for a in build_parser()._actions if a.dest == "command")
    return sorted(action.choices)


@pytest.mark.parametrize("command", _subcommands())
def test_every_subcommand_answers_help(command):
    """``tca-casadi COMMAND --help`` in a fresh process, for every command the parser has."""
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", command, "--help"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith(f"usage: tca-casadi {command}") and not run.stderr


@pytest.mark.parametrize("overrides, expected", [
    # the key once where the override and the key path say the same (issue 37's review)
    (["dynamics.integrator=bdf1", "dynamics.enabled=true"],
     "error: --set dynamics.integrator: 'bdf1' is not allowed: expected 'bdf2' or 'midpoint'"),
    # an override of a whole mapping is where its keys came from, not the file's old line
    (["solver={degree: x}"], "error: --set solver: solver.degree: input should be a valid integer"),
    # a later override replaces an earlier one below it
    (["solver.degree=2", "solver={degree: x}"], "error: --set solver: solver.degree: input should be a valid integer"),
])
def test_a_bad_override_is_named_once_and_where_it_came_from(scenarios, capsys, overrides, expected):
    code = main(["solve", str(scenarios / "bending_module.yaml")] + [arg for o in overrides for arg in ("--set", o)])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(expected), err

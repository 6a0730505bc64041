"""Messages name options as the user gave them (errors.flag): --flags on the command line, the
keyword arguments from Python; the same error in both front ends."""
import subprocess
import sys
from pathlib import Path

import pytest

from tca_casadi import Simulation
from tca_casadi.errors import ScenarioError, command_line, flag

ROOT = Path(__file__).resolve().parents[2]


def test_flag_follows_the_front_end():
    assert flag("--power-budget") == "power_budget" and flag("--allow-code", "allow_code=True") == "allow_code=True"
    with command_line():
        assert flag("--power-budget") == "--power-budget" and flag("--allow-code", "allow_code=True") == "--allow-code"
    assert flag("--set") == "set"                          # the context ends with the command


def test_a_bad_override_in_python_names_the_method_not_a_flag():
    sim = Simulation.from_file(ROOT / "scenarios" / "bending_module.yaml")
    with pytest.raises(ScenarioError, match=r"^set bending.nope: module 'bending' has no actuator or key 'nope'"):
        sim.set("bending.nope", 3)
    with pytest.raises(ScenarioError, match=r"^set bending.tca1.temperature: expected PATH=VALUE"):
        Simulation.from_file(ROOT / "scenarios" / "bending_module.yaml", ["bending.tca1.temperature"])


def test_the_same_error_on_the_command_line_names_the_flag():
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "solve", str(ROOT / "scenarios" / "bending_module.yaml"),
                          "--set", "bending.nope=3"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert run.stderr.startswith("error: --set bending.nope: module 'bending' has no actuator or key 'nope'")


def test_study_options_in_python_are_its_keyword_arguments():
    from tca_casadi.studies.batch.executors import executor_of
    with pytest.raises(ScenarioError, match=r"^study: give workers or scheduler, not both$"):
        executor_of(workers=2, scheduler="tcp://127.0.0.1:1")

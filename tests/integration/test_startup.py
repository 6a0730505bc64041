"""``tca-casadi --help`` and ``validate`` start without loading the numerical libraries (the
time they take is measured in scripts/bench.py, not here)."""
import subprocess
import sys

HEAVY = ("casadi", "matplotlib", "scipy.integrate", "scipy.optimize", "scipy.sparse", "scipy.interpolate")

PROBE = """
import sys
from tca_casadi import cli
code = cli.main({argv!r})
print("LOADED", [m for m in {heavy!r} if m in sys.modules], code)
"""


def _loaded(argv, cwd):
    result = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, heavy=HEAVY)], cwd=cwd,
                            capture_output=True, text=True, check=True)
    line = [line for line in result.stdout.splitlines() if line.startswith("LOADED")][-1]
    return line


def test_validate_loads_no_numerical_library(scenarios):
    for name in ("bending_module", "arm_pick_and_place", "tendon_robot_two_segments"):
        assert _loaded(["validate", str(scenarios / f"{name}.yaml")], scenarios) == "LOADED [] 0"


def test_help_loads_no_numerical_library(scenarios):
    probe = PROBE.replace("code = cli.main({argv!r})", "code = cli.build_parser().format_help() and 0")
    result = subprocess.run([sys.executable, "-c", probe.format(argv=[], heavy=HEAVY)],
                            capture_output=True, text=True, check=True)
    assert result.stdout.strip().endswith("LOADED [] 0"), result.stdout


def test_a_collocation_solve_does_not_load_the_shooting_solver(scenarios, tmp_path):
    """A command imports what it uses: ``solve`` by collocation (the default) never loads the
    shooting solver or scipy.integrate, which ``check`` and ``--method shooting`` need."""
    argv = ["solve", str(scenarios / "bending_module.yaml"), "-o", str(tmp_path), "--no-plot"]
    probe = PROBE.replace("print(\"LOADED\"", "print(\"SHOOTING\", 'tca_casadi.solvers.shooting' in sys.modules)\nprint(\"LOADED\"")
    result = subprocess.run([sys.executable, "-c", probe.format(argv=argv, heavy=("scipy.integrate",))],
                            cwd=scenarios, capture_output=True, text=True, check=True)
    assert "SHOOTING False" in result.stdout and result.stdout.strip().endswith("LOADED [] 0"), result.stdout


def test_a_dynamic_run_without_heating_does_not_load_the_thermal_integrator(scenarios, tmp_path):
    """``simulate`` with rod dynamics and no heating never loads scipy.integrate (the heating
    model's ``solve_ivp``) nor scipy.optimize (which it pulls in): 0.14 s of a run's start."""
    argv = ["simulate", str(scenarios / "analytic" / "steel_cantilever.yaml"), "--dt", "0.002", "--set",
            "duration=0.004", "-o", str(tmp_path), "--no-plot", "--no-animation"]
    result = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, heavy=("scipy.integrate", "scipy.optimize"))],
                            cwd=scenarios, capture_output=True, text=True, check=True)
    assert result.stdout.strip().endswith("LOADED [] 0"), result.stdout

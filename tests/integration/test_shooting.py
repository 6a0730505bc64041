"""The independent shooting solver agrees with collocation; the check command reports it."""
import json

import numpy as np
import pytest
from builders import mixed_chain, robot, rod, tca

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.cli import main
from tca_casadi.solvers import shooting
from tca_casadi.studies import check

SHIPPED = sorted(SCENARIOS.rglob("*.yaml"))


def assert_agree(report):
    assert report.converged == {"collocation": True, "shooting": True}
    assert report.tip_position_difference < 1e-6
    assert report.max_centerline_distance < 1e-6
    assert report.worst_relative_tension < 1e-5
    assert report.worst_relative_contact < 1e-5
    assert max(report.body_differences.values(), default=0.0) < 1e-6
    assert report.agree


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_every_shipped_scenario_agrees(path):
    """Contact scenarios included (issue 33): their closed contacts' forces and objects' positions
    are compared too."""
    sim = Simulation.from_file(path, allow_code=True)
    report, collocation, shooting = check(sim)
    assert_agree(report)
    assert collocation.method == "collocation" and shooting.method == "shooting"
    assert len(report.contact_differences) == len({(c.module, c.s, c.obstacle) for c in collocation.contacts}
                                                  | {(c.module, c.s, c.obstacle) for c in shooting.contacts})
    assert report.shooting_start == ("collocation" if sim.robot.path_dependent else "reference")


CHAINS = {
    "span_and_mid_module_mass": robot(
        [rod("lower", "22.5 mm", [tca("a", "0 deg", 90), tca("b", "120 deg", 25, span=["5 mm", "22.5 mm"])]),
         rod("upper", "22.5 mm")],
        loads=[{"name": "disc", "kind": "mass", "module": "upper", "at": "7.5 mm", "mass": "1 g"}]),
    "tilted_heavy_connector_and_tip_load": robot(
        [rod("lower", "30 mm", [tca("a", "0 deg", 90)]),
         rod("upper", "20 mm", [tca("b", "90 deg", 70)],
             connector={"offset": ["1 mm", "2 mm", "5 mm"], "mass": "3 g",
                        "rotation": {"axis": [0, 1, 0], "angle": "20 deg"}})],
        loads=[{"name": "tip", "kind": "point", "module": "upper", "force": [0.01, -0.005, 0.002],
                "moment": [1e-4, 0, -2e-4]}]),
    "point_load_at_junction_and_tca_starting_there": robot(
        [rod("lower", "20 mm", [tca("a", "0 deg", 80)]),
         rod("upper", "25 mm", [tca("b", "240 deg", 95, span=[0, "20 mm"])])],
        loads=[{"name": "push", "kind": "point", "module": "lower", "at": "end", "force": [0.003, 0.001, 0]},
               {"name": "side", "kind": "distributed", "module": "upper", "force": [0, 0.05, 0],
                "frame": "body"}]),
}


@pytest.mark.parametrize("name", sorted(CHAINS))
def test_chains_agree(name):
    assert_agree(check(Simulation.from_file(CHAINS[name]))[0])


def test_helical_span_and_curve_route_chain_agrees():
    sim = mixed_chain(24)
    assert_agree(check(sim)[0])


def test_shooting_warm_start_follows_a_temperature_step(scenarios):
    sim = Simulation.from_file(scenarios / "bending_module.yaml", method="shooting")
    first = sim.solve()
    sim.set_parameter("bending.tca2.temperature", 101.0)
    sim.set_parameter("bending.tca3.temperature", 101.0)
    warm = sim.solve(warm_start=first)
    assert warm.converged and warm.iterations < first.iterations
    reference = Simulation.from_file(scenarios / "bending_module.yaml",
                                     ["bending.tca2.temperature=101", "bending.tca3.temperature=101"]).solve()
    assert np.linalg.norm(warm.tip_position - reference.tip_position) < 1e-9


def test_shooting_never_reports_a_failure_as_converged(scenarios, monkeypatch):
    monkeypatch.setattr(shooting, "RHS_BUDGET", 3)      # every shot is abandoned
    sim = Simulation.from_file(scenarios / "analytic" / "tip_load.yaml", method="shooting")
    solution = sim.solve(continuation="never")
    assert not solution.converged
    assert solution.warnings[0].kind == "not_converged"


def test_check_cli_writes_json_and_exits_by_verdict(tmp_path, scenarios, capsys):
    code = main(["check", str(scenarios / "analytic" / "tendon_arc.yaml"), "-o", str(tmp_path)])
    assert code == 0
    data = json.loads((tmp_path / "check.json").read_text())
    assert data["agree"] is True and data["tip_position_difference"] < 1e-6
    assert {"collocation", "shooting"} == set(data["solve_times_s"])
    assert "AGREE" in capsys.readouterr().out
    # an absurdly tight tolerance must make it fail with exit code 1
    code = main(["check", str(scenarios / "analytic" / "tendon_arc.yaml"), "-o", str(tmp_path),
                 "--position-tolerance", "1e-30"])
    assert code == 1 and "DISAGREE" in capsys.readouterr().out


def test_solve_with_shooting_method(tmp_path, scenarios):
    assert main(["solve", str(scenarios / "analytic" / "pure_moment.yaml"), "--method", "shooting",
                 "-o", str(tmp_path), "--no-plot"]) == 0
    assert json.loads((tmp_path / "solution.json").read_text())["method"] == "shooting"



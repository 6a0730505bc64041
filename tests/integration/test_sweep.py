"""Continuation (tca-casadi sweep): the physical branch, agreement with shooting, exact
sensitivities, folds, step halving, and the paper's Figs. 4 and 5."""
import csv
import sys

import numpy as np
import pytest

from analytic import ELASTICA_TABLE
from conftest import ROOT, SCENARIOS
from tca_casadi import ScenarioError, Simulation, Sweep
from tca_casadi.cli import main

sys.path.insert(0, str(ROOT / "scripts"))
HEATED = ["bending.tca2.temperature", "bending.tca3.temperature"]


@pytest.fixture(scope="module")
def heating():
    """Bending module, TCAs 2 and 3 heated together from 25 to 125 degC."""
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    return sim, Sweep(sim, HEATED, 25, 125, steps=21).run()


def test_heating_stays_on_the_physical_branch(heating):
    _, result = heating
    assert result.completed and len(result.points) == 21
    assert all(p.solution.converged for p in result.points)
    for point in result.points[1:]:
        assert point.solution.actuators["bending.tca2"].tension > 0
        assert point.solution.actuators["bending.tca3"].tension > 0
    assert not [e for e in result.events if e["kind"] == "tension_sign"]
    assert result.tip_positions[-1][0] < -0.02           # bends away from TCA 1 (x < 0) by > 20 mm


def test_heating_matches_shooting_at_five_points(heating):
    sim, result = heating
    shooting = sim.solver("shooting")
    for index in (2, 6, 10, 15, 20):
        point = result.points[index]
        independent = shooting.solve(point.solution.parameters, point.solution)
        assert independent.converged, independent.message
        assert np.max(np.abs(independent.tip_position - point.solution.tip_position)) < 1e-6
        for key, actuator in point.solution.actuators.items():
            assert abs(independent.actuators[key].tension - actuator.tension) <= 1e-5 * abs(actuator.tension)


def test_sensitivities_match_finite_differences(heating):
    sim, result = heating
    solver, h = sim.solver("collocation"), 0.05          # degC, central differences
    for index in (4, 12, 20):
        point = result.points[index]
        for j, parameter in enumerate(result.parameters):
            tips = []
            for sign in (1, -1):
                params = parameter.with_value(point.solution.parameters, point.values[j] + sign * h)
                solution = solver.solve_newton(params, point.w)
                assert solution.converged
                tips.append(solution.tip_position)
            finite = (tips[0] - tips[1]) / (2 * h)
            exact = point.tip_derivative[:, j]
            assert np.linalg.norm(exact - finite) <= 1e-5 * np.linalg.norm(exact)


def test_sweep_of_a_force_component_and_gravity_magnitude():
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    result = Sweep(sim, ["gravity.magnitude"], 0.0, 9.81, steps=5).run()
    direct = Simulation.from_file(SCENARIOS / "bending_module.yaml").solve()
    assert result.completed
    assert np.max(np.abs(result.tip_positions[-1] - direct.tip_position)) < 1e-9
    assert result.points[0].values[0] == 0.0 and result.points[-1].values[0] == pytest.approx(9.81, rel=1e-12)
    forced = Sweep(sim, "tip_force.force.x", 0, "2 mN", steps=3).run()
    assert forced.values[-1, 0] == pytest.approx(2e-3, rel=1e-12)
    assert forced.tip_positions[-1][0] > forced.tip_positions[0][0]     # pushed towards +x


def test_coarse_steps_are_halved_and_land_on_the_same_solution():
    """The elastica from rest to PL^2/EI = 10 in one requested step: the step is subdivided."""
    sim = Simulation.from_file(SCENARIOS / "analytic" / "tip_load.yaml")
    EI = 1e9 * np.pi * 1e-12 / 64
    result = Sweep(sim, ["tip_force.force.x"], 0.0, -10 * EI, steps=2).run()
    assert result.completed and result.points[-1].substeps > 1
    sim.set("tip_force.force", [-10 * EI, 0, 0])
    fine = sim.solve(continuation="always")
    assert np.max(np.abs(result.tip_positions[-1] - fine.tip_position)) < 1e-9
    assert result.tip_positions[-1][0] == pytest.approx(-ELASTICA_TABLE[10.0][0], abs=1e-5)


# ---------------------------------------------------------------------- folds
def column(imperfection, load_factor):
    """A 1 m column pointing up, 1 x 3 mm section (buckles in the x-z plane), tip load
    ``(imperfection, 0, -1) * load_factor * P_cr``, P_cr = pi^2 EI / (4 L^2)."""
    EI = 1e9 * 3e-3 * 1e-3**3 / 12
    load = load_factor * np.pi**2 * EI / 4
    scenario = {"name": "column", "gravity": [0, 0, 0],
                "materials": {"m": {"youngs_modulus": "1 GPa", "poisson_ratio": 0.5}},
                "modules": [{"name": "rod", "length": 1.0, "material": "m",
                             "cross_section": {"shape": "rectangle", "width": 1e-3, "height": 3e-3}}],
                "loads": [{"name": "tip", "kind": "point", "module": "rod", "at": "end",
                           "force": [imperfection * load, 0, -load], "frame": "global"}]}
    return Simulation.from_file(scenario), load


def test_cold_start_of_a_buckled_column_takes_the_preferred_branch():
    """Continuation from rest must not jump to the near-straight unstable branch beyond P_cr."""
    sim, _ = column(0.02, 2.0)
    solution = sim.solve()
    assert solution.converged
    assert solution.tip_position[0] > 0.7          # bent towards the imperfection, not against it


@pytest.fixture(scope="module")
def folded():
    """Post-buckled column (1.2 P_cr) with the lateral force swept against the bend."""
    sim, load = column(0.05, 1.2)
    natural = Sweep(sim, ["tip.force.x"], 0.05 * load, -0.3 * load, steps=36).run()
    arclength = Sweep(sim, ["tip.force.x"], 0.05 * load, -0.3 * load, steps=101, arclength=True).run()
    return load, natural, arclength


def test_natural_continuation_stops_at_the_fold_and_says_so(folded):
    load, natural, arclength = folded
    assert not natural.completed
    assert "fold" in natural.message and "arclength=True follows the branch" in natural.message   # Python: its argument
    fold = [e for e in arclength.events if e["kind"] == "fold"][0]["values"]["tip.force.x"]
    last = natural.points[-1].values[0]
    assert fold < 0 and abs(last - fold) < 0.01 * abs(fold)      # stopped just before the fold


def test_arclength_goes_around_both_folds_symmetrically(folded):
    """The S-curve of the imperfect column is odd in the lateral force: folds at -F* and +F*."""
    load, _, arclength = folded
    assert arclength.completed
    folds = sorted(e["values"]["tip.force.x"] for e in arclength.events if e["kind"] == "fold")
    assert len(folds) == 2
    assert abs(folds[0] + folds[1]) < 1e-3 * abs(folds[0])
    assert 0.06 * load < folds[1] < 0.08 * load
    assert arclength.tip_positions[0][0] > 0.3 and arclength.tip_positions[-1][0] < -0.3   # snapped over
    assert min(p.lam for p in arclength.points) < 0.0          # went back beyond the start value


# ---------------------------------------------------------------------- input errors
@pytest.mark.parametrize("path, message", [
    ("bending.tca2.temprature", "did you mean 'bending.tca2.temperature'"),
    ("tip_force.force", "name one component"),
    ("tip_force.force.magnitude", "is zero"),
])
def test_bad_parameters_are_named(path, message):
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    with pytest.raises(ScenarioError, match=message):
        Sweep(sim, [path], 0, 1)


def test_bad_ranges_are_named():
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    with pytest.raises(ScenarioError, match="at least 2 steps"):
        Sweep(sim, HEATED, 25, 125, steps=1)
    with pytest.raises(ScenarioError, match="is not a temperature"):
        Sweep(sim, HEATED, "25 mm", 125)
    with pytest.raises(ScenarioError, match="nothing moves"):
        Sweep(sim, HEATED, 50, 50)


# ---------------------------------------------------------------------- CLI
def test_sweep_command_writes_csv_json_and_plots(tmp_path, capsys):
    code = main(["sweep", str(SCENARIOS / "bending_module.yaml"), "--param", HEATED[0], "--param", HEATED[1],
                 "--from", "25", "--to", "100 degC", "--steps", "6", "-o", str(tmp_path)])
    assert code == 0
    with (tmp_path / "sweep.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 6
    assert float(rows[-1]["bending.tca3.temperature [degC]"]) == 100.0
    for column_name in ("tip_x [m]", "bending.tca1.tension [N]", "bending.tca2.free_stroke [m]",
                        "dtip_x/dbending.tca2.temperature [m/degC]", "converged", "solve_time [s]"):
        assert column_name in rows[0]
    assert (tmp_path / "sweep.png").stat().st_size > 10_000
    assert (tmp_path / "sweep_robots.png").stat().st_size > 10_000
    assert "completed" in capsys.readouterr().out


def test_sweep_command_rejects_a_bad_parameter(capsys):
    code = main(["sweep", str(SCENARIOS / "bending_module.yaml"), "--param", "bending.tca2.temprature",
                 "--from", "25", "--to", "50"])
    assert code == 2
    assert "did you mean 'bending.tca2.temperature'" in capsys.readouterr().err


# ---------------------------------------------------------------------- the paper's figures
def test_fig4_more_than_40_percent_more_bending_without_the_passive_tca(tmp_path):
    from paper_figures import fig4
    data = fig4(tmp_path, steps=11)
    heated = data["temperature"] > 25
    assert np.all(data["ratio"][heated] > 1.40)
    assert (tmp_path / "fig4_antagonism.png").exists() and (tmp_path / "fig4_antagonism.csv").exists()


def test_fig5_higher_temperature_stiffer_module(tmp_path):
    from paper_figures import fig5
    data = fig5(tmp_path, steps=4)
    d75, d100, d125 = (data["displacement"][t][1:] for t in (75, 100, 125))
    assert np.all(d75 > d100) and np.all(d100 > d125) and np.all(d125 > 0)


def test_fig3_passive_law_peaks_at_the_monotone_limit(tmp_path):
    from paper_figures import fig3
    data = fig3(tmp_path, points=201)
    peak = data["force"][np.argmax(data["stretch"])]
    assert abs(peak - data["law"].monotone_limit) < 0.01 * data["law"].monotone_limit

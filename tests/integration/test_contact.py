"""Contact with fixed obstacles (issue 17): beam theory, consistency with point loads,
complementarity on a fine sampling, symmetry, localisation, bad input."""
import copy
import subprocess
import sys
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.errors import ScenarioError
from tca_casadi.model.contact import outline_of
from tca_casadi.model.obstacles import gap
from tca_casadi.model.rotations import rotation_numpy
from tca_casadi.simulation import Simulation

ROD = {"name": "rod", "length": "100 mm", "material": "m", "cross_section": {"shape": "circle", "diameter": "2 mm"}}


def propped(youngs_modulus):
    """A horizontal steel-density cantilever along x under self-weight, its tip resting on a thin
    frictionless cylinder (a knife edge) whose top is at the rod's underside."""
    return {"name": "propped", "materials": {"m": {"youngs_modulus": youngs_modulus, "poisson_ratio": 0.3, "density": 7800}},
            "base": {"orientation": {"axis": [0, 1, 0], "angle": "90 deg"}},
            "modules": [ROD],
            "obstacles": [{"name": "prop", "shape": "cylinder", "radius": "1 mm", "position": ["100 mm", 0, "-2 mm"],
                           "orientation": {"axis": [1, 0, 0], "angle": "90 deg"}}]}


def pushed(contact=None, force="3 mN"):
    """A vertical rubber rod pushed sideways at its tip into a ball that stops it half way up."""
    scenario = {"name": "pushed", "gravity": [0, 0, 0], "materials": {"m": {"youngs_modulus": "1 MPa", "poisson_ratio": 0.5}},
                "modules": [dict(ROD, cross_section={"shape": "circle", "diameter": "5 mm"})],
                "loads": [{"name": "push", "kind": "point", "module": "rod", "at": "end", "force": [force, 0, 0]}],
                "obstacles": [{"name": "ball", "shape": "sphere", "radius": "10 mm", "position": ["14 mm", 0, "63 mm"]}]}
    if contact is not None:
        scenario["contact"] = contact
    return scenario


def solve(scenario, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = Simulation.from_file(scenario)
        return sim, sim.solve(**options)


def fine_gaps(sim, solution):
    """Gaps [m] of every module against every obstacle at 64 points per collocation interval."""
    solver = sim.solver()
    out = []
    for m, (s, states) in solver.fine_states(solution.iterate.w, 64).items():
        module = sim.robot.modules[m]
        for shape in sim.robot.obstacles:
            out += [gap(shape, outline_of(module), states[0:3, j], rotation_numpy(states[3:7, j]))[0]
                    for j in range(states.shape[1])]
    return np.array(out)


@pytest.mark.parametrize("youngs_modulus", ["2 GPa", "200 GPa"])
def test_propped_cantilever_reactions_are_three_and_five_eighths_of_the_weight(youngs_modulus):
    sim, solution = solve(propped(youngs_modulus))
    assert solution.converged
    weight = sim.robot.modules[0].weight_density * 9.81 * 0.1
    (contact,) = solution.contacts          # at the tip, or localised a few um before it on the 1 mm knife edge
    assert contact.obstacle == "prop" and contact.s == pytest.approx(0.1, abs=1e-5)
    assert_allclose(contact.normal_force / weight, 3 / 8, rtol=1e-3, atol=0)
    assert_allclose(solution.modules[0].base_reaction["force"][2] / weight, 5 / 8, rtol=1e-3, atol=0)
    assert solution.balance.relative < 1e-9


def test_a_localised_candidate_beside_a_closed_one_is_solved_by_semismooth_newton(monkeypatch):
    """On the soft (2 GPa) propped cantilever, localisation adds a candidate 6 um before the tip
    on the knife edge; which of the two carries the prop is a complementarity kink where the
    line search finds no descent. Semismooth Newton passes it (IPOPT, which took 200 iterations
    and failed there, then continuation from rest, is not called), to the same reaction."""
    from tca_casadi.solvers.collocation import CollocationSolver

    def no_ipopt(self, params, initial=None):
        raise AssertionError("IPOPT was called")
    monkeypatch.setattr(CollocationSolver, "solve_ipopt", no_ipopt)
    sim, solution = solve(propped("2 GPa"))
    assert solution.converged and "semismooth" in solution.message
    assert len(sim.robot.added_contacts.get(0, ())) == 1
    weight = sim.robot.modules[0].weight_density * 9.81 * 0.1
    assert_allclose(sum(c.normal_force for c in solution.contacts) / weight, 3 / 8, rtol=1e-3, atol=0)
    assert solution.balance.relative < 1e-9


def test_propped_cantilever_converges_to_beam_theory_as_the_rod_stiffens():
    """Against the shear-deformable (Timoshenko) small-deflection reaction
    ``3/8 w L (1 + 4 phi) / (1 + 3 phi)``, ``phi = EI / (GA L^2)`` (6.5e-5 here; the rod shears
    as a Cosserat rod does), the error is the large-deflection one and falls as 1/E."""
    errors = []
    for modulus in ("2 GPa", "20 GPa", "200 GPa"):
        sim, solution = solve(propped(modulus))
        module = sim.robot.modules[0]
        weight = module.weight_density * 9.81 * 0.1
        phi = module.stiffness[0] / (module.stiffness[3] * 0.1 ** 2)
        errors.append(abs(solution.contacts[0].normal_force / weight - 3 / 8 * (1 + 4 * phi) / (1 + 3 * phi)))
    assert errors[0] < 1e-4
    assert errors[0] > 5 * errors[1] > 25 * errors[2]


def test_sphere_push_equals_a_point_load_of_the_reported_contact_force():
    sim, solution = solve(pushed())
    assert solution.converged
    (contact,) = solution.contacts
    module = solution.modules[0]
    j = int(np.argmin(np.abs(module.s - contact.s)))
    arm = contact.position - module.p[:, j]
    loaded = pushed()
    del loaded["obstacles"]
    loaded["loads"].append({"name": "contact_load", "kind": "point", "module": "rod", "at": contact.s,
                            "force": contact.force.tolist(), "moment": np.cross(arm, contact.force).tolist()})
    reference_sim = Simulation.from_file(loaded)
    reference_sim.use_meshes(sim.solver().nlp.meshes, sim.solver().degree)       # the same discretisation
    reference = reference_sim.solve(refine=False)
    s = np.linspace(0.0, 0.1, 201)
    shape = sim.solver()._poses_at(solution.iterate.w, 0, s)[0]
    expected = reference_sim.solver()._poses_at(reference.iterate.w, 0, s)[0]
    assert_allclose(shape, expected, rtol=0, atol=1e-9)


def test_localisation_moves_a_candidate_to_the_contact_and_leaves_no_penetration():
    sim, unlocalised = solve(pushed({"localise": 0}))
    assert unlocalised.penetration > 1e-6 and unlocalised.warning_texts("penetration")
    sim, solution = solve(pushed())
    assert solution.converged and solution.penetration <= 1e-8 and not solution.warning_texts("penetration")
    assert sim.robot.added_contacts                       # a candidate was added where the ball is
    assert fine_gaps(sim, solution).min() >= -1e-8


def random_obstacle_scenarios(count, seed=7):
    """Vertical rods under random sideways tip loads against random spheres, planes and boxes."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        scenario = pushed(force=f"{rng.uniform(1.0, 6.0):.3f} mN")
        angle = rng.uniform(0, 2 * np.pi)
        scenario["loads"][0]["force"] = [f"{c:.4f} mN" for c in rng.uniform(1.0, 5.0) * np.array([np.cos(angle), np.sin(angle), 0])]
        side, height = np.array([np.cos(angle), np.sin(angle), 0.0]), rng.uniform(0.03, 0.09)
        shape = rng.choice(["sphere", "plane", "box"])
        clear = rng.uniform(0.5e-3, 3e-3) + 2.5e-3
        if shape == "sphere":
            radius = rng.uniform(3e-3, 15e-3)
            centre = side * (clear + radius) + [0, 0, height]
            obstacle = {"shape": "sphere", "radius": radius, "position": centre.tolist()}
        elif shape == "plane":
            obstacle = {"shape": "plane", "position": (side * clear).tolist(), "normal": (-side).tolist()}
        else:
            size = np.r_[rng.uniform(4e-3, 20e-3, 2), 0.2]       # a wall: the rod meets a face, not an edge
            centre = side * (clear + size[0] / 2) + [0, 0, height]
            obstacle = {"shape": "box", "size": size.tolist(), "position": centre.tolist(),
                        "orientation": {"axis": [0, 0, 1], "angle": float(angle)}}
        scenario["obstacles"] = [dict(obstacle, name="obstacle")]
        yield scenario


@pytest.mark.parametrize("scenario", list(random_obstacle_scenarios(6)), ids=lambda s: s["obstacles"][0]["shape"])
def test_complementarity_and_no_penetration_on_random_robots(scenario):
    sim, solution = solve(scenario)
    assert solution.converged, solution.message
    assert solution.balance.relative < 1e-8
    solver = sim.solver()
    forces = solution.iterate.w[solver.nlp.contact_index] * solver.nlp.scale[solver.nlp.contact_index]
    modules = solution.modules
    for c in sim.robot.contacts:
        module = sim.robot.modules[c.module]
        j = int(np.argmin(np.abs(modules[c.module].s - c.s)))
        g = gap(sim.robot.obstacles[c.obstacle], outline_of(module), modules[c.module].p[:, j], modules[c.module].R[:, :, j])[0]
        assert g >= -1e-9 and forces[c.index] >= -1e-12 and abs(g * forces[c.index]) < 1e-9
    for contact in solution.contacts:
        assert contact.gap >= -1e-9 and contact.normal_force > 0
    assert solution.penetration <= 1e-8 and fine_gaps(sim, solution).min() >= -1e-8


def test_mirrored_pinch_presses_equally_from_both_sides():
    """A trunk carrying two mirrored fingers bent together by mirrored tip loads onto a centred
    box: equal normal forces, no net sideways push on it."""
    finger = {"length": "60 mm", "material": "m", "cross_section": {"shape": "circle", "diameter": "3 mm"}, "parent": "trunk"}
    scenario = {"name": "pinch", "gravity": [0, 0, 0], "materials": {"m": {"youngs_modulus": "2 MPa", "poisson_ratio": 0.5}},
                "modules": [{"name": "trunk", "length": "20 mm", "material": "m", "cross_section": {"shape": "circle", "diameter": "8 mm"}},
                            dict(finger, name="left", connector={"offset": [0, "10 mm", 0]}),
                            dict(finger, name="right", connector={"offset": [0, "-10 mm", 0]})],
                "loads": [{"name": "squeeze_left", "kind": "point", "module": "left", "at": "end", "force": [0, "-2 mN", 0]},
                          {"name": "squeeze_right", "kind": "point", "module": "right", "at": "end", "force": [0, "2 mN", 0]}],
                "obstacles": [{"name": "bar", "shape": "box", "size": ["20 mm", "8 mm", "20 mm"], "position": [0, 0, "70 mm"]}]}
    sim, solution = solve(scenario)
    assert solution.converged
    left = [c for c in solution.contacts if c.module == "left"]
    right = [c for c in solution.contacts if c.module == "right"]
    assert left and right
    assert_allclose(sum(c.normal_force for c in left), sum(c.normal_force for c in right), rtol=1e-9, atol=0)
    net = sum(c.force for c in solution.contacts)
    assert_allclose(net[1], 0.0, rtol=0, atol=1e-9)
    assert solution.balance.relative < 1e-8


def test_contact_results_reach_solution_json(tmp_path):
    _, solution = solve(pushed())
    data = solution.to_dict()
    (contact,) = data["contacts"]
    assert set(contact) >= {"module", "s", "position", "normal", "normal_force", "tangential_force", "gap",
                            "friction_margin", "obstacle"}
    assert data["clearance"]["ball"]["gap"] >= -1e-8 and data["penetration"] <= 1e-8
    assert "rod / ball" in solution.summary()


def test_warm_start_follows_the_contact_as_the_push_grows():
    sim, first = solve(pushed())
    sim.set("loads.push.force", ["4 mN", 0, 0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        second = sim.solve(warm_start=first)
    assert second.converged and second.penetration <= 1e-8
    assert second.contacts[0].normal_force > first.contacts[0].normal_force


@pytest.mark.parametrize("change, message", [
    ({"radius": "0 mm"}, "greater than 0"),
    ({"radius": "-1 mm"}, "greater than 0"),
    ({"friction": -0.2}, "greater than or equal to 0"),
    ({"position": [0, 0, "50 mm"]}, "intersects module 'rod' in its reference configuration by 10 mm at s = 50 mm"),
])
def test_bad_obstacles_are_one_line_errors(change, message):
    """Sizes and friction when the scenario is read; an obstacle cutting the unloaded robot when
    a cold solve would start there."""
    scenario = pushed()
    scenario["obstacles"][0].update(change)
    with pytest.raises(ScenarioError, match=message):
        Simulation.from_file(scenario).solve()


def test_bad_boxes_and_contact_points_are_errors():
    scenario = pushed()
    scenario["obstacles"] = [{"name": "b", "shape": "box", "size": ["1 mm", 0, "1 mm"], "position": ["30 mm", 0, 0]}]
    with pytest.raises(ScenarioError, match="every edge must be positive"):
        Simulation.from_file(scenario)
    with pytest.raises(ScenarioError, match="unknown module 'rdo'"):
        Simulation.from_file(pushed({"at": {"rdo": [0.05]}}))
    with pytest.raises(ScenarioError, match="beyond the module's length"):
        Simulation.from_file(pushed({"at": {"rod": ["200 mm"]}}))


def test_dynamics_from_an_equilibrium_in_contact_stays_there():
    """The rod pushed into the ball, as rod dynamics (issue 33): started at its static
    equilibrium, with nothing changing, it stays there (to 1e-12 m, at rest) with the same
    contact force."""
    scenario = pushed()
    scenario["materials"]["m"]["density"] = 1100
    sim = Simulation.from_file(dict(scenario, dynamics={"enabled": True}, duration=0.05))
    from tca_casadi.time_simulation.timeline import TimeSimulation
    series = TimeSimulation(sim, dt=0.005).run()
    assert series.completed, series.message
    force = [view.contact_columns()["ball.normal_force [N]"] for view in series.views]
    assert force[0] > 0 and np.ptp(force) < 1e-9 * force[0]
    assert np.max(np.abs(series.tip_positions() - series.tip_positions()[0])) < 1e-12
    assert np.max(np.abs(series.tip_velocities)) < 1e-9


def test_cli_exits_2_on_an_intersecting_obstacle(tmp_path):
    import yaml
    scenario = copy.deepcopy(pushed())
    scenario["obstacles"][0]["position"] = [0, 0, "50 mm"]
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(scenario))
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "solve", str(path), "-o", str(tmp_path / "out")],
                         capture_output=True, text=True)
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0 and "intersects module 'rod'" in run.stderr


def test_moving_an_obstacle_by_parameter_equals_rebuilding_with_it():
    """Obstacle positions and sizes are NLP parameters: setting one on a built model equals a
    model built with the new value (contact localised in both to where the gap's slope vanishes)."""
    sim, first = solve(pushed())
    sim.set("obstacles.ball.radius", "11 mm")
    sim.set("obstacles.ball.position", ["14.5 mm", 0, "60 mm"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        moved = sim.solve(warm_start=first)
    scenario = pushed()
    scenario["obstacles"][0].update(radius="11 mm", position=["14.5 mm", 0, "60 mm"])
    _, rebuilt = solve(scenario)
    assert moved.converged and rebuilt.converged
    assert_allclose(moved.tip_position, rebuilt.tip_position, rtol=0, atol=1e-9)
    assert_allclose(moved.contacts[0].normal_force, rebuilt.contacts[0].normal_force, rtol=1e-6, atol=0)
    sim.set_parameter("obstacles.ball.radius", -1e-3)
    assert any("radius must be positive" in problem for problem in sim.robot.problems(sim.params))


def test_grip_force_script_quick(tmp_path):
    """scripts/grip_force.py --quick: the shipped gripper presses equally with both fingertips,
    not at all when open (125 degC), harder on a wider bar and when colder."""
    sys.path.insert(0, str(__import__("conftest").ROOT / "scripts"))
    from grip_force import main
    rows = main(["--quick", "-o", str(tmp_path)])
    assert (tmp_path / "grip_force.csv").exists() and (tmp_path / "grip_force.png").exists()
    assert all(row["converged"] and row["penetration_m"] <= 1e-8 for row in rows)
    force = {(row["width_mm"], row["temperature_degC"]): row for row in rows}
    for row in rows:
        assert_allclose(row["finger_a_N"], row["finger_b_N"], rtol=1e-5, atol=1e-12)   # finger_a's hub carries 0.3 g
    assert force[(4.0, 125.0)]["finger_a_N"] == 0.0 and force[(8.0, 125.0)]["finger_a_N"] == 0.0
    assert force[(8.0, 25.0)]["finger_a_N"] > force[(8.0, 75.0)]["finger_a_N"] > 0.0
    assert force[(8.0, 25.0)]["finger_a_N"] > force[(4.0, 25.0)]["finger_a_N"] > 0.0


def test_sweep_reports_the_touch_and_the_growing_contact_force(tmp_path):
    """A sweep of the push: the rod touches the ball once, then presses harder; the CSV carries
    the force and the clearance, which closes to zero where the force appears."""
    from tca_casadi import Sweep
    scenario = pushed()       # against a wall: pressed on the ball, the rod's tip would slide round it (docs/contact.md)
    scenario["obstacles"] = [{"name": "wall", "shape": "box", "size": ["4 mm", "40 mm", "200 mm"],
                              "position": ["6.5 mm", 0, "50 mm"]}]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = Simulation.from_file(scenario)
        result = Sweep(sim, "push.force.x", 0, "4 mN", steps=9).run()
    assert result.completed, result.message
    touches = [e for e in result.events if e["kind"] == "touch"]
    assert len(touches) == 1 and "rod touches wall" in touches[0]["message"]
    rows = result.rows()
    forces = np.array([row["wall.normal_force [N]"] for row in rows])
    clearance = np.array([row["wall.clearance [m]"] for row in rows])
    assert forces[0] == 0.0 and forces[-1] > 0 and np.all(np.diff(forces) >= 0)
    assert np.all(clearance[forces > 0] >= -1e-8) and np.all(np.abs(clearance[forces > 0]) < 1e-6)
    assert np.all(clearance[forces == 0] > 0)


def test_sequence_table_carries_each_obstacles_force_and_clearance(tmp_path):
    """`sequence` on the wall scenario: the wall's force is zero until the pull brings the tip to
    it, and the table says so step by step."""
    import csv

    import yaml
    from conftest import SCENARIOS
    from tca_casadi.cli import main
    raw = yaml.safe_load((SCENARIOS / "tendon_robot_wall.yaml").read_text())
    raw["modules"][0]["actuators"][0]["displacement"] = 0.0
    raw["sequence"] = [{"name": "straight", "set": {}}, {"name": "pull", "set": {"body.t1.displacement": "5 mm"}}]
    path = tmp_path / "sequence.yaml"
    path.write_text(yaml.safe_dump(raw))
    assert main(["sequence", str(path), "-o", str(tmp_path / "out"), "--quiet"]) == 0
    with open(tmp_path / "out" / "sequence.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert float(rows[0]["wall.normal_force [N]"]) == 0.0 and float(rows[0]["wall.clearance [m]"]) > 9e-3
    assert float(rows[1]["wall.normal_force [N]"]) > 0.01 and abs(float(rows[1]["wall.clearance [m]"])) < 1e-8


def test_study_rows_carry_each_obstacles_force_and_clearance():
    """A grid study moving the wall (a parameter) under a fixed pull: the farther the wall, the
    smaller its force, zero once it is out of reach; clearance zero where it presses."""
    from conftest import SCENARIOS
    from tca_casadi import Study
    sim = Simulation.from_file(SCENARIOS / "tendon_robot_wall.yaml")
    result = Study(sim, vary={"obstacles.wall.position.x": ["18 mm", "40 mm", 4]}).run()
    frame = result.frame.sort_values("obstacles.wall.position.x [m]")
    assert frame["converged"].all()
    force, clearance = frame["wall.normal_force [N]"].to_numpy(), frame["wall.clearance [m]"].to_numpy()
    assert np.all(np.diff(force) <= 0) and force[0] > 0.01 and force[-1] == 0.0
    assert np.all(np.abs(clearance[force > 0]) < 1e-8) and clearance[-1] > 0.01


def test_simulate_heats_the_module_against_a_wall_and_releases_it(tmp_path):
    """`simulate` of the heating scenario beside a wall 1 mm from the body: the heated module
    touches it, presses harder while heated, lets go while cooling; the timeseries says so."""
    import csv

    import yaml
    from conftest import SCENARIOS
    from tca_casadi.cli import main
    raw = yaml.safe_load((SCENARIOS / "bending_module_heating.yaml").read_text())
    raw["obstacles"] = [{"name": "wall", "shape": "plane", "position": ["-6 mm", 0, 0], "normal": [1, 0, 0]}]
    path = tmp_path / "heating_wall.yaml"
    path.write_text(yaml.safe_dump(raw))
    assert main(["simulate", str(path), "-o", str(tmp_path / "out"), "--quiet", "--no-animation"]) == 0
    with open(tmp_path / "out" / "timeseries.csv") as stream:
        rows = list(csv.DictReader(stream))
    t = np.array([float(row["t [s]"]) for row in rows])
    force = np.array([float(row["wall.normal_force [N]"]) for row in rows])
    clearance = np.array([float(row["wall.clearance [m]"]) for row in rows])
    assert_allclose(clearance[0], 1e-3, rtol=0, atol=1e-8)         # the envelope's 5 mm radius, 1 mm clear
    assert force[t <= 10].max() == 0.0 and force[(t >= 25) & (t <= 40)].min() > 0 and force[-1] == 0.0
    assert np.all(np.diff(force[(t >= 20) & (t <= 40)]) > 0)            # heated: pressing harder
    assert np.all(np.abs(clearance[force > 0]) < 1e-8) and np.all(clearance >= -1e-8)

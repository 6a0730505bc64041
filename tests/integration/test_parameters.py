"""Material moduli and density, TCA geometry and fits, and route placements are NLP parameters
(issue 14, item 6): changing one re-solves the built NLP, and the answer equals a model rebuilt
from a scenario holding the new value (both solvers), on shipped and random robots."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi import Simulation
from tca_casadi.errors import ScenarioError
from tca_casadi.studies.sweep.run import Sweep

from analytic import beam_scenario, tendon_arc
from random_robots import random_robot

#: layout entries that are loads, poses or controls (tested elsewhere); the rest are the new ones
OLD = (".temperature", ".tension", ".displacement", ".force", ".moment", ".mass", ".held", "gravity",
       "base.position", "base.quaternion")


def _design_parameters(sim):
    return [name for name in sim.robot.layout.names() if not name.endswith(OLD) and name not in OLD]


def _perturbed(sim, rng, names):
    """New values for ``names``: moduli and fits by up to +-30 %, geometry by up to +-15 %,
    angles by up to +-0.4 rad, kept inside the body and the TCA's own constraints."""
    values = {}
    for name in names:
        value = sim.get_parameter(name)
        if name.endswith((".angle", ".phase", ".pitch_angle")):
            new = value + rng.uniform(-0.4, 0.4) if not name.endswith("pitch_angle") else value * rng.uniform(0.9, 1.1)
        elif name.endswith((".radius", "coil_radius", "fiber_radius")):
            new = value * rng.uniform(0.85, 1.0)
        elif name.endswith("poisson_ratio"):
            new = rng.uniform(0.3, 0.5)
        elif name.endswith("reference_temperature"):
            new = value + rng.uniform(-3, 3)
        else:
            new = value * rng.uniform(0.7, 1.3)
        values[name] = float(new)
    if any(n.endswith("fiber_radius") for n in names):        # keep fiber inside the coil
        for name in [n for n in names if n.endswith("fiber_radius")]:
            coil = values[name.replace("fiber_radius", "coil_radius")]
            values[name] = min(values[name], 0.9 * coil)
    return values


def _compare(first, second, tip_atol=1e-9, tension_rtol=1e-7):
    assert first.converged and second.converged, (first.message, second.message)
    for a, b in zip(first.modules, second.modules):
        assert_allclose(a.p[:, -1], b.p[:, -1], rtol=0, atol=tip_atol)
    for key, actuator in first.actuators.items():
        other = second.actuators[key].tension
        assert_allclose(actuator.tension, other, rtol=0, atol=tension_rtol * max(1e-3, abs(other)))


def test_every_parameter_name_is_a_set_path_of_the_scenario(scenarios):
    from tca_casadi.model.history import history_names_of
    """Each layout name, given to --set with its own value, leaves the parameters unchanged and
    needs no rebuild."""
    for path in sorted(scenarios.glob("*.yaml")):
        sim = Simulation.from_file(path, allow_code=True)
        robot = sim.robot
        for name in sim.robot.layout.names():
            if name in history_names_of(robot):
                continue          # contact objects' history: copied from a warm start, not a scenario key
            value = sim.get_parameter(name)
            if np.ndim(value):
                continue
            sim.set(name, value)
            assert sim.robot is robot, f"{path}: --set {name} rebuilt the model"
            assert_allclose(sim.params, robot.values, rtol=0, atol=1e-12 * (1 + np.abs(robot.values).max()))


@pytest.mark.parametrize("seed", [3, 11, 26])
def test_changed_parameters_equal_a_rebuilt_model_on_random_robots(seed):
    scenario = random_robot(seed)
    sim = Simulation.from_file(scenario)
    first = sim.solve()
    assert first.converged, first.message
    names = _design_parameters(sim)
    assert any("youngs_modulus" in n for n in names) and any(".route." in n for n in names)
    values = _perturbed(sim, np.random.default_rng(seed), names)
    solver = sim.solver()
    for name, value in values.items():
        sim.set(name, value)
    assert sim.solver() is solver                      # no rebuild
    moved = sim.solve(warm_start=first)
    rebuilt = Simulation.from_file(scenario, [f"{name}={value!r}" for name, value in values.items()])
    assert rebuilt.robot.structure_key(rebuilt.scenario) == sim.robot.structure_key(sim.scenario)
    fresh = rebuilt.solve()
    # the meshes are the same (structure): the two NLPs are the same equations
    _compare(moved, fresh)
    tip_change = np.abs(moved.modules[-1].p[:, -1] - first.modules[-1].p[:, -1]).max()
    assert tip_change > 1e-5, "the perturbation moved nothing: the test would not see a bug"


def test_shooting_follows_the_parameters_of_the_built_solver(scenarios):
    """The shooting solver built once, re-solved at new design parameters, agrees with collocation
    rebuilt at those values (an independent discretisation of the same parameters)."""
    sim = Simulation.from_file(scenarios / "twisting_module.yaml")
    shooting = sim.solver("shooting")
    names = _design_parameters(sim)
    values = _perturbed(sim, np.random.default_rng(5), names)
    for name, value in values.items():
        sim.set(name, value)
    assert sim.solver("shooting") is shooting
    shot = sim.solve(method="shooting")
    fresh = Simulation.from_file(scenarios / "twisting_module.yaml",
                                 [f"{name}={value!r}" for name, value in values.items()]).solve()
    # two discretisations: they agree to the tip tolerance that refinement guarantees (1e-7 m)
    _compare(shot, fresh, tip_atol=sim.scenario.solver.tip_tolerance, tension_rtol=1e-5)
    original = Simulation.from_file(scenarios / "twisting_module.yaml").solve(method="shooting")
    assert np.abs(shot.modules[-1].p[:, -1] - original.modules[-1].p[:, -1]).max() > 1e-5


def test_modulus_and_route_radius_against_the_exact_tendon_arc():
    """A straight tendon at offset r with tension F over a whole rod: ``u = F r / EI`` exactly.
    Changing E and r as parameters (no rebuild) follows the formula."""
    tension = 0.02
    scenario = beam_scenario(length=0.05, diameter=0.006, youngs=0.5e6, intervals=4, actuators=[
        {"name": "c", "kind": "tendon", "tension": tension, "route": {"kind": "straight", "radius": "1.5 mm"}}])
    sim = Simulation.from_file(scenario)
    previous = sim.solve()
    for youngs, radius in [(0.5e6, 0.0015), (0.8e6, 0.0015), (0.8e6, 0.002), (0.3e6, 0.0025)]:
        sim.set_parameter("materials.m.youngs_modulus", youngs)
        sim.set_parameter("rod.c.route.radius", radius)
        solution = sim.solve(warm_start=previous)
        ei = youngs * np.pi * 0.006**4 / 64
        ea = youngs * np.pi * 0.006**2 / 4
        u, v3 = tendon_arc(tension, radius, ei, ea)
        module = solution.modules[0]
        # the tendon at body +x: curvature about body y, u_y = F r / EI (SPEC sign convention)
        assert_allclose(module.u[1], u, rtol=1e-9, atol=0)
        assert_allclose(module.v[2], v3, rtol=0, atol=1e-12)
        previous = solution


def test_density_and_moduli_move_the_self_weight_balance(scenarios):
    """Density as a parameter: the base reaction equals the new weight (global balance)."""
    sim = Simulation.from_file(scenarios / "bending_module.yaml", ["tip_force.force=[0, 0, 0]"])
    sim.solve()
    for density in (500.0, 2500.0):
        sim.set("materials.ecoflex30.density", density)
        solution = sim.solve(warm_start="last")
        module = sim.robot.modules[0]
        weight = density * module.properties.area * module.length * np.asarray(sim.scenario.gravity)
        assert_allclose(solution.modules[0].base_reaction["force"], -weight, rtol=0, atol=1e-9 * np.abs(weight).max())


def test_a_route_radius_outside_the_body_is_refused(scenarios):
    sim = Simulation.from_file(scenarios / "bending_module.yaml")
    with pytest.raises(ScenarioError, match="outside the body"):
        sim.set("bending.tca1.route.radius", "9 mm")
    with pytest.raises(ScenarioError, match=r"route.radius = 0.009 m: bending.tca1: the route passes outside"):
        Sweep(sim, ["bending.tca1.route.radius"], 0.003, 0.009, steps=3)


def test_sweep_over_a_modulus_runs_on_the_built_nlp(scenarios):
    sim = Simulation.from_file(scenarios / "bending_module.yaml")
    sweep = Sweep(sim, ["materials.ecoflex30.youngs_modulus"], "0.1 MPa", "0.3 MPa", steps=5)
    result = sweep.run()
    assert all(p.solution.converged for p in result.points)
    assert result.parameters[0].label == "materials.ecoflex30.youngs_modulus [MPa]"      # as given
    assert result.parameters[0].si_label == "materials.ecoflex30.youngs_modulus [Pa]"    # in the files
    # each point is the equilibrium of a model built at that modulus (the NLP is not rebuilt)
    for point in (result.points[1], result.points[-1]):
        youngs = float(point.values[0])
        fresh = Simulation.from_file(scenarios / "bending_module.yaml",
                                     [f"materials.ecoflex30.youngs_modulus={youngs!r}"]).solve()
        _compare(point.solution, fresh)


def test_a_built_solver_is_reused_only_for_the_same_structure():
    """Simulations of one structure share the built NLP (parameters differ freely, the answers
    equal a fresh build's); another name, mesh or length gets its own."""
    from tca_casadi.solvers.collocation import clear_built_solvers
    scenario = random_robot(3)
    first = Simulation.from_file(scenario)
    refine_off = Simulation.from_file(scenario, ["solver.refine=off"])    # a solver option: structure
    assert first.solver() is Simulation.from_file(scenario).solver()
    assert refine_off.solver() is not first.solver()
    renamed = Simulation.from_file(dict(scenario, name="other"))
    assert renamed.solver() is not first.solver()
    name = first.robot.layout.names()[0]
    module = first.robot.modules[0].name
    changed = Simulation.from_file(scenario, [f"{module}.length={first.robot.modules[0].length * 1.1}"])
    assert changed.solver() is not first.solver()
    moved = Simulation.from_file(scenario)
    value = np.atleast_1d(moved.get_parameter(name))
    moved.set_parameter(name, value * 1.05 if np.any(value) else value + 0.01)
    shared = moved.solve(warn=False)
    assert moved.solver() is first.solver() or shared.accuracy.refinements > 0
    clear_built_solvers()
    fresh = Simulation.from_file(scenario)
    fresh.set_parameter(name, moved.get_parameter(name))
    alone = fresh.solve(warn=False)
    assert shared.converged and alone.converged
    assert_allclose(shared.tip_position, alone.tip_position, rtol=0, atol=1e-12)
    assert shared.scenario_name == alone.scenario_name == scenario["name"]

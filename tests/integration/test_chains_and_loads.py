"""Modules in series, connectors, spans, point and distributed loads, precurvature: each against an
equivalent single-module model, an analytic formula, or global force and moment balance."""
import copy

import numpy as np
from numpy.testing import assert_allclose
import pytest
from analytic import beam_scenario
from builders import mixed_chain, robot, rod, solve, tca

from tca_casadi import Simulation
from tca_casadi.model.rotations import rotation_numpy

def test_two_modules_equal_one_module_with_a_span_and_a_mid_module_mass():
    single = robot([rod("body", "45 mm", [tca("a", "0 deg", 90, span=[0, 0.0225]),
                                          tca("b", "120 deg", 25, span=[0, 0.0225])])],
                   loads=[{"name": "disc", "kind": "mass", "module": "body", "at": "30 mm", "mass": "1 g"}])
    chain = robot([rod("lower", "22.5 mm", [tca("a", "0 deg", 90), tca("b", "120 deg", 25)]),
                   rod("upper", "22.5 mm")],
                  loads=[{"name": "disc", "kind": "mass", "module": "upper", "at": "7.5 mm", "mass": "1 g"}])
    a, b = solve(single), solve(chain)
    assert np.linalg.norm(a.tip_position - b.tip_position) < 1e-8
    assert_allclose(a.tip_rotation, b.tip_rotation, rtol=0, atol=1e-7)
    assert a.actuators["body.a"].tension == pytest.approx(b.actuators["lower.a"].tension, rel=1e-6)
    assert a.actuators["body.b"].tension == pytest.approx(b.actuators["lower.b"].tension, rel=1e-6)
    assert np.linalg.norm(a.tip_position - np.array([0, 0, -0.045])) > 1e-3    # it really bent


def test_connector_mass_equals_a_point_mass_at_the_junction():
    heated = [tca("a", "0 deg", 80)]
    single = robot([rod("body", "45 mm", [tca("a", "0 deg", 80, span=[0, 0.0225])])],
                   loads=[{"name": "m", "kind": "mass", "module": "body", "at": "22.5 mm", "mass": "2 g"}])
    chain = robot([rod("lower", "22.5 mm", heated),
                   rod("upper", "22.5 mm", connector={"mass": "2 g"})])
    a, b = solve(single), solve(chain)
    assert np.linalg.norm(a.tip_position - b.tip_position) < 1e-8


def test_connector_offset_and_rotation_balance_forces_and_moments():
    """Weightless body, a heavy tilted connector and a tip force: global equilibrium."""
    chain = robot([rod("lower", "30 mm", [tca("a", "0 deg", 90)]),
                   rod("upper", "20 mm", [tca("b", "90 deg", 70)],
                       connector={"offset": ["1 mm", "2 mm", "5 mm"], "mass": "3 g",
                                  "rotation": {"axis": [0, 1, 0], "angle": "20 deg"}})],
                  loads=[{"name": "tip", "kind": "point", "module": "upper", "force": [0.01, -0.005, 0.002],
                          "moment": [1e-4, 0, -2e-4]}])
    chain["materials"]["ecoflex"]["density"] = 0.0
    sim = Simulation.from_file(chain)
    solution = sim.solve()
    assert solution.converged
    g = np.array([0, 0, -9.81])
    lower, upper = solution.modules
    connector = sim.robot.modules[1].connector
    com = lower.p[:, -1] + lower.R[:, :, -1] @ connector.center_of_mass
    forces = [(com, 0.003 * g), (upper.p[:, -1], np.array([0.01, -0.005, 0.002]))]
    reaction = lower.base_reaction
    total_force = reaction["force"] + sum(f for _, f in forces)
    total_moment = reaction["moment"] + sum(np.cross(x, f) for x, f in forces) + np.array([1e-4, 0, -2e-4])
    assert_allclose(total_force, 0.0, rtol=0, atol=1e-12)
    assert_allclose(total_moment, 0.0, rtol=0, atol=1e-13)
    # the pose really goes through the connector: offset and rotation are applied at the junction
    assert_allclose(upper.p[:, 0], com + lower.R[:, :, -1] @ connector.offset / 2, rtol=0, atol=1e-12)
    expected = lower.R[:, :, -1] @ rotation_numpy(connector.quaternion)
    assert_allclose(upper.R[:, :, 0], expected, rtol=0, atol=1e-12)
def test_point_load_at_a_junction_equals_one_inside_a_module():
    load = {"name": "push", "kind": "point", "force": [0.003, 0.001, 0], "frame": "global"}
    single = robot([rod("body", "45 mm")], loads=[dict(load, module="body", at="20 mm")])
    chain = robot([rod("lower", "20 mm"), rod("upper", "25 mm")], loads=[dict(load, module="lower", at="end")])
    a, b = solve(single), solve(chain)
    assert np.linalg.norm(a.tip_position - b.tip_position) < 1e-8


def test_uniform_distributed_load_matches_shear_corrected_cantilever():
    q = 1e-6   # N/m, small: linear regime
    scenario = beam_scenario(loads=[{"name": "q", "kind": "distributed", "module": "rod", "force": [q, 0, 0]}])
    sim = Simulation.from_file(scenario)
    solution = sim.solve()
    k = sim.robot.modules[0].stiffness
    length = 0.1
    expected = q * length**4 / (8 * k[0]) + q * length**2 / (2 * k[3])
    assert solution.tip_position[0] == pytest.approx(expected, rel=1e-6)


def test_body_frame_distributed_load_follows_the_rod():
    """A follower load in the body frame: tangential (body z) distributed force only stretches
    a straight rod, v3 - 1 = n / EA with n(s) = q (L - s)."""
    q = 0.5
    scenario = beam_scenario(loads=[{"name": "q", "kind": "distributed", "module": "rod", "force": [0, 0, q],
                                     "frame": "body"}])
    sim = Simulation.from_file(scenario)
    module = sim.solve().modules[0]
    ea = sim.robot.modules[0].stiffness[5]
    assert_allclose(module.v[2] - 1, q * (0.1 - module.s) / ea, rtol=0, atol=1e-12)
    assert_allclose(module.p[0:2], 0.0, rtol=0, atol=1e-15)
def test_precurved_module_at_rest_is_its_reference_arc():
    scenario = beam_scenario(precurvature=[0, "20 1/m", 0])
    solution = Simulation.from_file(scenario).solve()
    p = solution.modules[0].p
    radius = 1 / 20.0
    center = np.array([radius, 0, 0])   # u_y > 0 curls towards +x
    assert_allclose(np.linalg.norm(p - center[:, None], axis=0), radius, rtol=1e-9, atol=0)
    assert_allclose(solution.modules[0].force, 0.0, rtol=0, atol=1e-15)
def test_helical_tca_and_curve_tendon_in_a_chain_conserve_force():
    """An actuator's loads are internal: the base carries exactly the weight. Collocation meets
    this up to the quadrature of the tendon's distributed load, which converges at order 2d = 8."""
    imbalance = []
    for intervals in (12, 24):
        sim = mixed_chain(intervals, refine="off")     # the fixed meshes are the point here
        solution = sim.solve()
        assert solution.converged
        weight = 9.81 * (sum(m.weight_density * m.length for m in sim.robot.modules) + 1e-3)
        force = solution.modules[0].base_reaction["force"]
        imbalance.append(np.linalg.norm(force - np.array([0.0, 0.0, weight])))
    assert imbalance[0] < 1e-5 * weight
    assert np.log2(imbalance[0] / imbalance[1]) > 7.0
    assert solution.actuators["bend.a"].tension > 0 and solution.actuators["twist.h"].tension > 0
    twist = solution.modules[1]
    inside = (twist.s > 0.002) & (twist.s < 0.014)
    assert np.all(twist.u[2, inside] < 0)             # the right-handed helix twists it negatively
    assert_allclose(twist.u[2, twist.s < 0.002], twist.u[2, 0], rtol=1e-3, atol=0)   # no helix there yet


def test_deepcopy_of_scenario_dict_is_not_mutated():
    scenario = robot([rod("body", "45 mm")])
    before = copy.deepcopy(scenario)
    Simulation.from_file(scenario, ["body.length=40 mm"])
    assert scenario == before


def test_scenario_built_in_python_can_be_changed(scenarios):
    import yaml

    from tca_casadi import Scenario
    data = yaml.safe_load((scenarios / "analytic" / "tendon_arc.yaml").read_text())
    sim = Simulation(Scenario.model_validate(data))
    first = sim.solve()
    sim.set("rod.tendon.tension", "6 mN")
    second = sim.solve(warm_start=first)
    assert second.converged and second.tensions["rod.tendon"] == pytest.approx(0.006, rel=1e-12)
    # curvature scales with tension (u = F r / EI): 6/5 of the first
    assert second.modules[0].u[1, 0] == pytest.approx(1.2 * first.modules[0].u[1, 0], rel=1e-9)

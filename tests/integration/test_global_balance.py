"""Global equilibrium of the whole robot, from the solution alone: the base reaction balances
every external force and moment. The actuators are internal, so this holds only if their
distributed loads, anchor forces and corner forces (where an actuator runs through a point at
which the strains jump) are all applied. It is independent of both solvers' discretisations."""
import copy

import numpy as np
import pytest
from numpy.testing import assert_allclose
from random_robots import random_robot

from tca_casadi import Simulation
from tca_casadi.model import boundary

CORNER = {"name": "corner", "gravity": [0, 0, 0],
          "base": {"position": [0, 0, 0], "orientation": {"axis": [1, 0, 0], "angle": 0}},
          "materials": {"m": {"youngs_modulus": "0.1 MPa", "poisson_ratio": 0.5, "density": 1000}},
          "modules": [{"name": "rod", "length": "50 mm", "material": "m",
                       "cross_section": {"shape": "circle", "diameter": "10 mm"},
                       "actuators": [{"name": "t", "kind": "tendon", "tension": "0.5 N",
                                      "route": {"kind": "straight", "radius": "3 mm", "angle": 0}}]}],
          "loads": [{"name": "push", "kind": "point", "module": "rod", "at": "25 mm",
                     "force": [0, 0.05, 0], "frame": "global"}]}


def _by_hand(solution, point_s, force):
    """Reaction expected from a single point force at arc length point_s (no weight)."""
    module = solution.modules[0]
    at = module.p[:, np.argmin(np.abs(module.s - point_s))]
    return -np.asarray(force), -np.cross(at - module.p[:, 0], force)


@pytest.mark.parametrize("intervals", [6, 24, 48])
def test_a_tendon_running_past_a_point_load_keeps_global_equilibrium(intervals):
    """The issue's repro: without the corner force ``F (t+ - t-)`` the base reaction was
    [0.00254, -0.05999, 0.00261] N at every mesh, where equilibrium demands [0, -0.05, 0]."""
    scenario = copy.deepcopy(CORNER)
    scenario["solver"] = {"intervals": intervals}
    solution = Simulation.from_file(scenario).solve()
    assert solution.converged
    force, moment = _by_hand(solution, 0.025, [0, 0.05, 0])
    assert_allclose(solution.modules[0].base_reaction["force"], force, rtol=0, atol=1e-9)
    assert_allclose(solution.modules[0].base_reaction["moment"], moment, rtol=0, atol=1e-12)
    assert solution.balance.relative < 1e-9


def test_shooting_applies_the_corner_force_too():
    sim = Simulation.from_file(CORNER)
    shot = sim.solve(method="shooting")
    assert shot.converged
    force, moment = _by_hand(shot, 0.025, [0, 0.05, 0])
    assert_allclose(shot.modules[0].base_reaction["force"], force, rtol=0, atol=1e-9)
    assert_allclose(shot.modules[0].base_reaction["moment"], moment, rtol=0, atol=1e-12)
    collocation = sim.solve()
    assert_allclose(shot.tip_position, collocation.tip_position, rtol=0, atol=1e-9)


def test_the_balance_check_sees_a_missing_corner_force(monkeypatch):
    """The check can fail: dropping the corner part of every actuator's point wrench (keeping the
    anchors) breaks global equilibrium by about 10 mN, and the solution says so."""
    original = boundary.actuators_after

    def anchors_only(robot, m, s):
        return [a for a in original(robot, m, s) if abs(a.route.span[0] - s) < 1e-12]

    before = boundary.actuators_before
    monkeypatch.setattr(boundary, "actuators_after", anchors_only)
    monkeypatch.setattr(boundary, "actuators_before",
                        lambda robot, m, s: [a for a in before(robot, m, s) if abs(a.route.span[1] - s) < 1e-12])
    # refinement off: the estimate cannot make a wrong model balance, and would refine in vain
    solution = Simulation.from_file(dict(CORNER, solver={"refine": "off"})).solve()
    assert solution.converged
    assert np.abs(solution.balance.force).max() > 5e-3
    assert any("global balance" in w for w in solution.warning_texts())


def test_one_model_function_moves_both_solvers(monkeypatch):
    """Physics once: doubling the actuator point wrench in ``model.boundary`` changes the
    collocation and the shooting answers alike (they still agree with each other)."""
    reference = Simulation.from_file(CORNER).solve()
    original = boundary.tangent_wrench
    monkeypatch.setattr(boundary, "tangent_wrench", lambda *args: 2 * original(*args))
    sim = Simulation.from_file(dict(CORNER, solver={"refine": "off"}))
    collocation, shot = sim.solve(), sim.solve(method="shooting")
    assert collocation.converged and shot.converged
    assert np.linalg.norm(collocation.tip_position - reference.tip_position) > 1e-4
    assert_allclose(shot.tip_position, collocation.tip_position, rtol=0, atol=1e-7)


@pytest.mark.parametrize("name", ["bending_module", "twisting_module", "tendon_robot",
                                  "tendon_robot_two_segments", "arm", "analytic/tip_load",
                                  "analytic/pure_moment", "analytic/tendon_arc"])
def test_every_shipped_scenario_balances(scenarios, name):
    solution = Simulation.from_file(scenarios / f"{name}.yaml").solve()
    assert solution.converged
    assert solution.balance.relative < 1e-6, solution.balance.as_dict()
    assert not [w for w in solution.warning_texts() if "global balance" in w]
    assert solution.accuracy.met and solution.accuracy.refinements == 0     # the starting mesh suffices


@pytest.mark.parametrize("seed", range(8))
def test_random_robots_balance(seed):
    """Random robots (trees, connectors, spans, anchors inside other spans, loads in both frames,
    masses, gravity in any direction) on a mesh fine enough for them: balance to 1e-8."""
    scenario = random_robot(seed)
    scenario["solver"] = {"intervals": 32, "refine": "off"}      # the balance, not the refinement
    solution = Simulation.from_file(scenario).solve()
    assert solution.converged, solution.message
    assert solution.balance.relative < 1e-8, solution.balance.as_dict()
    assert solution.balance.force_scale > 0


@pytest.mark.parametrize("seed", [11, 14])
def test_random_robots_shooting_balances_and_agrees(seed):
    scenario = random_robot(seed)
    scenario["solver"] = {"intervals": 32}
    sim = Simulation.from_file(scenario)
    collocation, shot = sim.solve(), sim.solve(method="shooting")
    assert collocation.converged and shot.converged
    assert shot.balance.relative < 1e-8, shot.balance.as_dict()
    assert_allclose(shot.tip_position, collocation.tip_position, rtol=0, atol=1e-8)

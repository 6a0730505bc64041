"""Fuzzing with hypothesis (fixed seed, bounded examples in CI; ``TCA_FUZZ=long`` for a longer run).

1. The loader and ``--set`` parsing, on mutated shipped scenarios and random values: the only
   exception ever raised is a clean :class:`ScenarioError`, one line per problem, short.
2. Random valid robots (1-3 modules, trees, connectors, TCAs, tendons, loads, gravity): each solve
   converges and balances globally from the solution alone (a solve that does not converge fails
   the test); a solve stopped early says plainly that it did not converge.
"""
import copy
import os
from pathlib import Path

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_robots import random_robot

from tca_casadi import Simulation
from tca_casadi.errors import ScenarioError
from tca_casadi.model import Robot
from tca_casadi.scenario import load_scenario

LONG = os.environ.get("TCA_FUZZ") == "long"
SHIPPED = ["bending_module", "twisting_module", "tendon_robot", "tendon_robot_two_segments", "arm_pick_and_place",
           "tendon_robot_wall"]
ROOT = Path(__file__).resolve().parents[2]
RAW = {name: yaml.safe_load((ROOT / "scenarios" / f"{name}.yaml").read_text()) for name in SHIPPED}

LOADER = settings(max_examples=3000 if LONG else 150, derandomize=True, deadline=None,
                  suppress_health_check=[HealthCheck.too_slow])
ROBOTS = settings(max_examples=60 if LONG else 3, derandomize=True, deadline=None,
                  suppress_health_check=[HealthCheck.too_slow])

numbers = st.one_of(st.integers(-10**400, 10**400), st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from([0, -1, 1e-300, 1e300, 10**30, -0.0]))
texts = st.one_of(st.text(max_size=40), st.sampled_from(["1 1/0", "5 m)", "45 mm", "-3 degC", "1e999 m",
                                                         "nan", "inf N", "5 mm" + " " * 5000, "[", "{a: 1}"]))
leaves = st.one_of(numbers, texts, st.booleans(), st.none())
values = st.recursive(leaves, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                      st.dictionaries(st.text(max_size=8), inner, max_size=3)),
                      max_leaves=12)


def _paths(node, prefix=()):
    """Every key path of a raw scenario (dict keys and list indices)."""
    yield prefix
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _paths(value, prefix + (key,))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from _paths(value, prefix + (index,))


def _mutate(raw, path, action, value):
    raw = copy.deepcopy(raw)
    if not path:
        return value if action == "replace" else raw
    parent = raw
    for key in path[:-1]:
        parent = parent[key]
    if action == "delete" and isinstance(parent, dict):
        del parent[path[-1]]
    elif action == "add" and isinstance(parent, dict):
        parent["x" + str(value)[:8]] = value
    else:
        parent[path[-1]] = value
    return raw


def _check_clean(error):
    text = str(error)
    assert text and all(0 < len(line) < 600 for line in text.splitlines()), text[:2000]
    assert "Traceback" not in text


@LOADER
@given(name=st.sampled_from(SHIPPED), choice=st.integers(0, 10**6),
       action=st.sampled_from(["replace", "replace", "delete", "add"]), value=values)
def test_mutated_scenarios_give_only_clean_errors(name, choice, action, value):
    raw = RAW[name]
    paths = list(_paths(raw))
    mutated = _mutate(raw, paths[choice % len(paths)], action, value)
    try:
        scenario = load_scenario(mutated) if isinstance(mutated, dict) else load_scenario(yaml.safe_dump(mutated))
        robot = Robot.from_scenario(scenario)
        robot.check_clear(robot.rest_parameters(robot.values))      # where a cold solve starts (obstacles)
    except ScenarioError as error:
        _check_clean(error)


@LOADER
@given(name=st.sampled_from(SHIPPED), choice=st.integers(0, 10**6), text=st.text(max_size=60),
       path=st.one_of(st.none(), st.text(max_size=20)))
def test_random_set_values_give_only_clean_errors(name, choice, text, path):
    raw = RAW[name]
    known = [".".join(str(k) for k in p) for p in _paths(raw) if p and all(isinstance(k, str) for k in p)]
    names = [f"{m['name']}.{a['name']}.temperature" for m in raw["modules"] for a in m.get("actuators", [])]
    dotted = path if path is not None else (known + names)[choice % len(known + names)]
    try:
        robot = Robot.from_scenario(load_scenario(raw, [f"{dotted}={text}"]))
        robot.check_clear(robot.rest_parameters(robot.values))
    except ScenarioError as error:
        _check_clean(error)


@ROBOTS
@given(seed=st.integers(0, 10**6))
def test_random_robots_converge_and_balance(seed):
    # every random robot is a valid, solvable design: a solve that does not converge is a
    # failure of the solver, never a pass (the report of a failed solve is tested below)
    scenario = random_robot(seed)
    scenario["solver"] = {"intervals": 32}
    solution = Simulation.from_file(scenario).solve()
    assert solution.converged, f"random robot {seed} did not converge: {solution.message}"
    balance = solution.balance      # discretisation error only: a missing load would be ~1e-2
    assert balance.force_scale > 0
    assert balance.relative < 1e-6, balance.as_dict()
    assert not [w for w in solution.warning_texts() if "global balance" in w]


def test_a_solve_that_does_not_converge_says_so():
    # one IPOPT iteration from the reference state, without continuation, cannot solve it
    scenario = random_robot(7)
    scenario["solver"] = {"intervals": 32, "algorithm": "ipopt", "continuation": "never", "max_iterations": 1,
                          "refine": "off"}
    solution = Simulation.from_file(scenario).solve()
    assert not solution.converged
    assert solution.warnings and solution.warnings[0].kind == "not_converged", solution.warnings
    assert solution.to_dict()["converged"] is False

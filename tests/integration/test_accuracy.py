"""Accuracy under control: the error estimate against the error measured on a much finer mesh,
and refinement until the tolerances are met (or a warning says why not)."""
import functools
import json

import numpy as np
import pytest
from random_robots import random_robot

from tca_casadi import Simulation


def _reference(scenario):
    """The tip on a much finer mesh (the solver options of ``scenario`` replaced; 32 intervals
    of degree 5 agree with 64 to 1e-13 m on seed 22), computed once per robot, without an
    error estimate of its own."""
    return _reference_tip(json.dumps(dict(scenario, solver={})))


@functools.lru_cache(maxsize=4)
def _reference_tip(text):
    fine = Simulation.from_file(dict(json.loads(text), solver={"intervals": 32, "degree": 5, "refine": "off"}))
    solution = fine.continue_from_rest(fine.solver())
    assert solution.converged
    return solution.tip_position


@pytest.mark.parametrize("seed", [22])
def test_refinement_meets_the_tolerance_and_the_estimate_is_honest(seed):
    """Random 3-module robots whose starting mesh is too coarse (tip 1e-6 to 1e-5 m off)."""
    scenario = random_robot(seed)
    solution = Simulation.from_file(scenario).solve()
    reference = _reference(scenario)
    estimate = solution.accuracy
    assert solution.converged and estimate.met and estimate.refinements >= 1
    error = float(np.linalg.norm(solution.tip_position - reference))
    assert error <= estimate.tip_tolerance
    assert 0.5 <= estimate.tip_error / error <= 2.0, (estimate.tip_error, error)
    assert not [w for w in solution.warning_texts() if "accuracy" in w or "global balance" in w]


def test_without_refinement_the_estimate_says_how_far_off():
    scenario = random_robot(22)
    scenario["solver"] = {"refine": "off"}
    solution = Simulation.from_file(scenario).solve()
    error = float(np.linalg.norm(solution.tip_position - _reference(scenario)))
    assert error > 1e-6                                          # the starting mesh really is coarse
    assert 0.5 <= solution.accuracy.tip_error / error <= 2.0
    assert not solution.accuracy.met
    assert any("NOT met" in w and "refinement is off" in w for w in solution.warning_texts())


def test_reaching_the_mesh_limit_is_a_warning():
    scenario = random_robot(22)
    scenario["solver"] = {"max_intervals": 8}
    solution = Simulation.from_file(scenario).solve()
    assert solution.converged and not solution.accuracy.met and solution.accuracy.limit_reached
    assert any("mesh limit" in w and "solver.max_intervals" in w for w in solution.warning_texts())


def test_shipped_scenarios_meet_it_on_the_starting_mesh_and_report_it(scenarios, tmp_path):
    sim = Simulation.from_file(scenarios / "bending_module.yaml")
    solution = sim.solve()
    assert solution.accuracy.met and solution.accuracy.refinements == 0
    assert solution.accuracy.intervals == [6]
    solution.save(tmp_path)
    saved = json.loads((tmp_path / "solution.json").read_text())["accuracy"]
    assert saved["met"] and saved["tip_error_estimate"] < 1e-10 and saved["intervals"] == [6]


def test_the_refined_solver_serves_later_warm_solves():
    scenario = random_robot(4)
    scenario["solver"] = {"tip_tolerance": 1e-9}          # tighter than its starting mesh meets
    sim = Simulation.from_file(scenario)
    first = sim.solve()
    assert first.accuracy.refinements >= 1
    solver = sim.solver()
    assert [len(m.intervals) for m in solver.nlp.meshes] == first.accuracy.intervals
    warm = sim.solve(warm_start=first)
    assert warm.converged and warm.iterate.w.size == first.iterate.w.size


def test_refinement_keeps_only_the_meshes_it_may_need_again():
    """What refinement leaves behind is not kept: the error estimate's degree d + 1 solvers of
    every mesh but the last, and every intermediate mesh's solver (the starting mesh's stays:
    a later cold solve of the same robot starts there). The random 4-module robot of issue 36
    peaked at 640 MB with them and 471 MB without (``bench.py --targets``)."""
    from tca_casadi.solvers import collocation
    collocation.clear_built_solvers()
    scenario = random_robot(22)                          # refined in two rounds (docs/numerics.md)
    sim = Simulation.from_file(scenario)
    solution = sim.solve()
    assert solution.converged and solution.accuracy.refinements >= 2
    kept = {(len(key[2][0].intervals) if key[2] else None, key[3]) for key in collocation._built}
    final = len(sim.solver().nlp.meshes[0].intervals)
    degree = sim.solver().degree
    assert kept == {(None, degree), (final, degree), (final, degree + 1)}, kept
    again = Simulation.from_file(scenario).solve()       # the same answer from a fresh start
    np.testing.assert_allclose(again.tip_position, solution.tip_position, rtol=0, atol=1e-12)

"""Contact in the shooting solver (issue 33): the contact block's unknowns and conditions are
the collocation NLP's (written once, :mod:`tca_casadi.model.contact_unknowns`), so the shooting
solver's forces and poses come from its own integration of the same physics: ``check`` agrees on
random robots pushed against spheres, planes and boxes, on grasped free bodies and on every
step of the physical pick-and-place (tip 1e-6 m, tensions and contact forces 1e-5 relative)."""
import warnings

import numpy as np
import pytest

from .test_contact import pushed, random_obstacle_scenarios
from tca_casadi.model.contact import outline_of
from tca_casadi.model.obstacles import gap
from tca_casadi.simulation import Simulation
from tca_casadi.studies.compare import check


def _checked(scenario):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return check(Simulation.from_file(scenario))


@pytest.mark.parametrize("scenario", list(random_obstacle_scenarios(4, seed=11)), ids=lambda s: s["obstacles"][0]["shape"])
def test_shooting_agrees_with_collocation_against_random_obstacles(scenario):
    """Independent solves (shooting from the reference state by its own continuation): the same
    closed contacts, forces to 1e-5; the shooting solution itself satisfies complementarity at
    its candidates and balances globally."""
    report, collocation, shooting = _checked(scenario)
    assert report.agree, report.summary()
    assert report.shooting_start == "reference"
    assert report.contact_differences and report.worst_relative_contact <= 1e-5
    assert collocation.contacts and len(shooting.contacts) == len(collocation.contacts)
    for contact in shooting.contacts:
        assert contact.normal_force > 0 and contact.gap >= -1e-9
    (module,), outline = shooting.modules, outline_of(Simulation.from_file(scenario).robot.modules[0])
    gaps = [gap(obstacle, outline, module.p[:, j], module.R[:, :, j])[0]
            for obstacle in shooting.obstacles for j in range(module.p.shape[1])]
    assert min(gaps) >= -1e-8                      # nowhere inside the obstacle at its samples
    assert shooting.balance.relative < 1e-8


def test_a_contact_that_stays_open_costs_nothing_and_agrees():
    """A ball out of reach: every candidate open (forces ~0), the solutions those of no obstacle."""
    scenario = pushed(force="0.5 mN")
    scenario["obstacles"][0]["position"] = ["40 mm", 0, "63 mm"]
    report, collocation, shooting = _checked(scenario)
    assert report.agree and not collocation.contacts and not shooting.contacts
    free = dict(scenario)
    free.pop("obstacles")
    _, plain, _ = _checked(free)
    np.testing.assert_allclose(shooting.tip_position, plain.tip_position, rtol=0, atol=1e-9)


def test_a_grasped_free_body_agrees_in_both_solvers():
    """The free pinch (two fingers squeezing a cube on a table, Coulomb friction): grip forces,
    support corners and the cube's pose from shooting equal collocation's."""
    import yaml
    with open("scenarios/analytic/free_pinch.yaml") as handle:
        raw = yaml.safe_load(handle)
    sim = Simulation.from_file(raw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rest = sim.solve()
        sim.set_parameter("squeeze_left.force", [2e-3, 0, 0])
        sim.set_parameter("squeeze_right.force", [-2e-3, 0, 0])
        squeezed = sim.solve(warm_start=rest)
        shooting = sim.solver("shooting")
        shooting.sample_s = [m.s for m in squeezed.modules]
        shot = shooting.solve(sim.params, squeezed)
    from tca_casadi.studies.compare import compare_solutions
    report = compare_solutions(squeezed, shot)
    assert squeezed.contacts and report.agree, report.summary()
    assert report.worst_relative_contact <= 1e-5 and max(report.body_differences.values()) <= 1e-9

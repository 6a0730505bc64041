"""Free rigid bodies held by contact and friction (issue 17; docs/contact.md sections 4-5)."""
import warnings
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.errors import ScenarioError
from tca_casadi.model.bodies import SUPPORT_COMPLIANCE
from tca_casadi.simulation import Simulation

PINCH = "scenarios/analytic/free_pinch.yaml"
SQUEEZE = 2e-3          # [N] inward on each fingertip
LIFT = 2e-3             # [m] the base rises by this much


def _quiet(call, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return call(*args, **kwargs)


@pytest.fixture(scope="module")
def lifted():
    """``(sim, solutions)``: rest, squeezed (grips close, frictionless, the table holds the
    block), lifted (grips anchored where they closed: the block hangs on friction)."""
    sim = Simulation.from_file(PINCH)
    rest = _quiet(sim.solve)
    sim.set_parameter("squeeze_left.force", [SQUEEZE, 0, 0])
    sim.set_parameter("squeeze_right.force", [-SQUEEZE, 0, 0])
    squeezed = _quiet(sim.solve, warm_start=rest)
    sim.set_parameter("base.position", [0, 0, LIFT])
    up = _quiet(sim.solve, warm_start=squeezed)
    return sim, (rest, squeezed, up)


def test_resting_then_squeezed_block_is_held_by_its_table(lifted):
    _, (rest, squeezed, _) = lifted
    weight = 1e-4 * 9.81
    for solution in (rest, squeezed):
        assert solution.converged
        block = solution.bodies[0]
        lifted_by_grips = -sum(c.tangential_force[2] for c in block.grips)      # on the block
        assert_allclose(block.support_force, [0, 0, weight - lifted_by_grips], rtol=0, atol=1e-12)
        # four corners on the table, each carrying a quarter of what it carries and sinking by
        # the support's compliance under it (kappa L_o per weight: 2.25e-9 m at rest)
        pressed = block.corners.pressed
        assert pressed.sum() == 4 and np.all(block.corners.positions[pressed, 2] < block.position[2])
        # (to the solve's tolerance, a scaled residual of 1e-10: 2e-13 N measured, 9e-15 N at 1e-12)
        assert_allclose(block.corners.normal_forces[pressed], block.support_force[2] / 4, rtol=0, atol=1e-12)
        sink = SUPPORT_COMPLIANCE * 0.009 * block.support_force[2] / (4 * weight)
        assert_allclose(block.position, [0, 0, -0.038 - sink], rtol=0, atol=1e-12)
        assert_allclose(block.residual_force, 0, rtol=0, atol=1e-13)
    assert rest.bodies[0].support_force[2] == pytest.approx(weight, abs=1e-15)
    grips = squeezed.bodies[0].grips
    assert len(grips) == 2 and all(c.s == pytest.approx(0.03, rel=0, abs=1e-12) for c in grips)
    # a cantilever's tip pushed by P across a gap d: N = P - 3 E I d / L^3 (d = 0.5 mm), the
    # small-deflection, shear-free, frictionless estimate (measured 2e-3 of N off)
    EI = 10e6 * np.pi * 0.002 ** 4 / 64
    expected = SQUEEZE - 3 * EI * 0.5e-3 / 0.03 ** 3
    left, right = grips
    for c in grips:
        assert c.normal_force == pytest.approx(expected, rel=5e-3)
    # the grips close on the way and stick from there: squeezed further, the fingertips turn
    # and their friction carries a little of the block (3.7 %), equally on both sides
    assert left.tangential_force[2] == pytest.approx(right.tangential_force[2], rel=1e-6)
    assert 0 < -left.tangential_force[2] < 0.1 * weight and not squeezed.bodies[0].slipping


def test_lifted_block_hangs_on_friction_half_its_weight_per_finger(lifted):
    _, (_, squeezed, up) = lifted
    assert up.converged and not up.warning_texts("slipping")
    block = up.bodies[0]
    weight = 1e-4 * 9.81
    assert not block.resting and np.linalg.norm(block.support_force) < 1e-12
    assert block.position[2] - squeezed.bodies[0].position[2] == pytest.approx(LIFT, abs=5e-6)
    for c in block.grips:            # on the rod: half the weight, downwards (symmetry)
        assert_allclose(c.tangential_force, [0, 0, -weight / 2], rtol=0, atol=1e-12)
    left, right = block.grips
    assert left.normal_force == pytest.approx(right.normal_force, rel=1e-9)
    assert_allclose(block.residual_force, 0, rtol=0, atol=1e-12)
    assert_allclose(block.residual_moment, 0, rtol=0, atol=1e-14)
    assert_allclose(block.contact_force, [0, 0, weight], rtol=0, atol=1e-12)   # all through the grips
    assert up.balance.relative < 1e-8          # the robot: base reaction + grips + own weight
    assert block.friction_margin == pytest.approx(0.5 * left.normal_force - weight / 2, rel=1e-9)


def test_friction_limit_is_the_hand_calculation(lifted):
    """Heavier and heavier blocks: slipping is reported exactly when m g > 2 mu N (N the
    reported normal force of each fingertip), with the friction it would need."""
    sim, (_, _, up) = lifted
    previous, seen = up, set()
    for mass in (1.0e-4, 2.0e-4, 2.8e-4, 3.0e-4, 3.4e-4):
        sim.set_parameter("block.mass", mass)
        solution = _quiet(sim.solve, warm_start=previous)
        assert solution.converged
        block = solution.bodies[0]
        normal = block.grips[0].normal_force
        needed = mass * 9.81 / (2 * normal)
        assert block.needed_friction == pytest.approx(needed, rel=1e-9)
        assert block.slipping == (mass * 9.81 > 2 * 0.5 * normal)
        assert bool(solution.warning_texts("slipping")) == block.slipping
        seen.add(block.slipping)
        previous = solution
    assert seen == {True, False}
    sim.set_parameter("block.mass", 1e-4)


def test_block_in_results_and_tables(lifted):
    _, (_, _, up) = lifted
    data = up.to_dict()
    entry = data["objects"][0]
    assert entry["name"] == "block" and entry["slipping"] is False and entry["resting"] is False
    assert_allclose(entry["quaternion"], [1, 0, 0, 0], rtol=0, atol=1e-9)
    assert {c["obstacle"] for c in data["contacts"]} == {"block"}
    line = next(line for line in up.summary().splitlines() if line.startswith("  object block"))
    assert f"needs friction {up.bodies[0].needed_friction:.3g} of 0.5" in line and "support" not in line
    columns = up.contact_columns()
    assert columns["block.grip_force [N]"] == pytest.approx(up.bodies[0].grip_force, rel=1e-9)
    assert columns["block.support_force [N]"] < 1e-12


def test_cold_solve_starts_from_no_history(lifted):
    """A cold solve forgets the grasp (it starts from the scenario's history) and follows the
    loads up from the reference state, grips sticking from where they close on the way: an
    equilibrium of the block and of the robot, after which the history is its own (each closed
    grip anchored where it touches)."""
    from tca_casadi.model.bodies import anchor_of
    sim, _ = lifted
    cold = _quiet(sim.solve)
    assert cold.converged
    block = cold.bodies[0]
    assert np.abs(block.residual_force).max() < 1e-12 and cold.balance.relative < 1e-8
    for grip in block.grips:
        name = f"objects.block.grip.{grip.module}.3"
        assert sim.get_parameter(f"{name}.sticks") == 1.0
        assert_allclose(sim.get_parameter(f"{name}.anchor"), anchor_of(block.position, block.rotation, grip.position),
                        rtol=0, atol=1e-9)


@pytest.mark.parametrize("change, message", [
    ({"mass": 0}, "needs a mass > 0"),
    ({"support": None}, "needs a support"),
    ({"held": True}, "held is for objects without contact"),
    ({"support": "tabel"}, "unknown obstacle 'tabel'"),
    ({"position": [0, 0, -0.037]}, "lies 1 mm above its support 'table'"),
])
def test_bad_contact_objects(change, message):
    import yaml
    with open(PINCH) as handle:
        raw = yaml.safe_load(handle)
    raw["objects"][0].update(change)
    with pytest.raises(ScenarioError, match=message):
        Simulation.from_file(raw).solve()


@pytest.fixture(scope="module")
def pick_and_place(tmp_path_factory):
    """``(sim, SequenceResult)`` of scenarios/arm_pick_and_place_contact.yaml's sequence, run by
    the command docs/robots.md shows, whose transcript this checks (the documentation tests
    leave it to this fixture: one 20 s run, not two)."""
    from transcripts import fresh_copy, run_transcript_here
    root = Path(__file__).resolve().parents[2]
    command = ("tca-casadi sequence scenarios/arm_pick_and_place_contact.yaml -o results/pick_and_place_contact "
               "--no-animation")
    args, result = run_transcript_here(root, fresh_copy(tmp_path_factory.mktemp("robots_md"), root),
                                       "docs/robots.md", command, "tca_casadi.studies.sequence.steps.run_sequence")
    return args[0], result


def test_physical_pick_and_place(pick_and_place):
    """scenarios/arm_pick_and_place_contact.yaml: both fingertips press on the bar, its weight
    reaches the arm only through them (friction), it rises with the arm and turns with it; the
    bent arm puts it down (it lands and lies flat on the table, four corners pressed), the
    gripper opens and lets go of it, and it stays where it was put when the arm rises."""
    _, result = pick_and_place
    assert result.converged
    step = dict(zip(result.names, result.solutions))
    closing, lifting, turning, bent, down, released, clear = (step[n] for n in (
        "gripper closes on the bar", "arm lifts the bar", "twisting module cools back", "bending module bends to +x",
        "arm puts the bar down", "gripper opens: released", "arm rises clear"))
    weight = 0.5e-3 * 9.81
    for solution in (lifting, turning, bent):
        bar = solution.bodies[0]
        assert {c.module for c in bar.grips} == {"finger_a", "finger_b"}
        assert all(c.normal_force > 1e-3 for c in bar.grips)
        assert not bar.resting and not bar.slipping and bar.needed_friction < bar.grips[0].friction
        assert_allclose(bar.contact_force, [0, 0, weight], rtol=0, atol=1e-9)
        assert np.abs(bar.residual_force).max() < 1e-12
        assert solution.balance.relative < 1e-6
    assert closing.bodies[0].resting
    assert lifting.bodies[0].position[2] - closing.bodies[0].position[2] > 8e-3
    x_axis = turning.bodies[0].rotation[:, 0]
    assert abs(x_axis[1]) > 0.99         # turned 90 deg about z with the gripper
    assert bent.bodies[0].position[0] > 5e-3 and bent.bodies[0].rotation[2, 2] < np.cos(np.radians(3))   # carried, tilted
    for solution in (down, released, clear):
        bar = solution.bodies[0]
        assert bar.resting and bar.corners.pressed.sum() == 4
        assert bar.rotation[2, 2] > 1 - 1e-9                  # flat on the table
        assert bar.position[0] > 5e-3                          # put down further along +x
        assert np.abs(bar.residual_force).max() < 1e-12 and solution.balance.relative < 1e-6
    assert all(c.normal_force > 1e-3 for c in down.bodies[0].grips)        # still pressed as it lands
    for solution in (released, clear):                       # let go: the table carries all of it
        bar = solution.bodies[0]
        assert not bar.grips
        assert_allclose(bar.support_force, [0, 0, weight], rtol=0, atol=1e-12)
    assert_allclose(clear.bodies[0].position, released.bodies[0].position, rtol=0, atol=1e-12)


def test_the_arms_grasp_stays_at_rest_in_motion(pick_and_place):
    """Rod dynamics (BDF2, 2 ms) started at rest where the sequence lifted the bar, nothing
    changing: the bar stays, its speed at roundoff over 0.2 s. When friction held the fingertips'
    nearest outline points (which run along the bar's face as a fingertip tilts), this grasp
    was unstable at about 130/s: by 0.2 s the bar was falling (docs/contact.md section 5b)."""
    from tca_casadi.solvers.dynamics import RodDynamics
    sim, result = pick_and_place
    lifting = dict(zip(result.names, result.solutions))["arm lifts the bar"]
    dynamics = RodDynamics(sim.robot, sim.solver("collocation"), "bdf2")
    state, params = dynamics.start(lifting), np.array(lifting.parameters, float)
    speeds = []
    for _ in range(100):
        state = dynamics.advance(params, 0.002)
        assert state is not None, dynamics.last_status.message
        speeds.append(np.linalg.norm(state.bodies[6:9, 0]))
    assert max(speeds) < 1e-9


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_pinches_obey_the_balance_laws(seed):
    """Random pinches (moduli, finger sizes, gaps, unequal squeezes, masses): while supported
    and once lifted, every grip has g >= -1e-9 m, f >= 0, |f g| tiny; the block's equilibrium
    and the robot's global balance hold; lifted, the grips' forces on the rods add up to the
    block's weight."""
    import yaml
    rng = np.random.default_rng(seed)
    with open(PINCH) as handle:
        raw = yaml.safe_load(handle)
    raw["materials"]["rubber"]["youngs_modulus"] = float(rng.uniform(5e6, 20e6))
    diameter = float(rng.uniform(1.5e-3, 2.5e-3))
    gap = float(rng.uniform(0.2e-3, 0.6e-3))
    half = 6e-3 - diameter / 2 - gap
    for module in raw["modules"][1:]:
        module["cross_section"]["diameter"] = diameter
    mass = float(rng.uniform(0.05e-3, 0.2e-3))
    block = raw["objects"][0]
    block.update(mass=mass, size=[2 * half, 0.009, 0.009], friction=float(rng.uniform(0.5, 1.5)))
    sim = Simulation.from_file(raw)
    previous = _quiet(sim.solve)
    squeeze = rng.uniform(1.5e-3, 3e-3, 2)
    sim.set_parameter("squeeze_left.force", [squeeze[0], 0, 0])
    sim.set_parameter("squeeze_right.force", [-squeeze[1], 0, 0])
    for lift in (0.0, 1e-3):
        sim.set_parameter("base.position", [0, 0, lift])
        solution = _quiet(sim.solve, warm_start=previous)
        assert solution.converged, solution.message
        body = solution.bodies[0]
        for c in body.grips:
            assert c.gap >= -1e-9 and c.normal_force >= 0 and abs(c.gap * c.normal_force) < 1e-12
        assert np.abs(body.residual_force).max() < 1e-12 and np.abs(body.residual_moment).max() < 1e-13
        assert solution.balance.relative < 1e-8
        previous = solution
    assert not body.resting and len(body.grips) == 2
    # unequal squeezes shift and tilt the block a little (its faces' normals are not quite +-x,
    # so the normal forces differ by ~0.3 %), but the grips' total force on the rods is the
    # block's weight, nothing sideways
    total = sum(c.force for c in body.grips)
    assert_allclose(total, [0, 0, -mass * 9.81], rtol=0, atol=1e-12)


def test_the_physical_pick_and_place_grasp_agrees_with_shooting(pick_and_place):
    """The contact pick-and-place (friction, a free bar on a table) followed by collocation to
    the grasp; shooting at that step's parameters (the path's contact history) from its solution
    converges to the same equilibrium, the two grip forces included. (`sequence --check` does
    this at every step: the whole sequence, lift and put-down included, agrees to 3.7e-8 m,
    docs/contact.md.)"""
    from tca_casadi.studies.compare import compare_solutions
    sim, result = pick_and_place
    assert result.names[4] == "gripper closes on the bar"
    gripped = result.solutions[4]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        shooting = sim.solver("shooting")
        shooting.sample_s = [m.s for m in gripped.modules]
        report = compare_solutions(gripped, shooting.solve(gripped.parameters, gripped))
    assert report.agree, report.summary()
    assert len(report.contact_differences) == 2 and report.worst_relative_contact <= 1e-5
    assert all(c.normal_force > 1e-3 for c in gripped.contacts if c.obstacle == "bar")

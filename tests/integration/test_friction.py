"""Coulomb friction at the grips and a body's corners on its support (issue 17;
docs/contact.md sections 4-5): hand calculations for a pinch that slides, the corner forces of a
box under tilted gravity, a box that tips and a grasp that lets go."""
import warnings

import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

from tca_casadi.model.bodies import SUPPORT_COMPLIANCE
from tca_casadi.simulation import Simulation

PINCH = "scenarios/analytic/free_pinch.yaml"
SQUEEZE = 2e-3          # [N] inward on each fingertip
G = 9.81


def _quiet(call, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return call(*args, **kwargs)


def _pinch(law="coulomb", **block):
    """The free pinch (two fingers about a 9 mm cube on a table) with the friction law ``law``
    and the block's entries ``block`` changed."""
    with open(PINCH) as handle:
        raw = yaml.safe_load(handle)
    raw["contact"]["friction_law"] = law
    raw["objects"][0].update(block)
    return Simulation.from_file(raw)


def _squeezed(sim):
    """Rest, then both fingertips squeezed onto the block (warm, along the path)."""
    rest = _quiet(sim.solve)
    sim.set_parameter("squeeze_left.force", [SQUEEZE, 0, 0])
    sim.set_parameter("squeeze_right.force", [-SQUEEZE, 0, 0])
    return _quiet(sim.solve, warm_start=rest)


@pytest.fixture(scope="module")
def light():
    """A 0.1 g block squeezed and lifted 2 mm under each law: ``{law: (sim, squeezed, lifted)}``."""
    out = {}
    for law in ("stick", "coulomb"):
        sim = _pinch(law)
        squeezed = _squeezed(sim)
        sim.set_parameter("base.position", [0, 0, 2e-3])
        out[law] = (sim, squeezed, _quiet(sim.solve, warm_start=squeezed))
    return out


def test_inside_the_cone_coulomb_is_sticking(light):
    """A grasp that holds: Coulomb's law leaves every grip inside its cone (no slip) and gives
    the sticking law's equilibrium."""
    _, _, stick = light["stick"]
    _, _, coulomb = light["coulomb"]
    assert stick.converged and coulomb.converged
    block = coulomb.bodies[0]
    assert not block.resting and not block.slipping and not any(c.sliding for c in block.grips)
    for a, b in zip(stick.bodies[0].grips, block.grips):
        assert_allclose(b.tangential_force, a.tangential_force, rtol=0, atol=1e-12)
        assert b.normal_force == pytest.approx(a.normal_force, rel=1e-9)
    assert_allclose(block.position, stick.bodies[0].position, rtol=0, atol=1e-12)
    weight = 1e-4 * G
    for c in block.grips:
        assert_allclose(c.tangential_force, [0, 0, -weight / 2], rtol=0, atol=1e-12)


def test_too_heavy_block_stays_on_the_table_while_the_fingers_slide_up():
    """A 0.4 g block (m g = 3.9 mN) squeezed by two grips of N = 1.55 mN at mu = 0.5: lifting
    the fingers by 1 mm, each grip slides up the block on its cone, |f_t| = mu N, and the table
    carries the rest: m g - mu (N_1 + N_2) (the hand calculation, to 1e-12 N). Reported slipping."""
    mass, mu = 4e-4, 0.5
    sim = _pinch(mass=mass)
    squeezed = _squeezed(sim)
    assert squeezed.converged and squeezed.bodies[0].resting
    sim.set_parameter("base.position", [0, 0, 1e-3])
    up = _quiet(sim.solve, warm_start=squeezed)
    assert up.converged, up.message
    block = up.bodies[0]
    assert len(block.grips) == 2 and block.resting
    for c in block.grips:
        assert c.sliding and c.slipping
        assert np.linalg.norm(c.tangential_force) == pytest.approx(mu * c.normal_force, abs=1e-11)
        assert c.tangential_force[2] < 0                   # on the rod: down, against its slide up
        assert c.slid > 0.5e-3                             # over the block, since the squeezed state
    total_normal = sum(c.normal_force for c in block.grips)
    assert_allclose(block.support_force, [0, 0, mass * G - mu * total_normal], rtol=0, atol=1e-12)
    assert block.position[2] == pytest.approx(squeezed.bodies[0].position[2], abs=1e-8)   # it stayed
    assert np.abs(block.residual_force).max() < 1e-12 and up.balance.relative < 1e-8
    assert len(up.warning_texts("slipping")) >= 2
    assert "on its friction limit (0.5)" in up.warning_texts("slipping")[0]


def test_a_grasp_that_lets_go_is_a_drop_not_an_equilibrium(light):
    """The lifted 0.1 g block made 0.4 g: past 2 mu N = m g the grips slide and nothing holds
    it up; the solve refuses to jump to the block lying on its table (where it would land is
    no static result): not converged, saying so."""
    sim, _, lifted = light["coulomb"]
    sim.set_parameter("block.mass", 4e-4)
    try:
        dropped = _quiet(sim.solve, warm_start=lifted)
    finally:
        sim.set_parameter("block.mass", 1e-4)
    assert not dropped.converged
    assert "continuation from the previous solution" in dropped.message
    assert "cannot hold it (it would drop)" in dropped.message, dropped.message
    # it stops where the hand calculation says the grasp gives: m g = mu (N_1 + N_2)
    reached = float(dropped.message.split("reached block.mass ")[1].split()[0])
    grips = dropped.bodies[0].grips
    assert all(c.friction_margin < 1e-3 * 0.5 * c.normal_force for c in grips)
    assert reached * G == pytest.approx(0.5 * sum(c.normal_force for c in grips), rel=1e-3)


def _tilted(sim, ratio):
    """Solve with gravity tilted along +y by ``ratio`` of its vertical part, from rest."""
    rest = _quiet(sim.solve)
    sim.set_parameter("gravity", [0, ratio * G, -G])
    return _quiet(sim.solve, warm_start=rest)


def test_corner_forces_under_tilted_gravity_are_the_rigid_box_statics():
    """A box of base a (along y) whose centre is h above the table, under gravity with a
    sideways part r g: each corner's normal force is m g (1/4 -+ r h / (2 a)), each carries
    m r g / 4 sideways (equal compliances: a rigid translation loads them equally), to
    O(kappa) = 1e-6 of the weight."""
    ratio, mass = 0.3, 1e-4
    sim = _pinch(law="stick", friction=1.0)
    tilted = _tilted(sim, ratio)
    assert tilted.converged
    block = tilted.bodies[0]
    corners = block.corners
    pressed = corners.pressed
    assert pressed.sum() == 4 and not block.grips
    h, a = 4.5e-3, 9e-3
    low_side = corners.positions[:, 1] > block.position[1]         # the side gravity pulls towards
    expected = mass * G * (0.25 + np.where(low_side, 1, -1) * ratio * h / (2 * a))
    assert_allclose(corners.normal_forces[pressed], expected[pressed], rtol=0, atol=1e-6 * mass * G)
    assert_allclose(corners.tangential_forces[pressed], np.tile([0, -mass * G * ratio / 4, 0], (4, 1)),
                    rtol=0, atol=1e-6 * mass * G)
    assert_allclose(block.support_force, [0, -ratio * mass * G, mass * G], rtol=0, atol=1e-15)
    # the centre of pressure moves towards the low side by h r (the weight's line of action)
    assert block.support_point[1] - block.position[1] == pytest.approx(h * ratio, rel=1e-5)
    assert block.support_needed_friction == pytest.approx(ratio, rel=1e-9) and not block.support_slipping
    # the compliance: the box sinks and tilts by kappa L_o per weight on a corner
    assert abs(block.rotation[2, 1]) < 10 * SUPPORT_COMPLIANCE


def test_tall_box_tips_past_a_over_2h():
    """A 9 x 9 x 18 mm box (a / (2 h) = 0.5): at r = 0.4 its light corners carry m g (1/4 -
    r h / (2 a)) = m g / 20; past 0.5 no static equilibrium is left (it tips over), and the
    solve says it did not converge instead of returning one."""
    mass = 1e-4
    sim = _pinch(law="stick", friction=1.0, size=[0.009, 0.009, 0.018], position=[0, 0, -0.0335])
    standing = _tilted(sim, 0.4)
    assert standing.converged
    corners = standing.bodies[0].corners
    light_side = corners.positions[:, 1] < standing.bodies[0].position[1]
    pressed = corners.pressed
    assert pressed.sum() == 4
    assert_allclose(corners.normal_forces[pressed & light_side], mass * G / 20, rtol=0, atol=1e-6 * mass * G)
    sim.set_parameter("gravity", [0, 0.6 * G, -G])
    tipped = _quiet(sim.solve, warm_start=standing)
    assert not tipped.converged
    # it stops where the light corners let go: r = a / (2 h) (continuation's last step 1e-4)
    reached = float(tipped.message.split("reached gravity [0, ")[1].split(",")[0]) / G
    assert reached == pytest.approx(0.5, abs=1e-4)


def _frictional_prop(law, mu=0.5):
    """scenarios/analytic/propped_cantilever.yaml with friction ``mu`` on its knife edge (the
    ``law``) and a sideways tip load ``side``, solved under its weight alone (cold)."""
    with open("scenarios/analytic/propped_cantilever.yaml") as handle:
        raw = yaml.safe_load(handle)
    raw["obstacles"][0]["friction"] = mu
    raw["loads"] = [{"name": "side", "kind": "point", "module": "rod", "at": "end", "force": [0, 0, 0]}]
    raw["contact"] = {"friction_law": law}
    sim = Simulation.from_file(raw)
    return sim, _quiet(sim.solve)


def test_a_sticking_prop_carries_a_side_load_at_the_tip():
    """The propped cantilever's tip sticks on its knife edge: friction holds the rod's material
    point there, 1 mm under its axis. A sideways load P at the tip twists the rod about that
    point, so the tip rolls sideways by ``r theta`` without slipping and the clamp takes the
    bending that needs: the prop carries ``f_t = -P / (1 + 3 E I r^2 / (G J L^2))`` (rolling
    without slip, 3.9e-4 less than P; 1e-5 asked), and the tip moves ``(P - |f_t|) L^3 / 3EI``
    (1e-3). The friction it needs (the prop also holds the tip against the rod's shortening as
    it sags: an axial pull) is reported."""
    sim, sagged = _frictional_prop("stick")
    assert sagged.converged and sagged.contacts[0].obstacle == "prop"
    sim.set_parameter("side.force", [0, 3e-3, 0])
    loaded = _quiet(sim.solve, warm_start=sagged)
    assert loaded.converged, loaded.message
    (contact,) = loaded.contacts
    E, nu, r, L = 20e9, 0.3, 1e-3, 0.1
    EI, GJ = E * np.pi * (2 * r) ** 4 / 64, E / (2 * (1 + nu)) * np.pi * (2 * r) ** 4 / 32
    carried = 3e-3 / (1 + 3 * EI * r * r / (GJ * L * L))
    assert contact.tangential_force[1] == pytest.approx(-carried, rel=1e-5)
    assert_allclose(loaded.modules[0].base_reaction["moment"][0], carried * r, rtol=1e-4)
    assert_allclose(loaded.tip_position[1] - sagged.tip_position[1], (3e-3 - carried) * L ** 3 / (3 * EI), rtol=1e-3)
    assert abs(contact.held_at[1] - sagged.contacts[0].position[1]) < 1e-15        # the material point stays
    assert contact.slipping and contact.needed_friction > 0.5
    assert "needs friction" in loaded.warning_texts("slipping")[0]
    assert loaded.balance.relative < 1e-9


def test_a_coulomb_prop_lets_the_tip_slide_with_mu_n():
    """On Coulomb's cone (mu = 0.5) a sideways tip load P above mu N slides the tip along the
    knife edge: the prop holds back mu N, so the tip deflects as a cantilever under P - mu N,
    (P - mu N) L^3 / (3 E I) (small deflection; measured 1.8e-4 off)."""
    sim, sagged = _frictional_prop("coulomb")
    assert sagged.converged
    sim.set_parameter("side.force", [0, 6e-3, 0])
    loaded = _quiet(sim.solve, warm_start=sagged)
    assert loaded.converged, loaded.message
    (contact,) = loaded.contacts
    assert contact.sliding and contact.slipping
    assert np.linalg.norm(contact.tangential_force) == pytest.approx(0.5 * contact.normal_force, rel=1e-9)
    assert contact.tangential_force[1] < 0 and abs(contact.tangential_force[0]) < 1e-3 * abs(contact.tangential_force[1])
    EI = 20e9 * np.pi * 0.002 ** 4 / 64
    expected = (6e-3 - 0.5 * contact.normal_force) * 0.1 ** 3 / (3 * EI)
    assert loaded.tip_position[1] - sagged.tip_position[1] == pytest.approx(expected, rel=1e-3)
    assert loaded.balance.relative < 1e-9


@pytest.mark.parametrize("seed", [11, 12, 13, 14])
def test_random_frictional_contacts_obey_the_cone_and_the_balance(seed):
    """Rods pushed against random spheres, walls and boxes with random friction (either law),
    then loaded along the contact's tangent: every contact's friction is tangential, inside
    its cone (Coulomb; on it exactly where it slides), the verdict matches the margin
    (sticking), the complementarity holds and the robot balances."""
    import sys
    sys.path.insert(0, "tests/integration")
    from test_contact import random_obstacle_scenarios
    rng = np.random.default_rng(seed)
    scenario = next(random_obstacle_scenarios(1, seed=seed))
    mu, law = float(rng.uniform(0.2, 1.0)), ("stick", "coulomb")[seed % 2 == 0]    # 12 slides
    scenario["obstacles"][0]["friction"] = mu
    scenario["contact"] = {"friction_law": law}
    scenario["loads"].append({"name": "drag", "kind": "point", "module": "rod", "at": "end", "force": [0, 0, 0]})
    sim = Simulation.from_file(scenario)
    pushed = _quiet(sim.solve)
    assert pushed.converged, pushed.message
    sim.set_parameter("drag.force", [0, 0, float(rng.uniform(-3e-3, 3e-3))])
    dragged = _quiet(sim.solve, warm_start=pushed)
    assert dragged.converged, dragged.message
    assert dragged.balance.relative < 1e-8
    assert dragged.contacts
    for c in dragged.contacts:
        assert c.gap >= -1e-9 and c.normal_force > 0 and abs(c.gap * c.normal_force) < 1e-9
        assert abs(np.dot(c.tangential_force, c.normal)) < 1e-12
        cone = mu * c.normal_force
        if law == "coulomb":
            assert np.linalg.norm(c.tangential_force) <= cone * (1 + 1e-6) + 1e-12
            if c.sliding:
                assert np.linalg.norm(c.tangential_force) == pytest.approx(cone, rel=1e-6)
        else:
            assert c.slipping == (np.linalg.norm(c.tangential_force) > cone)


def test_a_sequence_whose_grasp_gives_says_so_and_keeps_its_files(tmp_path, capsys):
    """tca-casadi sequence on the pinch made too heavy while lifted (Coulomb): the step is not
    converged, the summary says why (the grasp cannot hold it), the files are written and the
    exit code is 1."""
    from tca_casadi.cli import main
    with open(PINCH) as handle:
        raw = yaml.safe_load(handle)
    raw["contact"]["friction_law"] = "coulomb"
    raw["sequence"] = [{"name": "squeeze", "set": {"squeeze_left.force": ["2 mN", 0, 0],
                                                   "squeeze_right.force": ["-2 mN", 0, 0]}},
                       {"name": "lift", "set": {"base.position": [0, 0, "2 mm"]}},
                       {"name": "heavier", "set": {"block.mass": "0.4 g"}}]
    path = tmp_path / "pinch.yaml"
    path.write_text(yaml.safe_dump(raw))
    code = _quiet(main, ["sequence", str(path), "-o", str(tmp_path / "out"), "--no-animation"])
    out = capsys.readouterr().out
    assert code == 1
    assert "NOT ALL CONVERGED" in out and "cannot hold it (it would drop)" in out
    assert "warning: step 'heavier': not converged" in out
    assert (tmp_path / "out" / "sequence.csv").exists() and (tmp_path / "out" / "step_02_heavier.png").exists()

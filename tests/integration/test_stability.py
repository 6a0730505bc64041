"""Growth rates of an equilibrium's small motions (``solvers.stability``) against Euler's
buckling load: the straight column is stable below it and diverges above it."""
import numpy as np
import pytest

from tca_casadi import Simulation
from tca_casadi.solvers.dynamics import RodDynamics
from tca_casadi.solvers.stability import growth_rates

E, LENGTH, WIDTH, HEIGHT = 1e9, 0.2, 0.002, 0.001


def _column(load):
    """A column standing on its clamp along +z, no gravity, a dead load ``load`` [N] pressing
    its top down; a 2 x 1 mm section, so its weaker axis buckles first at ``pi^2 E I / 4 L^2``."""
    return {"name": "column", "gravity": [0, 0, 0],
            "materials": {"stiff": {"youngs_modulus": E, "poisson_ratio": 0.5, "density": "1000 kg/m^3"}},
            "modules": [{"name": "rod", "length": LENGTH, "material": "stiff",
                         "cross_section": {"shape": "rectangle", "width": WIDTH, "height": HEIGHT}}],
            "loads": [{"name": "top", "kind": "point", "module": "rod", "at": "end", "force": [0, 0, -load],
                       "frame": "global"}],
            "solver": {"intervals": 8, "degree": 4, "refine": "off"}}


EULER = np.pi ** 2 * E * (WIDTH * HEIGHT ** 3 / 12) / (4 * LENGTH ** 2)


def _rates(fraction):
    sim = Simulation.from_file(_column(fraction * EULER))
    straight = sim.solve(warn=False)
    assert straight.converged
    np.testing.assert_allclose(straight.tip_position, [0, 0, LENGTH], rtol=0, atol=1e-4 * LENGTH)
    found = growth_rates(RodDynamics(sim.robot, sim.solver("collocation"), "bdf2"), straight)
    assert found.residual < 1e-9
    return found


@pytest.mark.parametrize("fraction", [0.5, 0.999])
def test_a_straight_column_below_eulers_load_has_no_growth_rate(fraction):
    """Straight, the column is an equilibrium at every load; below Euler's load (to 0.1 %) no
    real growth rate exists up to 1e4/s."""
    found = _rates(fraction)
    assert found.stable and found.rates.size == 0


def test_a_straight_column_diverges_above_eulers_load_like_the_square_root_of_the_excess():
    """0.1 % above Euler's load one real growth rate appears (the weaker axis alone: 4 times the
    load would take the other). Near a simple divergence the rate grows like the square root of
    the load's excess, ``lambda^2 ~ (P - P_cr)``: four times the excess doubles it (2 %), and
    at twice the load it is of the order of the first bending mode's frequency."""
    first, fourfold, double = (_rates(f) for f in (1.001, 1.004, 2.0))
    assert first.rates.size == fourfold.rates.size == double.rates.size == 1
    np.testing.assert_allclose(fourfold.rates[0] / first.rates[0], 2.0, rtol=0.02)
    mode = 1.8751 ** 2 * np.sqrt(E * HEIGHT ** 2 / 12 / (1000 * LENGTH ** 4))    # clamped-free, 25.4 rad/s
    assert 0.5 * mode < double.rates[0] < 2 * mode


def test_rectangular_fingers_pressing_flat_add_no_growth_rate_of_their_own():
    """The pinch's cube held by fingers of a 2 x 1 mm rectangular section, each pressing a flat
    side on it (the nearest outline point runs along that side as the finger twists). Friction
    holds the fingers' material points, so the hanging cube's only real growth rate is its
    inverted pendulum's, ``sqrt(m g d / I)`` (3 %; the fingers' compliance adds 2.4 %). When
    friction held the nearest outline point instead, two more appeared, at 447/s and 801/s."""
    from tca_casadi.studies.sequence import run_sequence
    steps = "sequence=[{name: rest, set: {}}, {name: lift, set: {obstacles.table.position: [0, 0, -50 mm]}}]"
    rect = "{shape: rectangle, width: 2 mm, height: 1 mm}"
    sim = Simulation.from_file("scenarios/analytic/pinch_lift.yaml",
                               [steps, f"modules.1.cross_section={rect}", f"modules.2.cross_section={rect}"])
    hanging = run_sequence(sim).solutions[-1]
    cube = hanging.bodies[0]
    assert hanging.converged and not cube.resting and len(cube.grips) == 2
    a, b = (np.asarray(c.position, float) for c in cube.grips)
    line = (b - a) / np.linalg.norm(b - a)
    arm = cube.position - a - ((cube.position - a) @ line) * line
    d, m = np.linalg.norm(arm), 1e-4
    inertia = m * (0.009 ** 2 + 0.009 ** 2) / 12 + m * d * d
    found = growth_rates(RodDynamics(sim.robot, sim.solver("collocation"), "bdf2"), hanging)
    assert found.residual < 1e-9 and found.rates.size == 1
    np.testing.assert_allclose(found.rates[0], np.sqrt(m * 9.81 * d / inertia), rtol=0.03)

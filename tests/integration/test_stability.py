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

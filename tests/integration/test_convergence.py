"""Mesh convergence on fixed meshes (refinement off): the tip error falls at the collocation
scheme's order, and the default mesh is already within a micrometre."""
import math

import numpy as np
import pytest

from tca_casadi import Simulation


def tip(scenarios, intervals, degree, scheme="legendre", name="analytic/tip_load.yaml", tolerance=1e-12):
    sim = Simulation.from_file(scenarios / name, [f"solver.intervals={intervals}", f"solver.degree={degree}",
                                                  f"solver.scheme={scheme}", f"solver.tolerance={tolerance}",
                                                  "solver.refine=off"])      # fixed meshes are the point
    solution = sim.solve()
    assert solution.converged
    return solution.tip_position


@pytest.mark.parametrize("scheme, degree, order", [("legendre", 1, 2), ("legendre", 2, 4), ("radau", 2, 3)])
def test_tip_error_falls_at_the_expected_order(scenarios, scheme, degree, order):
    reference = tip(scenarios, 40, 6)
    errors = [np.linalg.norm(tip(scenarios, n, degree, scheme) - reference) for n in (4, 8, 16)]
    rates = [math.log2(e0 / e1) for e0, e1 in zip(errors, errors[1:])]
    assert min(rates) > order - 0.5, (errors, rates)
    assert max(rates) < order + 1.0, (errors, rates)


@pytest.mark.parametrize("name", ["bending_module.yaml", "twisting_module.yaml"])
def test_default_mesh_is_within_a_micrometre(scenarios, name):
    sim = Simulation.from_file(scenarios / name)
    default = sim.solve().tip_position
    fine = tip(scenarios, 32, 6, name=name, tolerance=1e-10)
    assert np.linalg.norm(default - fine) < 1e-6

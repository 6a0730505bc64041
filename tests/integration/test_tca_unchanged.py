"""The actuator-law interface (issue 20) left the TCA results where they were: tip positions and
tensions of the shipped TCA and tendon robots as the code before the refactor (commit a050d36)
computed them, to 1e-12 (they agree to the last bit on this machine)."""
import pytest
from numpy.testing import assert_allclose

import tca_casadi as tc

BEFORE = [
    ('bending_module', [],
     [-0.016117968934837572, -8.560447041479559e-18, -0.03797799065882604],
     {'bending.tca1': 0.020882236674813523, 'bending.tca2': 0.03903853106940632, 'bending.tca3': 0.039038531069406336}),
    ('twisting_module', [],
     [0.00010117938373552761, -0.0001673347379968646, -0.015913131005708778],
     {'twisting.tca': 0.06937058369054801}),
    ('arm', [],
     [-2.9997206840074103e-09, -1.201701718865531e-08, -0.061480691630040475],
     {'bending.tca1': 0.001468897968346713, 'bending.tca2': 0.0014688970702864343, 'bending.tca3': 0.001468876890239589, 'twisting.tca': 2.0583062793997127e-05, 'finger_a.tca': 0.00018023677207746957, 'finger_b.tca': 0.0001802359847217031}),
    ('tendon_robot', [],
     [0.022391128992207153, -9.89425860747383e-18, -0.11615702932833237],
     {'body.t1': 0.5348258836681877, 'body.t2': 3.0917713896410696e-18, 'body.t3': 8.708875968456013e-19, 'body.t4': 3.0910363050384498e-18}),
    ('bending_module', ['bending.tca1.tension_only=true', 'bending.tca1.temperature=20'],
     [-0.016329467987087877, -9.958006302878454e-18, -0.037864170991592186],
     {'bending.tca1': 0.020335108205037616, 'bending.tca2': 0.03875043692090849, 'bending.tca3': 0.038750436920908495}),
]


@pytest.mark.parametrize("name, overrides, tip, tensions", BEFORE)
def test_tca_and_tendon_results_are_unchanged_by_the_law_interface(name, overrides, tip, tensions):
    solution = tc.Simulation.from_file(f"scenarios/{name}.yaml", overrides).solve(warn=False)
    assert solution.converged
    assert_allclose(solution.tip_position, tip, rtol=0, atol=1e-12)
    for key, tension in tensions.items():
        assert_allclose(solution.actuators[key].tension, tension, rtol=0, atol=1e-12)

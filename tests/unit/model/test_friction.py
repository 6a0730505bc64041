"""Coulomb's cone written once (:func:`tca_casadi.model.friction.cone_margin`): one value for
numbers, rows and CasADi symbols, against the closed form."""
import casadi as ca
import numpy as np
from numpy.testing import assert_allclose

from tca_casadi.model.friction import cone_margin


def test_the_margin_is_mu_fn_less_the_tangential_size_for_numbers_rows_and_symbols():
    rng = np.random.default_rng(3)
    forces, tangential, mu = rng.uniform(0, 2, 20), rng.normal(size=(20, 3)), 0.7
    expected = mu * forces - np.linalg.norm(tangential, axis=1)
    assert_allclose(cone_margin(mu, forces, tangential), expected, rtol=0, atol=1e-15)
    assert cone_margin(mu, forces[0], tangential[0]) == expected[0]
    t, f = ca.SX.sym("t", 3), ca.SX.sym("f")
    symbolic = ca.Function("m", [f, t], [cone_margin(mu, f, t, smoothing=1e-3)])
    for k in range(5):
        smoothed = mu * forces[k] - np.sqrt(tangential[k] @ tangential[k] + 1e-6)
        assert_allclose(float(symbolic(forces[k], tangential[k])), smoothed, rtol=0, atol=1e-14)
        assert_allclose(cone_margin(mu, forces[k], tangential[k], smoothing=1e-3), smoothed, rtol=0, atol=1e-14)
    assert cone_margin(0.5, 2.0, [1.0, 0.0, 0.0]) == 0.0          # on the cone

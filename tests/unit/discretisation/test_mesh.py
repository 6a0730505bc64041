"""The collocation scheme is exact on polynomials."""
import numpy as np
from numpy.testing import assert_allclose
import pytest

from tca_casadi.discretisation import CollocationScheme


@pytest.mark.parametrize("kind", ["legendre", "radau"])
@pytest.mark.parametrize("degree", [1, 2, 4, 6])
def test_collocation_scheme_is_exact_on_polynomials(kind, degree):
    scheme = CollocationScheme.create(degree, kind)
    poly = np.poly1d(np.arange(1.0, degree + 2))  # degree d polynomial
    values = poly(scheme.tau)
    assert_allclose(values @ scheme.C, np.polyder(poly)(scheme.tau), rtol=0, atol=1e-9)
    assert values @ scheme.D == pytest.approx(poly(1.0), rel=1e-12)
    exact_to = 2 * degree - 1 if kind == "legendre" else 2 * degree - 2
    quad_poly = np.poly1d(np.ones(exact_to + 1))
    assert scheme.weights @ quad_poly(scheme.tau[1:]) == pytest.approx(np.polyint(quad_poly)(1.0), rel=1e-12)

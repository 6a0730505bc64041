"""The dynamics' integrators (:mod:`tca_casadi.solvers.integrators`) on scalar ODEs: each
rule's ``x_t = c0 x + x_hist`` reproduces its textbook difference quotient, and the variable-step
BDF2 is exact on quadratics in time."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.errors import ScenarioError
from tca_casadi.solvers.integrators import BDF2, INTEGRATORS, ImplicitEuler, ImplicitMidpoint, integrator_named


def rate(integrator, h, x_next, x_now, x_before=None, h_before=None):
    c0, (history,) = integrator.coefficients(h, [np.array([x_now])], None if x_before is None else
                                             [np.array([x_before])], h_before)
    return float(c0 * x_next + history[0])


def test_implicit_euler_is_the_backward_difference():
    assert_allclose(rate(ImplicitEuler(), 0.1, 2.0, 1.5), (2.0 - 1.5) / 0.1, rtol=0, atol=1e-12)


@pytest.mark.parametrize("h, h_before", [(0.1, 0.1), (0.05, 0.2), (0.3, 0.1)])
def test_bdf2_is_exact_on_a_quadratic_with_any_step_ratio(h, h_before):
    x = lambda t: 1.0 + 2.0 * t - 3.0 * t ** 2                        # noqa: E731
    t = 0.7
    measured = rate(BDF2(), h, x(t + h), x(t), x(t - h_before), h_before)
    assert_allclose(measured, 2.0 - 6.0 * (t + h), rtol=0, atol=1e-12)   # x'(t + h)


def test_the_midpoint_rule_solves_in_the_middle():
    midpoint = ImplicitMidpoint()
    x_now, x_end = 1.0, 1.6
    z = 0.5 * (x_now + x_end)
    assert_allclose(rate(midpoint, 0.2, z, x_now), (x_end - x_now) / 0.2, rtol=0, atol=1e-12)
    assert_allclose(midpoint.end(np.array([z]), np.array([x_now])), [x_end], rtol=0, atol=1e-15)
    assert_allclose(midpoint.parameters_at(np.array([2.0]), np.array([1.0])), [1.5], rtol=0, atol=0)
    assert midpoint.at_midpoint and not BDF2().at_midpoint


def test_names_and_first_steps():
    assert set(INTEGRATORS) == {"bdf2", "midpoint", "bdf1"}
    assert isinstance(integrator_named("bdf2").first(), ImplicitEuler)
    assert isinstance(integrator_named("midpoint").first(), ImplicitMidpoint)
    with pytest.raises(ScenarioError, match="dynamics.integrator: 'rk4' is not one of bdf2, midpoint, bdf1"):
        integrator_named("rk4")

"""Whether an equilibrium is stable in motion: the real growth rates of its small motions.

A dynamic step's equations are ``g(w; c0, x_hist) = 0`` with every time derivative ``x_t = c0 x +
x_hist`` (:mod:`.integrators`). Linearised about an equilibrium ``w*`` at rest, a small motion
``dw e^(lambda t)`` has ``dx_t = lambda dx``: it solves the step's linearised equations with
``c0 = lambda`` and the history that keeps ``w*`` at rest, ``x_hist = -lambda x*``. So
``lambda`` is a growth rate of the time-continuous equations exactly where

    det J(lambda) = 0,        J(lambda) = dg/dw (w*; c0 = lambda, x_hist = -lambda x*),

and a real ``lambda > 0`` is a motion that grows like ``e^(lambda t)`` from any disturbance (a
divergence: a saddle of the potential energy for a conservative system). :func:`growth_rates`
finds those roots where the sign of ``det J`` changes along a logarithmic grid of ``lambda``
(one sparse LU each) and bisects each change. It is the time-continuous model's answer, free of
any integrator's step: a run started there grows at the same rate, to the integrator's error.
Complex pairs (flutter) and two roots between neighbouring grid points change no sign and are
not found.
"""
from dataclasses import dataclass

import numpy as np

from ..model.history import carried_history


@dataclass
class GrowthRates:
    """Real positive growth rates [1/s] of an equilibrium's small motions (ascending; empty:
    none found up to ``highest``), the largest residual of the equilibrium (scaled: it must
    be at rest for the rates to mean anything) and the range searched [1/s]."""
    rates: np.ndarray
    residual: float
    lowest: float
    highest: float

    @property
    def stable(self):
        """No real growth rate in the range searched."""
        return self.rates.size == 0


def growth_rates(dynamics, solution, lowest=0.1, highest=1e4, samples=64, rtol=1e-9):
    """The real growth rates of small motions about a static equilibrium (module docstring).

    Parameters
    ----------
    dynamics : RodDynamics
        The rod dynamics of the robot (:class:`~tca_casadi.solvers.dynamics.RodDynamics`: its
        damping counts); it is restarted at rest in ``solution``, friction anchored where the
        contacts touch, as a time step would be.
    solution : Solution
        A converged static equilibrium of the same robot.
    lowest, highest : float
        The range of rates searched [1/s].
    samples : int
        How many rates (logarithmically spaced) the sign of ``det J(lambda)`` is evaluated at:
        one sparse LU each.
    rtol : float
        Each sign change is bisected to this relative width.

    Returns
    -------
    GrowthRates
        The roots found [1/s], ascending, and the equilibrium's largest scaled residual.
    """
    state = dynamics.start(solution)
    params = np.asarray(solution.parameters, float)
    if dynamics.robot.path_dependent:
        params = carried_history(dynamics.robot, params, dynamics.contact_solution(state))
    at_rest = dynamics._history_values(state)
    square = dynamics.solver.square

    def at(rate):
        return dynamics.solver.parameters(params, rate, dynamics.damping, [-rate * x for x in at_rest])

    def sign(rate):
        _, J = square.evaluate(state.w, at(rate))
        return square.factorise(J).determinant_sign()

    residual = float(np.abs(square.residual(state.w, at(lowest))).max())
    grid = np.geomspace(lowest, highest, samples)
    signs = [sign(rate) for rate in grid]
    rates = []
    for low, high, s_low, s_high in zip(grid[:-1], grid[1:], signs[:-1], signs[1:]):
        if s_low == s_high or 0 in (s_low, s_high):
            continue
        while high - low > rtol * high:
            middle = 0.5 * (low + high)
            low, high = (middle, high) if sign(middle) == s_low else (low, middle)
        rates.append(0.5 * (low + high))
    return GrowthRates(np.array(rates), residual, lowest, highest)

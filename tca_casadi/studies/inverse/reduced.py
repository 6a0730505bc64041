"""The reduced-space path for inverse statics (``InverseStatics(method="reduced")``).

The same objective as a sum of squares ``r(w, tau)``, minimised over the temperatures only, with
the equilibrium ``g(w, P(tau)) = 0`` solved at every trial ``tau`` (Newton on the square system
from the tangent predictor, continuation if Newton fails) and eliminated by the implicit
function theorem: ``dr/dtau = r_w (-J_w^-1 J_P dP/dtau) + r_tau``, exact, with one sparse LU per
iteration. scipy's trust-region reflective least squares keeps ``tau`` in [0, 1]. Every iterate
is an equilibrium, so the constraints hold exactly as in the full-space NLP.
"""
import numpy as np
from scipy.optimize import least_squares

from ...solvers.continuation import walk_branch
from ...status import SolveStatus, Status


class _Equilibria:
    """Forward equilibria ``w(tau)``, each started from the nearest known one."""

    def __init__(self, inverse, w0, tau0):
        self.inverse, self.solver = inverse, inverse.solver
        self.tau, self.w, self.rate = np.array(tau0, float), np.asarray(w0, float), None
        self.lu = None            # the factorised Jacobian at the last linearised point
        self.failed = False

    def __call__(self, tau):
        tau = np.asarray(tau, float)
        if np.array_equal(tau, self.tau):
            return self.w
        params = self.inverse.params_at(tau)
        predicted = self.w if self.rate is None else self.w + self.rate @ (tau - self.tau)
        w, status = self.solver.square.newton(predicted, params, self.inverse.sim.scenario.solver.tolerance,
                                              lu=self.lu)
        w = w if status.success else self._continue(params)
        if w is not None:
            self.tau, self.w, self.rate = tau.copy(), w, None
        return w

    def _continue(self, params):
        """Predictor-corrector continuation from the last equilibrium to ``params``."""
        start = self.inverse.params_at(self.tau)
        solution = self.solver.evaluate(self.w, start, SolveStatus.judged(
            "start", float("nan"), self.inverse.sim.scenario.solver.tolerance))
        walk = walk_branch(self.solver, solution, start, params, first_step=0.5, max_step=0.5, min_step=1e-3)
        return walk.point.w if walk.completed else None


def reduced_attempt(inverse, w0, tau0, vector):
    """Minimise from ``(w0, tau0)``. Returns ``(w, tau, failure, iterations, detail)``;
    ``failure`` is None (least squares converged on equilibria throughout) or a :class:`Status`."""
    equilibria = _Equilibria(inverse, w0, tau0)
    size = int(inverse._residuals.size1_out(0))

    def residuals(tau):
        w = equilibria(tau)
        if w is None:                                   # no equilibrium reached: a bad trial point
            equilibria.failed = True
            return np.full(size, 1e6)
        return inverse.residual_values(w, tau, vector)[0]

    def jacobian(tau):
        w = equilibria(tau)
        if w is None:
            return np.zeros((size, len(tau)))
        start = np.array_equal(tau, tau0)                 # a start point: the same for every query
        linear = (inverse.linearisation_at if start else inverse.solver.linearise)(w, inverse.params_at(tau))
        rate = linear.state_derivative(inverse._dP_dtau)                  # (n, k)
        equilibria.rate, equilibria.lu = rate, linear.lu
        _, r_w, r_tau = inverse.residual_values(w, tau, vector)
        return r_w @ rate + r_tau

    result = least_squares(residuals, np.clip(tau0, 0.0, 1.0), jac=jacobian, bounds=(0.0, 1.0),
                           method="dogbox", x_scale=1.0, xtol=1e-8, ftol=1e-8, gtol=1e-8,
                           max_nfev=200)
    tau = np.clip(result.x, 0.0, 1.0)
    w = equilibria(tau)
    detail = f"least squares: {result.message}"
    if w is None:
        return np.asarray(w0, float), np.asarray(tau0, float), Status.NO_EQUILIBRIUM, int(result.nfev), detail
    failure = None if result.status > 0 else Status.MAX_ITERATIONS if result.status == 0 else Status.ALGORITHM_FAILED
    return w, tau, failure, int(result.nfev), detail

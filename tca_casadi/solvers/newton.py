"""The square forward system ``g(w, P) = 0`` of the collocation NLP, for Newton's method.

The residual and its exact sparse Jacobian come from the Function IPOPT already uses
(``nlp_jac_g``), evaluated into preallocated numpy buffers (CasADi's buffer API), so nothing is
rebuilt and no CasADi matrix is converted at solve time. The Jacobian is factorised by SuperLU
with the natural column order (the collocation Jacobian is block-banded: that order makes less
work than COLAMD here; row pivoting keeps it stable).
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .linearisation import Linearisation


@dataclass
class NewtonResult:
    w: np.ndarray
    converged: bool
    iterations: int
    residual: float           # max |g| (scaled) at w
    message: str


class SquareSystem:
    """``g`` and ``J_w = dg/dw`` at ``(w, P)`` for the NLP ``nlp`` solved by ``ipopt``."""

    def __init__(self, nlp, ipopt):
        self.nlp = nlp
        function = ipopt.get_function("nlp_jac_g")
        self._w, self._P = np.zeros(function.nnz_in(0)), np.zeros(function.nnz_in(1))
        self._g, self._J = np.zeros(function.nnz_out(0)), np.zeros(function.nnz_out(1))
        buffer, self._evaluate = function.buffer()
        for index, array in enumerate((self._w, self._P)):
            buffer.set_arg(index, memoryview(array))
        for index, array in enumerate((self._g, self._J)):
            buffer.set_res(index, memoryview(array))
        self._buffer = buffer                       # keep alive: it holds the pointers
        sparsity = function.sparsity_out(1)
        colind, row = sparsity.get_ccs()
        self._indptr, self._indices = np.array(colind), np.array(row)
        self.shape = (sparsity.size1(), sparsity.size2())
        self._sensitivity = None

    def evaluate(self, w, P):
        """``(g, J_w)``: copies of the residual (n,) and the Jacobian (CSC)."""
        self._w[:], self._P[:] = w, P
        self._evaluate()
        J = sp.csc_matrix((self._J.copy(), self._indices, self._indptr), shape=self.shape)
        return self._g.copy(), J

    def newton(self, w0, P, tolerance, max_iterations=25):
        """Damped Newton from ``w0`` until ``max |g| <= tolerance`` (backtracking on ``|g|_2``)."""
        w = np.array(w0, float)
        g, J = self.evaluate(w, P)
        for iteration in range(max_iterations + 1):
            residual = float(np.max(np.abs(g))) if g.size else 0.0
            if not np.isfinite(residual):
                return NewtonResult(w, False, iteration, residual, "Newton: the residual is not finite")
            if residual <= tolerance:
                return NewtonResult(w, True, iteration, residual, f"Newton: converged in {iteration} iterations")
            if iteration == max_iterations:
                break
            try:
                step = spla.splu(J, permc_spec="NATURAL").solve(g)
            except RuntimeError:
                return NewtonResult(w, False, iteration, residual, "Newton: singular Jacobian")
            w, g, J, accepted = self._line_search(w, g, step, P)
            if not accepted:
                return NewtonResult(w, False, iteration, residual, "Newton: no descent along the step")
        return NewtonResult(w, False, max_iterations, residual,
                            f"Newton: not converged in {max_iterations} iterations (residual {residual:.1e})")

    def _line_search(self, w, g, step, P, shortest=1 / 64):
        norm, alpha = np.linalg.norm(g), 1.0
        while alpha >= shortest:
            trial = w - alpha * step
            g_trial, J_trial = self.evaluate(trial, P)
            if np.all(np.isfinite(g_trial)) and np.linalg.norm(g_trial) < (1 - 1e-4 * alpha) * norm:
                return trial, g_trial, J_trial, True
            alpha /= 2
        return w, g, None, False

    # ------------------------------------------------------------------ sensitivities
    def _sensitivity_function(self):
        if self._sensitivity is None:
            nlp = self.nlp
            tip = nlp.outputs(nlp.w, nlp.P)[1][0:3, -1]
            self._sensitivity = ca.Function(
                "sensitivity", [nlp.w, nlp.P],
                [ca.jacobian(nlp.problem["g"], nlp.P), ca.jacobian(tip, nlp.w),
                 ca.jacobian(tip, nlp.P)]).expand()
        return self._sensitivity

    def parameter_jacobian(self, w, P):
        """``dg/dP`` (sparse, (n, nP)) at ``(w, P)``."""
        return self._sensitivity_function()(w, P)[0].sparse()

    def linearise(self, w, P):
        """:class:`Linearisation` at ``(w, P)``: adds ``dg/dP`` and the tip's derivatives."""
        g, J_w = self.evaluate(w, P)
        J_P, T_w, T_P = self._sensitivity_function()(w, P)
        return Linearisation(g, J_w, J_P.sparse(), T_w.sparse(), np.array(T_P))

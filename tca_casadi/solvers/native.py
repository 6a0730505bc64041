"""Chord steps of Newton's method in compiled code (``solver.jit``, issue 36).

A warm solve or a time step is mostly chord steps: the Jacobian factorised at an earlier point
(:class:`~tca_casadi.solvers.linearisation.OrderedLU`, SuperLU) solves for the step, and the
residual is evaluated at the new point, as long as each step cuts ``|g|_2`` tenfold. In Python
each such step costs a CasADi call, two SuperLU triangular solves and numpy's bookkeeping (about
0.15 ms on the bending module). Here the loop runs in C (``chord.c``, beside this file): CasADi's
generated code of the residual and the two sparse triangular solves on SuperLU's factors (copied
once per factorisation), compiled into one library with the residual, kept on disk like
:mod:`.compiled`'s. Python takes over where a step is rejected (a fresh Jacobian, the line
search, the roundoff floor): the iterates and the stopping rule are those of
:meth:`SquareSystem.newton <tca_casadi.solvers.newton.SquareSystem.newton>`, except that a
compiled chord step is kept while it cuts the residual threefold (not tenfold: it costs about
1/50 of the fresh Jacobian it saves).
"""
import ctypes
from pathlib import Path

import casadi as ca
import numpy as np

from .compiled import compiled_library

#: the C source of the chord steps
SOURCE = Path(__file__).with_name("chord.c")
#: what :meth:`NativeChord.steps` returns (``chord.c``'s codes)
CONVERGED, REJECTED, NOT_FINITE, STEPS_USED = 0, 1, 2, 3
#: the generated residual's argument and result arrays have room for this many (``chord.c``)
MAX_ARGUMENTS = 64

_POINTER, _INT, _DOUBLE = ctypes.c_void_p, ctypes.c_int, ctypes.c_double


class NativeChord:
    """The residual ``function`` ``(w, P) -> g`` compiled with the chord steps (module docstring).

    Attributes
    ----------
    residual : casadi.Function
        The compiled residual (an external Function, same inputs and outputs as ``function``).
    """

    def __init__(self, function, directory=None):
        if function.sz_arg() > MAX_ARGUMENTS or function.sz_res() > MAX_ARGUMENTS:
            raise ValueError(f"{function.name()} needs more than {MAX_ARGUMENTS} argument slots")
        path = compiled_library(function, directory, sources=(SOURCE,), defines=(f"RESIDUAL={function.name()}",))
        self.residual = ca.external(function.name(), str(path))
        library = ctypes.CDLL(str(path))
        self._chord = library.chord_steps
        self._chord.restype = _INT
        self._chord.argtypes = ([_INT] + [_POINTER] * 9 + [_POINTER] * 9 + [_DOUBLE, _DOUBLE, _INT, _POINTER, _POINTER])
        self.n = function.nnz_out(0)
        self._work = [np.zeros(self.n) for _ in range(4)]            # y, iterate, trial g, step
        self._iw = np.zeros(max(function.sz_iw(), 1), np.int64)
        self._w = np.zeros(max(function.sz_w(), 1))
        self._steps, self._residual = _INT(), _DOUBLE()
        self._scratch = [a.ctypes.data for a in self._work] + [self._iw.ctypes.data, self._w.ctypes.data]

    def steps(self, w, g, P, lu, tolerance, contraction, max_steps):
        """Chord steps with ``lu`` (an OrderedLU of the Jacobian at an earlier point) from ``w``
        (scaled variables, (n,), updated in place) where the residual is ``g`` (updated in
        place) at parameters ``P``, until ``max |g| <= tolerance``, a step cuts ``|g|_2`` less
        than ``contraction`` times (it is not taken) or ``max_steps`` steps are taken.
        Returns ``(code, steps)``: one of :data:`CONVERGED`, :data:`REJECTED`,
        :data:`NOT_FINITE`, :data:`STEPS_USED`, and the number of steps taken."""
        for array in (w, g):
            if array.dtype != np.float64 or not array.flags.c_contiguous or array.size != self.n:
                raise ValueError("w and g must be contiguous float64 arrays of the system's size")
        P = np.ascontiguousarray(P, dtype=np.float64)
        code = self._chord(self.n, P.ctypes.data, w.ctypes.data, g.ctypes.data, *self._scratch,
                           *_factors(lu), tolerance, contraction, int(max_steps),
                           ctypes.byref(self._steps), ctypes.byref(self._residual))
        return code, self._steps.value


def _factors(lu):
    """The pointers of an OrderedLU's factors as ``chord.c`` reads them (L and U in CSC, U's
    diagonal, the row permutation and where each solved entry goes), computed once per LU."""
    cached = getattr(lu, "_native_factors", None)
    if cached is None:
        factors = lu.factors
        L, U = factors.L.tocsc(), factors.U.tocsc()
        n = L.shape[0]
        # Pr A Pc = L U with A = J[:, order] (scipy's convention): x_A[i] = u[perm_c[i]], x[order] = x_A
        column = np.empty(n, np.int64)
        column[factors.perm_c] = np.arange(n) if lu.order is None else np.asarray(lu.order)
        arrays = [np.ascontiguousarray(a, dtype) for a, dtype in
                  ((L.indptr, np.int32), (L.indices, np.int32), (L.data, np.float64),
                   (U.indptr, np.int32), (U.indices, np.int32), (U.data, np.float64),
                   (U.diagonal(), np.float64), (factors.perm_r, np.int32), (column, np.int32))]
        if arrays[6].size != n:
            raise ValueError("the factors are not square")
        cached = (arrays, tuple(a.ctypes.data for a in arrays))
        lu._native_factors = cached                  # the arrays live as long as the LU
    return cached[1]

"""The square forward system ``g(w, P) = 0`` linearised at a point: sparse Jacobians from CasADi
and what follows from them (sensitivities by the implicit function theorem, the sign of the
Jacobian's determinant and its smallest singular value, which show folds).

``w`` is the collocation NLP's scaled variable vector, ``P`` the robot's parameter vector.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

#: COLAMD's column order is used when its LU fill is below this fraction of the natural order's
COLAMD_FILL = 0.5


class OrderedLU:
    """SuperLU factors of ``J[:, order]`` (natural order on the reordered columns; ``order`` None:
    J's own), solving in J's coordinates: ``solve(b)`` gives ``x`` with ``J x = b`` (``b``: (n,)
    or (n, k)), ``trans="T"`` with ``J^T x = b``."""

    def __init__(self, J, order=None):
        self.order = order
        self.factors = spla.splu(J if order is None else J[:, order].tocsc(), permc_spec="NATURAL")

    def solve(self, b, trans="N"):
        if self.order is None:
            return self.factors.solve(b, trans=trans)
        if trans == "T":                     # (J Q)^T y = Q^T b: the rows of b in the new order
            return self.factors.solve(np.ascontiguousarray(b[self.order]), trans="T")
        permuted = self.factors.solve(b)
        x = np.empty_like(permuted)
        x[self.order] = permuted
        return x

    @property
    def fill(self):
        """Nonzeros of the factors L and U."""
        return self.factors.L.nnz + self.factors.U.nnz


def column_order(J, banded=None):
    """The column order :class:`OrderedLU` uses for Jacobians with ``J``'s pattern: ``banded``
    (the NLP's block-banded order, :meth:`CollocationNLP.banded_columns`; None: J's own) or
    COLAMD's permutation when that roughly halves the fill (:data:`COLAMD_FILL`; a tree of
    modules, whose branches the banded order puts one after the other)."""
    first = OrderedLU(J, banded)
    colamd = spla.splu(J, permc_spec="COLAMD")
    if colamd.L.nnz + colamd.U.nnz >= COLAMD_FILL * first.fill:
        return banded
    order = np.empty_like(colamd.perm_c)
    order[colamd.perm_c] = np.arange(colamd.perm_c.size)
    return order


class Linearisation:
    """``g``, ``J_w = dg/dw`` (sparse, square), ``J_P = dg/dP`` and ``T_w, T_P``: the derivatives
    of the tip position [m] at one point ``(w, P)``; ``factorise(J_w)``: the system's sparse LU
    (an :class:`OrderedLU`; default in J_w's own column order)."""

    def __init__(self, g, J_w, J_P, T_w, T_P, factorise=None):
        self.g, self.J_w, self.J_P, self.T_w, self.T_P = g, J_w.tocsc(), J_P.tocsc(), T_w, T_P
        self._factorise = factorise
        self._lu = None

    @property
    def lu(self):
        """Sparse LU of ``J_w`` (an OrderedLU), computed once."""
        if self._lu is None:
            self._lu = (self._factorise or OrderedLU)(self.J_w)
        return self._lu

    def state_derivative(self, direction):
        """``dw/dlam`` for ``P = P0 + lam direction`` (direction: (nP,) or (nP, k))."""
        rhs = -(self.J_P @ np.asarray(direction, float))
        return self.lu.solve(np.asarray(rhs, float))

    def tip_derivative(self, direction):
        """``d tip / d lam`` [m per unit of lam], shape (3,) or (3, k)."""
        direction = np.asarray(direction, float)
        return self.T_w @ self.state_derivative(direction) + self.T_P @ direction

    def determinant_sign(self):
        """Sign (+1, -1; 0 if singular) of ``det J_w``: a change between two points of a branch
        means a fold or a bifurcation lies between them. Computed once."""
        if getattr(self, "_sign", None) is None:
            factors, order = self.lu.factors, self.lu.order
            diagonal = factors.U.diagonal()
            if np.any(diagonal == 0):
                self._sign = 0
            else:                            # det J[:, order] = det J sign(order)
                sign = np.prod(np.sign(diagonal)) * (1 if order is None else _parity(order))
                self._sign = int(sign * _parity(factors.perm_r) * _parity(factors.perm_c))
        return self._sign

    def smallest_singular_value(self, iterations=6, seed=0):
        """Estimate of ``sigma_min(J_w)`` by inverse iteration on ``J_w^T J_w`` (two sparse
        triangular solves per iteration, reusing the LU)."""
        x = np.random.default_rng(seed).standard_normal(self.J_w.shape[0])
        x /= np.linalg.norm(x)
        growth = 1.0
        for _ in range(iterations):
            y = self.lu.solve(self.lu.solve(x, trans="T"))
            growth = np.linalg.norm(y)
            if not np.isfinite(growth) or growth == 0:
                return 0.0
            x = y / growth
        return float(1.0 / np.sqrt(growth))


def _parity(permutation):
    """+1 for an even permutation, -1 for an odd one: ``(-1)^(n - cycles)``, the cycles counted
    as connected components of the permutation's graph."""
    permutation = np.asarray(permutation)
    n = permutation.size
    moved = np.flatnonzero(permutation != np.arange(n))
    if moved.size == 0:                                 # the identity (natural column order): even
        return 1
    if moved.size <= 64:                                # few pivots moved rows: follow their cycles
        seen, transpositions = set(), 0
        for start in moved.tolist():
            length, k = 0, start
            while k not in seen:
                seen.add(k)
                k = int(permutation[k])
                length += 1
            transpositions += max(length - 1, 0)
        return -1 if transpositions % 2 else 1
    graph = sp.csr_matrix((np.ones(n), (np.arange(n), permutation)), shape=(n, n))
    cycles = connected_components(graph, directed=True, connection="weak")[0]
    return -1 if (n - cycles) % 2 else 1

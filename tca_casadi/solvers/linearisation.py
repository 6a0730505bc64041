"""The square forward system ``g(w, P) = 0`` linearised at a point: sparse Jacobians from CasADi
and what follows from them (sensitivities by the implicit function theorem, the sign of the
Jacobian's determinant and its smallest singular value, which show folds).

``w`` is the collocation NLP's scaled variable vector, ``P`` the robot's parameter vector.
"""
import numpy as np
import scipy.sparse.linalg as spla

#: a linearisation takes ``dg/dP`` along up to this many directions by forward mode, and in full
#: for more (:meth:`~tca_casadi.solvers.newton.SquareSystem.linearise`)
FORWARD_DIRECTIONS = 2
#: COLAMD's column order is used when its LU fill is below this fraction of the natural order's
COLAMD_FILL = 0.5
#: parities of column orders in use: id -> (order, parity) (:attr:`OrderedLU.order_parity`)
_ORDER_PARITY = {}


class OrderedLU:
    """SuperLU factors of ``J[:, order]`` (natural order on the reordered columns; ``order`` None:
    J's own), solving in J's coordinates: ``solve(b)`` gives ``x`` with ``J x = b`` (``b``: (n,)
    or (n, k)), ``trans="T"`` with ``J^T x = b``."""

    def __init__(self, J, order=None):
        self.order = order
        self.factors = spla.splu(J if order is None else J[:, order].tocsc(), permc_spec="NATURAL")

    @classmethod
    def of_ordered(cls, ordered, order):
        """The LU of ``J`` given ``ordered = J[:, order]`` (CSC) itself."""
        lu = cls.__new__(cls)
        lu.order = order
        lu.factors = spla.splu(ordered, permc_spec="NATURAL")
        return lu

    def solve(self, b, trans="N"):
        if self.order is None:
            return self.factors.solve(b, trans=trans)
        if trans == "T":                     # (J Q)^T y = Q^T b: the rows of b in the new order
            return self.factors.solve(np.ascontiguousarray(b[self.order]), trans="T")
        permuted = self.factors.solve(b)
        x = np.empty_like(permuted)
        x[self.order] = permuted
        return x

    def determinant_sign(self):
        """Sign (+1, -1; 0 if singular) of ``det J`` from the factors: ``det J[:, order] = det J
        sign(order)``, and SuperLU's ``Pr A Pc = L U`` with L unit lower triangular."""
        diagonal = self.factors.U.diagonal()
        if np.any(diagonal == 0):
            return 0
        sign = np.prod(np.sign(diagonal)) * (1 if self.order is None else self.order_parity)
        return int(sign * _parity(self.factors.perm_r) * _parity(self.factors.perm_c))

    @property
    def order_parity(self):
        """The parity (+1, -1) of the column order, computed once per order (a system's order
        is fixed at its first factorisation and shared by every LU after it)."""
        key = id(self.order)
        if _ORDER_PARITY.get(key, (None,))[0] is not self.order:
            if len(_ORDER_PARITY) >= 64:
                _ORDER_PARITY.clear()
            _ORDER_PARITY[key] = (self.order, _parity(self.order))
        return _ORDER_PARITY[key][1]

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
    (an :class:`OrderedLU`; default in J_w's own column order). ``J_P``: a sparse matrix, or a
    function that makes it (on first use); ``rates``: ``directions (nP, k) -> dg/dP directions``
    without it, used for up to :data:`FORWARD_DIRECTIONS` directions."""

    def __init__(self, g, J_w, J_P, T_w, T_P, factorise=None, rates=None):
        self.g, self.J_w, self.T_w, self.T_P = g, J_w.tocsc(), T_w, T_P
        self._J_P, self._make_J_P = (None, J_P) if callable(J_P) else (J_P.tocsc(), None)
        self._rates = rates
        self._factorise = factorise
        self._lu = None

    @property
    def J_P(self):
        """``dg/dP`` (sparse, (n, nP)), made once."""
        if self._J_P is None:
            self._J_P = self._make_J_P().tocsc()
        return self._J_P

    def parameter_rates(self, direction):
        """``dg/dP direction`` (direction (nP,) or (nP, k); the result (n,) or (n, k))."""
        direction = np.asarray(direction, float)
        columns = direction.reshape(direction.shape[0], -1)
        if self._rates is None or self._J_P is not None or columns.shape[1] > FORWARD_DIRECTIONS:
            return np.asarray(self.J_P @ direction, float)
        rates = self._rates(columns)
        return rates[:, 0] if direction.ndim == 1 else rates

    @property
    def lu(self):
        """Sparse LU of ``J_w`` (an OrderedLU), computed once."""
        if self._lu is None:
            self._lu = (self._factorise or OrderedLU)(self.J_w)
        return self._lu

    def state_derivative(self, direction):
        """``dw/dlam`` for ``P = P0 + lam direction`` (direction: (nP,) or (nP, k))."""
        return self.lu.solve(-self.parameter_rates(direction))

    def tip_derivative(self, direction):
        """``d tip / d lam`` [m per unit of lam], shape (3,) or (3, k)."""
        direction = np.asarray(direction, float)
        return self.T_w @ self.state_derivative(direction) + self.T_P @ direction

    def determinant_sign(self):
        """Sign (+1, -1; 0 if singular) of ``det J_w``: a change between two points of a branch
        means a fold or a bifurcation lies between them. Computed once."""
        if getattr(self, "_sign", None) is None:
            self._sign = self.lu.determinant_sign()
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
    """+1 for an even permutation, -1 for an odd one: ``(-1)^(n - cycles)``. Each cycle is
    labelled by its smallest index by pointer doubling (``ceil(log2 n)`` vectorised rounds: after
    round k every entry holds the smallest index among its next ``2^k`` successors), so the
    cycles are the entries that are their own label."""
    permutation = np.asarray(permutation, dtype=np.intp)
    n = permutation.size
    if n == 0 or np.array_equal(permutation, np.arange(n)):
        return 1
    label, successor = np.arange(n), permutation.copy()
    for _ in range(max(int(np.ceil(np.log2(n))), 1)):
        label = np.minimum(label, label[successor])
        successor = successor[successor]
    cycles = int(np.count_nonzero(label == np.arange(n)))
    return -1 if (n - cycles) % 2 else 1

"""The collocation Jacobian through the rod equations at one point (issue 36).

Differentiating the whole expanded constraint vector ``g(w, P)`` symbolically costs CasADi
(number of colours) x (number of nodes): about 20 ms per interval, most of a cold solve on a
fine mesh. But nearly all of ``g``'s nonlinearity sits in one place, the rod equations at every
collocation point (:func:`~tca_casadi.model.rod.rod_equations`, mapped). The NLP therefore
builds its constraints with the rod equations' outputs ``Y`` as stand-in symbols,
``g = G(w, P, Y)``, and records each call's inputs ``I(w, P)`` (:class:`RodCall`). Then

    dg/dz = dG/dz + dG/dY  blockdiag(dR/dI at every point)  dI/dz        (z = w or P)

where ``dR/dI`` is the Jacobian of the rod equations at *one* point (a small function, mapped
over the points), and ``dG/dz``, ``dG/dY``, ``dI/dz`` are Jacobians of graphs with a few nodes
per interval (the linear collocation maps, links, boundary conditions, the muscles' laws). The
two sparse products are planned once (:class:`ProductPlan`, index arrays) and evaluated with
numpy gathers and ``bincount``: build and evaluation are linear in the mesh.
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np


@dataclass
class RodCall:
    """The rod equations at ``points`` points: ``flat`` (one point's stacked inputs ``(n_in,)``
    to its stacked outputs ``[kin (7); eq (6); speed (nA)]``), the inputs ``stacked`` (MX,
    ``(n_in, points)``) and the stand-in symbols ``outputs`` (MX, ``(n_out, points)``)."""
    flat: ca.Function
    stacked: ca.MX
    outputs: ca.MX
    points: int

    @classmethod
    def create(cls, rod, points, inputs, index):
        """``rod`` a Function of one point; ``inputs`` one matrix per input of ``rod``, each the
        point's blocks side by side."""
        shapes = [(rod.size1_in(k), rod.size2_in(k)) for k in range(rod.n_in())]
        stacked = ca.vertcat(*[ca.reshape(_mx(x), rows * cols, points) for x, (rows, cols) in zip(inputs, shapes)])
        z = ca.SX.sym("z", sum(rows * cols for rows, cols in shapes))
        parts, start = [], 0
        for rows, cols in shapes:
            parts.append(ca.reshape(z[start:start + rows * cols], rows, cols))
            start += rows * cols
        y = ca.vertcat(*rod(*parts))
        flat = ca.Function(f"rod_flat_{index}", [z], [y])
        return cls(flat, stacked, ca.MX.sym(f"rod_{index}", y.numel(), points), points)

    def evaluated(self):
        """The true outputs: the point function mapped over the points, on the inputs."""
        return self.flat.map(self.points)(self.stacked)

    def jacobian(self):
        """Function ``z (n_in,) -> dy/dz`` (sparse, (n_out, n_in)) of one point."""
        z = ca.SX.sym("z", self.flat.size1_in(0))
        return ca.Function(f"{self.flat.name()}_jac", [z], [ca.jacobian(self.flat(z), z)])


def _mx(value):
    return value if isinstance(value, ca.MX) else ca.MX(ca.DM(value))


class StructuredJacobian:
    """``(g, dg/dz)`` of an NLP's constraints at ``(w, P)``, ``z`` = ``w`` or ``P`` (module
    docstring). ``__call__(w, P)`` returns ``(g (n,), nonzeros of dg/dz in CSC order)``;
    ``indptr``, ``indices``, ``shape`` describe the pattern."""

    def __init__(self, nlp, wrt="w"):
        calls = nlp.rod_calls
        w, P = ca.SX.sym("w", nlp.w.numel()), ca.SX.sym("P", nlp.P.numel())
        Ys = [ca.SX.sym(f"Y{k}", *c.outputs.shape) for k, c in enumerate(calls)]
        z = w if wrt == "w" else P
        g = nlp.split.expand()(w, P, *Ys)
        stacked = ca.Function("rod_inputs", [nlp.w, nlp.P], [c.stacked for c in calls]).expand()(w, P) if calls else []
        stacked = [stacked] if isinstance(stacked, ca.SX) else list(stacked)
        dG_dz = split_jacobian(g, z)             # G's nonlinear part: contacts' geometry, muscles' laws
        dG_dY = ca.jacobian(g, ca.vertcat(*[ca.vec(Y) for Y in Ys])) if calls else ca.SX(g.numel(), 0)
        dI_dz = ca.jacobian(ca.vertcat(*[ca.vec(I) for I in stacked]), z) if calls else ca.SX(0, z.numel())
        pieces = ca.Function("jacobian_pieces", [w, P] + Ys, [g, _nonzeros(dG_dz), _nonzeros(dG_dY), _nonzeros(dI_dz)])
        jacobians = [c.jacobian() for c in calls]
        true_Y = [c.evaluated() for c in calls]
        mapped = [f.map(c.points)(c.stacked) for f, c in zip(jacobians, calls)]
        outputs = list(pieces(nlp.w, nlp.P, *true_Y)) + [_nonzeros(m) for m in mapped]
        self.function = ca.Function(f"nlp_jacobian_{wrt}", [nlp.w, nlp.P], outputs)
        blocks = [(f.sparsity_out(0), c.points) for f, c in zip(jacobians, calls)]
        self.plan = ProductPlan(dG_dz.sparsity(), dG_dY.sparsity(), blocks, dI_dz.sparsity())
        self.indptr, self.indices, self.shape = self.plan.indptr, self.plan.indices, self.plan.shape
        self._buffers = None

    def compile(self, compiler):
        """Evaluate through ``compiler(function)`` (e.g. :func:`~tca_casadi.solvers.compiled.compiled`)
        from now on: the same outputs, as machine code."""
        self.function = compiler(self.function)
        self._buffers = None

    def __call__(self, w, P):
        from ..buffers import BufferedFunction
        if self._buffers is None:
            self._buffers = BufferedFunction(self.function)
        g, dG_dz, dG_dY, dI_dz, *blocks = self._buffers(w, P)
        block = np.concatenate(blocks) if blocks else np.zeros(0)
        return g, self.plan.values(dG_dz, dG_dY, block, dI_dz)


#: rows and columns of a Jacobian with more nonzeros than this are differentiated apart
#: (:func:`split_jacobian`)
DENSE = 24


def split_jacobian(g, z, dense=DENSE):
    """``dg/dz`` (SX, ``z`` symbols) as three blocks, the same matrix CasADi's ``jacobian``
    gives (to roundoff: another mode of differentiation) at a fraction of its cost where a
    few rows and columns are dense. CasADi colours the whole Jacobian for one mode: forward
    needs at least as many sweeps of ``g``'s graph as its densest row has nonzeros, reverse as
    its densest column. A free body's balance rows (every grip's state and force) and its pose
    columns (every grip's gap) make both modes sweep hundreds of times over every contact's
    geometry (the arm holding a bar: 1.5 s of its 2.9 s build). So the rows and columns with
    more than ``dense`` nonzeros are taken apart: the sparse rows by the sparse columns, the
    dense rows by the sparse columns, and every row by the few dense columns, each in the
    mode that suits it (0.44 s there)."""
    pattern = ca.jacobian_sparsity(g, z)
    rows, cols = (np.asarray(x, int) for x in pattern.get_triplet())
    row_count = np.bincount(rows, minlength=g.numel())
    column_count = np.bincount(cols, minlength=z.numel())
    dense_rows, sparse_rows = np.flatnonzero(row_count > dense), np.flatnonzero(row_count <= dense)
    dense_columns, sparse_columns = np.flatnonzero(column_count > dense), np.flatnonzero(column_count <= dense)
    if dense_rows.size == 0 and dense_columns.size == 0:
        return ca.jacobian(g, z)
    sparse_z = z[sparse_columns.tolist()]
    left = ca.vertcat(ca.jacobian(g[sparse_rows.tolist()], sparse_z), ca.jacobian(g[dense_rows.tolist()], sparse_z))
    left = left[np.argsort(np.r_[sparse_rows, dense_rows]).tolist(), :]
    whole = ca.horzcat(left, ca.jacobian(g, z[dense_columns.tolist()]))
    return whole[:, np.argsort(np.r_[sparse_columns, dense_columns]).tolist()]


def _nonzeros(matrix):
    """The structural nonzeros of a matrix as a column (CSC order)."""
    return matrix.nz[:] if matrix.nnz() else type(matrix)(0, 1)


class ProductPlan:
    """``A + B D C`` for sparse ``A`` (n, m), ``B`` (n, y), ``C`` (i, m) and ``D`` block
    diagonal (y, i) with ``blocks`` ``[(pattern, count), ...]`` (``count`` copies of each
    block pattern along the diagonal), planned once: :meth:`values` takes the four matrices'
    nonzeros (CSC order; ``D``'s block after block) and returns the result's (CSC order of
    :attr:`indptr`, :attr:`indices`)."""

    def __init__(self, A, B, blocks, C):
        n, m = A.size1(), A.size2()
        d_rows, d_cols, d_index = _block_diagonal(blocks)
        c_rows, c_cols, c_index = _triplets(C)
        # D C: terms (row of D, column of C, D's nonzero, C's nonzero), summed per (row, column)
        t1 = _product_terms(d_rows, d_cols, d_index, c_rows, c_cols, c_index, C.size1())
        self._dc, dc_rows, dc_cols = _summed(t1, C.size2())
        b_rows, b_cols, b_index = _triplets(B)
        t2 = _product_terms(b_rows, b_cols, b_index, dc_rows, dc_cols, np.arange(dc_rows.size), B.size2())
        self._bdc, bdc_rows, bdc_cols = _summed(t2, m)
        self._dc_size = dc_rows.size
        a_rows, a_cols, _ = _triplets(A)
        keys = np.concatenate([a_cols * n + a_rows, bdc_cols * n + bdc_rows])
        unique, inverse = np.unique(keys, return_inverse=True)
        self._a_position, self._bdc_position = inverse[:a_rows.size], inverse[a_rows.size:]
        self.size = unique.size
        self.indices = (unique % n).astype(np.int64)
        self.indptr = np.searchsorted(unique // n, np.arange(m + 1)).astype(np.int64)
        self.shape = (n, m)

    def values(self, a, b, d, c):
        """The nonzeros (CSC order) of ``A + B D C`` from those of ``A``, ``B``, ``D``, ``C``."""
        k, (di, ci) = self._dc
        dc = np.bincount(k, weights=d[di] * c[ci], minlength=self._dc_size)
        k2, (bi, dci) = self._bdc
        bdc = np.bincount(k2, weights=b[bi] * dc[dci], minlength=self._bdc_position.size)
        out = np.zeros(self.size)
        out[self._a_position] = a
        out[self._bdc_position] += bdc
        return out


def _triplets(sparsity):
    """``(rows, columns, nonzero index)`` of a CasADi sparsity (CSC order)."""
    rows, cols = sparsity.get_triplet()
    return np.asarray(rows, np.int64), np.asarray(cols, np.int64), np.arange(len(rows), dtype=np.int64)


def _block_diagonal(blocks):
    """Triplets of the block-diagonal matrix of ``blocks`` ``[(pattern, count), ...]``, its
    nonzeros numbered block after block (each block's in CSC order)."""
    rows, cols, index = [], [], []
    row0 = col0 = nz0 = 0
    for pattern, count in blocks:
        r, c, _ = _triplets(pattern)
        k = np.arange(count)[:, None]
        rows.append((row0 + k * pattern.size1() + r[None, :]).ravel())
        cols.append((col0 + k * pattern.size2() + c[None, :]).ravel())
        index.append((nz0 + k * r.size + np.arange(r.size)[None, :]).ravel())
        row0, col0, nz0 = row0 + count * pattern.size1(), col0 + count * pattern.size2(), nz0 + count * r.size
    join = lambda parts: np.concatenate(parts) if parts else np.zeros(0, np.int64)      # noqa: E731
    return join(rows), join(cols), join(index)


def _product_terms(a_rows, a_cols, a_index, b_rows, b_cols, b_index, inner):
    """The terms of ``A B`` from their triplets: ``(rows, columns, A's nonzero, B's nonzero)``,
    one per product of a nonzero of A with a nonzero of B in the row its column names."""
    order = np.argsort(b_rows, kind="stable")
    b_rows, b_cols, b_index = b_rows[order], b_cols[order], b_index[order]
    indptr = np.searchsorted(b_rows, np.arange(inner + 1))
    counts = indptr[a_cols + 1] - indptr[a_cols]
    take = np.repeat(np.arange(a_rows.size), counts)
    within = np.arange(take.size) - np.repeat(np.cumsum(counts) - counts, counts)
    where = indptr[a_cols][take] + within
    return a_rows[take], b_cols[where], a_index[take], b_index[where]


def _summed(terms, columns):
    """``((term -> entry, (A's nonzeros, B's nonzeros)), rows, columns)`` of the entries the
    terms sum into (ordered by row, then column)."""
    rows, cols, first, second = terms
    keys = rows * columns + cols
    unique, inverse = np.unique(keys, return_inverse=True)
    return (inverse, (first, second)), unique // columns, unique % columns

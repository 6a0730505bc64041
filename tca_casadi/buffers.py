"""CasADi Functions evaluated into preallocated numpy arrays, and CasADi sparsity patterns as
scipy matrices: the low-level evaluation every stage uses (the model's rotations, the
discretisation's structured Jacobians, the solvers, studies and control), below all of them."""
import numpy as np
import scipy.sparse as sp


class BufferedFunction:
    """A CasADi Function evaluated into preallocated numpy arrays (CasADi's buffer API)."""

    def __init__(self, function):
        self.inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self.outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        self._buffer, self._evaluate = function.buffer()
        for index, array in enumerate(self.inputs):
            self._buffer.set_arg(index, memoryview(array))
        for index, array in enumerate(self.outputs):
            self._buffer.set_res(index, memoryview(array))

    def __call__(self, *values):
        for array, value in zip(self.inputs, values):
            array[:] = value
        self._evaluate()
        return self.outputs




class CscPattern:
    """A CasADi sparsity pattern, to wrap a buffer of nonzeros as a scipy CSC matrix."""

    def __init__(self, sparsity):
        if sparsity is not None:
            colind, row = sparsity.get_ccs()
            self.indptr, self.indices = np.array(colind), np.array(row)
            self.shape = (sparsity.size1(), sparsity.size2())

    @classmethod
    def of(cls, indptr, indices, shape):
        """The pattern of CSC arrays."""
        pattern = cls(None)
        pattern.indptr, pattern.indices, pattern.shape = np.asarray(indptr), np.asarray(indices), tuple(shape)
        return pattern

    def matrix(self, values):
        return sp.csc_matrix((values.copy(), self.indices, self.indptr), shape=self.shape)

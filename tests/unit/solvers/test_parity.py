"""The parity of a permutation (the sign of det J_w from its LU) against the determinant of the
permutation matrix: a few transpositions, many, and whole shuffles (long cycles, which the
pointer doubling must follow to their ends)."""
import numpy as np
import pytest

from tca_casadi.solvers.linearisation import _parity


@pytest.mark.parametrize("n, swaps", [(40, 0), (40, 1), (40, 5), (200, 3), (200, 150)])
def test_parity_is_the_sign_of_the_permutation_matrix(n, swaps):
    rng = np.random.default_rng(n + swaps)
    for _ in range(20):
        permutation = np.arange(n)
        for _ in range(swaps):                      # random transpositions (some may undo others)
            i, j = rng.choice(n, 2, replace=False)
            permutation[[i, j]] = permutation[[j, i]]
        matrix = np.zeros((n, n))
        matrix[np.arange(n), permutation] = 1.0
        assert _parity(permutation) == int(round(np.linalg.det(matrix)))


@pytest.mark.parametrize("n", [1, 2, 3, 7, 64, 65, 300])
def test_parity_of_shuffles(n):
    rng = np.random.default_rng(n)
    for _ in range(10):
        permutation = rng.permutation(n)
        matrix = np.zeros((n, n))
        matrix[np.arange(n), permutation] = 1.0
        assert _parity(permutation) == int(round(np.linalg.det(matrix)))

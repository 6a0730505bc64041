"""The structured Jacobian's pieces against CasADi's own Jacobian."""
import casadi as ca
import numpy as np
from numpy.testing import assert_allclose

from tca_casadi.discretisation.structure import split_jacobian


def _arrowhead(n, seed):
    """``g(z)`` (n + 2,) of ``z`` (n + 3,): each row nonlinear in its own few unknowns and the three
    last ones (dense columns, like a free body's pose), plus two rows that sum every unknown
    (dense rows, like its force balance)."""
    rng = np.random.default_rng(seed)
    z = ca.SX.sym("z", n + 3)
    pose = z[n:]
    rows = [ca.sin(z[k] * pose[0]) + z[(k + 1) % n] ** 2 * pose[1] + ca.exp(0.1 * pose[2] * z[k])
            for k in range(n)]
    rows.append(ca.sum1(ca.cos(z[:n]) * rng.normal(size=n)) * pose[0])
    rows.append(ca.sum1(z[:n] ** 3) + ca.dot(pose, pose))
    return ca.vertcat(*rows), z


def test_split_jacobian_is_casadis_jacobian_on_dense_rows_and_columns():
    """The three blocks put back together are CasADi's Jacobian: the same pattern and the same
    values at random points (to roundoff), with dense rows and columns to split and without."""
    for n, dense in ((60, 24), (60, 1000), (10, 2)):
        g, z = _arrowhead(n, seed=n)
        whole, split = ca.jacobian(g, z), split_jacobian(g, z, dense=dense)
        assert split.sparsity() == whole.sparsity()
        f = ca.Function("f", [z], [whole.nz[:], split.nz[:]])
        for seed in range(3):
            a, b = f(np.random.default_rng(seed).normal(size=z.numel()))
            assert_allclose(np.array(b).ravel(), np.array(a).ravel(), rtol=1e-14, atol=1e-14)

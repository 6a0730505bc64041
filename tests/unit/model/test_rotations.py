"""Rotations of non-unit quaternions."""
import casadi as ca
import numpy as np
from numpy.testing import assert_allclose
import pytest

from tca_casadi.model.rotations import matrix_to_quaternion, quaternion_product, rotation_matrix, rotation_numpy


@pytest.mark.parametrize("h", [[1, 0, 0, 0], [0.3, -1.2, 0.7, 2.0], [5.0, 0.1, 0.2, -0.3]])
def test_rotation_from_nonunit_quaternion(h):
    R = rotation_numpy(h)
    assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    q = matrix_to_quaternion(R)
    assert_allclose(np.abs(q @ (np.array(h) / np.linalg.norm(h))), 1.0, rtol=0, atol=1e-12)


def test_quaternion_product_composes_rotations():
    a, b = ca.DM([0.3, -1.2, 0.7, 2.0]), ca.DM([1.0, 0.4, -0.2, 0.1])
    lhs = np.array(rotation_matrix(quaternion_product(a, b)))
    assert_allclose(lhs, rotation_numpy(a) @ rotation_numpy(b), rtol=0, atol=1e-14)



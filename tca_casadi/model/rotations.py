"""Rotations from non-unit quaternions ``h = [h0, h1, h2, h3]`` (Rucker 2018), SPEC section 2.

Every function accepts CasADi symbols (SX/MX) or numbers; ``R(h)`` is a rotation for any h != 0.
"""
import functools

import casadi as ca
import numpy as np


def rotation_matrix(h):
    """Body-to-global rotation ``R(h) = I + 2/(h.h) M(h)``, shape (3, 3). On MX, one call of
    :data:`ROTATION` (the same expression once expanded, built in one node instead of forty)."""
    if isinstance(h, ca.MX) and h.shape == (4, 1):
        return ROTATION(h)
    h0, h1, h2, h3 = h[0], h[1], h[2], h[3]
    m = ca.vertcat(
        ca.horzcat(-h2**2 - h3**2, h1 * h2 - h3 * h0, h1 * h3 + h2 * h0),
        ca.horzcat(h1 * h2 + h3 * h0, -h1**2 - h3**2, h2 * h3 - h1 * h0),
        ca.horzcat(h1 * h3 - h2 * h0, h2 * h3 + h1 * h0, -h1**2 - h2**2))
    return ca.DM.eye(3) + 2.0 / (h0**2 + h1**2 + h2**2 + h3**2) * m


def omega(u):
    """``Omega(u)`` with ``h' = 1/2 Omega(u) h``, shape (4, 4)."""
    ux, uy, uz = u[0], u[1], u[2]
    return ca.vertcat(
        ca.horzcat(0, -ux, -uy, -uz),
        ca.horzcat(ux, 0, uz, -uy),
        ca.horzcat(uy, -uz, 0, ux),
        ca.horzcat(uz, uy, -ux, 0))


def quaternion_product(a, b):
    """Hamilton product ``a * b``: ``R(a * b) = R(a) R(b)``."""
    a0, av = a[0], ca.vertcat(a[1], a[2], a[3])
    b0, bv = b[0], ca.vertcat(b[1], b[2], b[3])
    return ca.vertcat(a0 * b0 - ca.dot(av, bv), a0 * bv + b0 * av + ca.cross(av, bv))


_h = ca.SX.sym("h", 4)
#: CasADi Function ``R = rotation(h)``
ROTATION = ca.Function("rotation", [_h], [rotation_matrix(_h)], ["h"], ["R"])


@functools.lru_cache(maxsize=64)
def _mapped_rotation(n):
    from ..buffers import BufferedFunction
    return BufferedFunction(ROTATION.map(n))


def rotations_of(h):
    """:data:`ROTATION` of ``n`` quaternions ``h`` (4, n) as an array (3, 3, n) (the mapped
    Function built once per ``n``, evaluated into buffers)."""
    h = np.asarray(h, float)
    n = h.shape[1]
    values = _mapped_rotation(n)(h.ravel(order="F"))[0]           # R_k column-major, side by side
    return values.reshape(3, 3, n, order="F").copy()


def rotation_numpy(h):
    """``R(h)`` for a numpy quaternion (4,) -> (3, 3) (:func:`rotations_of` of one: buffered,
    about a hundredth of calling :data:`ROTATION` on a DM)."""
    return rotations_of(np.asarray(h, dtype=float).reshape(4, 1))[:, :, 0]


def matrix_to_quaternion(R):
    """Unit quaternion ``[w, x, y, z]`` (w >= 0) of a rotation matrix (3, 3) (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    trace = np.trace(R)
    candidates = [trace, R[0, 0], R[1, 1], R[2, 2]]
    k = int(np.argmax(candidates))
    if k == 0:
        w = 0.5 * np.sqrt(1 + trace)
        q = [w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)]
    else:
        i, j, l = [(0, 1, 2), (1, 2, 0), (2, 0, 1)][k - 1]
        x = 0.5 * np.sqrt(1 + R[i, i] - R[j, j] - R[l, l])
        q = [0.0] * 4
        q[0] = (R[l, j] - R[j, l]) / (4 * x)
        q[1 + i] = x
        q[1 + j] = (R[j, i] + R[i, j]) / (4 * x)
        q[1 + l] = (R[l, i] + R[i, l]) / (4 * x)
    q = np.array(q)
    return q if q[0] >= 0 else -q


def rotation_angle(R_a, R_b):
    """Angle [rad] of the rotation ``R_a^T R_b``."""
    c = (np.trace(np.asarray(R_a).T @ np.asarray(R_b)) - 1.0) / 2.0
    return float(np.arccos(np.clip(c, -1.0, 1.0)))

"""Arithmetic that works on numbers, numpy arrays and CasADi symbols alike, so that each piece
of physics is written once and evaluated symbolically (inside an NLP) or numerically (in
post-processing) from the same code."""
import numpy as np


def is_casadi(value):
    """True for a CasADi symbol or matrix (checked without importing CasADi)."""
    return type(value).__module__.split(".")[0] == "casadi"


def _casadi():
    import casadi as ca
    return ca


def cos(x):
    return _casadi().cos(x) if is_casadi(x) else np.cos(x)


def sin(x):
    return _casadi().sin(x) if is_casadi(x) else np.sin(x)


def tanh(x):
    return _casadi().tanh(x) if is_casadi(x) else np.tanh(x)


def sqrt(x):
    return _casadi().sqrt(x) if is_casadi(x) else np.sqrt(x)


def clip(x, low, high):
    """``x`` clamped to ``[low, high]`` (CasADi ``fmin``/``fmax`` for symbols)."""
    if is_casadi(x) or is_casadi(low) or is_casadi(high):
        ca = _casadi()
        return ca.fmin(ca.fmax(x, low), high)
    return np.minimum(np.maximum(x, low), high)


def vector(*items):
    """Column of the scalars ``items``: a CasADi column if any is symbolic, else a numpy array."""
    if any(is_casadi(item) for item in items):
        return _casadi().vertcat(*items)
    return np.array([float(item) for item in items])


def cross(a, b):
    """Cross product of 3-vectors, or column by column of (3, k) arrays; CasADi if either is
    symbolic."""
    if is_casadi(a) or is_casadi(b):
        return _casadi().cross(a, b)
    a, b = np.asarray(a, float), np.asarray(b, float)        # row by row: np.cross's axis shuffling costs more
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def placement_matrix(radius, angle):
    """``radius Rz(angle)`` (3, 3): a route's unit data (radius 1, angle 0) placed on the body."""
    c, s = cos(angle), sin(angle)
    if is_casadi(radius) or is_casadi(angle):
        ca = _casadi()
        return radius * ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
    return float(radius) * np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def matmul(matrix, data):
    """``matrix @ data`` for a numpy or CasADi ``matrix`` and numpy ``data``."""
    if is_casadi(matrix):
        return _casadi().mtimes(matrix, _casadi().DM(data))
    return matrix @ data


__all__ = ["is_casadi", "cos", "sin", "sqrt", "clip", "vector", "placement_matrix", "matmul"]

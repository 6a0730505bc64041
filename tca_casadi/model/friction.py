"""Coulomb's cone, written once (issue 37): how far a contact's tangential force is inside the
cone its normal force allows. Every place that asks (the friction equations, the contact and
support results, the slipping verdicts) calls :func:`cone_margin`."""
import numpy as np

from .arith import is_casadi


def cone_margin(friction, normal_force, tangential, smoothing=0.0):
    """``mu f_n - |f_t|`` [N]: positive inside Coulomb's cone, zero on it, negative outside.

    ``tangential``: (3,) [N], or (k, 3) rows for k contacts (numpy; ``normal_force`` then (k,));
    numbers or CasADi. ``smoothing`` [N]: ``|f_t|`` taken as ``sqrt(|f_t|^2 + smoothing^2)`` (a
    C-infinity margin for Newton; zero in results)."""
    if is_casadi(tangential) or is_casadi(normal_force):
        import casadi as ca
        return friction * normal_force - ca.sqrt(ca.dot(tangential, tangential) + smoothing ** 2)
    tangential = np.asarray(tangential, float)
    size = np.sqrt(np.sum(tangential * tangential, axis=-1) + smoothing ** 2)
    margin = friction * np.asarray(normal_force, float) - size
    return float(margin) if np.ndim(margin) == 0 else margin


__all__ = ["cone_margin"]

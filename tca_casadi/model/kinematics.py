"""The reference (unloaded) shape of a robot, integrated exactly for constant strains: each
module's pose along s from its base through its connector on its parent's tip. Used by the
model (clearance checks of the reference state), the initial guesses of both solvers and the
drawings."""
import numpy as np
from scipy.linalg import expm

import casadi as ca

from .rotations import omega, quaternion_product, rotation_numpy


def _hat(u):
    """The cross-product matrix ``[u]x``."""
    return np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])


def _omega(u):
    return np.array(omega(ca.DM(u)))


def _qmul(a, b):
    return np.array(quaternion_product(ca.DM(a), ca.DM(b))).ravel()


def reference_states(module, s, p0, h0):
    """States ``[p, h, u, v]`` (13, n) of a module in its reference shape (strains xi*) at ``s``."""
    u, v = module.xi_star[:3], module.xi_star[3:]
    twist = np.zeros((4, 4))
    twist[:3, :3], twist[:3, 3] = _hat(u), v
    R0 = rotation_numpy(h0)
    out = np.zeros((13, len(s)))
    for k, sk in enumerate(s):
        g = expm(twist * sk)
        out[0:3, k] = p0 + R0 @ g[:3, 3]
        out[3:7, k] = expm(0.5 * _omega(u) * sk) @ h0
    out[7:13] = module.xi_star[:, None]
    return out


def reference_chain(robot, params, samples):
    """Every module's reference shape from the base pose in ``params``, each on its parent's tip
    through its connector:
    ``[states (13, n_m), ...]`` at the arc lengths ``samples[m]``."""
    layout = robot.layout
    p0 = np.asarray(params[layout["base.position"]], float)
    h0 = np.asarray(params[layout["base.quaternion"]], float)
    out, ends = [], []
    for m, module in enumerate(robot.modules):
        if m > 0:
            p0, h0 = ends[module.parent]
            if module.connector is not None:
                p0 = p0 + rotation_numpy(h0) @ module.connector.offset
                h0 = _qmul(h0, module.connector.quaternion)
        states = reference_states(module, np.append(samples[m], module.length), p0, h0)
        out.append(states[:, :-1])
        ends.append((states[0:3, -1], states[3:7, -1]))
    return out


__all__ = ["reference_states", "reference_chain"]

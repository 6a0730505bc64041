"""Rod dynamics (issue 16): inertia and the velocity compatibility of a Cosserat rod, in the
statics' state and sign conventions (SPEC section 2), written once for every solver.

Besides the strains ``xi = [u, v]`` each cross-section has a body-frame linear velocity ``q``
[m/s] and angular velocity ``w`` [rad/s]. Equality of the mixed partial derivatives of the
pose (``p_st = p_ts``, ``R_st = R_ts``) gives their compatibility along the rod:

    q' = v_t - u x q + w x v            w' = u_t - u x w

and the balance laws gain the inertia of the section (density rho, area A, second moments
Ix, Iy: ``rho J = rho diag(Ix, Iy, Ix + Iy)``), which enter exactly as body-frame distributed
loads:

    f_inertial = -rho A (q_t + w x q)        l_inertial = -(rho J w_t + w x rho J w)

Time derivatives are discretised by the integrator as ``x_t = c0 x + x_hist``
(:mod:`tca_casadi.solvers.dynamics`): ``c0`` and the history ``x_hist`` are NLP parameters, so
every time step solves the same boundary-value problem in s on one built NLP.
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .arith import cross, is_casadi, vector


@dataclass(frozen=True)
class KelvinVoigt:
    """Kelvin-Voigt damping: the internal wrench ``K (xi - xi*) + B xi_t`` with
    ``B = diag(eta Ix, eta Iy, eta_s J, eta_s A, eta_s A, eta A)`` from an extensional
    ``viscosity`` eta and a ``shear_viscosity`` eta_s [Pa s] (default ``eta / 3``, the ratio of
    G to E of an incompressible material). With ``eta_s / G = eta / E = beta`` it is stiffness
    proportional, ``B = beta K``, and every mode k of the undamped rod has the damping ratio
    ``zeta_k = beta omega_k / 2``."""
    viscosity: float
    shear_viscosity: float = None

    @classmethod
    def with_ratio(cls, ratio, frequency, youngs_modulus):
        """The stiffness-proportional damping (eta_s = eta / 3) with damping ratio ``ratio`` at
        ``frequency`` [Hz] for a material of Young's modulus [Pa]: ``eta = 2 ratio E / omega``."""
        return cls(2.0 * ratio * youngs_modulus / (2.0 * np.pi * frequency))

    def matrix(self, module):
        """The diagonal of ``B`` (6,) of ``module`` [N m^2 s, N s]."""
        eta = self.viscosity
        shear = eta / 3.0 if self.shear_viscosity is None else self.shear_viscosity
        props = module.properties
        return np.array([eta * props.ix, eta * props.iy, shear * props.torsion, shear * props.area,
                         shear * props.area, eta * props.area])


def inertia_per_length(module, param):
    """``(rho A [kg/m], rho J (3,) [kg m])`` of a module at the parameters (numbers or CasADi
    symbols): its material's density times the section's area and ``diag(Ix, Iy, Ix + Iy)``."""
    density = param(f"materials.{module.material}.density")[0]
    props = module.properties
    return density * props.area, vector(density * props.ix, density * props.iy, density * (props.ix + props.iy))


def velocity_rates(u, v, q, w, u_t, v_t):
    """``(q', w')``: the velocity compatibility ``q' = v_t - u x q + w x v``,
    ``w' = u_t - u x w`` (all body frame; numbers or CasADi symbols)."""
    return v_t - ca.cross(u, q) + ca.cross(w, v), u_t - ca.cross(u, w)


def inertial_loads(q, w, q_t, w_t, mass, rotary):
    """Body-frame distributed force and moment of the section's inertia [N/m, N m/m]:
    ``-rho A (q_t + w x q)`` and ``-(rho J w_t + w x rho J w)`` (``mass`` = rho A, ``rotary`` =
    the diagonal of rho J, (3,); q, w, q_t, w_t: (3, k), numpy or CasADi)."""
    if is_casadi(w) or is_casadi(q) or is_casadi(mass) or is_casadi(rotary):
        rotary = (ca.DM(rotary) if isinstance(rotary, np.ndarray) else rotary) @ ca.DM.ones(1, w.shape[1])
    else:
        rotary = np.asarray(rotary, float).reshape(3, 1)
    spin = rotary * w
    return -mass * (q_t + cross(w, q)), -(rotary * w_t + cross(w, spin))


def point_mass_of(load, param):
    """The mass [kg] a point load carries: a ``mass`` load's, a held object's share
    (``held * mass * share``, as its weight), none for a force."""
    if load.kind == "mass":
        return param(f"{load.name}.mass")[0]
    if load.kind == "object":
        return param(f"{load.name}.held")[0] * param(f"{load.name}.mass")[0] * load.share
    return 0.0


def point_inertia(mass, q, w, q_t, w_t, offset=None):
    """Body-frame wrench ``[moment; force]`` (6,) of a rigid point mass fixed in the section's
    frame at ``offset`` (3,) from the centreline (None: on it): ``F = -mass a`` with the
    body-frame acceleration ``a = q_t + w x q + w_t x c + w x (w x c)``, and ``c x F`` (its
    rotary inertia about its own centre neglected). Numbers (numpy) or CasADi symbols."""
    symbolic = any(is_casadi(v) for v in (mass, q, w, q_t, w_t))
    stack = ca.vertcat if symbolic else (lambda a, b: np.concatenate([np.ravel(a), np.ravel(b)]))
    acceleration = q_t + cross(w, q)
    if offset is None:
        return stack(ca.DM.zeros(3) if symbolic else np.zeros(3), -mass * acceleration)
    c = ca.DM(offset) if symbolic else np.asarray(offset, float)
    acceleration = acceleration + cross(w_t, c) + cross(w, cross(w, c))
    force = -mass * acceleration
    return stack(cross(c, force), force)


def kinetic_energy_density(q, w, mass, rotary):
    """``rho A |q|^2 / 2 + w . rho J w / 2`` [J/m] at each node (q, w: (3, n) numpy)."""
    return 0.5 * mass * np.sum(q * q, axis=0) + 0.5 * np.sum(np.asarray(rotary)[:, None] * w * w, axis=0)


def elastic_energy_density(stiffness, deviation):
    """``(xi - xi*) . K (xi - xi*) / 2`` [J/m] at each node (deviation: (6, n) numpy)."""
    return 0.5 * np.sum(np.asarray(stiffness)[:, None] * deviation * deviation, axis=0)

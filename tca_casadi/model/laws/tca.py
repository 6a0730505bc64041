"""The TCA's own law by Castigliano's second theorem (SPEC section 4).

``delta = A_cst (dtheta(T) - dtheta(T_ref)) + F / K_cst(F)``, with
``A_cst = l_t r_c cos(alpha)``, ``1/K_cst = l_t r_c^2 cos^2(alpha) / (G_t(F) J_t)``,
``J_t = pi r_t^4 / 2``. The residual is multiplied through by ``G_t(F)`` (never divided).
Every method accepts CasADi symbols or numpy arrays, and so may the constants themselves (the
geometry and the fits are NLP parameters: :meth:`TcaLaw.from_parameters`).
"""
import math
from dataclasses import dataclass

import numpy as np

from ..arith import cos, is_casadi, sin
from ...catalogue.tca import Tca
from .base import HeatedLaw, compression_warnings


@dataclass(frozen=True)
class TcaLaw(Tca, HeatedLaw):
    """Constants of one TCA. Units: m, N, Pa, degC, rad/m. Its type lives in ``tca_types``
    (its parameters: :data:`tca_casadi.catalogue.tca.TCA_KEYS`)."""
    coil_radius: float
    fiber_radius: float
    pitch_angle: float
    fiber_length: float
    reference_length: float
    reference_temperature: float
    untwist_coefficients: tuple  # (c2, c1, c0), rad/m
    shear_coefficients: tuple    # (a2, a1, a0), Pa
    min_temperature: float = -273.15   # degC: the range the law is validated for
    max_temperature: float = float("inf")
    fiber_length_given: bool = False   # the type gives fiber_length (else l* / sin(alpha))

    @classmethod
    def from_type(cls, tca_type, reference_length, **context):
        """Law of a TCA of ``tca_type`` whose path has reference length ``l*`` [m]."""
        alpha = tca_type.pitch_angle
        fiber = tca_type.fiber_length or reference_length / math.sin(alpha)
        return cls(tca_type.coil_radius, tca_type.fiber_radius, alpha, fiber, reference_length,
                   tca_type.reference_temperature,
                   (tca_type.untwist.c2, tca_type.untwist.c1, tca_type.untwist.c0),
                   (tca_type.shear_modulus.a2, tca_type.shear_modulus.a1, tca_type.shear_modulus.a0),
                   tca_type.min_temperature, tca_type.max_temperature, tca_type.fiber_length is not None)

    def with_parameters(self, param, prefix, reference_length):
        return TcaLaw.from_parameters(self, param, prefix, reference_length, self.fiber_length_given)

    @classmethod
    def from_parameters(cls, nominal, param, prefix, reference_length, fiber_length_given):
        """The law with every constant read from the parameter vector (``param(name)``, names
        ``prefix + 'coil_radius'`` ...; see :mod:`tca_casadi.model.parameters`): numbers or CasADi
        symbols. ``reference_length`` is the path's ``l*`` at those parameters; without a given
        fiber length it is ``l* / sin(alpha)``. ``nominal`` supplies the validated range."""
        value = lambda key: param(prefix + key)[0]          # noqa: E731
        alpha = value("pitch_angle")
        fiber = value("fiber_length") if fiber_length_given else reference_length / sin(alpha)
        return cls(value("coil_radius"), value("fiber_radius"), alpha, fiber, reference_length,
                   value("reference_temperature"),
                   tuple(value(f"untwist.{c}") for c in ("c2", "c1", "c0")),
                   tuple(value(f"shear_modulus.{a}") for a in ("a2", "a1", "a0")),
                   nominal.min_temperature, nominal.max_temperature, fiber_length_given)

    @property
    def stroke_coefficient(self):
        """``A_cst = l_t r_c cos(alpha)`` [m^2]."""
        return self.fiber_length * self.coil_radius * cos(self.pitch_angle)

    @property
    def compliance_numerator(self):
        """``l_t r_c^2 cos^2(alpha) / J_t`` [1/m]: ``1/K_cst = this / G_t``."""
        polar = math.pi * self.fiber_radius**4 / 2.0
        return self.fiber_length * self.coil_radius**2 * cos(self.pitch_angle)**2 / polar

    @property
    def monotone_limit(self):
        """Tension [N] where ``F / G_t(F)`` peaks: beyond it the fit is not monotone."""
        a2, _, a0 = self.shear_coefficients
        return math.sqrt(a0 / a2) if a2 > 0 else math.inf

    def untwist(self, temperature):
        """``dtheta(T)`` [rad per m of fiber]."""
        c2, c1, c0 = self.untwist_coefficients
        return c2 * temperature**2 + c1 * temperature + c0

    def free_stroke(self, temperature):
        """Free stroke [m] at zero force (negative = contraction)."""
        return self.stroke_coefficient * (self.untwist(temperature)
                                          - self.untwist(self.reference_temperature))

    def shear_modulus(self, force):
        """``G_t(F)`` [Pa]: the fit for F >= 0, a positive C1 exponential extension for F < 0."""
        a2, a1, a0 = self.shear_coefficients
        fit = a2 * force**2 + a1 * force + a0
        if is_casadi(force) or is_casadi(a0):
            import casadi as ca
            extension = a0 * ca.exp(force * a1 / a0)
            return ca.if_else(force >= 0, fit, extension)
        force = np.asarray(force, dtype=float)
        return np.where(force >= 0, fit, a0 * np.exp(np.minimum(force, 0.0) * a1 / a0))

    def stretch(self, force):
        """Elastic part ``F / K_cst(F)`` [m]."""
        return force * self.compliance_numerator / self.shear_modulus(force)

    def residual(self, stroke, force, temperature):
        """``G_t(F) (delta - free_stroke(T)) - F l_t r_c^2 cos^2(alpha) / J_t`` [Pa m]."""
        return (self.shear_modulus(force) * (stroke - self.free_stroke(temperature))
                - force * self.compliance_numerator)

    @property
    def residual_scale(self):
        """A natural size of :meth:`residual` [Pa m], to scale it to order one."""
        return self.shear_coefficients[2] * self.reference_length

    # ------------------------------------------------------------------ the interface's rest
    def input_problem(self, key, value, type_path=None):
        low, high = self.input_range
        if low <= value <= high:
            return None
        return (f"{key}: {value:g} degC is outside the TCA type's validated range [{low:g}, {high:g}] degC "
                "(min_temperature, max_temperature of its tca_types entry)")

    def gap(self, stroke, force, value):
        """Slack length [m]: ``free_stroke(T) - delta`` at F = 0 (the residual over ``G_t``)."""
        return float(-self.residual(stroke, force, value) / self.shear_modulus(max(force, 0.0)))

    def warnings(self, key, stroke, force, value, tension_only):
        out = compression_warnings(key, force, tension_only, "a real TCA would buckle or go slack; the "
                                   "law's extension G_t(0) exp(F G_t'(0)/G_t(0)) was used")
        if force > self.monotone_limit:
            out.append(("fit_range", f"{key} tension {force * 1e3:.4g} mN "
                        f"is beyond the fit's monotone range ({self.monotone_limit * 1e3:.4g} mN)"))
        return out

    def structural_problems(self, key):
        out = []
        if not 0 < self.fiber_radius < self.coil_radius:
            out.append(f"{key}: need 0 < fiber_radius < coil_radius "
                       f"(got {self.fiber_radius:g} m and {self.coil_radius:g} m)")
        if not 0 < self.pitch_angle < np.pi / 2:
            out.append(f"{key}: pitch_angle {self.pitch_angle:g} rad is outside (0, pi/2)")
        if not self.shear_coefficients[2] > 0:
            out.append(f"{key}: shear_modulus.a0 must be positive")
        return out


def thermal_law(config, law):
    """The lumped :class:`~tca_casadi.model.thermal.ThermalLaw` of a TCA of type ``config`` with
    ``law`` (its fibre's length)."""
    from ..thermal import thermal_law as tca_thermal_law
    return tca_thermal_law(config, law.fiber_length)


LAW = TcaLaw

"""A McKibben pneumatic muscle: the static force-length-pressure law of Tondu and Lopez.

A braided sleeve of initial radius ``r0`` and braid angle ``alpha0`` (to the muscle's axis) around
a bladder at gauge pressure ``P`` pulls with (Tondu and Lopez, IEEE Control Systems Magazine 20
(2000) 15-38; with ``k = 1`` it is Chou and Hannaford's ideal law, IEEE Trans. Robot. Autom. 12
(1996) 90-102)::

    F = pi r0^2 P (a (1 - k eps)^2 - b),   a = 3 / tan^2(alpha0),   b = 1 / sin^2(alpha0),

``eps = (l0 - l) / l0`` the contraction ratio from its rest length ``l0`` (default: the path's
reference length ``l*``: installed at rest), ``k`` >= 1 Tondu and Lopez's correction for the
muscle's conical ends. So the blocked force (``eps = 0``) is ``pi r0^2 P (a - b)`` and the free
contraction (``F = 0``) ``eps_max = (1 - sqrt(b / a)) / k = (1 - 1 / (sqrt(3) cos alpha0)) / k``,
both independent of the pressure; the bladder's own elasticity is neglected (the ideal, thin-walled
muscle: at ``P = 0`` it carries nothing). The residual, in newtons, ``r = F_law(eps, P) - F``.

Defaults: a thin muscle of 2 mm initial radius with a 20 deg braid (braid angles of 18-25 deg
are typical of the muscles these papers test; the radius is this project's choice), ``k = 1``,
pressures up to 600 kPa.
"""
from dataclasses import dataclass
import math

from ...catalogue.mckibben import NEUTRAL_ANGLE, McKibben
from ..arith import cos, sin, sqrt
from .base import ActuatorLaw


@dataclass(frozen=True)
class McKibbenLaw(McKibben, ActuatorLaw):
    """One McKibben muscle (SI). Its type lives in ``muscle_types`` with ``kind: mckibben``."""
    reference_length: float
    radius: float = 2e-3
    braid_angle: float = math.radians(20.0)
    correction: float = 1.0
    rest_length: object = None
    max_pressure: float = 600e3

    def structural_problems(self, key):
        out = super().structural_problems(key)
        if not float(self.braid_angle) < NEUTRAL_ANGLE:
            out.append(f"{key}: braid_angle {math.degrees(float(self.braid_angle)):.4g} deg must be below 54.7 deg")
        if not float(self.correction) >= 1.0:
            out.append(f"{key}: correction {float(self.correction):g} must be at least 1")
        return out

    # ------------------------------------------------------------------ the law
    @property
    def length_at_rest(self):
        """``l0`` [m]."""
        return self.reference_length if self.rest_length is None else self.rest_length

    @property
    def coefficients(self):
        """``(a, b) = (3 / tan^2(alpha0), 1 / sin^2(alpha0))``."""
        s, c = sin(self.braid_angle), cos(self.braid_angle)
        return 3.0 * c * c / (s * s), 1.0 / (s * s)

    def contraction(self, stroke):
        """``eps = (l0 - l) / l0`` with ``l = l* + delta``."""
        return 1.0 - (self.reference_length + stroke) / self.length_at_rest

    def pulling_force(self, stroke, pressure):
        """``F = pi r0^2 P (a (1 - k eps)^2 - b)`` [N]."""
        a, b = self.coefficients
        shortening = 1.0 - self.correction * self.contraction(stroke)
        return math.pi * self.radius ** 2 * pressure * (a * shortening * shortening - b)

    def residual(self, stroke, force, pressure):
        """``F_law(eps, P) - F`` [N]."""
        return self.pulling_force(stroke, pressure) - force

    @property
    def residual_scale(self):
        """The blocked force at ``max_pressure``, ``pi r0^2 P_max (a - b)`` [N]."""
        a, b = self.coefficients
        return math.pi * self.radius ** 2 * self.max_pressure * (a - b)

    def blocked_force(self, pressure):
        """``pi r0^2 P (a - b)`` [N]: the force at the rest length."""
        a, b = self.coefficients
        return math.pi * self.radius ** 2 * pressure * (a - b)

    @property
    def free_contraction(self):
        """``eps_max = (1 - sqrt(b / a)) / k``: where the force vanishes."""
        a, b = self.coefficients
        return (1.0 - sqrt(b / a)) / self.correction

    def free_stroke(self, pressure):
        """Stroke [m] at zero force, ``l0 (1 - eps_max) - l*`` (None at zero pressure: an
        unpressurised ideal muscle carries nothing at any length)."""
        if not pressure > 0:
            return None
        return float(self.length_at_rest * (1.0 - self.free_contraction) - self.reference_length)

    # ------------------------------------------------------------------ range and warnings
    INVERSE_RANGE_TEXT = "0 to max_pressure"

    @property
    def input_range(self):
        return (0.0, self.max_pressure)


    def warnings(self, key, stroke, force, value, tension_only):
        out, eps = [], float(self.contraction(stroke))
        if value > 0 and eps < -1e-9:
            out.append(("fit_range", f"{key} is stretched {-eps * 100:.3g} % beyond its rest length: "
                        "the law is written for contraction (0 <= eps <= eps_max)"))
        if value > 0 and eps > float(self.free_contraction) + 1e-9 and not tension_only:
            out.append(("compression", f"{key} is contracted beyond its free contraction "
                        f"({float(self.free_contraction) * 100:.3g} %), so the law pushes "
                        f"(F = {force * 1e3:.4g} mN): a muscle cannot; set tension_only: true"))
        return out

    def heated(self, value):
        return value > 0


LAW = McKibbenLaw

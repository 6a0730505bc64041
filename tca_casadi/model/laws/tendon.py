"""The displacement-controlled tendon as an actuator law.

Pulled by ``q`` at its proximal end, with compliance ``C`` (strain per newton): its free length is
its reference path length ``l*``, so ``l_path + q = l* (1 + C F)``, i.e. with the stroke
``delta = l_path - l*`` (SPEC section 3) ``r = delta + q - l* C F = 0``.
"""
from dataclasses import dataclass, replace

from .base import ActuatorLaw


@dataclass(frozen=True)
class TendonLaw(ActuatorLaw):
    """A displacement-controlled tendon: reference length ``l*`` [m], compliance [1/N]."""
    reference_length: float
    compliance: float

    KIND = "tendon"
    INPUT = ("displacement", "length", 0.0)

    def with_parameters(self, param, prefix, reference_length):
        return replace(self, reference_length=reference_length)

    def residual(self, stroke, force, displacement):
        """``delta + q - l* C F`` [m]."""
        return stroke + displacement - self.reference_length * self.compliance * force

    @property
    def residual_scale(self):
        return self.reference_length

    def free_stroke(self, displacement):
        """The stroke at which the tendon is just taut, ``-q`` [m]."""
        return -displacement

    def gap(self, stroke, force, displacement):
        """Slack length [m]: how much longer the tendon is than its path (0 when taut)."""
        return float(-self.residual(stroke, force, displacement))

"""Length conditions of actuators with unknown tension, written once for both solvers.

* a TCA: its law (SPEC section 4), ``r = G_t(F) (delta - free(T)) - F l_t r_c^2 cos^2(a) / J_t``;
* a displacement-controlled tendon, pulled by ``q`` at its proximal end, with compliance ``C``
  (strain per newton): the tendon's free length is its reference path length ``l*``, so
  ``l_path + q = l* (1 + C F)``, i.e. with the stroke ``delta = l_path - l*`` (SPEC section 3)
  ``r = delta + q - l* C F = 0``.

Both are scaled to order one (``r / scale``). A ``tension_only`` actuator may go slack: with the
gap ``s = -r / scale`` (how much longer the free actuator is than its path, scaled) the condition
is the complementarity ``F >= 0, s >= 0, F s = 0``, written as the smoothed Fischer-Burmeister
equation ``F/F_s + s - sqrt((F/F_s)^2 + s^2 + eps^2) = 0`` (``eps`` = 1e-9). It is smooth, so
Newton, IPOPT and the shooting solver's root finder all take it as is; at ``F > 0`` it moves
the taut condition by about ``eps^2 F_s / (2 F)``, far below the solver tolerance.
"""
from dataclasses import dataclass


from .arith import sqrt

SMOOTHING = 1e-9


@dataclass(frozen=True)
class TendonLaw:
    """A displacement-controlled tendon: reference length ``l*`` [m], compliance [1/N]."""
    reference_length: float
    compliance: float

    def residual(self, stroke, force, displacement):
        """``delta + q - l* C F`` [m]."""
        return stroke + displacement - self.reference_length * self.compliance * force

    @property
    def residual_scale(self):
        return self.reference_length

    def gap(self, stroke, force, displacement):
        """Slack length [m]: how much longer the tendon is than its path (0 when taut)."""
        return -self.residual(stroke, force, displacement)


def compatibility(actuator, law, stroke, force, parameter, force_scale):
    """The scaled length condition of an actuator with unknown tension (see module docstring);
    ``law`` is its law at the current parameters (scaled by the nominal law's size)."""
    scaled = law.residual(stroke, force, parameter) / actuator.law.residual_scale
    if not actuator.tension_only:
        return scaled
    f, s = force / force_scale, -scaled
    return f + s - sqrt(f * f + s * s + SMOOTHING**2)


def compatibility_residuals(robot, lengths, tension, param):
    """The scaled length condition of every actuator with unknown tension (``robot.unknowns``
    order); ``lengths[k]`` is the path length of ``robot.actuators[k]`` [m]."""
    out = []
    for actuator in robot.unknowns:
        law = actuator.law_of(param)
        stroke = lengths[robot.actuators.index(actuator)] - law.reference_length
        out.append(compatibility(actuator, law, stroke, tension(actuator), param(actuator.parameter)[0],
                                 robot.modules[actuator.module].force_scale))
    return out


#: a gap below this fraction of the reference length counts as taut (the smoothing leaves
#: about 1e-9 of it at the switching point)
TAUT = 1e-7


def slack_length(actuator, stroke, force, parameter):
    """Slack length [m] of a ``tension_only`` actuator (0 when taut, None otherwise)."""
    if not actuator.tension_only:
        return None
    law = actuator.law
    if isinstance(law, TendonLaw):
        gap = law.gap(stroke, force, parameter)
    else:
        gap = -law.residual(stroke, force, parameter) / law.shear_modulus(max(force, 0.0))
    return float(gap) if gap > TAUT * actuator.reference_length else 0.0

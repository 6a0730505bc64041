"""Length conditions of actuators with unknown tension, written once for both solvers: each
actuator's law (:mod:`tca_casadi.model.laws`: a TCA, a displacement tendon, an SMA wire, a
McKibben muscle, a user's law) gives ``r(delta, F, u)``, zero on the law and positive when the
path is longer than the free actuator at that tension.

Each is scaled to order one (``r / scale``). A ``tension_only`` actuator may go slack: with the
gap ``s = -r / scale`` (how much longer the free actuator is than its path, scaled) the condition
is the complementarity ``F >= 0, s >= 0, F s = 0``, written as the smoothed Fischer-Burmeister
equation ``F/F_s + s - sqrt((F/F_s)^2 + s^2 + eps^2) = 0`` (``eps`` = 1e-9). It is smooth, so
Newton, IPOPT and the shooting solver's root finder all take it as is; at ``F > 0`` it moves
the taut condition by about ``eps^2 F_s / (2 F)``, far below the solver tolerance.
"""
from .arith import sqrt

SMOOTHING = 1e-9


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
    gap = actuator.law.gap(stroke, force, parameter)
    return float(gap) if gap > TAUT * actuator.reference_length else 0.0

"""What can be measured on a robot, as CasADi expressions of a collocation NLP's variables
``(w, P)``: its tip, any module's end, any actuator's stroke, length or tension. Calibration
fits these to data; their derivatives (exact, by CasADi) carry the implicit-function-theorem
sensitivities of the states to the measured quantities.

Names (the columns of a measurement file, without their ``[unit]``):

    tip_x, tip_y, tip_z                      the robot's tip [m]
    MODULE.tip_x, MODULE.tip_y, MODULE.tip_z  a module's end [m]
    ACTUATOR.stroke, ACTUATOR.length          an actuator's ``l - l*`` and ``l`` [m] (e.g. bending.tca1)
    ACTUATOR.tension                          its tension [N]
"""
import casadi as ca

from ..errors import ScenarioError

AXES = {"tip_x": 0, "tip_y": 1, "tip_z": 2}
ACTUATOR_QUANTITIES = ("stroke", "length", "tension")


def quantity_kind(robot, name):
    """``"length"`` or ``"force"`` for a measurable quantity's name, None if it is not one."""
    if name in AXES:
        return "length"
    stem, _, what = name.rpartition(".")
    if what in AXES and stem in [m.name for m in robot.modules]:
        return "length"
    if what in ACTUATOR_QUANTITIES and stem in [a.key for a in robot.actuators]:
        return "force" if what == "tension" else "length"
    return None


def measurable_names(robot):
    """Every measurable quantity's name, for messages."""
    names = list(AXES) + [f"{m.name}.{a}" for m in robot.modules for a in AXES]
    return names + [f"{a.key}.{q}" for a in robot.actuators for q in ACTUATOR_QUANTITIES]


def measurement_function(nlp, names):
    """``ca.Function (w, P) -> (y (k,), dy/dw, dy/dP)`` of the quantities ``names`` (expanded to
    SX: cheap to evaluate and differentiate)."""
    robot = nlp.robot
    lengths, ends, _ = nlp.outputs(nlp.w, nlp.P)
    values = []
    for name in names:
        stem, _, what = name.rpartition(".")
        if name in AXES:
            values.append(ends[AXES[name], robot.tip_index])
        elif what in AXES and stem in [m.name for m in robot.modules]:
            values.append(ends[AXES[what], [m.name for m in robot.modules].index(stem)])
        elif what in ACTUATOR_QUANTITIES and stem in [a.key for a in robot.actuators]:
            index = [a.key for a in robot.actuators].index(stem)
            actuator = robot.actuators[index]
            if what == "tension":
                values.append(nlp.tension_of(actuator))
            elif what == "length":
                values.append(lengths[index])
            else:
                values.append(lengths[index] - actuator.reference_length_of(nlp.param))
        else:
            raise ScenarioError(f"{name!r} is not a measurable quantity; measurable: {', '.join(measurable_names(robot))}")
    y = ca.vertcat(*values)
    value = ca.Function("measure", [nlp.w, nlp.P], [y]).expand()
    w, P = ca.SX.sym("w", nlp.w.numel()), ca.SX.sym("P", nlp.P.numel())
    y_sx = value(w, P)
    return ca.Function("measure_jacobian", [w, P], [y_sx, ca.jacobian(y_sx, w), ca.jacobian(y_sx, P)])

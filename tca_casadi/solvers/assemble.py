"""Turn a solver's raw result (node states, tensions, lengths) into a :class:`Solution`.
Shared by every solver so that all report the same quantities the same way."""
import functools

import numpy as np

from ..errors import PhysicsWarning
from ..model.balance import global_balance, load_markers
from ..model.compatibility import slack_length
from ..model.rotations import rotations_of
from ..solution import ActuatorResult, ModuleResult, Solution

#: a tension_only actuator with less tension than this fraction of its module's force scale is
#: at the corner of its complementarity (taut with no tension: just taut, or an unpressurised
#: McKibben muscle); the smoothing leaves about 1e-9 of it there
CORNER = 1e-6
#: a global balance residual above this (relative to the forces in play) is reported
BALANCE_TOLERANCE = 1e-6


def module_result(module, s, states, base_wrench_body, weights):
    """:class:`ModuleResult` from node states (13, n) at arc lengths s (n,) with the solver's
    quadrature weights (n,) [m]."""
    R = rotations_of(states[3:7])                                            # (3, 3, n)
    wrench = module.stiffness[:, None] * (states[7:13] - module.xi_star[:, None])
    moment = np.einsum("ijk,jk->ik", R, wrench[0:3])
    force = np.einsum("ijk,jk->ik", R, wrench[3:6])
    R0 = R[:, :, 0]
    reaction = {"force": -R0 @ base_wrench_body[3:6], "moment": -R0 @ base_wrench_body[0:3]}
    return ModuleResult(module.name, s, states[0:3], states[3:7], R, states[7:10], states[10:13],
                        force, moment, reaction, section_outline(module.section), np.asarray(weights, float))


def section_outline(section, points=48):
    """Body-frame polygon (3, k) of the body's outline (the envelope where one is given); read
    only (one array per outline, shared by every solution)."""
    outline = section.envelope or section
    if outline.shape == "circle":
        return _outline("circle", outline.diameter / 2, 0.0, points)
    return _outline("rectangle", outline.width / 2, outline.height / 2, points)


@functools.lru_cache(maxsize=64)
def _outline(shape, a, b, points):
    if shape == "circle":
        angle = np.linspace(0, 2 * np.pi, points)
        polygon = np.vstack([a * np.cos(angle), a * np.sin(angle), np.zeros(points)])
    else:
        polygon = np.array([[-a, a, a, -a, -a], [-b, -b, b, b, -b], [0, 0, 0, 0, 0]], dtype=float)
    polygon.flags.writeable = False
    return polygon


def actuator_result(actuator, module_res, tension, length, parameter, force_scale=1.0):
    """:class:`ActuatorResult`: the path ``p + R r`` over the actuator's span; ``parameter`` is
    the actuator's temperature, tension or displacement; ``force_scale`` [N] its module's
    ``EI / L^2`` (a ``tension_only`` actuator with less than :data:`CORNER` of it is at the
    corner of its complementarity)."""
    s_a, s_b = actuator.route.span
    tol = 1e-12 * max(1.0, s_b)
    inside = (module_res.s >= s_a - tol) & (module_res.s <= s_b + tol)
    r = actuator.route.evaluate(np.clip(module_res.s[inside], s_a, s_b))[0]
    path = module_res.p[:, inside] + np.einsum("ijk,jk->ik", module_res.R[:, :, inside], r)
    law = actuator.law if actuator.is_muscle else None
    stroke = float(length) - actuator.reference_length
    free = law.free_stroke(parameter) if law is not None else None
    own = {name: float(parameter) if actuator.control == name else None
           for name in ("temperature", "displacement", "pressure", "input")}
    return ActuatorResult(
        key=actuator.key, kind=actuator.kind, temperature=own["temperature"],
        reference_temperature=getattr(law, "reference_temperature", None) if own["temperature"] is not None else None,
        tension=float(tension), length=float(length), reference_length=actuator.reference_length,
        free_stroke=None if free is None else float(free), path=path,
        control=actuator.control, tension_only=actuator.tension_only, displacement=own["displacement"],
        slack_length=slack_length(actuator, stroke, float(tension), float(parameter)),
        pressure=own["pressure"], input=own["input"], heated=bool(law is not None and law.heated(parameter)),
        at_corner=bool(actuator.tension_only and abs(float(tension)) <= CORNER * force_scale))


def physics_warnings(robot, actuators, params):
    """Warnings for slack actuators and what each muscle's law says of its state (a TCA in
    compression or beyond its fit's monotone range, an SMA wire over its stress limit...)."""
    out = []
    for actuator in robot.unknowns:
        result = actuators[actuator.key]
        if result.slack_length:
            out.append(PhysicsWarning("slack", f"{actuator.key} is slack (F = 0; slack length {result.slack_length * 1e3:.4g} mm)"))
        if actuator.is_muscle:
            value = float(params[robot.layout[actuator.parameter]][0])
            out.extend(PhysicsWarning(kind, message) for kind, message in
                       actuator.law.warnings(actuator.key, result.stroke, result.tension, value, actuator.tension_only))
    return out


def build_solution(robot, params, module_data, tensions, lengths, result, method, raw, notices=(), extra_loads=None):
    """Solution from ``module_data = [(s, states, base_wrench_body, weights), ...]``, tensions per
    actuator (list in ``robot.actuators`` order) and lengths; ``result`` the
    :class:`SolveStatus`, ``method`` the solver's name, ``raw`` its variables (``w`` or ``z``),
    ``notices`` the solver's own :class:`PhysicsWarning` s (e.g. a floored tolerance);
    ``extra_loads``: ``(points, forces, moments)`` (3, k) global, beyond the robot's own loads,
    for the global balance (a dynamic step's inertial loads)."""
    robot = robot.at(params)          # stiffness, routes, laws at these parameters
    modules = [module_result(robot.modules[m], *data) for m, data in enumerate(module_data)]
    actuators = {}
    for k, actuator in enumerate(robot.actuators):
        parameter = params[robot.layout[actuator.parameter]][0]
        actuators[actuator.key] = actuator_result(actuator, modules[actuator.module], tensions[k],
                                                  lengths[k], parameter, robot.modules[actuator.module].force_scale)
    warnings = physics_warnings(robot, actuators, params)
    balance = global_balance(robot, modules, params, tensions, extra_loads)
    if result.success and balance.relative > BALANCE_TOLERANCE:
        warnings.append(PhysicsWarning("global_balance", f"global balance off by {balance.relative:.1e} of the forces in play "
                        f"(force {np.abs(balance.force).max():.2e} N, moment "
                        f"{np.abs(balance.moment).max():.2e} N m): the mesh is too coarse for this "
                        "robot; raise solver.intervals"))
    warnings.extend(notices)
    if not result.success:
        warnings.insert(0, not_converged(result))
    return Solution(result=result, method=method, raw=dict(raw, method=method),
                    modules=modules, actuators=actuators, warnings=warnings,
                    parameters=np.array(params, float), parameter_names=dict(robot.layout.slices),
                    scenario_name=robot.name, tip_module=robot.tip_index, balance=balance,
                    loads=load_markers(robot, modules, params))


def not_converged(result):
    """The warning an unconverged :class:`SolveStatus` puts first in its solution's warnings."""
    return PhysicsWarning("not_converged", f"not converged: {result.message}")

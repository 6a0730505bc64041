"""Turn a solver's raw result (node states, tensions, lengths) into a :class:`Solution`.
Shared by every solver so that all report the same quantities the same way."""
import functools

import numpy as np

from ..errors import PhysicsWarning
from ..model.balance import global_balance, load_markers
from ..model.compatibility import slack_length
from ..model.contact import CLOSED, contact_geometry, gaps, held_point, outline_of, outline_size
from ..model.friction import cone_margin
from ..model.rotations import rotations_of
from ..text import unit_text
from ..solution import ActuatorResult, ContactResult, ModuleResult, Solution

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
    """:class:`ActuatorResult` (its path ``p + R r`` over the actuator's span made when first
    read: :func:`actuator_path`); ``parameter`` is the actuator's temperature, tension or
    displacement; ``force_scale`` [N] its module's ``EI / L^2`` (a ``tension_only`` actuator with less than :data:`CORNER` of it is at the
    corner of its complementarity)."""
    law = actuator.law if actuator.is_muscle else None
    stroke = float(length) - actuator.reference_length
    free = law.free_stroke(parameter) if law is not None else None
    own = {name: float(parameter) if actuator.control == name else None
           for name in ("temperature", "displacement", "pressure", "input")}
    return ActuatorResult(
        key=actuator.key, kind=actuator.kind, temperature=own["temperature"],
        reference_temperature=getattr(law, "reference_temperature", None) if own["temperature"] is not None else None,
        tension=float(tension), length=float(length), reference_length=actuator.reference_length,
        free_stroke=None if free is None else float(free), path_of=functools.partial(actuator_path, actuator, module_res),
        control=actuator.control, tension_only=actuator.tension_only, displacement=own["displacement"],
        slack_length=slack_length(actuator, stroke, float(tension), float(parameter)),
        pressure=own["pressure"], input=own["input"], heated=bool(law is not None and law.heated(parameter)),
        at_corner=bool(actuator.tension_only and abs(float(tension)) <= CORNER * force_scale))


def actuator_path(actuator, module_res):
    """The path ``p + R r`` (3, n) [m] of ``actuator`` over its span of the module
    (:class:`ModuleResult`), at the module's nodes inside it."""
    s_a, s_b = actuator.route.span
    tol = 1e-12 * max(1.0, s_b)
    inside = (module_res.s >= s_a - tol) & (module_res.s <= s_b + tol)
    r = actuator.route.evaluate(np.clip(module_res.s[inside], s_a, s_b))[0]
    return module_res.p[:, inside] + np.einsum("ijk,jk->ik", module_res.R[:, :, inside], r)


def physics_warnings(robot, actuators, params):
    """Warnings where slack is a surprise (a muscle that is heated, pressurised or otherwise
    active and yet slack: its input does nothing; a passive tendon or a cool TCA going slack is
    a state, kept in the actuator table and solution.json, not a warning) and what each muscle's
    law says of its state (a TCA in compression or beyond its fit's monotone range, an SMA wire
    over its stress limit...)."""
    out = []
    for actuator in robot.unknowns:
        result = actuators[actuator.key]
        if result.slack_length and result.heated:
            out.append(PhysicsWarning("slack", f"{actuator.key} is active but slack: its input does nothing (F = 0; "
                                               f"slack length {result.slack_length * 1e3:.4g} mm)"))
        if actuator.is_muscle:
            value = float(params[robot.layout[actuator.parameter]][0])
            out.extend(PhysicsWarning(kind, message) for kind, message in
                       actuator.law.warnings(actuator.key, result.stroke, result.tension, value, actuator.tension_only))
    return out


def contact_results(robot, params, module_data, forces, clearance=None, frictions=None):
    """``(contacts, loads, clearance, warnings, pattern)`` of a solution with contacts: the
    :class:`ContactResult` of every closed contact, ``{m: (points, forces)}`` (3, k) of all of
    them for the global balance, per obstacle the body's nearest approach ``{name: {gap,
    module, s}}`` (``clearance``, the solver's search between nodes; else the nearest node)
    a penetration warning where the body cuts deeper than ``robot.contact_tolerance``, a
    ``slipping`` warning for each contact against an obstacle with friction that needs more
    than it has or slides, and, per candidate, which side of its complementarities' corners it
    is on (``f / f_s > g / g_s``: the equation's row is the gap's; continuation's corners).
    ``frictions``: ``{contact index: (f_t (3), slip multiplier)}`` [SI] of the contacts against
    obstacles with friction, whose force acts at the rod's material point the history's
    ``offset`` names (:func:`~tca_casadi.model.contact.held_point`) at ``params``."""
    closed, loads, found, warnings, pattern = [], {}, {}, [], []
    param = robot.param_function(params)
    for c in robot.contacts:
        module, shape = robot.modules[c.module], robot.obstacles[c.obstacle]
        s, states = module_data[c.module][0], module_data[c.module][1]
        state = states[:, int(np.argmin(np.abs(s - c.s)))]
        g, n, point = contact_geometry(shape, module, state)
        force = float(forces[c.index])
        tangential, multiplier = (frictions or {}).get(c.index, (np.zeros(3), 0.0))
        held, anchored = point, None
        if robot.frictional(c):
            held = _material_point(state, param, robot.contact_parameter(c, "offset"))
            anchored = np.asarray(param(f"obstacles.{shape.name}.position"), float).ravel() + \
                np.asarray(param(robot.contact_parameter(c, "anchor")), float).ravel()
        points, pushes = loads.setdefault(c.module, ([], []))
        points += [point, held]
        pushes += [force * n, np.asarray(tangential, float)]
        _closed_contact(module, c.s, "obstacle", shape.name, point, n, float(g), force, tangential, multiplier,
                        shape.friction, robot.frictional(c) and robot.friction_law == "coulomb",
                        closed, warnings, pattern, held, anchored)
    loads = {m: (np.array(p).T, np.array(f).T) for m, (p, f) in loads.items()}
    names = [shape.name for shape in robot.obstacles] + [body.name for body in robot.bodies]
    for name in names:
        shape = next((shape for shape in robot.obstacles if shape.name == name), None)
        nearest = (clearance or {}).get(name) or (_nearest_node(robot, shape, module_data) if shape else None)
        if nearest is None:
            continue
        found[name] = nearest
        if nearest["gap"] < -robot.contact_tolerance:
            what = "obstacle" if shape is not None else "object"
            warnings.append(PhysicsWarning(
                "penetration", f"module {nearest['module']} cuts {-nearest['gap'] * 1e6:.3g} {unit_text('um')} into {what} "
                f"{name!r} at s = {nearest['s'] * 1e3:.4g} mm, between contact candidates: add a point "
                "there to contact.at or raise contact.points"))
    return closed, loads, found, warnings, tuple(pattern)


def body_results(robot, params, module_data, values):
    """``(grips, loads, bodies, warnings, pattern)`` of a solution with free bodies
    (:mod:`tca_casadi.model.bodies`): the :class:`ContactResult` of every closed grip, their
    forces on each module ``{m: (points, forces)}`` for the global balance, one
    :class:`BodyResult` per body, a ``slipping`` warning for each grip (or support) that needs
    more friction than it has or slides, and each grip's and support corner's side of its
    complementarities' corners. ``values``: ``{"grips": [(f_n, f_t (3), slip multiplier), ...],
    "poses": [(6,), ...], "supports": {b: (8 x 5,)}}`` [SI], in dynamics with ``"inertia"``: per
    body its d'Alembert force and moment (global)."""
    from ..model.bodies import body_pose, body_shape
    from ..solution import BodyResult
    param = robot.param_function(params)
    closed, loads, warnings, pattern = [], {}, [], []
    placed = [body_pose(body, values["poses"][body.index]) for body in robot.bodies]
    shapes = [body_shape(body, *pose) for body, pose in zip(robot.bodies, placed)]
    on_body = [[] for _ in robot.bodies]
    for c in robot.grips:
        module, body = robot.modules[c.module], robot.bodies[c.body]
        s, states = module_data[c.module][0], module_data[c.module][1]
        state = states[:, int(np.argmin(np.abs(s - c.s)))]
        g, n, point = contact_geometry(shapes[c.body], module, state)
        held = _material_point(state, param, robot.grip_parameter(c, "offset"))
        r, R = placed[c.body]
        anchored = r + R @ np.asarray(param(robot.grip_parameter(c, "anchor")), float).ravel()
        grip = np.asarray(values["grips"][c.index], float)
        force, tangential, multiplier = float(grip[0]), grip[1:4], float(grip[4])
        points, pushes = loads.setdefault(c.module, ([], []))
        points += [point, held]
        pushes += [force * n, tangential]
        on_body[c.body] += [(point, force * n), (held, tangential)]
        _closed_contact(module, c.s, "object", body.name, point, n, float(g), force, tangential, multiplier,
                        body.friction, body.sliding, closed, warnings, pattern, held, anchored)
    loads = {m: (np.array(p).T, np.array(f).T) for m, (p, f) in loads.items()}
    bodies, inertia = [], values.get("inertia") or [None] * len(robot.bodies)
    for body, (r, R), forces, inertial in zip(robot.bodies, placed, on_body, inertia):
        corners = None
        if body.index in values["supports"]:
            corners, corner_pattern = _support_corners(robot, body, r, R, values["supports"][body.index], param)
            pattern.extend(corner_pattern)
        weight = float(param(f"{body.name}.mass")[0]) * param("gravity")
        result = BodyResult.of(body, r, R, weight, forces, [c for c in closed if c.obstacle == body.name], corners,
                               inertial)
        if result.support_slipping:
            warnings.append(PhysicsWarning("slipping", _support_message(body, result)))
        bodies.append(result)
    return closed, loads, bodies, warnings, tuple(pattern)


def _support_corners(robot, body, r, R, unknowns, param):
    """``(SupportCorners, pattern)`` of a body's support from its corners' unknowns (8 x 5,)
    [SI]; the pattern says per corner which side of its normal (and, Coulomb, its slip)
    complementarity's corner it is on."""
    from ..model.bodies import CONTACT_UNKNOWNS, body_scales, corner_points, slides, support_gaps
    from ..solution import SupportCorners
    plane = robot.obstacle_of(body.support, param)
    fo, lo = body_scales(body)
    rows = np.asarray(unknowns, float).reshape(-1, CONTACT_UNKNOWNS)
    gaps, n = support_gaps(plane, body, r, R)
    gaps, n = np.array([float(g) for g in gaps]), np.asarray(n, float).ravel()
    margins = cone_margin(body.support_friction, rows[:, 0], rows[:, 1:4])
    sliding = np.array([body.sliding and body.support_friction > 0 and slides(lam, margin, fo)
                        for lam, margin in zip(rows[:, 4], margins)], bool)
    pattern = [bool(f / fo > g / lo) for f, g in zip(rows[:, 0], gaps)]
    if body.sliding:
        pattern += [bool(s) for s in sliding]
    corners = SupportCorners(np.array(corner_points(body, r, R), float), rows[:, 0].copy(), rows[:, 1:4].copy(), gaps,
                             sliding, n, fo)
    return corners, pattern


def _support_message(body, result):
    """What a ``slipping`` warning says of a body sliding on its support."""
    if np.any(result.corners.sliding & result.corners.pressed):
        return f"object {body.name!r} slides on its support on its friction limit ({body.support_friction:.3g})"
    return (f"object {body.name!r} slips on its support: it needs friction {result.support_needed_friction:.3g} "
            f"there and has {body.support_friction:.3g}")


def record_slides(robot, start, solution):
    """Mark in ``solution`` how far each closed grip's rod point moved over its body since the
    state the solve started from (``start``: the parameters it started at, whose history says
    which grips stuck where, the rod's material point and the body's point under it;
    :attr:`ContactResult.slid`: how far apart those two points are now, along the body), with a
    ``slipping`` warning for a grip that slid and is no longer sliding (one still sliding has
    its warning). Only Coulomb grips slide (a sticking grip's material point stays on its
    anchor; a finger that rolls moves its contact over the body without slipping). Returns
    ``solution``."""
    if not robot.bodies or not solution.bodies or len(start) != robot.layout.size:
        return solution
    layout, found = robot.layout, {body.name: body for body in solution.bodies}
    for c in robot.grips:
        body, module = robot.bodies[c.body], robot.modules[c.module]
        result = found.get(body.name)
        if not body.sliding or result is None or start[layout[robot.grip_parameter(c, "sticks")]][0] < 0.5:
            continue
        grip = next((g for g in result.grips if g.module == module.name and abs(g.s - c.s) <= 1e-12 * module.length),
                    None)
        if grip is None:
            continue
        anchor = np.asarray(start[layout[robot.grip_parameter(c, "anchor")]], float)
        offset = np.asarray(start[layout[robot.grip_parameter(c, "offset")]], float)
        rod = solution.modules[c.module]
        j = int(np.argmin(np.abs(rod.s - c.s)))
        moved = rod.p[:, j] + rod.R[:, :, j] @ offset - (result.position + result.rotation @ anchor)
        moved = moved - np.dot(moved, grip.normal) * np.asarray(grip.normal, float)
        grip.slid = float(np.linalg.norm(moved))
        if grip.slipping and not grip.sliding and grip.friction_margin >= 0:
            solution.warnings.append(PhysicsWarning(
                "slipping", f"object {body.name!r} slipped at module {module.name} (s = {c.s * 1e3:.4g} mm): the grip "
                f"slid {grip.slid * 1e3:.4g} mm over it during this solve, on its friction limit ({body.friction:.3g})"))
    return solution


def _material_point(state, param, name):
    """The rod's material point that friction holds (3,) [m] at a node's deviation ``state``:
    the history parameter ``name`` (an ``offset``) at ``param``."""
    return np.asarray(held_point(state, np.asarray(param(name), float).ravel()), float).ravel()


def _closed_contact(module, s, kind, name, point, n, g, force, tangential, multiplier, friction, coulomb, closed,
                    warnings, pattern, held=None, anchored=None):
    """Append to ``closed`` the :class:`ContactResult` of a rod contact (module ``module`` at
    arc length ``s`` against the ``kind`` (``object`` or ``obstacle``) ``name``; ``held`` the
    material point its friction acts at, ``anchored`` the point of the body or obstacle its
    anchor names) when it is closed, to ``warnings`` a ``slipping``
    warning when it needs more friction than it has (``friction``) or slides (``coulomb``: on
    Coulomb's cone), to ``pattern`` the sides of its complementarities' corners."""
    from ..model.bodies import slides
    fs = module.force_scale
    pattern.append(force / fs > g / outline_size(module))
    margin = cone_margin(friction, force, tangential)
    sliding = coulomb and friction > 0 and slides(multiplier, margin, fs)
    if coulomb:
        pattern.append(sliding)
    if force <= CLOSED * fs:
        return
    slip = multiplier * outline_size(module) / fs * float(np.linalg.norm(tangential)) if sliding else 0.0
    result = ContactResult(module.name, float(s), name, point, n, force, np.asarray(tangential, float), g,
                           float(friction), sliding=sliding, slip=slip, held_at=point if held is None else held,
                           anchored_at=anchored)
    closed.append(result)
    if result.slipping:
        warnings.append(PhysicsWarning("slipping", _slipping_message(kind, name, module, s, result)))


def _slipping_message(kind, name, module, s, contact):
    """What a slipping contact's warning says: it slides (Coulomb), or the friction it would need."""
    where = f"{kind} {name!r} slips at module {module.name} (s = {s * 1e3:.4g} mm): "
    if contact.sliding:
        return where + (f"it slides {contact.slip * 1e6:.3g} {unit_text('um')} over it on its friction limit "
                        f"({contact.friction:.3g})")
    what = "grasp" if kind == "object" else "contact"
    return where + f"the {what} needs friction {contact.needed_friction:.3g} there and has {contact.friction:.3g}"


def _nearest_node(robot, shape, module_data):
    """``{gap, module, s}``: the node of any module nearest ``shape``."""
    best = None
    for m, (s, states) in enumerate(data[:2] for data in module_data):
        g = gaps(shape, outline_of(robot.modules[m]), states[0:3], states[3:7])
        j = int(np.argmin(g))
        if best is None or g[j] < best["gap"]:
            best = {"gap": float(g[j]), "module": robot.modules[m].name, "s": float(s[j])}
    return best


def build_solution(robot, params, module_data, tensions, lengths, result, method, iterate, notices=(), extra_loads=None,
                   contact_forces=None, clearance=None, bodies=None, frictions=None, check_balance=True):
    """Solution from ``module_data = [(s, states, base_wrench_body, weights), ...]``, tensions per
    actuator (list in ``robot.actuators`` order) and lengths; ``result`` the
    :class:`SolveStatus`, ``method`` the solver's name, ``iterate`` its variables (an :class:`Iterate`),
    ``notices`` the solver's own :class:`PhysicsWarning` s (e.g. a floored tolerance);
    ``extra_loads``: ``(points, forces, moments)`` (3, k) global, beyond the robot's own loads,
    for the global balance (a dynamic step's inertial loads); ``contact_forces`` (n,) [N] the
    normal force of each of ``robot.contacts`` and ``clearance`` the solver's nearest approach
    to each obstacle and ``frictions`` the tangential forces and slips of the contacts against
    obstacles with friction (:func:`contact_results`); ``bodies`` the free bodies' unknowns
    (:func:`body_results`); ``check_balance`` False: no global balance (``balance`` None; a
    time step between the scheduled checks of a dynamic run)."""
    robot = robot.at(params)          # stiffness, routes, laws at these parameters
    modules = [module_result(robot.modules[m], *data) for m, data in enumerate(module_data)]
    actuators = {}
    for k, actuator in enumerate(robot.actuators):
        parameter = params[robot.layout[actuator.parameter]][0]
        actuators[actuator.key] = actuator_result(actuator, modules[actuator.module], tensions[k],
                                                  lengths[k], parameter, robot.modules[actuator.module].force_scale)
    warnings = physics_warnings(robot, actuators, params)
    contacts, contact_loads, nearest, pattern = [], None, {}, ()
    if robot.obstacles:
        contacts, contact_loads, nearest, found, pattern = contact_results(robot, params, module_data,
                                                                           contact_forces, clearance, frictions)
        warnings.extend(found)
    body_list = []
    if robot.bodies:
        grips, grip_loads, body_list, slipping, grip_pattern = body_results(robot, params, module_data, bodies)
        contacts, pattern = contacts + grips, pattern + grip_pattern
        contact_loads = _merged(contact_loads or {}, grip_loads)
        warnings.extend(slipping)
    balance = global_balance(robot, modules, params, tensions, extra_loads, contact_loads) if check_balance else None
    if balance is not None and result.success and balance.relative > BALANCE_TOLERANCE:
        warnings.append(PhysicsWarning("global_balance", f"global balance off by {balance.relative:.1e} of the forces in play "
                        f"(force {np.abs(balance.force).max():.2e} N, moment "
                        f"{np.abs(balance.moment).max():.2e} N m): the mesh is too coarse for this "
                        "robot; raise solver.intervals"))
    warnings.extend(notices)
    if not result.success:
        warnings.insert(0, not_converged(result))
    return Solution(result=result, method=method, iterate=iterate,
                    modules=modules, actuators=actuators, warnings=warnings,
                    parameters=np.array(params, float), parameter_names=dict(robot.layout.slices),
                    scenario_name=robot.name, tip_module=robot.tip_index, balance=balance,
                    loads=load_markers(robot, modules, params), contacts=contacts, clearance=nearest, contact_pattern=pattern,
                    obstacles=robot.obstacles, bodies=body_list)


def _merged(loads, more):
    """``{m: (points, forces)}`` of both (3, k) sets of point loads."""
    out = dict(loads)
    for m, (points, forces) in more.items():
        if m in out:
            out[m] = (np.hstack([out[m][0], points]), np.hstack([out[m][1], forces]))
        else:
            out[m] = (points, forces)
    return out


def not_converged(result):
    """The warning an unconverged :class:`SolveStatus` puts first in its solution's warnings."""
    return PhysicsWarning("not_converged", f"not converged: {result.message}")

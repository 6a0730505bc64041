"""The history a static solve with friction needs (issue 17; ``docs/contact.md`` section 4).

Friction depends on the path: a contact that was closed in the solution a solve starts from is
anchored where it touched. That history is a set of parameters (no scenario keys), copied from
the solution a solve starts from (:func:`carried_history`) and carried again after every
accepted continuation step:

- per grip (a candidate of a ``held_by`` module against a contact object)
  ``objects.NAME.grip.MODULE.K.anchor`` (3: the body-frame point its rod point touched),
  ``.offset`` (3: that rod point in the rod's section frame, ``R^T (x - p)``: friction holds the
  rod's material point ``p + R offset``, not the outline point nearest the body, which runs
  along a flat face as the section tilts) and ``.sticks`` (1 when it was closed);
- per corner ``J`` of a supported contact object ``objects.NAME.support.J.anchor`` (3: where on
  the plane it pressed, from its placed position) and ``.sticks``;
- per candidate ``K`` of each module against each obstacle with ``friction > 0``
  ``obstacles.NAME.contact.MODULE.K.anchor`` (3: where on the obstacle the rod's outline point
  touched, from the obstacle's position), ``.offset`` (as a grip's) and ``.sticks``.

Written without any numerical library beyond numpy (``validate`` declares these parameters).
"""
import numpy as np

#: the first element of a history parameter's ``source`` (it is no scenario key)
HISTORY = "history"
#: a rod contact's history (a grip's, or a candidate's against an obstacle with friction): key, size
ROD_HISTORY = (("anchor", 3), ("offset", 3), ("sticks", 1))


def grip_parameter(body, module, number, key):
    """The name of a grip's history parameter ``key`` (``anchor``, ``offset`` or ``sticks``): ``body``,
    ``module`` names, ``number`` its place among the module's candidates."""
    return f"objects.{body}.grip.{module}.{number}.{key}"


def support_parameter(body, corner, key):
    """The name of a body's support history parameter ``key`` (``anchor`` or ``sticks``) of its
    ``corner`` (0-7, :data:`.bodies.CORNER_SIGNS`)."""
    return f"objects.{body}.support.{corner}.{key}"


def contact_parameter(obstacle, module, number, key):
    """The name of a rod contact's history parameter ``key`` (``anchor``, ``offset`` or ``sticks``) against
    an obstacle with friction: ``obstacle``, ``module`` names, ``number`` the candidate's place
    among the module's candidates."""
    return f"obstacles.{obstacle}.contact.{module}.{number}.{key}"


def frictional_obstacles(scenario):
    """The names of the scenario's obstacles with ``friction > 0``."""
    return [o.name for o in scenario.obstacles if o.friction > 0]


def module_candidates(scenario):
    """Per module, its contact candidates (:func:`.contact.candidate_points`, without any a
    localisation adds): ``[[s, ...], ...]``."""
    from .contact import candidate_points
    given = scenario.contact.at
    return [candidate_points(m.length, scenario.contact.points, given.get(m.name, ())) for m in scenario.modules]


def history_names(scenario):
    """The history parameters, ``[(name, size), ...]`` (module docstring)."""
    from .bodies import CORNER_SIGNS, contact_objects, grip_points
    bodies = contact_objects(scenario)
    out = []
    for b, m, K, _ in grip_points(scenario):
        out += [(grip_parameter(bodies[b][1].name, scenario.modules[m].name, K, key), size)
                for key, size in ROD_HISTORY]
    for _, item in bodies:
        if item.support is not None:
            out += [(support_parameter(item.name, j, key), size) for j in range(len(CORNER_SIGNS))
                    for key, size in (("anchor", 3), ("sticks", 1))]
    frictional = frictional_obstacles(scenario)
    if frictional:
        for module, points in zip(scenario.modules, module_candidates(scenario)):
            for K in range(len(points)):
                out += [(contact_parameter(name, module.name, K, key), size) for name in frictional
                        for key, size in ROD_HISTORY]
    return out


def history_names_of(robot):
    """The names of a robot's history parameters (declared by :func:`history_names`)."""
    return [name for name in robot.layout.names() if robot.layout.entries[name].source[0] == HISTORY]


def carried_history(robot, params, solution):
    """``params`` with the history set from ``solution`` (the state a solve starts from; None: a
    cold start, the scenario's history): each grip closed there is anchored where its rod point
    touched the body (in the body's frame) and sticks, an open one does not; so does each
    corner pressed on its support there, anchored where it pressed, and each rod contact against
    an obstacle with friction, anchored where it touched (from the obstacle's position)."""
    params = np.array(params, float)
    names = history_names_of(robot)
    if not names:
        return params
    layout = robot.layout
    if solution is None or solution.parameters is None:
        for name in names:
            params[layout[name]] = robot.values[layout[name]]
        return params
    _carry_grips(robot, params, solution)
    _carry_supports(robot, params, solution)
    _carry_contacts(robot, params, solution)
    return params


def _closed(found, module, s, obstacle):
    """The closed contact of ``found`` (a list of ContactResult) at module ``module`` (a
    ModuleModel), arc length ``s``, against ``obstacle`` (a name), or None."""
    return next((c for c in found if c.module == module.name and c.obstacle == obstacle
                 and abs(c.s - s) <= 1e-12 * module.length), None)


def _carry_grips(robot, params, solution):
    from .bodies import anchor_of
    results = {b.name: b for b in solution.bodies}
    for c in robot.grips:
        body, module = robot.bodies[c.body], robot.modules[c.module]
        found = results.get(body.name)
        closed = None if found is None else _closed(found.grips, module, c.s, body.name)
        params[robot.layout[robot.grip_parameter(c, "sticks")]] = 0.0 if closed is None else 1.0
        if closed is not None:
            point = _held(solution, robot.grip_parameter(c, "sticks"), closed, module)
            params[robot.layout[robot.grip_parameter(c, "anchor")]] = anchor_of(found.position, found.rotation, point)
            params[robot.layout[robot.grip_parameter(c, "offset")]] = _section_offset(solution, c, point)


#: a held material point still touches while it lies within this fraction of its section's size
#: of the surface (normal distance to the point in contact)
TOUCHING = 1e-3


def _held(solution, sticks, closed, module):
    """Where a closed contact is anchored for the next solve: the rod's material point friction
    held in ``solution`` while that still touches (a contact that was anchored there, ``sticks``
    its history name, and whose held point lies within :data:`TOUCHING` of the surface), else
    the point in contact now. A sticking contact thus keeps its material point, as a corner keeps
    its anchor (re-anchoring at the outline point nearest the body, which runs along a flat face
    as the section tilts, would move where friction acts at every solve); a rolling one (the
    held point lifts off) moves on to the new point of contact."""
    from .contact import outline_size
    point = np.asarray(closed.position, float)
    if closed.held_at is None or solution.parameter_names is None or sticks not in solution.parameter_names:
        return point
    if np.asarray(solution.parameters[solution.parameter_names[sticks]]).ravel()[0] < 0.5:
        return point
    held = np.asarray(closed.held_at, float)
    return held if abs(float(np.dot(closed.normal, held - point))) <= TOUCHING * outline_size(module) else point


def _section_offset(solution, contact, point):
    """``point`` (3,) [m] in the section frame of ``contact``'s rod at its arc length: ``R^T
    (point - p)``, the material point of the rod that touches there (candidates sit on nodes)."""
    module = solution.modules[contact.module]
    j = int(np.argmin(np.abs(module.s - contact.s)))
    return module.R[:, :, j].T @ (np.asarray(point, float) - module.p[:, j])


def _carry_supports(robot, params, solution):
    """Each pressed corner anchored where it pressed, less its elastic give: a corner's
    tangential compliance moves it ``kappa L_o f_t / f_o`` against its friction force
    (:mod:`.bodies`), so the anchor is where it would rest unloaded. A sticking corner thus keeps
    its anchor (re-anchoring it where it stands would let it creep by its give at every solve:
    every time step of a dynamic run); a sliding one carries its slip."""
    from .bodies import SUPPORT_COMPLIANCE, body_scales, placed_corners
    results = {b.name: b for b in solution.bodies}
    for body in robot.bodies:
        found = results.get(body.name)
        if body.support is None or found is None or found.corners is None:
            continue
        corners, (fo, lo) = found.corners, body_scales(body)
        pressed = corners.pressed
        for j, origin in enumerate(placed_corners(body)):
            params[robot.layout[support_parameter(body.name, j, "sticks")]] = float(pressed[j])
            if pressed[j]:
                give = SUPPORT_COMPLIANCE * lo / fo * corners.tangential_forces[j]
                params[robot.layout[support_parameter(body.name, j, "anchor")]] = corners.positions[j] + give - origin


def _carry_contacts(robot, params, solution):
    placed = robot.param_function(solution.parameters)
    for c in robot.contacts:
        if not robot.frictional(c):
            continue
        shape, module = robot.obstacles[c.obstacle], robot.modules[c.module]
        closed = _closed(solution.contacts, module, c.s, shape.name)
        params[robot.layout[robot.contact_parameter(c, "sticks")]] = 0.0 if closed is None else 1.0
        if closed is not None:
            origin = np.asarray(placed(f"obstacles.{shape.name}.position"), float).ravel()
            point = _held(solution, robot.contact_parameter(c, "sticks"), closed, module)
            params[robot.layout[robot.contact_parameter(c, "anchor")]] = point - origin
            params[robot.layout[robot.contact_parameter(c, "offset")]] = _section_offset(solution, c, point)

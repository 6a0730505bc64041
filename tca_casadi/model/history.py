"""The history a static solve with friction needs (issue 17; ``docs/contact.md`` section 4).

Friction depends on the path: a contact that was closed in the solution a solve starts from is
anchored where it touched. That history is a set of parameters (no scenario keys), copied from
the solution a solve starts from (:func:`carried_history`) and carried again after every
accepted continuation step:

- per grip (a candidate of a ``held_by`` module against a contact object)
  ``objects.NAME.grip.MODULE.K.anchor`` (3: the body-frame point its rod point touched) and
  ``.sticks`` (1 when it was closed);
- per corner ``J`` of a supported contact object ``objects.NAME.support.J.anchor`` (3: where on
  the plane it pressed, from its placed position) and ``.sticks``;
- per candidate ``K`` of each module against each obstacle with ``friction > 0``
  ``obstacles.NAME.contact.MODULE.K.anchor`` (3: where on the obstacle the rod's outline point
  touched, from the obstacle's position) and ``.sticks``.

Written without any numerical library beyond numpy (``validate`` declares these parameters).
"""
import numpy as np

#: the first element of a history parameter's ``source`` (it is no scenario key)
HISTORY = "history"


def grip_parameter(body, module, number, key):
    """The name of a grip's history parameter ``key`` (``anchor`` or ``sticks``): ``body``,
    ``module`` names, ``number`` its place among the module's candidates."""
    return f"objects.{body}.grip.{module}.{number}.{key}"


def support_parameter(body, corner, key):
    """The name of a body's support history parameter ``key`` (``anchor`` or ``sticks``) of its
    ``corner`` (0-7, :data:`.bodies.CORNER_SIGNS`)."""
    return f"objects.{body}.support.{corner}.{key}"


def contact_parameter(obstacle, module, number, key):
    """The name of a rod contact's history parameter ``key`` (``anchor`` or ``sticks``) against
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
                for key, size in (("anchor", 3), ("sticks", 1))]
    for _, item in bodies:
        if item.support is not None:
            out += [(support_parameter(item.name, j, key), size) for j in range(len(CORNER_SIGNS))
                    for key, size in (("anchor", 3), ("sticks", 1))]
    frictional = frictional_obstacles(scenario)
    if frictional:
        for module, points in zip(scenario.modules, module_candidates(scenario)):
            for K in range(len(points)):
                out += [(contact_parameter(name, module.name, K, key), size) for name in frictional
                        for key, size in (("anchor", 3), ("sticks", 1))]
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
            params[robot.layout[robot.grip_parameter(c, "anchor")]] = anchor_of(found.position, found.rotation,
                                                                                closed.position)


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
            params[robot.layout[robot.contact_parameter(c, "anchor")]] = np.asarray(closed.position, float) - origin

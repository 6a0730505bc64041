"""Checks that need the whole scenario: names unique and resolvable, spans and load positions
inside their module. Each failure is one line naming file, line and key path."""
from ..catalogue import declarations
from ..errors import ScenarioError
from .schema import Scenario
from .sources import did_you_mean, located

#: top-level keys; module and load names must differ from them so dotted paths stay unambiguous
RESERVED = tuple(Scenario.model_fields)


def fail(raw, sources, path, message):
    """Raise :class:`ScenarioError` for ``path`` (a raw-data key path)."""
    raise ScenarioError(f"{located(sources, path, raw)}: {message}")


def closest(word, options):
    """`` (did you mean 'x'?)`` or a list of the valid names."""
    return did_you_mean(word, options)


def check_references(scenario, raw, sources):
    """Cross-reference checks on a schema-valid scenario."""
    module_names = _unique_names(scenario.modules, ("modules",), raw, sources)
    load_names = _unique_names(scenario.loads, ("loads",), raw, sources)
    for index, name in enumerate(load_names):
        if name in module_names:
            fail(raw, sources, ("loads", index, "name"), f"load name {name!r} is also a module name")
    _check_muscle_types(scenario, raw, sources)
    for index, module in enumerate(scenario.modules):
        _check_module(scenario, index, module, raw, sources)
    for index, load in enumerate(scenario.loads):
        _check_load(scenario, index, load, raw, sources)
    _unique_names(scenario.objects, ("objects",), raw, sources)
    for index, item in enumerate(scenario.objects):
        if item.name in module_names or item.name in load_names:
            fail(raw, sources, ("objects", index, "name"), f"object name {item.name!r} is also a module or load name")
        for k, holder in enumerate(item.held_by):
            if holder not in module_names:
                fail(raw, sources, ("objects", index, "held_by", k),
                     f"unknown module {holder!r}{closest(holder, module_names)}")
    _unique_names(scenario.obstacles, ("obstacles",), raw, sources)
    _check_contact(scenario, module_names, raw, sources)
    _check_bodies(scenario, raw, sources)
    _check_timeline(scenario, raw, sources)


def _check_contact(scenario, module_names, raw, sources):
    """``contact.at``: known modules, arc lengths inside them."""
    for name, points in scenario.contact.at.items():
        if name not in module_names:
            fail(raw, sources, ("contact", "at", name), f"unknown module {name!r}{closest(name, module_names)}")
        length = scenario.modules[module_names.index(name)].length
        for k, s in enumerate(points):
            if s > length * (1 + 1e-12):
                fail(raw, sources, ("contact", "at", name, k),
                     f"s = {s * 1e3:g} mm is beyond the module's length ({length * 1e3:g} mm)")


def _check_bodies(scenario, raw, sources):
    """Contact objects: a ``support`` that names a plane obstacle."""
    planes = {o.name: o for o in scenario.obstacles}
    for k, item in enumerate(scenario.objects):
        if item.support is None:
            continue
        if not item.contact:
            fail(raw, sources, ("objects", k, "support"), "support is for contact objects (contact: true)")
        if item.support not in planes:
            fail(raw, sources, ("objects", k, "support"),
                 f"unknown obstacle {item.support!r}{closest(item.support, list(planes))}")
        if planes[item.support].shape != "plane":
            fail(raw, sources, ("objects", k, "support"),
                 f"obstacle {item.support!r} is a {planes[item.support].shape}: a support must be a plane")


def _check_timeline(scenario, raw, sources):
    """Events in time order, inside ``duration``, each ramp over before the next event; a
    dynamic run's ``start_after`` names a sequence step."""
    start = scenario.dynamics.start_after
    names = [step.name for step in scenario.sequence or []]
    if start is not None and start not in names:
        fail(raw, sources, ("dynamics", "start_after"),
             f"no sequence step {start!r}" + (closest(start, names) if names else ": the scenario has no sequence"))
    events = scenario.timeline
    for k, event in enumerate(events):
        if scenario.duration is not None and event.at > scenario.duration:
            fail(raw, sources, ("timeline", k, "at"),
                 f"event at {event.at:g} s is after the duration ({scenario.duration:g} s)")
        if k and event.at < events[k - 1].at:
            fail(raw, sources, ("timeline", k, "at"),
                 f"event at {event.at:g} s comes before the previous one ({events[k - 1].at:g} s): events must be in time order")
        if event.ramp is not None:
            end = events[k + 1].at if k + 1 < len(events) else scenario.duration
            if end is not None and event.at + event.ramp > end + 1e-12:
                what = "the next event" if k + 1 < len(events) else "the duration"
                fail(raw, sources, ("timeline", k, "ramp"),
                     f"ramp of {event.ramp:g} s from {event.at:g} s ends after {what} ({end:g} s)")


def _unique_names(items, path, raw, sources):
    names = []
    for index, item in enumerate(items):
        if item.name in names:
            fail(raw, sources, path + (index, "name"), f"duplicate name {item.name!r}")
        if item.name in RESERVED:
            fail(raw, sources, path + (index, "name"), f"{item.name!r} is a reserved top-level key")
        if "." in item.name or "=" in item.name:
            fail(raw, sources, path + (index, "name"), "names must not contain '.' or '='")
        names.append(item.name)
    return names


def _check_module(scenario, index, module, raw, sources):
    path = ("modules", index)
    if module.material not in scenario.materials:
        fail(raw, sources, path + ("material",),
             f"unknown material {module.material!r}{closest(module.material, scenario.materials)}")
    if index == 0:
        for key in ("parent", "decoupled"):
            if getattr(module, key):
                fail(raw, sources, path + (key,), f"the first module sits on the base; it has no "
                     f"parent (remove {key}:)")
    elif module.parent is not None:
        earlier = [m.name for m in scenario.modules[:index]]
        if module.parent not in earlier:
            later = " (a parent must come before its children)" if module.parent in \
                [m.name for m in scenario.modules] else closest(module.parent, earlier)
            fail(raw, sources, path + ("parent",), f"unknown parent {module.parent!r}{later}")
    if index == 0 and module.connector is not None:
        fail(raw, sources, path + ("connector",),
             "the first module has no previous module to connect to (use base:)")
    _unique_names(module.actuators, path + ("actuators",), raw, sources)
    for a_index, actuator in enumerate(module.actuators):
        a_path = path + ("actuators", a_index)
        if actuator.kind in declarations():                  # a TCA or a muscle: it has a type
            _check_typed(scenario, actuator, declarations()[actuator.kind], a_path, raw, sources)
        _check_span(route_span(actuator.route, module.length), module, a_path + ("route",), raw, sources)
    _check_coupling(module, path, raw, sources)


def _check_muscle_types(scenario, raw, sources):
    """The code a muscle type names can serve as its law (a custom law's entry point imports
    and builds a scalar CasADi expression)."""
    for name, config in scenario.muscle_types.items():
        problem = declarations()[config.kind].code_problem(config)
        if problem:
            fail(raw, sources, ("muscle_types", name, "entry_point"), problem)


def _check_typed(scenario, actuator, declaration, path, raw, sources):
    """A TCA's or muscle's type exists (in its declaration's section) and is of its kind; its
    input lies in the type's range."""
    section = declaration.TYPES_KEY
    types = getattr(scenario, section)
    if actuator.type not in types:
        fail(raw, sources, path + ("type",),
             f"unknown {declaration.NAME or declaration.KIND} type {actuator.type!r}{closest(actuator.type, types)}")
    config = types[actuator.type]
    if getattr(config, "kind", declaration.KIND) != declaration.KIND:
        fail(raw, sources, path + ("type",), f"{section}.{actuator.type} is a {config.kind} type, "
             f"not a {actuator.kind} one")
    input_name = declaration.INPUT[0]
    problem = declaration.input_problem_of(config, getattr(actuator, input_name), f"{section}.{actuator.type}")
    if problem:
        fail(raw, sources, path + (input_name,), problem)


def _check_coupling(module, path, raw, sources):
    """``thermal_coupling.between``: pairs of two different TCAs of this module."""
    coupling = module.thermal_coupling
    if coupling is None or coupling.between is None:
        return
    from ..catalogue import thermal_kinds
    tcas = [a.name for a in module.actuators if a.kind in thermal_kinds()]
    for k, pair in enumerate(coupling.between):
        for j, name in enumerate(pair):
            if name not in tcas:
                fail(raw, sources, path + ("thermal_coupling", "between", k, j),
                     f"not a TCA of module {module.name!r} (nor another heated muscle): {name!r}{closest(name, tcas)}")
        if pair[0] == pair[1]:
            fail(raw, sources, path + ("thermal_coupling", "between", k), "a TCA cannot be coupled to itself")


def route_span(route, length):
    """``(s_a, s_b)`` of a route on a module of ``length`` [m]."""
    if route.span is not None:
        return tuple(route.span)
    if route.kind == "curve":
        return (route.points[0][0], route.points[-1][0])
    return (0.0, length)


def _check_span(span, module, path, raw, sources):
    s_a, s_b = span
    if not (0.0 <= s_a < s_b <= module.length * (1 + 1e-12)):
        fail(raw, sources, path, f"span [{s_a * 1e3:g}, {s_b * 1e3:g}] mm must satisfy "
             f"0 <= s_a < s_b <= length ({module.length * 1e3:g} mm)")


def _check_load(scenario, index, load, raw, sources):
    path = ("loads", index)
    modules = {m.name: m for m in scenario.modules}
    if load.module not in modules:
        fail(raw, sources, path + ("module",),
             f"unknown module {load.module!r}{closest(load.module, modules)}")
    module = modules[load.module]
    if load.kind == "distributed":
        if load.span is not None:
            _check_span(load.span, module, path + ("span",), raw, sources)
    elif not isinstance(load.at, str) and load.at > module.length * (1 + 1e-12):
        fail(raw, sources, path + ("at",), f"at = {load.at * 1e3:g} mm lies beyond the module's "
             f"length ({module.length * 1e3:g} mm)")

"""What may change between solves without rebuilding anything, declared in one place.

Every entry of the parameter vector ``P`` is declared by :func:`declare` with its name, its unit
kind (:data:`tca_casadi.units.KINDS`), the scenario key it is read from, and its value in the
unloaded reference state. From these declarations alone come the layout (names and slices),
the values of a scenario, the reference-state parameters (:meth:`ParameterLayout.rest`) and the
structure key (the scenario without its parameters: when it changes, the model is rebuilt).

The entries, in this order:

=====================================================  ========================  =============
name                                                   what                      at rest
=====================================================  ========================  =============
``gravity``                                            (3,) [m/s^2]              zero
``base.position``, ``base.quaternion``                 the base pose             kept
``materials.M.youngs_modulus``                         E [Pa]                    kept
``materials.M.poisson_ratio`` or ``.shear_modulus``    G = E / (2 (1 + nu)) or G kept
``materials.M.density``                                [kg/m^3]                  kept
``tca_types.T.fiber_radius``, ``.coil_radius``,        geometry [m, rad]         kept
``.pitch_angle`` (and ``.fiber_length`` if given)
``tca_types.T.reference_temperature``                  [degC]                    kept
``tca_types.T.untwist.c2|c1|c0``                       untwist fit [rad/m/degC^k] kept
``tca_types.T.shear_modulus.a2|a1|a0``                 modulus fit [Pa/N^k]      kept
``muscle_types.T.KEY``                                 a muscle's constants      kept
                                                       (its law's ``PARAMETERS``)
``MODULE.ACTUATOR.route.radius``, ``.angle``/``.phase``  straight and helix routes kept
``MODULE.TCA.temperature``                             [degC]                    its reference
``MODULE.MUSCLE.temperature|pressure|input``           its law's input           its rest value
``MODULE.TENDON.tension`` / ``.displacement``          [N] / [m]                 zero
``OBJECT.mass``, ``OBJECT.held``                       [kg], 0 or 1              zero
``objects.OBJECT.grip|support...anchor|sticks``        a contact object's        kept
                                                       history (:mod:`.bodies`)
``LOAD.mass`` or ``LOAD.force``, ``LOAD.moment``       [kg] or [N], [N m]        zero
=====================================================  ========================  =============

Only materials, TCA types and muscle types that some module or actuator uses are declared.
"""
from dataclasses import dataclass

import numpy as np

from ..catalogue import declarations

#: keys of the scenario that are neither parameters nor structure (they never change a solve)
IGNORED = (("name",), ("description",), ("inverse",), ("sequence",), ("ambient_temperature",),
           ("duration",), ("timeline",), ("dynamics",))
#: keys of each grasped object that only drawings use
OBJECT_DRAWING = ("position", "yaw", "size")


@dataclass(frozen=True)
class Entry:
    """One declared parameter: ``name``, unit ``kind``, the scenario key ``source`` it comes
    from (a path in ``scenario.model_dump(mode="json")``) and ``rest``: ``None`` keeps the value
    in the reference state, a number replaces it, a name copies that entry's value."""
    name: str
    kind: str
    source: tuple
    rest: object = None


class ParameterLayout:
    """Names, slices, unit kinds and reference-state rules of the parameter vector."""

    def __init__(self):
        self.slices, self.entries, self.size = {}, {}, 0

    def add(self, entry, size):
        self.slices[entry.name] = slice(self.size, self.size + size)
        self.entries[entry.name] = entry
        self.size += size

    def __contains__(self, name):
        return name in self.slices

    def __getitem__(self, name):
        return self.slices[name]

    def names(self):
        return list(self.slices)

    def kind(self, name):
        """Unit kind of an entry (a key of :data:`tca_casadi.units.KINDS`)."""
        return self.entries[name].kind

    def rest(self, values):
        """Parameters of the unloaded reference state (see the module docstring)."""
        rest = np.array(values, dtype=float)
        for name, entry in self.entries.items():
            if isinstance(entry.rest, str):
                rest[self.slices[name]] = np.asarray(values, float)[self.slices[entry.rest]]
            elif entry.rest is not None:
                rest[self.slices[name]] = entry.rest
        return rest

    def structure(self, data):
        """``data`` (a scenario dump, modified in place) without any parameter or ignored key."""
        for path in [entry.source for entry in self.entries.values()] + list(IGNORED):
            _drop(data, path)
        for item in data.get("objects", []):
            for key in OBJECT_DRAWING if not item.get("contact") else ():   # a free body's are built in
                item.pop(key, None)
        for tca_type in data.get("tca_types", {}).values():
            for key in declarations()["tca"].THERMAL_KEYS:
                tca_type.pop(key, None)
        for muscle_type in data.get("muscle_types", {}).values():
            for key in declarations()[muscle_type.get("kind")].THERMAL_KEYS:
                muscle_type.pop(key, None)
        for module in data.get("modules", []):
            module.pop("thermal_coupling", None)       # simulate's, never the statics'
            for actuator in module.get("actuators", []):
                actuator.pop("drive", None)            # simulate's, never the statics'
        return data


def _drop(data, path):
    for key in path[:-1]:
        try:
            data = data[key]
        except (KeyError, IndexError, TypeError):
            return
    if isinstance(data, dict):
        data.pop(path[-1], None)


#: an obstacle's sizes that are parameters (a grip-force map over object widths without rebuilding)
OBSTACLE_SIZES = {"sphere": ("radius",), "cylinder": ("radius",), "box": ("size",)}


def declare(scenario, actuators, point_loads, distributed):
    """``(layout, values)`` of ``scenario`` for a robot with these actuators and loads."""
    layout, values = ParameterLayout(), []

    def put(name, value, kind, source, rest=None):
        value = np.atleast_1d(np.asarray(value, dtype=float))
        layout.add(Entry(name, kind, tuple(source), rest), value.size)
        values.extend(value.tolist())

    put("gravity", scenario.gravity, "acceleration", ("gravity",), 0.0)
    put("base.position", scenario.base.position, "length", ("base", "position"))
    put("base.quaternion", scenario.base.orientation.as_quaternion(), "dimensionless", ("base", "orientation"))
    for name in dict.fromkeys(module.material for module in scenario.modules):
        _material(put, name, scenario.materials[name])
    typed = dict.fromkeys((declarations()[a.kind], a.type) for m in scenario.modules for a in m.actuators
                          if a.kind in declarations())
    for declaration, name in sorted(typed, key=lambda pair: pair[0].TYPES_KEY != "tca_types"):   # TCAs first
        _type_parameters(put, declaration, name, getattr(scenario, declaration.TYPES_KEY)[name])
    for actuator in actuators:
        source, config = _actuator_source(scenario, actuator)
        for key in actuator.placement_keys:
            put(f"{actuator.key}.route.{key}", getattr(config.route, key), "length" if key == "radius" else "angle",
                source + ("route", key))
    for actuator in actuators:
        source, config = _actuator_source(scenario, actuator)
        rest, kind = _input_rest(actuator, config)
        put(actuator.parameter, getattr(config, actuator.control), kind, source + (actuator.control,), rest)
    for k, item in enumerate(scenario.objects):
        put(f"{item.name}.mass", item.mass, "mass", ("objects", k, "mass"), 0.0)
        if not item.contact:
            put(f"{item.name}.held", float(item.held), "dimensionless", ("objects", k, "held"), 0.0)
    from .history import HISTORY, history_names
    for name, size in history_names(scenario):      # set from the solution a solve starts from
        # placed on its support: every corner sticks where it is (one above the plane is open,
        # its sticking idle); no grip yet
        sticks = ".support." in name
        put(name, np.full(size, float(sticks)) if name.endswith("sticks") else np.zeros(size), "dimensionless",
            (HISTORY,) + tuple(name.split(".")))
    for k, obstacle in enumerate(scenario.obstacles):      # moved without a rebuild (a grasp, a study)
        put(f"obstacles.{obstacle.name}.position", obstacle.position, "length", ("obstacles", k, "position"))
        for key in OBSTACLE_SIZES.get(obstacle.shape, ()):
            put(f"obstacles.{obstacle.name}.{key}", getattr(obstacle, key), "length", ("obstacles", k, key))
    positions = {load.name: k for k, load in enumerate(scenario.loads)}
    for load in point_loads + distributed:
        if load.kind == "object":
            continue
        k = positions[load.name]
        config = scenario.loads[k]
        if config.kind == "mass":
            put(f"{load.name}.mass", config.mass, "mass", ("loads", k, "mass"), 0.0)
        else:
            put(f"{load.name}.force", config.force, "force" if config.kind == "point" else "force_per_length",
                ("loads", k, "force"), 0.0)
            put(f"{load.name}.moment", config.moment, "moment" if config.kind == "point" else "moment_per_length",
                ("loads", k, "moment"), 0.0)
    return layout, np.array(values)


def _actuator_source(scenario, actuator):
    """``(path of the actuator in the scenario dump, its scenario entry)``."""
    entries = scenario.modules[actuator.module].actuators
    k = [a.name for a in entries].index(actuator.name)
    return ("modules", actuator.module, "actuators", k), entries[k]


def _material(put, name, material):
    prefix, source = f"materials.{name}.", ("materials", name)
    put(prefix + "youngs_modulus", material.youngs_modulus, "pressure", source + ("youngs_modulus",))
    if material.shear_modulus is not None:
        put(prefix + "shear_modulus", material.shear_modulus, "pressure", source + ("shear_modulus",))
    else:
        nu = 0.5 if material.poisson_ratio is None else material.poisson_ratio
        put(prefix + "poisson_ratio", nu, "dimensionless", source + ("poisson_ratio",))
    put(prefix + "density", material.density, "density", source + ("density",))


def _input_rest(actuator, config):
    """``(rest rule, unit kind)`` of an actuator's own parameter (its input or tension)."""
    if actuator.kind == "tendon":
        return 0.0, {"tension": "force", "displacement": "length"}[actuator.control]
    law = actuator.law
    rest = f"{law.TYPES_KEY}.{config.type}.{law.REST_INPUT}" if law.REST_INPUT else law.INPUT[2]
    return rest, law.INPUT[1]


def _type_parameters(put, declaration, name, config):
    """An actuator type's constants as NLP parameters (its declaration's ``parameter_entries``)."""
    section = declaration.TYPES_KEY
    for key, kind, value in declaration.parameter_entries(config):
        if value is not None:
            put(f"{section}.{name}.{key}", value, kind, (section, name) + tuple(key.split(".")))

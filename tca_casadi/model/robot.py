"""The model of a whole robot: modules in series with their actuators and loads, built from a
validated scenario, and the layout of the parameter vector (what may change between solves
without rebuilding anything: temperatures, tendon tensions, loads, gravity, base pose).

All lengths in m, forces in N, temperatures in degC.
"""
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..scenario.checks import fail, route_span
from .routes import make_route
from .sections import outline_contains, section_properties, stiffness_diagonal
from .compatibility import TendonLaw
from .tca_law import TcaLaw


@dataclass
class ActuatorModel:
    """One actuator. ``kind`` is ``"tca"`` (tension unknown, fixed by its law) or ``"tendon"``;
    a tendon's ``control`` is ``"tension"`` (given) or ``"displacement"`` (tension unknown, fixed
    by its length condition). ``tension_only``: may go slack (F = 0)."""
    name: str
    module: int
    kind: str
    route: object
    law: Optional[object]     # TcaLaw, TendonLaw (displacement control) or None
    reference_length: float
    parameter: str            # 'MODULE.NAME.temperature' | '.tension' | '.displacement'
    control: str = "temperature"
    tension_only: bool = False

    @property
    def key(self):
        return self.parameter.rsplit(".", 1)[0]

    @property
    def unknown_tension(self):
        """True when the tension is an unknown of the problem (TCAs, displacement tendons)."""
        return self.control != "tension"


@dataclass
class PointLoadModel:
    """A point force/moment (or a mass's weight) at arc length ``s`` of module ``module``; an
    ``object`` load is a held object's weight share, ``held * mass * share * g``."""
    name: str
    module: int
    s: float
    frame: str                # 'global' or 'body'
    kind: str                 # 'point', 'mass' or 'object'
    share: float = 1.0


@dataclass
class DistributedLoadModel:
    """Force and moment per unit length over ``span`` of module ``module``."""
    name: str
    module: int
    span: tuple
    frame: str
    kind: str = "distributed"


@dataclass
class ConnectorModel:
    """Rigid link from the previous tip frame A to this base frame B."""
    offset: np.ndarray        # (3,) in A
    quaternion: np.ndarray    # (4,) rotation of B relative to A
    mass: float
    center_of_mass: np.ndarray


@dataclass
class ModuleModel:
    """One rod: length, stiffness diagonal, reference strains, weight per length, geometry."""
    name: str
    length: float
    stiffness: np.ndarray     # (6,) [E Ix, E Iy, G J, G A, G A, E A]
    xi_star: np.ndarray       # (6,) [u*, v*]
    weight_density: float     # rho A [kg/m]
    section: object
    connector: Optional[ConnectorModel] = None
    actuators: list = field(default_factory=list)
    parent: Optional[int] = None      # index of the module whose tip carries this base
    decoupled: bool = False           # only its net force loads the parent (SPEC section 5)

    @property
    def bending_stiffness(self):
        return float(min(self.stiffness[0], self.stiffness[1]))

    @property
    def force_scale(self):
        """Natural force of this module, ``EI / L^2`` [N]."""
        return self.bending_stiffness / self.length**2

    @property
    def state_scale(self):
        """(13,) scale of the deviation state ``[p, h, u - u*, v - v*]`` that both solvers work
        in: ``[L, 1, F_s L / K_bt, F_s / K_se]``, so the strains are order-one internal moments
        and forces (``F_s`` = :attr:`force_scale`)."""
        return np.r_[np.full(3, self.length), np.ones(4), self.force_scale * self.length / self.stiffness[0:3],
                     self.force_scale / self.stiffness[3:6]]

    @property
    def wrench_scale(self):
        """(6,) factors that make a wrench ``[moment; force]`` order one: ``1/(F_s L)``, ``1/F_s``."""
        return np.r_[np.full(3, 1 / (self.force_scale * self.length)), np.full(3, 1 / self.force_scale)]


class ParameterLayout:
    """Names and slices of the parameter vector: ``'gravity'``, ``'base.position'``,
    ``'base.quaternion'``, ``'MODULE.TCA.temperature'``, ``'MODULE.TENDON.tension'``,
    ``'LOAD.force'``, ``'LOAD.moment'``, ``'LOAD.mass'``."""

    def __init__(self):
        self.slices, self.size = {}, 0

    def add(self, name, size):
        self.slices[name] = slice(self.size, self.size + size)
        self.size += size

    def __contains__(self, name):
        return name in self.slices

    def __getitem__(self, name):
        return self.slices[name]

    def names(self):
        return list(self.slices)


class Robot:
    """Modules in series from a base. Build with :meth:`from_scenario`."""

    def __init__(self, modules, actuators, point_loads, distributed_loads, layout, values, name):
        self.modules = modules
        self.actuators = actuators
        self.point_loads = point_loads
        self.distributed_loads = distributed_loads
        self.layout = layout
        self.values = values
        self.name = name

    @property
    def unknowns(self):
        """Actuators whose tension is unknown (TCAs and displacement-controlled tendons), in
        order: the solvers' tension unknowns and compatibility equations."""
        return [a for a in self.actuators if a.unknown_tension]

    def children(self, m):
        """Indices of the modules whose base sits on module m's tip, in scenario order."""
        return [c for c, module in enumerate(self.modules) if module.parent == m]

    def coupled_children(self, m):
        """Children of module m that pass their whole base wrench on (not decoupled)."""
        return [c for c in self.children(m) if not self.modules[c].decoupled]

    @property
    def tip_index(self):
        """The module whose tip is "the tip": the end of the trunk, followed from the base while a
        module carries exactly one coupled child (the last module of a chain; the module that
        carries a tree's fingers or a decoupled gripper)."""
        m = 0
        while True:
            coupled = self.coupled_children(m)
            if len(coupled) != 1:
                return m
            m = coupled[0]

    @property
    def tcas(self):
        """Actuators whose tension is an unknown, in the order of the NLP's tension variables."""
        return [a for a in self.actuators if a.kind == "tca"]

    @classmethod
    def from_scenario(cls, scenario):
        """Model of a validated scenario; raises ScenarioError for a route outside the body."""
        modules, actuators = [], []
        names = [config.name for config in scenario.modules]
        for index, config in enumerate(scenario.modules):
            module = _module(scenario, config)
            if index > 0:
                module.parent = names.index(config.parent) if config.parent else index - 1
                module.decoupled = bool(config.decoupled)
            modules.append(module)
            for a_index, a_config in enumerate(config.actuators):
                actuator = _actuator(scenario, index, config, a_index, a_config)
                module.actuators.append(actuator)
                actuators.append(actuator)
        point_loads, distributed = _loads(scenario)
        layout, values = _parameters(scenario, actuators, point_loads, distributed)
        return cls(modules, actuators, point_loads, distributed, layout, values, scenario.name)

    def parameter_vector(self, scenario):
        """Parameter values of ``scenario`` (same structure as this robot)."""
        return _parameters(scenario, self.actuators, self.point_loads, self.distributed_loads)[1]

    def rest_parameters(self, values):
        """Parameters of the unloaded reference state: no gravity, no loads, tendons slack, TCAs at
        their reference temperature; base pose kept. Its equilibrium is the reference shape."""
        rest = np.array(values, dtype=float)
        rest[self.layout["gravity"]] = 0.0
        for actuator in self.actuators:
            slot = self.layout[actuator.parameter]
            rest[slot] = actuator.law.reference_temperature if actuator.kind == "tca" else 0.0
            # a displacement tendon at q = 0 is exactly taut with no tension: the reference state
        for name in self.layout.names():
            if name.endswith((".force", ".moment", ".mass", ".held")):
                rest[self.layout[name]] = 0.0
        return rest

    def structure_key(self, scenario):
        """A hashable summary of everything that is *not* a parameter (rebuild when it changes)."""
        data = scenario.model_dump(mode="json")
        for module in data["modules"]:
            for actuator in module["actuators"]:
                actuator.pop("temperature", None)
                actuator.pop("tension", None)
        for load in data["loads"]:
            for key in ("force", "moment", "mass"):
                load.pop(key, None)
        for item in data["objects"]:
            for key in ("mass", "held", "position", "yaw", "size"):
                item.pop(key)
        data.pop("gravity"), data.pop("base"), data.pop("name"), data.pop("description")
        data.pop("inverse", None), data.pop("sequence", None)
        return repr(data)


# ----------------------------------------------------------------------------- builders
def _module(scenario, config):
    material = scenario.materials[config.material]
    props = section_properties(config.cross_section)
    stiffness = stiffness_diagonal(props, material.youngs_modulus, material.shear())
    xi_star = np.array(list(config.precurvature) + [0.0, 0.0, 1.0])
    connector = None
    if config.connector is not None:
        c = config.connector
        com = np.array(c.center_of_mass if c.center_of_mass is not None else np.array(c.offset) / 2)
        connector = ConnectorModel(np.array(c.offset), np.array(c.rotation.as_quaternion()), c.mass, com)
    return ModuleModel(config.name, config.length, stiffness, xi_star,
                       material.density * props.area, config.cross_section, connector)


def _actuator(scenario, index, config, a_index, a_config):
    span = route_span(a_config.route, config.length)
    route = make_route(a_config.route, span)
    _check_inside(scenario, index, config, a_index, route)
    xi_star = np.array(list(config.precurvature) + [0.0, 0.0, 1.0])
    reference_length = reference_path_length(route, xi_star)
    law, control = None, "temperature"
    if a_config.kind == "tca":
        law = TcaLaw.from_type(scenario.tca_types[a_config.type], reference_length)
    else:
        control = a_config.control
        if control == "displacement":
            compliance = a_config.compliance if a_config.compliance is not None else (
                1.0 / a_config.stiffness if a_config.stiffness is not None else 0.0)
            law = TendonLaw(reference_length, compliance)
    parameter = f"{config.name}.{a_config.name}.{control}"
    return ActuatorModel(a_config.name, index, a_config.kind, route, law, reference_length, parameter,
                         control, bool(a_config.tension_only))


def reference_path_length(route, xi_star, points=4001):
    """``l*``: length of the route in the reference configuration [m] (composite Simpson rule on
    a fine grid, ``points`` odd; exact for straight routes and helices on a straight body)."""
    s = np.linspace(*route.span, points)
    r, dr, _ = route.evaluate(s)
    a = xi_star[3:6, None] + np.cross(xi_star[0:3], r, axis=0) + dr
    speed = np.linalg.norm(a, axis=0)
    weights = np.ones(points)
    weights[1:-1:2], weights[2:-1:2] = 4.0, 2.0
    return float(weights @ speed * (s[1] - s[0]) / 3.0)


def _check_inside(scenario, index, config, a_index, route):
    outline = config.cross_section.envelope or config.cross_section
    points = route.samples(400)
    inside = outline_contains(outline, points[0], points[1])
    if not np.all(inside):
        worst = points[:, np.argmin(inside)]
        size = (f"radius {outline.diameter * 500:g} mm" if outline.shape == "circle"
                else f"{outline.width * 1e3:g} x {outline.height * 1e3:g} mm")
        hint = "" if config.cross_section.envelope else (
            "; if the body is larger than its stiffness-equivalent section, give "
            "cross_section.envelope")
        raw, sources = scenario._raw or {}, scenario._sources
        if sources is None:
            from ..scenario.sources import SourceMap
            sources = SourceMap("<scenario>")
        fail(raw, sources, ("modules", index, "actuators", a_index, "route"),
             f"route passes outside the body ({size}) at x={worst[0] * 1e3:.3g} mm, "
             f"y={worst[1] * 1e3:.3g} mm{hint}")


def _loads(scenario):
    module_index = {m.name: i for i, m in enumerate(scenario.modules)}
    point, distributed = [], []
    for load in scenario.loads:
        index = module_index[load.module]
        length = scenario.modules[index].length
        if load.kind == "distributed":
            span = tuple(load.span) if load.span is not None else (0.0, length)
            distributed.append(DistributedLoadModel(load.name, index, span, load.frame))
        else:
            s = {"end": length, "start": 0.0}.get(load.at, load.at) if isinstance(load.at, str) else load.at
            frame = load.frame if load.kind == "point" else "global"
            point.append(PointLoadModel(load.name, index, float(s), frame, load.kind))
    for item in scenario.objects:
        for holder in item.held_by:
            index = module_index[holder]
            point.append(PointLoadModel(item.name, index, scenario.modules[index].length, "global",
                                        "object", 1.0 / len(item.held_by)))
    return point, distributed


def _parameters(scenario, actuators, point_loads, distributed):
    layout, values = ParameterLayout(), []

    def put(name, value):
        value = np.atleast_1d(np.asarray(value, dtype=float))
        layout.add(name, value.size)
        values.extend(value.tolist())

    put("gravity", scenario.gravity)
    put("base.position", scenario.base.position)
    put("base.quaternion", scenario.base.orientation.as_quaternion())
    configs = {(m.name, a.name): a for m in scenario.modules for a in m.actuators}
    for actuator in actuators:
        config = configs[(scenario.modules[actuator.module].name, actuator.name)]
        put(actuator.parameter, getattr(config, actuator.control))
    loads = {load.name: load for load in scenario.loads}
    for item in scenario.objects:
        put(f"{item.name}.mass", item.mass)
        put(f"{item.name}.held", float(item.held))
    for load in point_loads + distributed:
        if load.kind == "object":
            continue
        config = loads[load.name]
        if config.kind == "mass":
            put(f"{load.name}.mass", config.mass)
        else:
            put(f"{load.name}.force", config.force)
            put(f"{load.name}.moment", config.moment)
    return layout, np.array(values)

"""The model of a whole robot: modules in series with their actuators and loads, built from a
validated scenario, with the parameter vector declared in :mod:`.parameters` (what may change
between solves without rebuilding anything: temperatures, tendon tensions, loads, gravity,
base pose, material moduli and density, TCA geometry and fits, route radius and angle).

Everything that depends on a parameter is a method taking ``param(name)`` (numbers or CasADi
symbols alike): ``module.stiffness_of(param)``, ``actuator.law_of(param)``,
``actuator.route_values(s, param)``... The plain attributes (``module.stiffness``,
``actuator.law``, ``actuator.route``...) hold the values at the scenario's parameters; the
solvers use them only for scaling, and :meth:`Robot.at` gives the robot at other parameters
(for post-processing).

All lengths in m, forces in N, temperatures in degC.
"""
from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np

from ..scenario.checks import fail, route_span
from .laws import laws, muscle_module
from .laws.tendon import TendonLaw
from .parameters import OBSTACLE_SIZES, ParameterLayout, declare  # noqa: F401  (ParameterLayout: re-exported)
from .routes import ANGLE_KEY, make_route, reference_path_length
from .sections import outside_point, section_properties, stiffness_diagonal


@dataclass
class ActuatorModel:
    """One actuator. ``kind`` is ``"tca"``, a muscle of ``muscle_types`` (``"sma"``,
    ``"mckibben"``, ``"custom"``: tension unknown, fixed by its law at its input, ``control``) or
    ``"tendon"``, whose ``control`` is ``"tension"`` (given) or ``"displacement"`` (tension
    unknown, fixed by its length condition). ``tension_only``: may go slack (F = 0)."""
    name: str
    module: int
    kind: str
    route: object
    law: Optional[object]     # an ActuatorLaw (model.laws) or None (a tendon of given tension)
    reference_length: float
    parameter: str            # 'MODULE.NAME.temperature' | '.pressure' | '.tension' | ...
    control: str = "temperature"
    tension_only: bool = False
    xi_star: np.ndarray = None        # (6,) the module's reference strains (for l*)
    tca_type: Optional[str] = None    # the name of its type (tca_types or muscle_types)

    @property
    def key(self):
        return self.parameter.rsplit(".", 1)[0]

    @property
    def placement_keys(self):
        """Names of the route's parameters: ``("radius", "angle")`` or ``("radius", "phase")``."""
        return ("radius", ANGLE_KEY[self.route.kind]) if self.route.has_placement else ()

    def placement_of(self, param):
        """``(radius, angle)`` of the route from the parameters (``(1, 0)`` for a curve)."""
        if not self.placement_keys:
            return 1.0, 0.0
        return tuple(param(f"{self.key}.route.{k}")[0] for k in self.placement_keys)

    def route_values(self, s, param):
        """``(r, r', r'')`` (3, n each) at arc lengths ``s`` [m] (numbers) for the placement in
        the parameters (numbers or CasADi symbols)."""
        return self.route.placed(np.atleast_1d(np.asarray(s, float)), *self.placement_of(param))

    def reference_length_of(self, param):
        """``l*`` [m] at the parameters (kept per placement: a quadrature along the route that
        time runs and sweeps of other parameters would otherwise repeat at every point)."""
        placement = self.placement_of(param)
        if not all(isinstance(v, (float, int, np.number)) for v in placement):
            return reference_path_length(self.route, self.xi_star, *placement)       # CasADi symbols
        placement = tuple(float(v) for v in placement)
        cache = self.__dict__.setdefault("_reference_lengths", {})
        if placement not in cache:
            if len(cache) >= 64:
                cache.pop(next(iter(cache)))
            cache[placement] = reference_path_length(self.route, self.xi_star, *placement)
        return cache[placement]

    def outside_body(self, section, param):
        """Whether the route, at the placement in the parameters, leaves ``section`` (the
        module's envelope or section); kept per placement."""
        placement = tuple(float(v) for v in self.placement_of(param))
        cache = self.__dict__.setdefault("_outside", {})
        if placement not in cache:
            if len(cache) >= 64:
                cache.pop(next(iter(cache)))
            cache[placement] = outside_point(section, self.route.moved(*placement)) is not None
        return cache[placement]

    @property
    def type_path(self):
        """Where its type lives: ``tca_types.NAME`` or ``muscle_types.NAME`` (None: a tendon)."""
        if self.tca_type is None:
            return None
        return f"{self.law.TYPES_KEY}.{self.tca_type}"

    @property
    def is_muscle(self):
        """A TCA or a muscle of ``muscle_types`` (an input drives it; not a tendon)."""
        return self.tca_type is not None

    @property
    def thermal(self):
        """Heated by a drive in ``simulate`` (its input is a temperature with a thermal model)."""
        return self.law is not None and self.law.THERMAL

    def law_of(self, param):
        """The actuator's law (an :class:`~tca_casadi.model.laws.base.ActuatorLaw` or None) with
        its constants read from the parameters."""
        if self.law is None:
            return None
        prefix = f"{self.type_path}." if self.type_path else ""
        return self.law.with_parameters(param, prefix, self.reference_length_of(param))

    def thermal_law(self, scenario):
        """Its lumped :class:`~tca_casadi.model.thermal.ThermalLaw` (``THERMAL`` laws only)."""
        return muscle_module(self.kind).thermal_law(getattr(scenario, self.law.TYPES_KEY)[self.tca_type], self.law)

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
    material: str = ""                # the material's name
    shear_given: bool = False         # the material gives G (else G = E / (2 (1 + nu)))
    properties: object = None         # SectionProperties

    def moduli_of(self, param):
        """``(E, G)`` [Pa] of the module's material from the parameters."""
        prefix = f"materials.{self.material}."
        youngs = param(prefix + "youngs_modulus")[0]
        if self.shear_given:
            return youngs, param(prefix + "shear_modulus")[0]
        return youngs, youngs / (2.0 * (1.0 + param(prefix + "poisson_ratio")[0]))

    def stiffness_of(self, param):
        """(6,) diagonal of K at the parameters: ``[E Ix, E Iy, G J, G A, G A, E A]``."""
        return stiffness_diagonal(self.properties, *self.moduli_of(param))

    def weight_density_of(self, param):
        """``rho A`` [kg/m] at the parameters."""
        return param(f"materials.{self.material}.density")[0] * self.properties.area

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


class Robot:
    """Modules in series from a base. Build with :meth:`from_scenario`."""

    def __init__(self, modules, actuators, point_loads, distributed_loads, layout, values, name,
                 obstacles=(), contacts=(), contact_tolerance=1e-8):
        self.modules = modules
        self.actuators = actuators
        self.point_loads = point_loads
        self.distributed_loads = distributed_loads
        self.layout = layout
        self.values = values
        self.name = name
        #: fixed rigid shapes (:mod:`.obstacles`) and the contact candidates against them
        #: (:class:`.contact.ContactModel`, one per candidate point and obstacle)
        self.obstacles = list(obstacles)
        self.contacts = list(contacts)
        #: a body cutting into an obstacle deeper than this [m] is a penetration (contact.tolerance)
        self.contact_tolerance = contact_tolerance
        #: ``{module index: (s, ...)}``: candidates localisation added (part of the structure)
        self.added_contacts = {}
        #: free rigid bodies (:class:`.bodies.BodyModel`) and the grip candidates against them
        #: (:class:`.contact.ContactModel` with ``body`` set; ``index`` into this list)
        self.bodies, self.grips = [], []
        #: how anchored contacts hold (``contact.friction_law``): ``stick`` or ``coulomb``
        self.friction_law = "stick"

    def obstacle_of(self, k, param):
        """Obstacle k at the parameters: its position ``obstacles.NAME.position`` and its size
        (``.radius`` of a sphere or cylinder, ``.size`` of a box)."""
        shape = self.obstacles[k]
        kind = type(shape).__name__.lower()
        sizes = {key: param(f"obstacles.{shape.name}.{key}") for key in OBSTACLE_SIZES.get(kind, ())}
        if "radius" in sizes:
            sizes["radius"] = sizes["radius"][0]
        return replace(shape, position=param(f"obstacles.{shape.name}.position"), **sizes)

    def contacts_at(self, m, s):
        """The contacts at arc length s of module m."""
        tol = 1e-12 * self.modules[m].length
        return [c for c in self.contacts + self.grips if c.module == m and abs(c.s - s) <= tol]

    def contact_points(self, m):
        """Sorted candidate arc lengths [m] of module m (against obstacles and bodies)."""
        return sorted({c.s for c in self.contacts + self.grips if c.module == m})

    def grip_parameter(self, c, key):
        """The name of a grip's history parameter ``key`` (``anchor`` or ``sticks``)."""
        from .history import grip_parameter
        return grip_parameter(self.bodies[c.body].name, self.modules[c.module].name, c.number, key)

    def contact_parameter(self, c, key):
        """The name of a rod contact's history parameter ``key`` against a frictional obstacle."""
        from .history import contact_parameter
        return contact_parameter(self.obstacles[c.obstacle].name, self.modules[c.module].name, c.number, key)

    def frictional(self, c):
        """True for a rod contact (not a grip) against an obstacle with friction."""
        return c.body is None and self.obstacles[c.obstacle].friction > 0

    @property
    def frictional_contacts(self):
        """True when some obstacle has friction: its contacts stay at the candidate points
        (localisation, which adds and moves candidates, is off: they carry history)."""
        return any(shape.friction > 0 for shape in self.obstacles)

    @property
    def path_dependent(self):
        """True when friction makes an equilibrium depend on the path to it (contact objects, or
        obstacles with friction): warm solves follow the parameters from the warm start."""
        return bool(self.bodies) or self.frictional_contacts

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
        """The TCAs, in scenario order."""
        return [a for a in self.actuators if a.kind == "tca"]

    @property
    def muscles(self):
        """TCAs and other muscles (actuators driven by an input through their law), in order."""
        return [a for a in self.actuators if a.is_muscle]

    @property
    def thermal_actuators(self):
        """Muscles heated in ``simulate`` (TCAs, SMA wires), in order."""
        return [a for a in self.actuators if a.thermal]

    @classmethod
    def from_scenario(cls, scenario, added=None):
        """Model of a validated scenario; raises ScenarioError for a route outside the body.
        ``added``: ``{module index:
        [s, ...]}``, contact candidates localisation added (:mod:`tca_casadi.solvers.localisation`)."""
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
        layout, values = declare(scenario, actuators, point_loads, distributed)
        obstacles, contacts = _contacts(scenario, modules, added or {})
        robot = cls(modules, actuators, point_loads, distributed, layout, values, scenario.name, obstacles, contacts,
                    scenario.contact.tolerance)
        robot.bodies, robot.grips = _bodies(scenario, obstacles)
        robot.friction_law = scenario.contact.friction_law
        robot.added_contacts = {m: tuple(sorted(points)) for m, points in (added or {}).items() if points}
        return robot

    def is_clear(self, params):
        """False when an obstacle cuts the reference configuration at ``params`` (:meth:`check_clear`)."""
        from ..errors import ScenarioError
        try:
            self.check_clear(params)
        except ScenarioError:
            return False
        return True

    def check_clear(self, params):
        """ScenarioError if an obstacle cuts the reference configuration at ``params`` (the
        unloaded robot, where a cold solve starts) by more than 1e-9 m: naming the obstacle,
        the module, how deep and where. A grasp that the closed robot would cut starts from an
        open configuration instead (a sequence step, a warm start)."""
        if self.obstacles or self.bodies:
            _check_clear(self.at(params), np.asarray(params, float))

    def parameter_vector(self, scenario):
        """Parameter values of ``scenario`` (same structure as this robot)."""
        return declare(scenario, self.actuators, self.point_loads, self.distributed_loads)[1]

    def rest_parameters(self, values):
        """Parameters of the unloaded reference state: no gravity, no loads, tendons slack (a
        displacement tendon at q = 0 is exactly taut with no tension), TCAs at their reference
        temperature; base pose, materials and geometry kept. Its equilibrium is the reference
        shape."""
        return self.layout.rest(values)

    def structure_key(self, scenario):
        """A hashable summary of everything that is *not* a parameter (rebuild when it changes)."""
        return repr((self.layout.structure(scenario.model_dump(mode="json")), sorted(self.added_contacts.items())))

    def param_function(self, params):
        """``param(name)`` -> the (n,) numeric value of a layout entry in ``params``."""
        params = np.asarray(params, float)
        return lambda name: np.atleast_1d(params[self.layout[name]])

    def at(self, params):
        """The robot with every parameter-dependent attribute (stiffness, weight density, routes,
        laws, reference lengths, obstacle positions) evaluated at ``params``; same structure and layout (the last
        few are kept: post-processing asks for the same parameters repeatedly)."""
        params = np.asarray(params, float)
        key = self._without_drive_values(params)
        cache = self.__dict__.setdefault("_at_cache", {})
        if key not in cache:
            if len(cache) >= 8:
                cache.pop(next(iter(cache)))
            cache[key] = self._evaluated(params)
        evaluated = cache[key]
        return self._sharing_bodies(Robot(evaluated.modules, evaluated.actuators, self.point_loads,
                                          self.distributed_loads, self.layout, params, self.name,
                                          evaluated.obstacles, self.contacts, self.contact_tolerance))

    def _sharing_bodies(self, robot):
        robot.bodies, robot.grips, robot.friction_law = self.bodies, self.grips, self.friction_law
        return robot

    def _without_drive_values(self, params):
        """``params`` (bytes) with each actuator's own value (TCA temperature, tendon tension or
        displacement) zeroed: the key of what :meth:`at` evaluates, which never reads them
        (time runs and sweeps of temperatures re-use one evaluation)."""
        key = np.array(params, float)
        for actuator in self.actuators:
            key[self.layout[actuator.parameter]] = 0.0
        return key.tobytes()

    def _evaluated(self, params):
        param = self.param_function(params)
        modules = [replace(module, stiffness=module.stiffness_of(param),
                           weight_density=float(module.weight_density_of(param)), actuators=[])
                   for module in self.modules]
        actuators = []
        for actuator in self.actuators:
            law = actuator.law_of(param)
            moved = replace(actuator, route=actuator.route.moved(*actuator.placement_of(param)), law=law,
                            reference_length=float(actuator.reference_length_of(param)))
            modules[actuator.module].actuators.append(moved)
            actuators.append(moved)
        obstacles = [self.obstacle_of(k, param) for k in range(len(self.obstacles))]
        return self._sharing_bodies(Robot(modules, actuators, self.point_loads, self.distributed_loads, self.layout,
                                          np.asarray(params, float), self.name, obstacles, self.contacts,
                                          self.contact_tolerance))

    def problems(self, params):
        """What is physically impossible at ``params`` (a list of messages, empty if none):
        moduli or TCA sizes out of range, a TCA temperature outside its law's range, a route
        outside the body. Checked by sweeps and
        inverse statics, which move parameters without validating a scenario."""
        params = np.asarray(params, float)
        key = self._without_drive_values(params)
        cache = self.__dict__.setdefault("_problem_cache", {})
        if key not in cache:            # all but the temperatures: kept (time runs change only those)
            if len(cache) >= 16:
                cache.pop(next(iter(cache)))
            cache[key] = self._structural_problems(params)
        out = list(cache[key])
        for actuator in self.muscles:           # the range is the type's, never a parameter
            problem = actuator.law.input_problem(actuator.parameter, float(params[self.layout[actuator.parameter]][0]),
                                                 actuator.type_path)
            if problem:
                out.append(problem)
        return out

    def _structural_problems(self, params):
        """:meth:`problems` but for the TCA temperatures."""
        param, out = self.param_function(params), []
        for module in self.modules:
            youngs, shear = module.moduli_of(param)
            if not (youngs > 0 and shear > 0):
                out.append(f"module {module.name}: E = {youngs:g} Pa and G = {shear:g} Pa must be positive")
            if module.weight_density_of(param) < 0:
                out.append(f"module {module.name}: the density must not be negative")
        for k, shape in enumerate(self.obstacles):
            placed = self.obstacle_of(k, param)
            for key in OBSTACLE_SIZES.get(type(shape).__name__.lower(), ()):
                size = np.atleast_1d(np.asarray(getattr(placed, key), float))
                if np.any(size <= 0):
                    out.append(f"obstacles[{shape.name}]: its {key} must be positive (got {size.tolist()} m)")
        for actuator in self.actuators:
            if actuator.is_muscle:
                out.extend(actuator.law_of(param).structural_problems(actuator.key))
            if actuator.placement_keys:
                radius = actuator.placement_of(param)[0]
                if radius < 0 or (radius == 0 and actuator.route.kind == "helix"):
                    out.append(f"{actuator.key}: route radius {radius:g} m must be positive")
                    continue
            section = self.modules[actuator.module].section
            if actuator.outside_body(section.envelope or section, param):
                out.append(f"{actuator.key}: the route passes outside the body")
        return out


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
                       material.density * props.area, config.cross_section, connector,
                       material=config.material, shear_given=material.shear_modulus is not None,
                       properties=props)


def _actuator(scenario, index, config, a_index, a_config):
    span = route_span(a_config.route, config.length)
    route = make_route(a_config.route, span)
    _check_inside(scenario, index, config, a_index, route)
    xi_star = np.array(list(config.precurvature) + [0.0, 0.0, 1.0])
    reference_length = reference_path_length(route, xi_star)
    law, control, tca_type = None, "temperature", None
    if a_config.kind in laws():                         # a TCA or a muscle: its type drives its law
        tca_type = a_config.type
        law_class = laws()[a_config.kind]
        law = law_class.from_type(getattr(scenario, law_class.TYPES_KEY)[a_config.type], reference_length)
        control = law.INPUT[0]
    else:
        control = a_config.control
        if control == "displacement":
            compliance = a_config.compliance if a_config.compliance is not None else (
                1.0 / a_config.stiffness if a_config.stiffness is not None else 0.0)
            law = TendonLaw(reference_length, compliance)
    parameter = f"{config.name}.{a_config.name}.{control}"
    return ActuatorModel(a_config.name, index, a_config.kind, route, law, reference_length, parameter,
                         control, bool(a_config.tension_only), xi_star, tca_type)





def _check_inside(scenario, index, config, a_index, route):
    outline = config.cross_section.envelope or config.cross_section
    worst = outside_point(outline, route)
    if worst is not None:
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
        for holder in item.held_by if not item.contact else ():      # a contact object: by contact
            index = module_index[holder]
            point.append(PointLoadModel(item.name, index, scenario.modules[index].length, "global",
                                        "object", 1.0 / len(item.held_by)))
    return point, distributed


def _contacts(scenario, modules, added):
    """``(obstacles, contacts)``: the shapes of ``scenario.obstacles`` and one
    :class:`.contact.ContactModel` per candidate point of each module and obstacle."""
    if not scenario.obstacles:
        return [], []
    from .contact import ContactModel, candidate_points, shape_of
    obstacles = [shape_of(config) for config in scenario.obstacles]
    names = [module.name for module in modules]
    given = {names.index(name): points for name, points in scenario.contact.at.items()}
    contacts = []
    for m, module in enumerate(modules):
        for K, s in enumerate(candidate_points(module.length, scenario.contact.points, given.get(m, ()),
                                               added.get(m, ()))):
            for k in range(len(obstacles)):
                contacts.append(ContactModel(m, float(s), k, len(contacts), number=K))
    return obstacles, contacts


def _bodies(scenario, obstacles):
    """``(bodies, grips)`` of the scenario's contact objects (:mod:`.bodies`)."""
    from .bodies import BodyModel, contact_objects, grip_points
    if not contact_objects(scenario):
        return [], []
    from .rotations import rotation_numpy
    from .contact import ContactModel
    names = [o.name for o in obstacles]
    bodies = []
    for b, (_, item) in enumerate(contact_objects(scenario)):
        rotation = rotation_numpy(np.array([np.cos(item.yaw / 2), 0.0, 0.0, np.sin(item.yaw / 2)]))   # about z
        holders = tuple(m for m, module in enumerate(scenario.modules) if module.name in item.held_by)
        bodies.append(BodyModel(item.name, b, float(item.mass), np.asarray(item.size, float), np.asarray(item.position, float),
                                rotation, float(item.friction),
                                names.index(item.support) if item.support is not None else None, holders,
                                sliding=scenario.contact.friction_law == "coulomb",
                                support_friction=float(item.friction if item.support_friction is None
                                                       else item.support_friction)))
    grips = [ContactModel(m, s, None, k, body=b, number=K) for k, (b, m, K, s) in enumerate(grip_points(scenario))]
    return bodies, grips


#: samples per module when checking that no obstacle cuts the reference configuration
CLEAR_SAMPLES = 401


def _check_clear(robot, values):
    """ScenarioError if an obstacle already cuts a module's reference configuration (by more
    than 1e-9 m): naming the obstacle, the module, how deep and where."""
    from ..errors import ScenarioError
    from .kinematics import reference_chain
    from .contact import gaps, outline_of
    from .bodies import body_shape, support_gaps
    samples = [np.linspace(0.0, module.length, CLEAR_SAMPLES) for module in robot.modules]
    placed = [body_shape(body, body.position, body.rotation) for body in robot.bodies]
    for body in robot.bodies:
        if body.support is not None:
            g = min(support_gaps(robot.obstacles[body.support], body, body.position, body.rotation)[0])
            if abs(g) > 1e-9:
                raise ScenarioError(
                    f"objects[{body.name}]: {'lies' if g > 0 else 'cuts'} {abs(g) * 1e3:.4g} mm "
                    f"{'above' if g > 0 else 'into'} its support {robot.obstacles[body.support].name!r}: "
                    "place it on it (its lowest point on the plane)")
    for m, states in enumerate(reference_chain(robot, values, samples)):
        module = robot.modules[m]
        for shape in robot.obstacles + placed:
            found = gaps(shape, outline_of(module), states[0:3], states[3:7])
            j = int(np.argmin(found))
            if found[j] < -1e-9:
                kind = "objects" if any(shape is body for body in placed) else "obstacles"
                raise ScenarioError(
                    f"{kind}[{shape.name}]: intersects module {module.name!r} in its reference configuration "
                    f"by {-found[j] * 1e3:.4g} mm at s = {samples[m][j] * 1e3:.4g} mm, where a cold solve starts: move it "
                    "clear, or start from a configuration clear of it (a sequence step, a warm start)")

"""The scenario schema (SPEC section 7): pydantic models, every quantity unit-aware, unknown keys
rejected. Values are stored in SI (temperatures in degC) after validation.

Cross-references (materials, TCA types, module names, routes inside the body) are checked in
:mod:`tca_casadi.scenario.checks`, where the file lines are known.
"""
import math
from typing import Annotated, Literal, Optional, Union

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, PrivateAttr, create_model, model_validator

from ..text import shorten
from ..units import to_si


def _quantity(kind):
    def convert(value):
        return to_si(value, kind)
    convert.kind = kind                 # the unit kind, read by the scenario reference (reference.py)
    return BeforeValidator(convert)


def _vector(kind, size):
    def convert(value):
        if not isinstance(value, (list, tuple)):
            raise ValueError(f"expected a list of {size} values, got {shorten(value)}")
        if len(value) != size:
            raise ValueError(f"expected a list of {size} values, got {len(value)}")
        return tuple(to_si(item, kind) for item in value)
    convert.kind = kind
    return BeforeValidator(convert)


Length = Annotated[float, _quantity("length")]
PositiveLength = Annotated[float, _quantity("length"), Field(gt=0)]
NonNegativeLength = Annotated[float, _quantity("length"), Field(ge=0)]
Angle = Annotated[float, _quantity("angle")]
Temperature = Annotated[float, _quantity("temperature"), Field(ge=-273.15)]
Force = Annotated[float, _quantity("force")]
NonNegativeMass = Annotated[float, _quantity("mass"), Field(ge=0)]
Number = Annotated[float, _quantity("dimensionless")]
Vector3Length = Annotated[tuple[float, float, float], _vector("length", 3)]
Vector3 = Annotated[tuple[float, float, float], _vector("dimensionless", 3)]
Vector3Force = Annotated[tuple[float, float, float], _vector("force", 3)]
Vector3Moment = Annotated[tuple[float, float, float], _vector("moment", 3)]
Vector3ForcePerLength = Annotated[tuple[float, float, float], _vector("force_per_length", 3)]
Vector3MomentPerLength = Annotated[tuple[float, float, float], _vector("moment_per_length", 3)]
Vector3Acceleration = Annotated[tuple[float, float, float], _vector("acceleration", 3)]
Vector3Curvature = Annotated[tuple[float, float, float], _vector("curvature", 3)]
Quaternion = Annotated[tuple[float, float, float, float], _vector("dimensionless", 4)]


class Strict(BaseModel):
    """Base of every scenario model: unknown keys are errors, numbers must be finite."""
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=False)


# ----------------------------------------------------------------------------- orientation
class Orientation(Strict):
    """A rotation given as axis + angle, or as a quaternion ``[w, x, y, z]`` (normalised)."""
    axis: Optional[Vector3] = None
    angle: Optional[Angle] = None
    quaternion: Optional[Quaternion] = None

    @model_validator(mode="after")
    def _one_form(self):
        if self.quaternion is not None:
            if self.axis is not None or self.angle is not None:
                raise ValueError("give either 'quaternion' or 'axis' + 'angle', not both")
            if math.sqrt(sum(q * q for q in self.quaternion)) < 1e-12:
                raise ValueError("quaternion must not be zero")
        elif (self.axis is None) != (self.angle is None):
            raise ValueError("'axis' and 'angle' go together")
        elif self.axis is not None and math.sqrt(sum(a * a for a in self.axis)) < 1e-12:
            raise ValueError("rotation axis must not be zero")
        return self

    def as_quaternion(self):
        """Unit quaternion ``(w, x, y, z)``."""
        if self.quaternion is not None:
            norm = math.sqrt(sum(q * q for q in self.quaternion))
            return tuple(q / norm for q in self.quaternion)
        if self.axis is None:
            return (1.0, 0.0, 0.0, 0.0)
        norm = math.sqrt(sum(a * a for a in self.axis))
        half = 0.5 * self.angle
        return (math.cos(half),) + tuple(math.sin(half) * a / norm for a in self.axis)


class Base(Strict):
    """Pose of the first module's base in the global frame."""
    position: Vector3Length = (0.0, 0.0, 0.0)
    orientation: Orientation = Field(default_factory=Orientation)


# ----------------------------------------------------------------------------- materials
class Material(Strict):
    """Isotropic body material. Shear modulus from ``poisson_ratio`` (default 0.5: G = E/3, the
    paper's choice) unless ``shear_modulus`` is given."""
    youngs_modulus: Annotated[float, _quantity("pressure"), Field(gt=0)]
    poisson_ratio: Optional[Annotated[float, _quantity("dimensionless"), Field(gt=-1, le=0.5)]] = None
    shear_modulus: Optional[Annotated[float, _quantity("pressure"), Field(gt=0)]] = None
    density: Annotated[float, _quantity("density"), Field(ge=0)] = 0.0

    @model_validator(mode="after")
    def _one_shear(self):
        if self.poisson_ratio is not None and self.shear_modulus is not None:
            raise ValueError("give either 'poisson_ratio' or 'shear_modulus', not both")
        return self

    def shear(self):
        """Shear modulus G [Pa]."""
        if self.shear_modulus is not None:
            return self.shear_modulus
        nu = 0.5 if self.poisson_ratio is None else self.poisson_ratio
        return self.youngs_modulus / (2.0 * (1.0 + nu))


class UntwistFit(Strict):
    """Fiber untwist per unit fiber length, ``c2 T^2 + c1 T + c0`` [rad/m], T in degC."""
    c2: Number = -0.0161
    c1: Number = 0.3338
    c0: Number = -7.7311


class ShearModulusFit(Strict):
    """TCA fiber shear modulus ``a2 F^2 + a1 F + a0`` [Pa], F the tension in N."""
    a2: Annotated[float, _quantity("pressure_per_force2")] = 37.58e6
    a1: Annotated[float, _quantity("pressure_per_force")] = 111.33e6
    a0: Annotated[float, _quantity("pressure"), Field(gt=0)] = 0.85e6


class TcaThermal(Strict):
    """The lumped thermal model of a TCA type (:mod:`tca_casadi.model.thermal`): ``heat_capacity``
    [J/K] and ``conductance`` [W/K] given, or derived from the fibre's geometry with ``density``,
    ``specific_heat``, ``convection_coefficient`` and ``area_factor`` (the exposed fraction of
    the fibre's lateral surface). Defaults: nylon 6,6 in still air."""
    heat_capacity: Optional[Annotated[float, _quantity("heat_capacity"), Field(gt=0)]] = None
    conductance: Optional[Annotated[float, _quantity("thermal_conductance"), Field(gt=0)]] = None
    density: Annotated[float, _quantity("density"), Field(gt=0)] = 1140.0
    specific_heat: Annotated[float, _quantity("specific_heat"), Field(gt=0)] = 1700.0
    convection_coefficient: Annotated[float, _quantity("heat_transfer_coefficient"), Field(gt=0)] = 25.0
    area_factor: Annotated[float, _quantity("dimensionless"), Field(gt=0, le=1)] = 1.0


class TcaType(Strict):
    """Geometry and thermo-mechanical law of a TCA (SPEC section 4); defaults are the paper's."""
    fiber_radius: PositiveLength
    coil_radius: PositiveLength
    pitch_angle: Annotated[float, _quantity("angle"), Field(gt=0, lt=math.pi / 2)]
    fiber_length: Optional[PositiveLength] = None
    reference_temperature: Temperature = 25.0
    #: the range the law is used in: below 15 degC the paper's untwist fit nears its vertex
    #: (10.4 degC), under which it would make a cooled TCA contract; above 150 degC nylon softens
    min_temperature: Temperature = 15.0
    max_temperature: Temperature = 150.0
    untwist: UntwistFit = Field(default_factory=UntwistFit)
    shear_modulus: ShearModulusFit = Field(default_factory=ShearModulusFit)
    thermal: TcaThermal = Field(default_factory=TcaThermal)
    #: electrical resistance at reference_temperature [ohm] (needed by voltage and current drives)
    resistance: Optional[Annotated[float, _quantity("resistance"), Field(gt=0)]] = None
    resistance_temperature_coefficient: Annotated[float, _quantity("per_kelvin")] = 0.0

    @model_validator(mode="after")
    def _geometry(self):
        if self.coil_radius <= self.fiber_radius:
            raise ValueError(f"coil_radius ({self.coil_radius * 1e3:g} mm) must be larger than "
                             f"fiber_radius ({self.fiber_radius * 1e3:g} mm)")
        if self.max_temperature <= self.reference_temperature:
            raise ValueError("max_temperature must be above reference_temperature")
        if self.min_temperature > self.reference_temperature:
            raise ValueError("min_temperature must not be above reference_temperature")
        return self


# ----------------------------------------------------------------------------- sections
class Circle(Strict):
    shape: Literal["circle"]
    diameter: PositiveLength


class Rectangle(Strict):
    """Width along body x, height along body y. ``torsion``: Saint-Venant's constant (default)
    or the paper's polar ``J = Ix + Iy``."""
    shape: Literal["rectangle"]
    width: PositiveLength
    height: PositiveLength
    torsion: Literal["saint_venant", "polar"] = "saint_venant"


Outline = Annotated[Union[Circle, Rectangle], Field(discriminator="shape")]


class CircleSection(Circle):
    envelope: Optional[Outline] = None


class RectangleSection(Rectangle):
    envelope: Optional[Outline] = None


#: ``envelope`` is the outline of the body the channels must lie in, when the stiffness-equivalent
#: section is smaller than the real body (the paper's bending module); default: the section.
CrossSection = Annotated[Union[CircleSection, RectangleSection], Field(discriminator="shape")]


# ----------------------------------------------------------------------------- routes
Span = Annotated[tuple[float, float], _vector("length", 2)]


class Straight(Strict):
    """``r = radius [cos(angle), sin(angle), 0]``."""
    kind: Literal["straight"]
    radius: NonNegativeLength
    angle: Angle = 0.0
    span: Optional[Span] = None


class Helix(Strict):
    """``r = radius [cos b, sin b, 0]``, ``b = phase + 2 pi turns (s - s_a)/(s_b - s_a)``."""
    kind: Literal["helix"]
    radius: PositiveLength
    turns: Number
    phase: Angle = 0.0
    span: Optional[Span] = None

    @model_validator(mode="after")
    def _turns(self):
        if self.turns == 0:
            raise ValueError("a helix needs nonzero 'turns' (use kind: straight)")
        return self


class Curve(Strict):
    """Points ``[s, x, y]`` through which a C2 cubic spline passes; the span defaults to the
    points' range of s."""
    kind: Literal["curve"]
    points: list[Annotated[tuple[float, float, float], _vector("length", 3)]] = Field(min_length=2)
    span: Optional[Span] = None

    @model_validator(mode="after")
    def _increasing(self):
        s = [point[0] for point in self.points]
        if any(b <= a for a, b in zip(s, s[1:])):
            raise ValueError("curve points must have strictly increasing arc length s")
        return self


Route = Annotated[Union[Straight, Helix, Curve], Field(discriminator="kind")]


# ----------------------------------------------------------------------------- actuators
#: a drive's kind -> the unit kind of its value
DRIVE_UNITS = {"power": "power", "voltage": "voltage", "current": "current", "temperature": "temperature",
               "setpoint": "temperature", "mpc": "power"}


class PiGains(Strict):
    """A PI temperature controller's gains: ``proportional`` [W/K], ``integral`` [W/(K s)]."""
    proportional: Annotated[float, _quantity("thermal_conductance"), Field(ge=0)]
    integral: Annotated[float, _quantity("integral_gain"), Field(gt=0)]


class MpcSettings(Strict):
    """A model-predictive controller of the tip (``drive: {kind: mpc, mpc: {...}}``): every
    ``period`` [s] it plans the powers over ``horizon`` [s] (``nodes`` steps, the minimum-time
    plan of ``tca-casadi plan``, or its tracking plan of ``path``) from the measured
    temperatures, towards ``target`` [m] (or the path ahead) shifted
    by the estimated mismatch of plant and model (``disturbance_gain``: the filter of the
    measured tip less the model's; ``integral_gain``: of the tip error near the target, per
    period: no steady offset when the plant differs from the model), and applies the first
    step."""
    target: Optional[Vector3Length] = None
    #: instead of a target: a tip path to follow, a CSV with columns t [s], x, y, z (as ``plan
    #: --path`` reads; relative to the scenario's folder)
    path: Optional[str] = None
    period: Annotated[float, _quantity("time"), Field(gt=0)] = 0.5
    horizon: Annotated[float, _quantity("time"), Field(gt=0)] = 10.0
    nodes: Annotated[int, Field(ge=1, le=500)] = 20
    tolerance: Annotated[float, _quantity("length"), Field(gt=0)] = 1e-4
    integral_gain: Annotated[float, Field(ge=0, le=1)] = 0.2
    disturbance_gain: Annotated[float, Field(ge=0, le=1)] = 0.5

    @model_validator(mode="after")
    def _target_or_path(self):
        if (self.target is None) == (self.path is None):
            raise ValueError("an mpc controller follows a target: [x, y, z] or a path: CSV file (one of them)")
        return self

    @model_validator(mode="after")
    def _horizon_holds_a_period(self):
        if self.horizon < self.period:
            raise ValueError(f"the horizon ({self.horizon:g} s) is shorter than the period ({self.period:g} s)")
        return self


class TcaDrive(Strict):
    """How a TCA is heated in ``tca-casadi simulate``: ``kind`` ``power`` [W], ``voltage`` [V],
    ``current`` [A], ``temperature`` [degC] (set directly, as in ``solve``), ``setpoint``
    [degC] (a PI controller with ``gains`` and a ``max_power`` [W]) or ``mpc`` (its power [W]
    chosen by the model-predictive controller ``mpc``, at most ``max_power``; ``value``: the
    power before it starts), and its ``value``."""
    kind: Literal["power", "voltage", "current", "temperature", "setpoint", "mpc"]
    value: Union[float, str] = 0.0
    gains: Optional[PiGains] = None
    max_power: Optional[Annotated[float, _quantity("power"), Field(gt=0)]] = None
    mpc: Optional[MpcSettings] = None

    @model_validator(mode="after")
    def _value_in_its_unit(self):
        self.value = to_si(self.value, DRIVE_UNITS[self.kind])
        if self.kind not in ("temperature", "setpoint") and self.value < 0:
            raise ValueError(f"a {self.kind} drive's value must not be negative (got {self.value:g})")
        if self.kind == "setpoint" and (self.gains is None or self.max_power is None):
            raise ValueError("a setpoint drive needs gains: {proportional, integral} and max_power")
        if self.kind != "setpoint" and self.gains is not None:
            raise ValueError("gains belong to a setpoint drive")
        if self.kind not in ("setpoint", "mpc") and self.max_power is not None:
            raise ValueError("max_power belongs to a setpoint or mpc drive")
        if (self.kind == "mpc") != (self.mpc is not None):
            raise ValueError("an mpc drive needs its controller's settings, mpc: {target: [x, y, z], period, horizon, "
                             "...}, and only an mpc drive has them")
        return self


class Tca(Strict):
    """A TCA: tension unknown, fixed by the TCA law at ``temperature`` [degC]; ``drive``: how
    ``simulate`` heats it (default: its temperature, as given)."""
    name: str = Field(min_length=1)
    kind: Literal["tca"]
    type: str
    route: Route
    temperature: Temperature = 25.0
    tension_only: bool = False
    drive: Optional[TcaDrive] = None


class Tendon(Strict):
    """A tendon: ``control: tension`` (a given ``tension`` [N]) or ``control: displacement``
    (pulled by ``displacement`` [m] at its proximal end; tension unknown; optional
    ``compliance`` [1/N] or axial ``stiffness`` [N]; ``tension_only``: may go slack)."""
    name: str = Field(min_length=1)
    kind: Literal["tendon"]
    route: Route
    control: Literal["tension", "displacement"] = "tension"
    tension: Force = 0.0
    displacement: Length = 0.0
    compliance: Optional[Annotated[float, _quantity("compliance"), Field(ge=0)]] = None
    stiffness: Optional[Annotated[float, _quantity("force"), Field(gt=0)]] = None
    tension_only: bool = False

    @model_validator(mode="after")
    def _control_keys(self):
        if self.control == "tension" and (self.displacement != 0 or self.tension_only or
                                          self.compliance is not None or self.stiffness is not None):
            raise ValueError("displacement, compliance, stiffness and tension_only need "
                             "control: displacement (a given tension cannot go slack)")
        if self.control == "displacement" and self.tension != 0:
            raise ValueError("a displacement-controlled tendon's tension is unknown: remove 'tension'")
        if self.compliance is not None and self.stiffness is not None:
            raise ValueError("give compliance or stiffness, not both")
        return self


# ----------------------------------------------------------------------------- other muscles
def _law_field(kind_or_type, default, positive=False):
    """A pydantic field from a law's declaration: a unit kind (quantity) or a type."""
    from ..units import KINDS
    if isinstance(kind_or_type, str) and kind_or_type in KINDS:
        annotation = Annotated[float, _quantity(kind_or_type)]
        if positive:
            annotation = Annotated[float, _quantity(kind_or_type), Field(gt=0)]
        if kind_or_type == "temperature":
            annotation = Annotated[float, _quantity("temperature"), Field(ge=-273.15)]
    else:
        annotation = kind_or_type
    if default is None:
        return (Optional[annotation], None)
    return (annotation, default)


def _muscle_type_model(law):
    """The ``muscle_types`` entry of one muscle kind, made from its declarations
    (:mod:`tca_casadi.catalogue`)."""
    fields = {"kind": (Literal[law.KIND], ...)}
    for p in law.PARAMETERS:
        fields[p.name] = _law_field(p.kind, p.default, p.positive)
    for name, (kind_or_type, default) in law.OPTIONS.items():
        fields[name] = _law_field(kind_or_type, default)
    defaults = getattr(law, "THERMAL_DEFAULTS", None)
    if defaults is not None:
        thermal = create_model(f"{law.__name__}Thermal", __base__=TcaThermal,
                               **{k: (TcaThermal.model_fields[k].rebuild_annotation(), v)
                                  for k, v in defaults.items()})
        fields["thermal"] = (thermal, Field(default_factory=thermal))

    def check(self):
        law.validate_type(self)
        return self
    return create_model(f"{law.__name__}Type", __base__=Strict, __doc__=law.__doc__,
                        __validators__={"_law_checks": model_validator(mode="after")(check)}, **fields)


def _muscle_actuator_model(law):
    """An actuator of one muscle kind: ``name, kind, type, route, tension_only``, its input
    (``temperature``, ``pressure``, ``input``... with its unit) and, when heated in ``simulate``,
    a ``drive``."""
    name, kind, default = law.INPUT
    fields = {"name": (str, Field(min_length=1)), "kind": (Literal[law.KIND], ...), "type": (str, ...),
              "route": (Route, ...), name: _law_field(kind, default), "tension_only": (bool, False)}
    if law.THERMAL:
        fields["drive"] = (Optional[TcaDrive], None)
    return create_model(f"{law.__name__}Actuator", __base__=Strict,
                        __doc__=f"A {law.KIND} actuator: tension unknown, fixed by its law at its {name}.",
                        **fields)


def _muscles():
    from ..catalogue import muscle_declarations
    return muscle_declarations()


_MUSCLE_TYPES = [_muscle_type_model(law) for law in _muscles().values()]
_MUSCLE_ACTUATORS = [_muscle_actuator_model(law) for law in _muscles().values()]
MuscleType = Annotated[Union[tuple(_MUSCLE_TYPES)], Field(discriminator="kind")]

Actuator = Annotated[Union[(Tca, Tendon, *_MUSCLE_ACTUATORS)], Field(discriminator="kind")]


class Connector(Strict):
    """Rigid piece between the previous module's tip and this module's base: offset and rotation
    in the previous tip frame, a mass at ``center_of_mass`` (default: half the offset)."""
    offset: Vector3Length = (0.0, 0.0, 0.0)
    rotation: Orientation = Field(default_factory=Orientation)
    mass: NonNegativeMass = 0.0
    center_of_mass: Optional[Vector3Length] = None


class ThermalCoupling(Strict):
    """Heat conducted through a module's body between its TCAs (``simulate``): ``conductance``
    [W/K] between each pair in ``between`` (pairs of the module's TCA names; default every
    pair of its TCAs)."""
    conductance: Annotated[float, _quantity("thermal_conductance"), Field(ge=0)]
    between: Optional[list[tuple[str, str]]] = None


class Module(Strict):
    """One Cosserat rod (SPEC sections 2 and 5). Its base sits on the tip of ``parent`` (default:
    the module before it), so modules form a chain or a tree (several fingers on one parent).
    ``decoupled``: solved on its own at the parent's tip frame; only its net external force
    (its weight and any payload) loads the parent's tip, its moment is neglected (the paper's
    treatment of the gripper)."""
    name: str = Field(min_length=1)
    length: PositiveLength
    material: str
    cross_section: CrossSection
    actuators: list[Actuator] = Field(default_factory=list)
    precurvature: Vector3Curvature = (0.0, 0.0, 0.0)
    connector: Optional[Connector] = None
    parent: Optional[str] = None
    decoupled: bool = False
    thermal_coupling: Optional[ThermalCoupling] = None


# ----------------------------------------------------------------------------- loads
Where = Union[Literal["end", "start"], Annotated[float, _quantity("length"), Field(ge=0)]]


class PointLoad(Strict):
    """A force and moment at one arc length of a module, in the global or body frame."""
    name: str = Field(min_length=1)
    kind: Literal["point"]
    module: str
    at: Where = "end"
    force: Vector3Force = (0.0, 0.0, 0.0)
    moment: Vector3Moment = (0.0, 0.0, 0.0)
    frame: Literal["global", "body"] = "global"


class MassLoad(Strict):
    """A point mass on the centerline: its weight ``mass * gravity`` acts there."""
    name: str = Field(min_length=1)
    kind: Literal["mass"]
    module: str
    at: Where = "end"
    mass: NonNegativeMass


class DistributedLoad(Strict):
    """Force and moment per unit reference length over a span (default: the whole module)."""
    name: str = Field(min_length=1)
    kind: Literal["distributed"]
    module: str
    span: Optional[Span] = None
    force: Vector3ForcePerLength = (0.0, 0.0, 0.0)
    moment: Vector3MomentPerLength = (0.0, 0.0, 0.0)
    frame: Literal["global", "body"] = "global"


Load = Annotated[Union[PointLoad, MassLoad, DistributedLoad], Field(discriminator="kind")]


# ----------------------------------------------------------------------------- objects
class GraspedObject(Strict):
    """A rigid box the robot can pick: it rests at ``position`` (its centre, global frame, turned
    ``yaw`` about the global z axis) until ``held`` is set; while held, its weight hangs from the
    tips of the ``held_by`` modules in equal shares and it moves with them. With ``contact: true``
    it is a free rigid body instead (``docs/contact.md`` section 5): resting on the plane obstacle
    ``support``, touched by the ``held_by`` modules (``friction`` between them and it;
    ``support_friction`` between it and its support, by default ``friction``), held only by the
    contact forces."""
    name: str = Field(min_length=1)
    mass: NonNegativeMass
    size: Vector3Length
    position: Vector3Length
    yaw: Angle = 0.0
    held_by: list[str] = Field(min_length=1)
    held: bool = False
    #: a free rigid body (issue 17): its pose is unknown, it rests on ``support`` and the
    #: ``held_by`` modules can touch it, press on it and carry it by friction
    contact: bool = False
    support: Optional[str] = None
    friction: Annotated[float, _quantity("dimensionless"), Field(ge=0)] = 0.0
    support_friction: Optional[Annotated[float, _quantity("dimensionless"), Field(ge=0)]] = None

    _positive_size = model_validator(mode="after")(lambda self: _positive_edges(self))

    @model_validator(mode="after")
    def _contact_body(self):
        if self.contact and self.held:
            raise ValueError("held is for objects without contact: a contact object is held by its contact forces")
        if self.contact and self.mass <= 0:
            raise ValueError("a contact object needs a mass > 0 (its weight is what the grasp carries)")
        if self.contact and self.support is None:
            raise ValueError("a contact object needs a support: the plane obstacle it rests on where it is placed")
        return self


def _positive_edges(box):
    """``box`` (an object or a box obstacle) when every edge of its ``size`` is positive."""
    if min(box.size) <= 0:
        raise ValueError("size: every edge must be positive")
    return box


# ----------------------------------------------------------------------------- obstacles
Friction = Annotated[float, _quantity("dimensionless"), Field(ge=0)]


class ObstacleBase(Strict):
    """A fixed rigid shape the rods may touch (issue 17; ``docs/contact.md``): ``name``,
    ``position`` [m] (global frame), ``friction`` (Coulomb's coefficient)."""
    name: str = Field(min_length=1)
    position: Vector3Length = (0.0, 0.0, 0.0)
    friction: Friction = 0.0


class PlaneObstacle(ObstacleBase):
    """The half-space below the plane through ``position``; ``normal`` points out of it."""
    shape: Literal["plane"]
    normal: Vector3 = (0.0, 0.0, 1.0)

    @model_validator(mode="after")
    def _nonzero_normal(self):
        if math.sqrt(sum(n * n for n in self.normal)) < 1e-12:
            raise ValueError("normal must not be zero")
        return self


class SphereObstacle(ObstacleBase):
    """A ball of ``radius`` centred on ``position``."""
    shape: Literal["sphere"]
    radius: PositiveLength


class CylinderObstacle(ObstacleBase):
    """An infinitely long cylinder of ``radius`` about its frame's z axis (``orientation``
    turns it), through ``position``: a post, a bar."""
    shape: Literal["cylinder"]
    radius: PositiveLength
    orientation: Orientation = Field(default_factory=Orientation)


class BoxObstacle(ObstacleBase):
    """A box of edges ``size`` along its frame's axes (``orientation`` turns it), centred on
    ``position``."""
    shape: Literal["box"]
    size: Vector3Length
    orientation: Orientation = Field(default_factory=Orientation)

    _positive_size = model_validator(mode="after")(lambda self: _positive_edges(self))


Obstacle = Annotated[Union[PlaneObstacle, SphereObstacle, CylinderObstacle, BoxObstacle],
                     Field(discriminator="shape")]


class ContactOptions(Strict):
    """Where contact is checked (``docs/contact.md``): each module's ends, ``points`` evenly
    spaced points inside it and the arc lengths ``at`` lists per module (``{MODULE: [s, ...]}``)
    are contact candidates against every obstacle; after a solve, the gap is sampled finely and
    a candidate is added where the body still penetrates by more than ``tolerance``, up to
    ``localise`` times. ``friction_law``: how the grips of contact objects hold (``stick``: they
    stick whatever it takes, and a grasp needing more friction than it has is reported slipping
    with the friction it would need; ``coulomb``: they slide on Coulomb's cone, so a grasp can
    let go and an object can slide out of it)."""
    points: int = Field(default=8, ge=0, le=200)
    at: dict[str, list[Annotated[float, _quantity("length"), Field(ge=0)]]] = Field(default_factory=dict)
    tolerance: Annotated[float, _quantity("length"), Field(gt=0)] = 1e-8
    localise: int = Field(default=8, ge=0, le=50)
    friction_law: Literal["stick", "coulomb"] = "stick"


# ----------------------------------------------------------------------------- solver
class SolverOptions(Strict):
    """How to discretise and solve (SPEC section 6)."""
    method: Literal["collocation", "shooting"] = "collocation"
    intervals: Union[Annotated[int, Field(ge=1, le=2000)], Literal["auto"]] = "auto"
    degree: int = Field(default=4, ge=1, le=9)
    scheme: Literal["legendre", "radau"] = "legendre"
    tolerance: float = Field(default=1e-10, gt=0, lt=1e-2)
    max_iterations: int = Field(default=200, ge=1)
    continuation: Literal["auto", "always", "never"] = "auto"
    algorithm: Literal["ipopt", "newton"] = "newton"
    #: accuracy asked of a cold collocation solve: tip position [m] and tensions (relative to
    #: the largest), checked by an error estimate and met by refining the mesh (``refine: auto``)
    tip_tolerance: Annotated[float, _quantity("length"), Field(gt=0)] = 1e-7
    tension_tolerance: Annotated[float, Field(gt=0, lt=1)] = 1e-6
    #: ``off`` (YAML reads a bare ``off`` as false, accepted too) keeps the mesh and only reports
    refine: Annotated[Literal["auto", "off"], BeforeValidator(
        lambda v: {False: "off", True: "auto"}.get(v, v) if isinstance(v, bool) else v)] = "auto"
    max_intervals: int = Field(default=200, ge=1, le=2000)
    #: compile the collocation residual, its Jacobians and Newton's chord steps to machine code
    #: (gcc -O1, kept on disk per structure): residual evaluations about six times faster,
    #: Jacobians ten times, chord steps with no Python between them, after a one-time compile of
    #: seconds; ``auto``: only for a long dynamic run (:data:`~tca_casadi.solvers.dynamics.AUTO_JIT_STEPS`
    #: steps or more) and only where a C compiler is found
    jit: Union[bool, Literal["auto"]] = "auto"

    @model_validator(mode="before")
    @classmethod
    def _tolerance_mapping(cls, data):
        """``tolerance: {residual, tip, tension}`` sets the three tolerances at once."""
        if isinstance(data, dict) and isinstance(data.get("tolerance"), dict):
            data = dict(data)
            given = dict(data.pop("tolerance"))
            unknown = set(given) - {"residual", "tip", "tension"}
            if unknown:
                raise ValueError(f"tolerance: unknown key(s) {sorted(unknown)}; valid: residual, tip, tension")
            for key, field in (("residual", "tolerance"), ("tip", "tip_tolerance"), ("tension", "tension_tolerance")):
                if key in given:
                    data[field] = given[key]
        return data


# ----------------------------------------------------------------------------- inverse statics
class InverseTarget(Strict):
    """A target pose for inverse statics: a position, and optionally the tip tangent's direction
    or a full orientation (quaternion [w, x, y, z]) of the point's frame."""
    position: Vector3Length
    direction: Optional[Vector3] = None
    orientation: Optional[Quaternion] = None
    point: str = "tip"

    @model_validator(mode="after")
    def _one_orientation(self):
        if self.direction is not None and self.orientation is not None:
            raise ValueError("give a direction or an orientation, not both")
        for name in ("direction", "orientation"):
            value = getattr(self, name)
            if value is not None and math.sqrt(sum(v * v for v in value)) == 0:
                raise ValueError(f"{name} must not be zero")
        return self


class InverseOptions(Strict):
    """Inverse statics (SPEC section 6): which temperatures vary, their bounds, the target."""
    target: Optional[InverseTarget] = None
    vary: Optional[list[str]] = None
    #: [low, high] of every varied input, in its unit (temperatures in degC, pressures in Pa;
    #: strings with units allowed)
    bounds: Optional[tuple[Union[float, str], Union[float, str]]] = None
    tolerance: Annotated[float, _quantity("length"), Field(gt=0)] = 1e-4
    regularisation: Annotated[float, Field(ge=0)] = 1e-3
    orientation_weight: Annotated[float, Field(ge=0)] = 1.0
    starts: int = Field(default=4, ge=1, le=64)
    method: Literal["ipopt", "reduced"] = "reduced"


# ----------------------------------------------------------------------------- sequences
class SequenceStep(Strict):
    """One step of a sequence: values set by dotted path (applied on top of the previous steps)."""
    name: str = Field(min_length=1)
    set: dict[str, object] = Field(default_factory=dict)


Time = Annotated[float, _quantity("time"), Field(ge=0)]


class TimelineEvent(Strict):
    """At time ``at`` [s], set values by dotted path (drive values, temperatures, tensions,
    loads, ...), at once or linearly over ``ramp`` [s]."""
    at: Time
    set: dict[str, object] = Field(default_factory=dict)
    ramp: Optional[Annotated[float, _quantity("time"), Field(gt=0)]] = None


class Damping(Strict):
    """Kelvin-Voigt damping of the rods (:class:`tca_casadi.model.dynamics.KelvinVoigt`): an
    extensional ``viscosity`` [Pa s] (and ``shear_viscosity``, default a third of it), or a
    damping ``ratio`` at a ``frequency`` [Hz] (stiffness proportional)."""
    viscosity: Optional[Annotated[float, _quantity("viscosity"), Field(ge=0)]] = None
    shear_viscosity: Optional[Annotated[float, _quantity("viscosity"), Field(ge=0)]] = None
    ratio: Optional[Annotated[float, Field(ge=0, le=10)]] = None
    frequency: Optional[Annotated[float, _quantity("frequency"), Field(gt=0)]] = None

    @model_validator(mode="after")
    def _one_way(self):
        if (self.viscosity is None) == (self.ratio is None):
            raise ValueError("give either viscosity (and shear_viscosity) or ratio and frequency")
        if self.ratio is not None and self.frequency is None:
            raise ValueError("a damping ratio needs the frequency it holds at (frequency: Hz)")
        if self.ratio is not None and self.shear_viscosity is not None:
            raise ValueError("shear_viscosity goes with viscosity, not with ratio")
        return self


class Dynamics(Strict):
    """``simulate`` with the rods' inertia (issue 16): ``enabled``, the ``integrator``
    (``bdf2`` or ``midpoint``), optional ``damping``, and how often the global force and
    moment balance (inertial loads included) is checked: every ``balance_every`` steps, the
    first and the last (1: every step). ``start_after``: the name of a ``sequence`` step; the
    run starts at rest in the state the sequence reaches there (its steps solved in order, as
    ``sequence`` does: a grasp with its friction history), with that step's values."""
    enabled: bool = False
    integrator: Literal["bdf2", "midpoint"] = "bdf2"
    damping: Optional[Damping] = None
    balance_every: Annotated[int, Field(ge=1)] = 25
    start_after: Optional[str] = None


class Scenario(Strict):
    """A whole robot: modules in series from a base, loads, gravity and solver options."""
    name: str = "scenario"
    description: str = ""
    gravity: Vector3Acceleration = (0.0, 0.0, -9.81)
    #: the air (or body) the TCAs exchange heat with [degC]
    ambient_temperature: Temperature = 25.0
    base: Base = Field(default_factory=Base)
    materials: dict[str, Material]
    tca_types: dict[str, TcaType] = Field(default_factory=dict)
    #: other muscles' types (SMA wires, McKibben muscles, user laws), each with its ``kind``
    muscle_types: dict[str, MuscleType] = Field(default_factory=dict)
    modules: list[Module] = Field(min_length=1)
    loads: list[Load] = Field(default_factory=list)
    objects: list[GraspedObject] = Field(default_factory=list)
    #: fixed rigid shapes the rods may touch, and where contact is checked (issue 17)
    obstacles: list[Obstacle] = Field(default_factory=list)
    contact: ContactOptions = Field(default_factory=ContactOptions)
    solver: SolverOptions = Field(default_factory=SolverOptions)
    inverse: Optional[InverseOptions] = None
    sequence: Optional[list[SequenceStep]] = None
    #: ``simulate``: how long [s], and the events on the way
    duration: Optional[Annotated[float, _quantity("time"), Field(gt=0)]] = None
    timeline: list[TimelineEvent] = Field(default_factory=list)
    dynamics: Dynamics = Field(default_factory=Dynamics)
    _raw: Optional[dict] = PrivateAttr(default=None)
    _sources: object = PrivateAttr(default=None)
    #: the user allowed its custom laws' Python code (``load_scenario(allow_code=True)``)
    _allow_code: bool = PrivateAttr(default=False)

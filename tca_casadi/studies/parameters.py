"""Scalar study parameters addressed by scenario path: what a sweep moves and what inverse
statics varies.

A path names one entry of the robot's parameter vector (``robot.layout``), a component of a
vector entry, or its magnitude:

    bending.tca2.temperature     a TCA temperature [degC]
    cable.tension / MOD.TENDON.tension   a tendon tension [N]
    MOD.TENDON.displacement      a displacement-controlled tendon's pull q [m]
    payload.force.x  (or .y, .z, [0], [1], [2])   one component [N]
    gravity.magnitude            the length of a vector, its direction kept [m/s^2]
    materials.silicone.youngs_modulus   a material's E [Pa] (also poisson_ratio, density)
    tca_types.nylon.coil_radius  a TCA type's geometry or fit coefficient
    bending.tca1.route.radius    a straight route's radius or angle, a helix's radius or phase

(every name of ``robot.layout``: :mod:`tca_casadi.model.parameters`).
"""
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ScenarioError
from ..scenario.checks import closest
from ..scenario.written import written_value as scenario_written
from ..units import UNIT_OF, in_unit, readable_unit, to_si, unit_given, unit_text

COMPONENTS = {"x": 0, "y": 1, "z": 2, "[0]": 0, "[1]": 1, "[2]": 2, "[3]": 3}


@dataclass
class StudyParameter:
    """One scalar: ``value(P) = direction . P[slice]``; moving it by ``dv`` adds
    ``dv * direction`` to ``P[slice]`` (``direction`` is a unit vector)."""
    path: str
    name: str                 # robot.layout name
    slice: slice
    direction: np.ndarray
    kind: str                 # unit kind (units.KINDS)
    #: the unit values are shown in (summaries, plots); None: the SI unit. Files keep SI.
    display: str = None

    @property
    def unit(self):
        """The SI unit of the parameter's values (files, columns, arguments)."""
        return UNIT_OF[self.kind]

    @property
    def shown_unit(self):
        """The unit shown to people: the one the user gave, else the SI unit."""
        return unit_text(self.display) if self.display else self.unit

    @property
    def label(self):
        """``"path [unit]"`` in the shown unit (plots, summaries)."""
        return f"{self.path} [{self.shown_unit}]"

    @property
    def si_label(self):
        """``"path [SI unit]"``: the header of the parameter's column in files."""
        return f"{self.path} [{self.unit}]"

    def shown(self, value):
        """``value`` (SI, scalar or array) in :attr:`shown_unit`."""
        return in_unit(value, self.kind, self.display)

    def describe(self, value, digits=6):
        """``"path = 6 mm"``: the value in the shown unit."""
        return f"{self.path} = {self.shown(value):.{digits}g} {self.shown_unit}"

    def shown_in(self, *given, values=()):
        """A copy shown in the unit of the first of ``given`` that has one (``"6 mm"``), else, where
        ``values`` (SI) are passed, in a readable unit for them (``519.6 µm``, ``200 kPa``)."""
        unit = next((u for u in map(unit_given, given) if u), None)
        if unit is None and len(values):
            unit = readable_unit(self.kind, values)
        if unit is None or self.kind == "temperature":
            return self
        try:
            in_unit(1.0, self.kind, unit)
        except Exception:       # a unit of another dimension was refused where the value was read
            return self
        return replace(self, display=unit)

    def value(self, params):
        return float(self.direction @ np.asarray(params)[self.slice])

    def vector(self, size):
        """``dP / d value`` as a full parameter-vector direction, shape (size,)."""
        out = np.zeros(size)
        out[self.slice] = self.direction
        return out

    def with_value(self, params, value):
        """A copy of ``params`` with this parameter set to ``value``."""
        out = np.array(params, float)
        out[self.slice] += (value - self.value(params)) * self.direction
        return out

    def to_si(self, value, what="value"):
        """``value`` (number or string with a unit) in this parameter's unit."""
        try:
            return to_si(value, self.kind)
        except ValueError as exc:
            raise ScenarioError(f"{what} for {self.path}: {exc}") from None


def resolve_parameter(robot, params, path):
    """The :class:`StudyParameter` for ``path``; :class:`ScenarioError` naming the valid paths."""
    layout = robot.layout
    name, component = _split(path, layout)
    if name is None:
        raise ScenarioError(f"{path!r} is not a study parameter{closest(path, _scalar_paths(layout))}"
                            f" (vectors take .x/.y/.z or .magnitude)")
    size = layout[name].stop - layout[name].start
    kind = layout.kind(name)
    if component is None:
        if size != 1:
            raise ScenarioError(f"{path!r} is a vector of {size}: name one component "
                                f"({path}.x, {path}.y, {path}.z) or {path}.magnitude")
        direction = np.ones(1)
    elif component == "magnitude":
        current = np.asarray(params)[layout[name]]
        norm = float(np.linalg.norm(current))
        if norm == 0.0:
            raise ScenarioError(f"{path}: {name} is zero, so it has no direction to scale; "
                                f"sweep a component instead ({name}.x ...)")
        direction = current / norm
    else:
        if component >= size:
            raise ScenarioError(f"{path!r}: {name} has {size} components")
        direction = np.eye(size)[component]
    return StudyParameter(path, name, layout[name], direction, kind)


def _split(path, layout):
    if path in layout:
        return path, None
    for suffix, index in list(COMPONENTS.items()) + [("magnitude", "magnitude")]:
        for separator in (".", ""):
            stem = path[:-len(separator + suffix)] if path.endswith(separator + suffix) else None
            if stem and stem in layout and (separator or suffix.startswith("[")):
                return stem, index
    return None, None


def _scalar_paths(layout):
    out = []
    for name in layout.names():
        size = layout[name].stop - layout[name].start
        out += [name] if size == 1 else [f"{name}.{c}" for c in "xyz"] + [f"{name}.magnitude"]
    return out


def resolve_parameters(robot, params, paths):
    """Several parameters; the same entry twice is an error."""
    resolved = [resolve_parameter(robot, params, path) for path in paths]
    seen = {}
    for p in resolved:
        key = (p.name, tuple(np.round(p.direction, 12)))
        if key in seen:
            raise ScenarioError(f"{p.path!r} and {seen[key]!r} are the same parameter")
        seen[key] = p.path
    return resolved


def check_range(robot, parameter, *values, params=None):
    """A value that a sweep or inverse statics would reach and a scenario could not hold is an
    error: a muscle's input outside its law's range (a TCA's ``min_temperature`` /
    ``max_temperature``, a McKibben muscle's ``max_pressure``...) or, at ``params`` otherwise, anything
    :meth:`Robot.problems` finds (a modulus not positive, a route outside the body...)."""
    actuator = next((a for a in robot.actuators if a.parameter == parameter.name), None)
    if actuator is None or not actuator.is_muscle:
        if params is None or parameter.kind in ("force", "moment", "mass", "acceleration"):
            return
        for value in np.ravel(values):
            problems = robot.problems(parameter.with_value(params, value))
            if problems:
                raise ScenarioError(f"{parameter.path} = {value:g} {parameter.unit}: " + "; ".join(problems))
        return
    for value in np.ravel(values):
        problem = actuator.law.input_problem(parameter.path, value, actuator.type_path)
        if problem:
            raise ScenarioError(problem)


def written_value(scenario, parameter):
    """What the scenario file wrote for ``parameter`` (``"0.5 mm"``, ``125000``), or None
    (:func:`tca_casadi.scenario.written.written_value`; a vector's component by its direction)."""
    index = np.flatnonzero(parameter.direction == 1.0)
    return scenario_written(scenario, parameter.name, int(index[0]) if index.size == 1 else None,
                            parameter.direction.size)


def shown_as_given(parameter, scenario, *given, values=()):
    """``parameter`` shown in the first unit found in ``given`` (command-line values), else the unit
    the scenario wrote it in, else a readable unit for ``values`` (:meth:`StudyParameter.shown_in`)."""
    return parameter.shown_in(*given, written_value(scenario, parameter), values=values)

"""The actuator-law interface: what every muscle (and the displacement tendon) gives the solvers.

An actuator with unknown tension ``F`` is routed through the body; its path length ``l`` gives the
stroke ``delta = l - l*`` (``l*``: the path length in the reference state). Its law is one
equation ``r(delta, F, u) = 0`` in the stroke, the tension and the actuator's input ``u`` (a
temperature, a pressure, a displacement...). Every solver, continuation, the sensitivities,
inverse statics, the time simulation and calibration see a law only through this interface:

* :meth:`ActuatorLaw.residual` ``r(delta, F, u)``: numbers, numpy arrays or CasADi symbols,
  its constants too (they may be NLP parameters); **positive when the path is longer than the
  free actuator at that tension** (so that ``-r`` is the slack of a ``tension_only`` one);
* :attr:`ActuatorLaw.residual_scale`: the residual's natural size (the solvers use ``r / scale``);
* :attr:`ActuatorLaw.input_range`: the inputs the law is valid for, and :meth:`input_problem`;
* :meth:`ActuatorLaw.free_stroke` (stroke at zero tension), :meth:`ActuatorLaw.gap` (slack
  length), :meth:`ActuatorLaw.warnings` (e.g. leaving a fit's range) for the results;
* the class's declarations: ``KIND``, ``INPUT`` (name, unit kind, default), ``PARAMETERS``
  (:class:`LawParameter`: name, unit kind, default, meaning; each becomes the NLP parameter
  ``muscle_types.TYPE.NAME``), ``OPTIONS`` (non-numeric keys of the type), ``THERMAL``
  (heated by a drive in ``simulate``).

A muscle is one file in this package defining ``LAW = TheLawClass``: the scenario schema
(``muscle_types:`` entries and the actuators of that kind), the parameter vector and the checks
are made from its declarations (:mod:`tca_casadi.model.laws`).
"""
from dataclasses import replace
import math
from typing import ClassVar

from ...catalogue.base import Declaration, range_text


class ActuatorLaw(Declaration):
    """Base of every actuator law (see the module docstring). Subclasses are frozen dataclasses
    whose fields are ``reference_length`` [m], the :attr:`PARAMETERS` and the :attr:`OPTIONS`;
    their declarations (``KIND``, ``INPUT``, ``PARAMETERS``, ...) are their catalogue entry's
    (:mod:`tca_casadi.catalogue`), which they inherit."""
    # ------------------------------------------------------------------ construction
    @classmethod
    def from_type(cls, config, reference_length, **context):
        """The law of an actuator of type ``config`` (the scenario's validated entry) whose path
        has reference length ``l*`` [m]."""
        values = {p.name: getattr(config, p.name) for p in cls.PARAMETERS}
        values.update({name: getattr(config, name) for name in cls.OPTIONS})
        return cls(reference_length=reference_length, **values)

    def with_parameters(self, param, prefix, reference_length):
        """This law with every declared constant read from the parameter vector (``param(name)``,
        names ``prefix + key``; numbers or CasADi symbols) and the path's ``l*`` at them."""
        values = {p.name: param(prefix + p.name)[0] for p in self.PARAMETERS if getattr(self, p.name) is not None}
        return replace(self, reference_length=reference_length, **values)

    # ------------------------------------------------------------------ the law
    def residual(self, stroke, force, value):
        """``r(delta, F, u)``: zero on the law, positive when the path is too long for ``F``."""
        raise NotImplementedError

    @property
    def residual_scale(self):
        """A natural size of :meth:`residual` (its unit), to scale it to order one."""
        raise NotImplementedError

    @property
    def input_range(self):
        """``(low, high)`` of the input the law is valid for (SI, degC)."""
        return (-math.inf, math.inf)

    def input_problem(self, key, value, type_path="its type"):
        """Why the input ``value`` (of the parameter ``key``) is outside :attr:`input_range`, or None."""
        return range_problem(self, value, key, type_path)

    #: what :attr:`inverse_range` spans (for messages)
    INVERSE_RANGE_TEXT: ClassVar[str] = "its law's input range"

    @property
    def inverse_range(self):
        """The inputs inverse statics may choose from by default (``input_range``)."""
        return self.input_range

    def free_stroke(self, value):
        """Stroke [m] at zero tension (negative = contraction), or None when there is none."""
        return None

    def gap(self, stroke, force, value):
        """Slack length [m]: how much longer the free actuator is than its path (<= 0 when taut)."""
        free = self.free_stroke(value)
        return 0.0 if free is None else float(free - stroke)

    def warnings(self, key, stroke, force, value, tension_only):
        """``[(kind, message)]`` about a solved state of actuator ``key`` (e.g. a fit's range)."""
        return []

    def heated(self, value):
        """Whether the input counts as active in drawings (a heated muscle)."""
        return False

    @property
    def monotone_limit(self):
        """Tension [N] beyond which the law stops being monotone (inf: never)."""
        return math.inf

    def structural_problems(self, key):
        """Messages about constants that moved (by a parameter) outside what the law allows."""
        out = []
        for p in self.PARAMETERS:
            value = getattr(self, p.name)
            if p.positive and value is not None and not float(value) > 0:
                out.append(f"{key}: {p.name} = {float(value):g} must be positive")
        return out


class HeatedLaw(ActuatorLaw):
    """A law whose input is a temperature: heated in ``simulate``, valid from the type's
    ``min_temperature`` to ``max_temperature``, active above its ``reference_temperature`` (the
    subclass's fields)."""
    INVERSE_RANGE_TEXT = "reference_temperature to max_temperature"

    @property
    def input_range(self):
        return (self.min_temperature, self.max_temperature)

    @property
    def inverse_range(self):
        """Heating only: ``(reference_temperature, max_temperature)`` [degC]."""
        return (self.reference_temperature, self.max_temperature)

    def heated(self, value):
        return value > self.reference_temperature + 0.5


#: a tension below this [N] counts as compression
COMPRESSION_TOLERANCE = 1e-9


def compression_warnings(key, force, tension_only, consequence):
    """``[("compression", text)]`` when a muscle that may not go slack is in compression."""
    if force < -COMPRESSION_TOLERANCE and not tension_only:
        return [("compression", f"{key} is in compression (F = {force * 1e3:.4g} mN): {consequence}")]
    return []


def range_problem(law, value, key=None, type_path="its type"):
    """Why ``value`` lies outside ``law.input_range`` (one line), or None."""
    low, high = law.input_range
    return range_text(law, value, low, high, key, type_path)

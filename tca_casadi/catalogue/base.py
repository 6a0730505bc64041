"""What an actuator law declares (no law math): its kind, the scenario section its types live
in, its input, its numeric constants (each an NLP parameter), its other keys, whether it is
heated in ``simulate`` and the checks of a type's values. The scenario's schema is made from
these declarations; each law in :mod:`tca_casadi.model.laws` inherits its own."""
from dataclasses import dataclass
import math
from typing import ClassVar, Optional


@dataclass(frozen=True)
class LawParameter:
    """One numeric constant of a law: its key (in ``muscle_types.TYPE`` and in the parameter
    vector), unit kind (:data:`tca_casadi.units.KINDS`), default (None: may be left out, and is
    then no parameter), whether it must be positive, and what it is."""
    name: str
    kind: str
    default: Optional[float]
    doc: str
    positive: bool = True


class Declaration:
    """One kind of actuator law, declared: the class attributes below and :meth:`validate_type`."""
    #: the actuator's ``kind`` in a scenario
    KIND: ClassVar[str] = ""
    #: the scenario section its types live in
    TYPES_KEY: ClassVar[str] = "muscle_types"
    #: (input name, unit kind, default value): the actuator's scenario key and parameter
    INPUT: ClassVar[tuple] = ("input", "dimensionless", 0.0)
    #: its numeric constants (:class:`LawParameter`), each the NLP parameter ``TYPES_KEY.TYPE.NAME``
    PARAMETERS: ClassVar[tuple] = ()
    #: non-numeric keys of the type: name -> (annotation or unit kind, default)
    OPTIONS: ClassVar[dict] = {}
    #: keys of the type that only the thermal model (``simulate``) reads
    THERMAL_KEYS: ClassVar[tuple] = ()
    #: the thermal model's defaults that differ from a TCA's (``simulate``), or None
    THERMAL_DEFAULTS: ClassVar[Optional[dict]] = None
    #: heated by a drive in ``simulate`` (its input is a temperature with a thermal model)
    THERMAL: ClassVar[bool] = False
    #: the key of the type whose value is the input at rest (None: ``INPUT``'s default)
    REST_INPUT: ClassVar[Optional[str]] = None
    #: the type's keys that set the input's range (for messages)
    RANGE_KEYS: ClassVar[tuple] = ()
    #: how messages call it (None: its ``KIND``)
    NAME: ClassVar[Optional[str]] = None

    @classmethod
    def validate_type(cls, config):
        """Raise ``ValueError`` (a one-line message) when the type's constants are inconsistent."""

    @classmethod
    def code_problem(cls, config):
        """Why the code a type names cannot serve as its law (a custom law's entry point that
        does not import, or does not build a scalar CasADi expression), one line, or None. It
        runs that code: the scenario's checks call it only for scenarios that allow code."""
        return None

    @classmethod
    def parameter_entries(cls, config):
        """``[(key, unit kind, value)]`` of a type's NLP parameters (``TYPES_KEY.TYPE.key``;
        a value None is no parameter): its :attr:`PARAMETERS`."""
        return [(p.name, p.kind, getattr(config, p.name)) for p in cls.PARAMETERS]

    @classmethod
    def range_of(cls, config):
        """``(low, high)``: the inputs a type is valid for."""
        return (-math.inf, math.inf)

    @classmethod
    def input_problem_of(cls, config, value, type_path):
        """Why the input ``value`` is outside the range of the type ``config`` (at ``type_path``,
        e.g. ``muscle_types.wire``), one line, or None."""
        low, high = cls.range_of(config)
        return range_text(cls, value, low, high, None, type_path)


class Heated(Declaration):
    """A law whose input is a temperature, heated in ``simulate``, valid from its type's
    ``min_temperature`` to ``max_temperature``."""
    INPUT = ("temperature", "temperature", 25.0)
    THERMAL = True
    RANGE_KEYS = ("min_temperature", "max_temperature")

    @classmethod
    def range_of(cls, config):
        return (config.min_temperature, config.max_temperature)


def range_text(declaration, value, low, high, key=None, type_path="its type"):
    """Why ``value`` lies outside ``[low, high]`` of a law of ``declaration`` (one line), or None."""
    if low <= value <= high:
        return None
    from ..units import UNIT_OF
    kind = declaration.INPUT[1]
    unit = "" if UNIT_OF.get(kind, "-") == "-" else " " + UNIT_OF[kind]
    where = f"{key}: " if key else ""
    keys = " and ".join(declaration.RANGE_KEYS) or "its range"
    return (f"{where}{value:g}{unit} is outside the {declaration.KIND} law's range [{low:g}, {high:g}]{unit}; "
            f"to go there, set {keys} of {type_path}")


__all__ = ["LawParameter", "Declaration", "Heated", "range_text"]

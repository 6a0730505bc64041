"""The one place where a quantity such as ``"45 mm"`` becomes an SI float.

Plain numbers are SI (m, N, Pa, kg, rad), temperatures are degC. A string carries its unit:
``"45 mm"``, ``"0.125 MPa"``, ``"120 deg"``, ``"5 g"``, ``"100 degC"``, ``"373.15 K"``.
"""
import functools
import json
import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np

from .resources import cache_root
from .text import clip, shorten, unit_text  # noqa: F401  (messages cut long values alike)


@functools.cache
def _registry():
    """pint's unit registry, its parsed definitions cached on disk by pint (``~/.cache/pint``:
    30 ms instead of 190 ms a process); without the cache where it cannot be used. pint is
    imported here, on the first conversion that :data:`_CONVERSIONS` does not know."""
    import pint
    try:
        return pint.UnitRegistry(cache_folder=":auto:")
    except Exception:             # an unwritable or damaged cache: parse the definitions
        return pint.UnitRegistry()


def __getattr__(name):
    """``ureg``: pint's registry, made on first use (module ``__getattr__``, PEP 562)."""
    if name == "ureg":
        return _registry()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class Conversions:
    """What pint said a unit converts to, kept on disk: ``(source, target) -> (scale, offset)``
    with ``target value = scale * source value + offset`` (every conversion pint makes between
    the units here is affine: a factor, or an offset for degC and degF). A command whose units
    were all seen before then does not import pint (0.17 s of each process, dask's import
    included). pint remains the authority: a new pair is converted by pint, and is kept only if
    the affine map reproduces pint's answer at the value asked and one more (1e-12 relative).
    A kept pair is converted by its map from the first time on, so that a value does not depend
    on whether the file existed. The file, ``units.json`` in ``$TCA_CASADI_CACHE`` or
    ``~/.cache/tca_casadi``, records pint's version (another version starts it afresh) and is
    replaced atomically; where it cannot be written, nothing is kept."""

    def __init__(self, path=None):
        self.path = Path(path) if path is not None else cache_root() / "units.json"
        self._maps = None

    def convert(self, number, source, target):
        """``number`` in ``source`` units expressed in ``target`` units (pint's errors raised
        as pint raises them, for a pair it cannot convert)."""
        key = f"{source}\u2192{target}"
        maps = self._loaded()
        if key in maps:
            scale, offset = maps[key]
            return scale * number + offset
        registry = _registry()
        converted = float(registry.Quantity(number, source).to(target).magnitude)
        try:
            at_zero = float(registry.Quantity(0.0, source).to(target).magnitude)
            scale = float(registry.Quantity(1.0, source).to(target).magnitude) - at_zero
            probe = 1.0 + abs(number)
            check = float(registry.Quantity(probe, source).to(target).magnitude)
        except Exception:                 # not affine where pint is asked (none such here yet)
            return converted
        affine = all(math.isclose(scale * x + at_zero, y, rel_tol=1e-12, abs_tol=1e-12 * abs(at_zero))
                     for x, y in ((number, converted), (probe, check)))
        if not affine:
            return converted
        maps[key] = (scale, at_zero)
        self._save()
        return scale * number + at_zero            # as every later process will (to the last bit)

    def _loaded(self):
        if self._maps is None:
            self._maps = {}
            try:
                stored = json.loads(self.path.read_text())
                if stored.get("pint") == _pint_version():
                    self._maps = {key: tuple(value) for key, value in stored["maps"].items()}
            except (OSError, ValueError, KeyError, TypeError, AttributeError):
                pass
        return self._maps

    def _save(self):
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with tempfile.NamedTemporaryFile("w", dir=self.path.parent, prefix=".units-", suffix=".json",
                                             delete=False) as handle:
                json.dump({"pint": _pint_version(), "maps": self._maps}, handle, indent=0)
            os.replace(handle.name, self.path)
        except OSError:
            pass


@functools.cache
def _pint_version():
    from importlib.metadata import version
    return version("pint")


#: the conversions of this process (:class:`Conversions`)
_CONVERSIONS = Conversions()

#: quantity kind -> (SI unit that plain numbers are taken in, human name)
KINDS = {
    "length": ("m", "a length"),
    "pressure": ("Pa", "a pressure / modulus"),
    "angle": ("rad", "an angle"),
    "mass": ("kg", "a mass"),
    "force": ("N", "a force"),
    "moment": ("N*m", "a moment"),
    "density": ("kg/m^3", "a density"),
    "acceleration": ("m/s^2", "an acceleration"),
    "force_per_length": ("N/m", "a force per length"),
    "moment_per_length": ("N*m/m", "a moment per length"),
    "curvature": ("1/m", "a curvature"),
    "temperature": ("degC", "a temperature"),
    "pressure_per_force": ("Pa/N", "a modulus per force"),
    "compliance": ("1/N", "a compliance (strain per newton)"),
    "pressure_per_force2": ("Pa/N^2", "a modulus per force squared"),
    "dimensionless": ("", "a plain number"),
    "heat_capacity": ("J/K", "a heat capacity"),
    "thermal_conductance": ("W/K", "a thermal conductance"),
    "specific_heat": ("J/(kg*K)", "a specific heat"),
    "heat_transfer_coefficient": ("W/(m^2*K)", "a heat transfer coefficient"),
    "resistance": ("ohm", "an electrical resistance"),
    "per_kelvin": ("1/K", "a temperature coefficient"),
    "resistivity": ("ohm*m", "an electrical resistivity"),
    "pressure_per_kelvin": ("Pa/K", "a stress per kelvin"),
    "power": ("W", "a power"),
    "voltage": ("V", "a voltage"),
    "current": ("A", "a current"),
    "time": ("s", "a time"),
    "temperature_difference": ("K", "a temperature difference (e.g. 0.5 K)"),
    "viscosity": ("Pa*s", "a viscosity"),
    "frequency": ("Hz", "a frequency"),
    "integral_gain": ("W/(K*s)", "an integral gain (W/(K s))"),
    "untwist_c2": ("", "an untwist coefficient in rad/(m degC^2) (a plain number)"),
    "untwist_c1": ("", "an untwist coefficient in rad/(m degC) (a plain number)"),
    "untwist_c0": ("", "an untwist coefficient in rad/m (a plain number)"),
}

#: unit kind -> the unit written in labels and CSV headers
UNIT_OF = {"temperature": "degC", "force": "N", "moment": "N m", "mass": "kg", "acceleration": "m/s^2",
           "length": "m", "angle": "rad", "pressure": "Pa", "density": "kg/m^3", "force_per_length": "N/m",
           "moment_per_length": "N m/m", "pressure_per_force": "Pa/N", "pressure_per_force2": "Pa/N^2",
           "untwist_c2": "rad/(m degC^2)", "untwist_c1": "rad/(m degC)", "untwist_c0": "rad/m",
           "dimensionless": "-", "heat_capacity": "J/K", "thermal_conductance": "W/K",
           "specific_heat": "J/(kg K)", "heat_transfer_coefficient": "W/(m^2 K)", "resistance": "ohm",
           "per_kelvin": "1/K", "resistivity": "ohm m", "pressure_per_kelvin": "Pa/K", "power": "W", "voltage": "V", "current": "A", "time": "s",
           "integral_gain": "W/(K s)"}

_NUMBER_AND_UNIT = re.compile(r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*)", re.DOTALL)

#: a quantity string longer than this is refused before it is parsed
MAX_TEXT = 200
#: the largest magnitude accepted for any quantity in SI units (beyond it the physics overflows)
MAX_MAGNITUDE = 1e30


def to_si(value, kind):
    """Convert a number or a ``"number unit"`` string to a float in the SI unit of ``kind``.

    Raises ``ValueError`` with a message fit for the user (unknown unit, wrong dimension,
    not a number, not finite, too large).
    """
    si_unit, name = KINDS[kind]
    if isinstance(value, bool):
        raise ValueError(f"expected {name}, got a boolean")
    if isinstance(value, (int, float)):
        try:
            number = float(value)
        except OverflowError:
            raise ValueError(f"{shorten(value)} is too large") from None
    elif isinstance(value, str):
        number = _parse_string(value, si_unit, name)
        if kind == "angle" and _bare(value):
            _check_bare_angle(number)
    else:
        raise ValueError(f"expected {name} (a number or a string like '45 mm'), got {shorten(value)}")
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, got {shorten(value)}")
    if kind == "angle" and isinstance(value, (int, float)):
        _check_bare_angle(number)
    if abs(number) > MAX_MAGNITUDE:
        raise ValueError(f"{shorten(value)} is out of range: |value| must be at most "
                         f"{MAX_MAGNITUDE:g} {si_unit or ''}".rstrip())
    return number


def temperature_difference(value):
    """A temperature difference [K] from a number or a string (``"0.5 K"``, ``"0.5 degC"``: a
    step of one degC is one kelvin), e.g. a standard deviation of temperatures; ``ValueError``
    as :func:`to_si`."""
    if isinstance(value, str):
        value = re.sub(r"(delta_degC|degC|°C)", "K", value)
    return to_si(value, "temperature_difference")


#: a bare number (no unit) for an angle is radians; beyond a full turn it is refused as a likely
#: angle in degrees ("30" meant as 30 deg would be 30 rad = 1719 deg)
BARE_ANGLE_LIMIT = 2 * math.pi


def _bare(text):
    match = _NUMBER_AND_UNIT.fullmatch(text.strip())
    return bool(match) and not match.group(2)


def _check_bare_angle(number):
    if math.isfinite(number) and abs(number) > BARE_ANGLE_LIMIT + 1e-9:
        raise ValueError(f"a bare number is an angle in radians: {number:g} would be {number:g} rad = "
                         f"{math.degrees(number):.6g} deg, more than a full turn; write '{number:g} deg' "
                         f"for degrees, or '{number:g} rad' if you mean radians")


def _parse_string(text, si_unit, name):
    stripped = text.strip()
    if len(stripped) > MAX_TEXT:
        raise ValueError(f"cannot read {shorten(text)} as {name}: longer than {MAX_TEXT} characters")
    match = _NUMBER_AND_UNIT.fullmatch(stripped)
    if not match:
        raise ValueError(f"cannot read {shorten(text)} as {name}: expected a number followed by a unit")
    number, unit = float(match.group(1)), match.group(2)
    if not unit:
        return number
    try:
        return float(_CONVERSIONS.convert(number, unit, si_unit or "dimensionless"))
    except _pint_errors().UndefinedUnitError:
        raise ValueError(f"unknown unit {shorten(unit)} in {shorten(text)}") from None
    except _pint_errors().DimensionalityError:
        raise ValueError(f"{shorten(text)} is not {name} (expected units convertible to "
                         f"{si_unit or 'a plain number'})") from None
    except Exception:   # pint's parser raises many kinds (ZeroDivisionError, TokenError, ...)
        raise ValueError(f"cannot read the unit {shorten(unit)} in {shorten(text)}") from None


def _pint_errors():
    import pint
    return pint.errors


# ---------------------------------------------------------------------- showing quantities
#: per kind, the units a value may be shown in when the user gave none, largest first: a value is
#: shown in the first unit where its magnitude is at least 1 (else the last)
READABLE = {
    "length": ("m", "mm", "um"),
    "pressure": ("GPa", "MPa", "kPa", "Pa"),
    "force": ("N", "mN"),
    "moment": ("N*m", "N*mm"),
    "mass": ("kg", "g", "mg"),
    "time": ("s", "ms"),
    "power": ("W", "mW"),
    "current": ("A", "mA"),
    "voltage": ("V", "mV"),
}


def unit_given(value):
    """The unit written in a quantity string (``"6 mm"`` -> ``"mm"``); None for a plain number,
    a bare numeric string or anything that is not a quantity."""
    if not isinstance(value, str):
        return None
    match = _NUMBER_AND_UNIT.fullmatch(value.strip()[:MAX_TEXT])
    return match.group(2).strip() or None if match else None


def readable_unit(kind, values):
    """The unit of :data:`READABLE` that shows ``values`` (SI) with a magnitude of 1 or more
    (the largest |value| decides); the SI unit for kinds without a choice or no finite value."""
    choices = READABLE.get(kind)
    finite = np.abs(np.asarray(values, float).ravel())
    finite = finite[np.isfinite(finite) & (finite > 0)]
    if not choices or finite.size == 0:
        return KINDS[kind][0]
    largest = float(finite.max())
    for unit in choices:
        if largest * _CONVERSIONS.convert(1.0, KINDS[kind][0], unit) >= 1.0 - 1e-12:
            return unit
    return choices[-1]


def in_unit(value, kind, unit):
    """``value`` (SI, scalar or array) expressed in ``unit`` (a pint unit string)."""
    si = KINDS[kind][0]
    if not unit or unit == si or kind == "temperature":
        return value
    return _CONVERSIONS.convert(1.0, si, unit) * np.asarray(value, float) if np.ndim(value) \
        else float(_CONVERSIONS.convert(float(value), si, unit))


def show(value, kind, unit=None, digits=6, plain=None):
    """``value`` (SI) as ``"0.51958 mm"``: in ``unit`` if given, else in :func:`readable_unit`."""
    unit = unit or readable_unit(kind, [value])
    written = unit_text(unit, plain) if unit != KINDS[kind][0] else UNIT_OF.get(kind, unit)
    return f"{in_unit(value, kind, unit):.{digits}g} {'' if written == '-' else written}".rstrip()

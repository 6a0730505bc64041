"""The one place where a quantity such as ``"45 mm"`` becomes an SI float.

Plain numbers are SI (m, N, Pa, kg, rad), temperatures are degC. A string carries its unit:
``"45 mm"``, ``"0.125 MPa"``, ``"120 deg"``, ``"5 g"``, ``"100 degC"``, ``"373.15 K"``.
"""
import math
import re

import pint

ureg = pint.UnitRegistry()

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
}

_NUMBER_AND_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def to_si(value, kind):
    """Convert a number or a ``"number unit"`` string to a float in the SI unit of ``kind``.

    Raises ``ValueError`` with a message fit for the user (unknown unit, wrong dimension,
    not a number, not finite).
    """
    si_unit, name = KINDS[kind]
    if isinstance(value, bool):
        raise ValueError(f"expected {name}, got a boolean")
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str):
        number = _parse_string(value, si_unit, name)
    else:
        raise ValueError(f"expected {name} (a number or a string like '45 mm'), got {value!r}")
    if not math.isfinite(number):
        raise ValueError(f"expected a finite number, got {value!r}")
    return number


def _parse_string(text, si_unit, name):
    match = _NUMBER_AND_UNIT.match(text)
    if not match:
        raise ValueError(f"cannot read {text!r} as {name}: expected a number followed by a unit")
    number, unit = float(match.group(1)), match.group(2)
    if not unit:
        return number
    try:
        quantity = ureg.Quantity(number, unit)
        return float(quantity.to(si_unit or "dimensionless").magnitude)
    except pint.errors.UndefinedUnitError:
        raise ValueError(f"unknown unit {unit!r} in {text!r}") from None
    except pint.errors.DimensionalityError:
        raise ValueError(f"{text!r} is not {name} (expected units convertible to "
                         f"{si_unit or 'a plain number'})") from None
    except (pint.errors.PintError, ValueError, TypeError, AttributeError, SyntaxError):
        raise ValueError(f"cannot read the unit {unit!r} in {text!r}") from None

import math

import pytest

from tca_casadi.units import to_si


@pytest.mark.parametrize("value, kind, expected", [
    ("45 mm", "length", 0.045), (0.045, "length", 0.045), ("0.125 MPa", "pressure", 125e3),
    ("120 deg", "angle", 2 * math.pi / 3), ("5 g", "mass", 5e-3), ("100 degC", "temperature", 100.0),
    ("373.15 K", "temperature", 100.0), ("1070 kg/m^3", "density", 1070.0), ("10 mN", "force", 0.01),
    ("37.58 MPa/N^2", "pressure_per_force2", 37.58e6), ("2 1/m", "curvature", 2.0), (25, "temperature", 25.0),
])
def test_to_si_converts(value, kind, expected):
    assert to_si(value, kind) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("value, kind, fragment", [
    ("45 kg", "length", "is not a length"), ("45 furlongz", "length", "unknown unit"),
    ("abc", "length", "cannot read"), (float("nan"), "length", "finite"), (True, "length", "boolean"),
    ([1, 2], "length", "expected a length"),
])
def test_to_si_rejects(value, kind, fragment):
    with pytest.raises(ValueError, match=fragment):
        to_si(value, kind)

import math

import numpy as np

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


@pytest.mark.parametrize("value", [30, 30.0, "30", " -7 ", 1e3])
def test_a_bare_angle_beyond_a_full_turn_is_refused_with_both_readings(value):
    with pytest.raises(ValueError) as error:
        to_si(value, "angle")
    text = str(error.value)
    assert "rad" in text and "deg" in text and "\n" not in text


@pytest.mark.parametrize("value, expected", [(6.28, 6.28), (-6.28, -6.28), ("30 deg", math.radians(30)),
                                             ("30 rad", 30.0), ("720 deg", 4 * math.pi), (2 * math.pi, 2 * math.pi)])
def test_angles_with_a_unit_or_within_a_turn_are_read(value, expected):
    assert to_si(value, "angle") == pytest.approx(expected, rel=1e-15)


def test_a_bare_route_angle_in_degrees_is_refused_from_the_command_line(capsys, scenarios):
    from tca_casadi.cli import main
    code = main(["validate", str(scenarios / "bending_module.yaml"), "--set", "bending.tca1.route.angle=30"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "bending.tca1.route.angle" in err and "1718.87 deg" in err and "'30 deg'" in err


# ---------------------------------------------------------------------- showing quantities (issue 35)
@pytest.mark.parametrize("value, kind, unit, expected", [
    (0.00051958, "length", None, "519.58 µm"), (0.006, "length", "mm", "6 mm"), (199998.39, "pressure", None,
     "199.998 kPa"), (140011.0, "pressure", "MPa", "0.140011 MPa"), (2.33e-5, "force", None, "0.0233 mN"),
    (23.3, "force", None, "23.3 N"), (1.5, "length", None, "1.5 m"), (100.0, "temperature", None, "100 degC"),
    (2.0, "moment", None, "2 N m"), (0.5, "moment", None, "500 N mm"), (0.0, "length", None, "0 m"),
])
def test_a_quantity_is_shown_in_the_unit_given_or_a_readable_one(value, kind, unit, expected):
    from tca_casadi.units import show
    assert show(value, kind, unit, plain=False) == expected


def test_micro_is_written_plain_where_asked_and_units_are_read_back_from_text():
    from tca_casadi.units import in_unit, readable_unit, unit_given, unit_text
    assert unit_text("um", plain=True) == "um" and unit_text("um", plain=False) == "µm"
    assert unit_text("μm", plain=False) == "µm" and unit_text("N*mm") == "N mm"
    assert unit_given("6 mm") == "mm" and unit_given(" -2.5e-3 kPa ") == "kPa"
    assert unit_given("6") is None and unit_given(6) is None and unit_given("hot") is None
    assert readable_unit("length", [0.0, 4e-3]) == "mm" and readable_unit("length", [np.nan]) == "m"
    assert readable_unit("pressure", [1.2e9]) == "GPa" and readable_unit("curvature", [3.0]) == "1/m"
    np.testing.assert_allclose(in_unit(np.array([1e-3, 2e-3]), "length", "mm"), [1.0, 2.0], rtol=0, atol=1e-15)
    assert in_unit(25.0, "temperature", "K") == 25.0          # temperatures stay degC


def test_temperature_differences_take_kelvin_and_degc_steps_alike():
    from tca_casadi.units import temperature_difference
    for text in ("0.5 K", "0.5 degC", "0.5 delta_degC", "500 mK"):
        assert temperature_difference(text) == pytest.approx(0.5, rel=0, abs=1e-15)
    assert temperature_difference(2.0) == 2.0
    with pytest.raises(ValueError, match="'3 mm' is not a temperature difference"):
        temperature_difference("3 mm")


@pytest.mark.parametrize("usable", [True, False])
def test_the_unit_registry_is_cached_on_disk_where_it_can_be(tmp_path, usable):
    """A fresh process keeps pint's parsed definitions in its cache folder (XDG_CACHE_HOME/pint);
    where that cannot be made (the cache home is a file), units work all the same, uncached."""
    import os
    import subprocess
    import sys
    home = tmp_path / ("cache" if usable else "file")
    if not usable:
        home.write_text("")
    code = "from tca_casadi.units import to_si, ureg; print(to_si('100 degC', 'temperature'), ureg.cache_folder)"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                         env={**os.environ, "XDG_CACHE_HOME": str(home)})
    assert run.returncode == 0, run.stderr
    value, folder = run.stdout.split()
    assert float(value) == 100.0
    if usable:
        assert folder == str(home / "pint") and any((home / "pint").iterdir())
    else:
        assert folder == "None"


PROBE = ("import sys; from tca_casadi.units import to_si, in_unit\n"
         "values = [to_si(v, k) for v, k in {asked!r}] + [in_unit(0.0125, 'length', 'mm')]\n"
         "print(repr(values), 'pint' in sys.modules)")
ASKED = [("45 mm", "length"), ("0.125 MPa", "pressure"), ("373.15 K", "temperature"), ("50 degF", "temperature"),
         ("5 g", "mass"), ("120 deg", "angle"), ("37.58 MPa/N^2", "pressure_per_force2")]


def _fresh_process(cache, asked=ASKED):
    """``(values, pint imported)`` of :data:`PROBE` in a fresh process whose cache is ``cache``."""
    import os
    import subprocess
    import sys
    run = subprocess.run([sys.executable, "-c", PROBE.format(asked=asked)], capture_output=True, text=True,
                         timeout=120, env={**os.environ, "TCA_CASADI_CACHE": str(cache)})
    assert run.returncode == 0, run.stderr
    values, imported = run.stdout.rsplit(" ", 1)
    return eval(values), imported.strip() == "True"


def test_conversions_pint_made_once_are_read_from_disk_without_pint(tmp_path):
    """A fresh cache: pint converts (and is imported); the next process converts the same
    quantities from ``units.json`` without importing pint, to the same bits, which are pint's to
    1e-12 (temperatures with their offsets: 373.15 K and 50 degF are 100 and 10 degC). A file of
    another pint version is not used; a new unit still goes to pint."""
    import json
    first, imported = _fresh_process(tmp_path)
    assert imported
    second, imported = _fresh_process(tmp_path)
    assert not imported and second == first
    np.testing.assert_allclose(first, [0.045, 125e3, 100.0, 10.0, 5e-3, 2 * math.pi / 3, 37.58e6, 12.5],
                               rtol=1e-12, atol=1e-12)
    stored = json.loads((tmp_path / "units.json").read_text())
    assert stored["maps"]["K\u2192degC"] == [1.0, -273.15]
    assert _fresh_process(tmp_path, ASKED + [("2 inch", "length")]) == (first[:-1] + [0.0508, 12.5], True)
    stored["pint"] = "0.0"
    (tmp_path / "units.json").write_text(json.dumps(stored))
    assert _fresh_process(tmp_path) == (first, True)


def test_a_cache_that_cannot_be_written_or_read_changes_nothing(tmp_path):
    """The cache root is a file (nothing can be kept) or ``units.json`` is damaged: the values
    are the same, from pint."""
    blocked = tmp_path / "blocked"
    blocked.write_text("")
    reference, _ = _fresh_process(tmp_path / "fresh")
    assert _fresh_process(blocked) == (reference, True)
    (tmp_path / "damaged").mkdir()
    (tmp_path / "damaged" / "units.json").write_text("{not json")
    assert _fresh_process(tmp_path / "damaged") == (reference, True)

"""The thermal keys of a TCA type (issue 15, first part): read with units, refused cleanly when
wrong, shown by ``validate`` with the time constant of the closed form, never a rebuild."""
import re

import pytest
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.cli import main

BENDING = SCENARIOS / "bending_module.yaml"


def test_validate_shows_each_tcas_time_constant(capsys):
    assert main(["validate", str(BENDING), "--set", "tca_types.nylon.thermal.convection_coefficient=30 W/m^2/K",
                 "--set", "tca_types.nylon.resistance=12 ohm"]) == 0
    out = capsys.readouterr().out
    taus = [float(t) for t in re.findall(r"tau ([0-9.]+) s, R0 12 ohm", out)]
    assert len(taus) == 3                                   # one per TCA of the module
    # rho c r / (2 h) = 16.15 s, printed to 3 digits: within half a unit of the last one
    assert_allclose(taus, 1140.0 * 1700.0 * 0.5e-3 / (2 * 30.0), rtol=0, atol=0.05 + 1e-9)


@pytest.mark.parametrize("setting, words", [
    ("tca_types.nylon.thermal.heat_capacity=-1", "heat_capacity: input should be greater than 0"),
    ("tca_types.nylon.thermal.conductance=3 W", "is not a thermal conductance"),
    ("tca_types.nylon.thermal.area_factor=1.5", "less than or equal to 1"),
    ("tca_types.nylon.resistance=0", "resistance: input should be greater than 0"),
    ("tca_types.nylon.thermal.heat_capcity=1", "did you mean 'heat_capacity'"),
    ("ambient_temperature=-300", "ambient_temperature: input should be greater than or equal to -273.15"),
])
def test_bad_thermal_input_is_one_line(capsys, setting, words):
    assert main(["validate", str(BENDING), "--set", setting]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err


def test_thermal_keys_never_rebuild_the_statics():
    sim = Simulation.from_file(BENDING)
    solver = sim.solver()
    first = sim.solve(warn=False)
    sim.set("tca_types.nylon.thermal.convection_coefficient", "40 W/m^2/K")
    sim.set("ambient_temperature", "30 degC")
    assert sim.solver() is solver
    again = sim.solve(warm_start=first, warn=False)
    assert_allclose(again.tip_position, first.tip_position, rtol=0, atol=1e-12)

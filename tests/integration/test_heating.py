"""Quasi-static motion while TCAs heat (issue 15): every output time's shape equals an
independent solve at those temperatures; the table has the contracted columns."""
import csv

import numpy as np
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.model.thermal import thermal_law
from tca_casadi.solvers.thermal import Drive, Schedule, integrate
from tca_casadi.time_simulation.heating import follow_temperatures

BENDING = SCENARIOS / "bending_module.yaml"
KEYS = ["bending.tca2", "bending.tca3"]


def _heating(sim, power=0.5, duration=20.0, step=1.0):
    laws = [thermal_law(sim.scenario.tca_types[a.tca_type], a.law.fiber_length)
            for a in sim.robot.tcas if a.key in KEYS]
    drive = Drive("power", Schedule((0.0, 1.0, 1.0), (0.0, 0.0, power)))      # on at t = 1 s
    ambient = sim.scenario.ambient_temperature
    return integrate(laws, [drive, drive], ambient, [ambient, ambient], np.arange(0.0, duration + step / 2, step))


def test_every_output_time_equals_an_independent_solve(tmp_path):
    sim = Simulation.from_file(BENDING, ["bending.tca2.temperature=25", "bending.tca3.temperature=25"])
    history = _heating(sim)
    series = follow_temperatures(sim, KEYS, history)
    assert series.completed, series.message
    assert np.all(np.diff(history.temperature[:, 0]) >= 0) and history.temperature[-1, 0] > 60
    bend = series.tip_positions()[:, 0]
    assert np.all(np.diff(bend[1:]) < 0)                     # heating TCAs 2 and 3 bends it steadily one way
    for k in (2, 9, 20):
        alone = Simulation.from_file(BENDING)
        for j, key in enumerate(KEYS):
            alone.set_parameter(f"{key}.temperature", history.temperature[k, j])
        independent = alone.solve(warn=False)
        assert_allclose(series.solutions[k].tip_position, independent.tip_position, rtol=0, atol=1e-9)
    with open(series.to_csv(tmp_path / "timeseries.csv"), newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0][:3] == ["t [s]", "bending.tca2.temperature [degC]", "bending.tca2.power [W]"]
    assert rows[0][-8:] == ["tip_x [m]", "tip_y [m]", "tip_z [m]", "tip_qw", "tip_qx", "tip_qy", "tip_qz", "converged"]
    assert len(rows) == 22 and all(row[-1] == "1" for row in rows[1:])
    assert float(rows[1][2]) == 0.0 and float(rows[3][2]) == 0.5           # off before 1 s, on from 1 s

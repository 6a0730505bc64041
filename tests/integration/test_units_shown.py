"""Quantities shown in the unit the user gave (issue 35): a sweep, an inverse solve and a fit
print and plot their parameters in the unit of the command line or the scenario file, while
their files keep SI."""
import csv
import json

import matplotlib
import numpy as np
import pytest

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.studies import Sweep
from tca_casadi.studies.parameters import resolve_parameter, shown_as_given, written_value


def test_the_scenario_s_own_unit_is_found_for_every_kind_of_path():
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    expected = {"materials.ecoflex30.youngs_modulus": ("0.125 MPa", "MPa"), "tca_types.nylon.fiber_radius": ("0.5 mm", "mm"),
                "bending.tca1.route.radius": ("4 mm", "mm"), "bending.tca2.route.angle": ("120 deg", "deg"),
                "bending.tca2.temperature": (100, "degC"), "tca_types.nylon.untwist.c1": (None, "rad/(m degC)")}
    for path, (written, unit) in expected.items():
        parameter = resolve_parameter(sim.robot, sim.params, path)
        assert written_value(sim.scenario, parameter) == written, path
        assert shown_as_given(parameter, sim.scenario).shown_unit == unit, path
    radius = shown_as_given(resolve_parameter(sim.robot, sim.params, "tca_types.nylon.fiber_radius"), sim.scenario)
    assert radius.shown(0.00051958) == pytest.approx(0.51958, rel=1e-12)
    assert radius.describe(0.00051958) == "tca_types.nylon.fiber_radius = 0.51958 mm"
    given = shown_as_given(radius, sim.scenario, "510 um")          # the command line wins over the file
    assert given.shown_unit in ("µm", "um") and given.shown(0.00051958) == pytest.approx(519.58, rel=1e-12)


def test_a_sweep_over_millimetres_is_shown_in_millimetres_with_named_events_and_contact_forces(tmp_path):
    from tca_casadi.plotting.sweep_plots import contact_forces, plot_sweep
    sim = Simulation.from_file(SCENARIOS / "tendon_robot_wall.yaml")
    result = Sweep(sim, ["body.t1.displacement"], 0, "6 mm", steps=13).run()
    assert result.completed, result.message
    assert [e["message"] for e in result.events] == [
        "body.t2 goes slack near body.t1.displacement = 0.25 mm", "body.t4 goes slack near body.t1.displacement = 0.25 mm",
        "body touches wall near body.t1.displacement = 1.75 mm"]
    figure = plot_sweep(result, None)
    tip, tension, contact = figure.axes
    assert contact.get_xlabel() == "body.t1.displacement [mm]"
    assert contact.get_xlim()[1] == pytest.approx(6.0, abs=0.5)                   # millimetres, not metres
    names = [text.get_text() for text in tip.texts]                                # events at one x share a label
    assert names == ["body.t2 goes slack\nbody.t4 goes slack", "body touches wall"]
    (line,) = [l for l in contact.get_lines() if l.get_label() == "body / wall"]
    total = [sum(c.normal_force for c in p.solution.contacts) * 1e3 for p in result.points]
    np.testing.assert_allclose(line.get_ydata(), total, rtol=0, atol=1e-12)
    assert np.all(np.asarray(total)[result.values[:, 0] < 1.5e-3] == 0) and total[-1] > 10   # closes at ~1.75 mm
    figure.canvas.draw()
    for ax in figure.axes:                                                          # legends beside the panels
        assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1 - 1
    matplotlib.pyplot.close(figure)
    written = result.save(tmp_path, plots=False)
    with open(tmp_path / "sweep.csv") as stream:
        rows = list(csv.DictReader(line for line in stream if not line.startswith("#")))
    assert "body.t1.displacement [m]" in rows[0] and any(str(p).endswith("sweep.csv") for p in written)
    assert float(rows[-1]["body.t1.displacement [m]"]) == pytest.approx(0.006, rel=1e-12)   # files stay SI


def test_a_fit_reports_its_parameters_in_the_scenario_s_units_and_keeps_si_in_its_file(tmp_path):
    from tca_casadi.studies.fit.least_squares import Fit, synthetic_measurements
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    data = synthetic_measurements(sim, {"tca_types.nylon.fiber_radius": 0.00052},
                                  {"bending.tca2.temperature": np.linspace(40, 110, 6)}, ["tip_x", "tip_z"],
                                  {"length": 1e-7}, seed=1)
    result = Fit(sim, data, ["tca_types.nylon.fiber_radius"]).run()
    assert result.converged, result.message
    (line,) = [l for l in result.summary().splitlines() if "fiber_radius =" in l]
    assert line.startswith("  tca_types.nylon.fiber_radius = 0.52") and " mm +- " in line and "nominal 0.5" in line
    result.save(tmp_path)
    saved = json.loads((tmp_path / "fit.json").read_text())["parameters"][0]
    assert saved["unit"] == "m" and saved["value"] == pytest.approx(0.00052, rel=1e-4)

"""Figures checked where eyes are not needed (issue 35): one colour per actuator in every panel
of timeseries.png, every event named, the energy account drawn for a dynamic run and no panel
spent on what a run does not have."""
import matplotlib
import numpy as np
import pytest

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.plotting.timeseries import event_labels, save_timeseries_png
from tca_casadi.time_simulation.timeline import TimeSimulation


def _colours(ax):
    return {line.get_label(): line.get_color() for line in ax.get_lines() if not line.get_label().startswith("_")}


def _figure(path, overrides, dt):
    sim = Simulation.from_file(SCENARIOS / path, overrides)
    series = TimeSimulation(sim, dt=dt).run()
    assert series.completed, series.message
    return save_timeseries_png(series, None, event_labels(sim.scenario.timeline)), sim


def test_heating_cycle_colours_events_and_panels():
    figure, sim = _figure("bending_module_heating.yaml", ["bending.tca3.drive={kind: power, value: 0}",
                                                          "timeline=[{at: 1 s, set: {bending.tca3.drive.value: 0.2 W}},"
                                                          " {at: 2 s, set: {bending.tca2.drive.value: 0.3 W}}]",
                                                          "duration=4"], 1.0)
    temperature, power, tension, tip = figure.axes
    assert power.get_ylabel() == "electrical power [mW]"
    shared = _colours(temperature)
    for panel in (power, tension):                 # the power panel draws only the heated TCAs: tca2, tca3
        for key, colour in _colours(panel).items():
            assert shared[key] == colour, (key, panel.get_ylabel())
    assert set(_colours(power)) == {"bending.tca2", "bending.tca3"}
    labels = [text.get_text() for text in temperature.texts]
    assert labels == ["bending.tca3.drive.value = 0.2 W", "bending.tca2.drive.value = 0.3 W"]
    matplotlib.pyplot.close(figure)


def test_a_dynamic_run_draws_its_energies_and_no_empty_power_panel():
    figure, _ = _figure("bending_module.yaml", ["dynamics={enabled: true, integrator: bdf2}",
                                                "bending.tca2.temperature=25", "bending.tca3.temperature=25",
                                                "duration=0.02", "timeline=[{at: 0.004 s, set: {bending.tca2.temperature: 60}}]"],
                        0.002)
    names = [ax.get_ylabel() for ax in figure.axes]
    assert names == ["temperature [degC]", "tension [mN]", "tip displacement [mm]", "energy [mJ]"]
    assert "energy balance" in _colours(figure.axes[-1]) and len(_colours(figure.axes[-1])) == 7
    matplotlib.pyplot.close(figure)


def test_a_rod_without_actuators_gets_no_empty_temperature_or_tension_panel():
    """Till's cantilever has no TCA and no actuator: its time series shows the tip and, moving,
    its energies only; quasi-static, the tip alone."""
    moving, _ = _figure("analytic/steel_cantilever.yaml", ["duration=0.01"], 0.002)
    assert [ax.get_ylabel() for ax in moving.axes] == ["tip displacement [mm]", "energy [mJ]"]
    still, _ = _figure("analytic/steel_cantilever.yaml", ["duration=0.1", "dynamics.enabled=false"], 0.05)
    assert [ax.get_ylabel() for ax in still.axes] == ["tip displacement [mm]"]
    for figure in (moving, still):
        matplotlib.pyplot.close(figure)


def test_robot_drawing_colours_tcas_by_temperature_keeps_the_legend_outside_and_projects():
    """robot.png: each TCA's line is its temperature's colour on the colour bar's scale, the
    legend lies beside the drawing (not over it), the joints between modules are marked, and
    ``projection='xz'`` looks along y orthographically."""
    from tca_casadi.plotting.robot3d import save_robot_png, temperature_colours, temperature_norm
    solution = Simulation.from_file(SCENARIOS / "arm.yaml", ["bending.tca1.temperature=90"]).solve(warn=False)
    figure = save_robot_png(solution, None, projection="xz")
    ax, bar = figure.axes[0], figure.axes[1]
    assert bar.get_ylabel() == "TCA temperature [degC]"
    norm, colours = temperature_norm(solution), temperature_colours()
    lines = {line.get_label().split(" (")[0]: line for line in ax.get_lines()}
    for key in ("bending.tca1", "bending.tca2", "twisting.tca"):
        expected = colours(norm(solution.actuators[key].temperature))
        assert matplotlib.colors.to_rgba(lines[key].get_color()) == pytest.approx(expected, abs=1e-9), key
    figure.canvas.draw()
    legend = figure.legends[0].get_window_extent()
    assert legend.x0 >= ax.get_window_extent().x1 - 1 and legend.x1 <= figure.bbox.x1 + 1
    assert any(c.get_label() == "joints between modules" for c in ax.collections)
    assert (ax.elev, ax.azim) == (0.0, -90.0) and ax._focal_length == float("inf")
    matplotlib.pyplot.close(figure)


def test_bad_view_and_projection_are_one_line(tmp_path, capsys):
    from tca_casadi.cli import main
    assert main(["solve", str(SCENARIOS / "bending_module.yaml"), "-o", str(tmp_path), "--view", "30"]) == 2
    assert "--view '30': give AZIMUTH,ELEVATION in degrees" in capsys.readouterr().err
    assert not (tmp_path / "solution.json").exists()


def test_a_one_input_monte_carlo_is_drawn_as_a_curve_without_roundoff_histograms_or_hulls():
    """One varied input: the tip moves on a curve, so no covariance ellipses, no convex hulls
    and no reachability density; tip y of the symmetric module is constant (roundoff), written as
    its value instead of a histogram; the input's axis in the unit it was given in."""
    from tca_casadi.plotting.fit_plots import histogram_bins
    from tca_casadi.plotting.study_plots import plot_monte_carlo, plot_workspace
    from tca_casadi.studies.batch.study import Study
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    result = Study(sim, vary={"tca_types.nylon.fiber_radius": {"normal": {"mean": "0.5 mm", "std": "0.01 mm"}}},
                   samples=20, seed=1).run()
    assert len(result.converged) == 20
    figure = plot_monte_carlo(result, None)
    top, bottom = figure.axes[:3], figure.axes[3:6]
    assert [ax.get_title().split(":")[1].strip().split(" ")[0] for ax in top] == ["std", "constant", "std"]
    assert not top[1].patches and "in every sample" in top[1].texts[0].get_text()
    assert len(top[0].patches) == histogram_bins(20) == 6
    assert not any("sigma" in line.get_label() for ax in bottom for line in ax.get_lines())
    assert figure.axes[-1].get_ylabel() == "tca_types.nylon.fiber_radius [mm]"      # the colour bar
    assert "µm" in top[0].get_xlabel()
    matplotlib.pyplot.close(figure)
    figure = plot_workspace(result, None)
    assert not any(line.get_label() == "convex hull" for ax in figure.axes for line in ax.get_lines())
    assert not any("density" in ax.get_title() for ax in figure.axes)
    matplotlib.pyplot.close(figure)


def _inside(ax, tolerance=1e-6):
    """Whether every finite point of every line of a 3D axes lies in its limits."""
    box = [ax.get_xlim(), ax.get_ylim(), ax.get_zlim()]
    for line in ax.get_lines():
        points = np.array(line.get_data_3d(), float)
        points = points[:, np.all(np.isfinite(points), axis=0)]
        for k, (low, high) in enumerate(box):
            if points.size and (points[k].min() < low - tolerance or points[k].max() > high + tolerance):
                return line.get_label()
    return None


def test_planes_are_cut_to_the_axes_and_forces_share_one_unit():
    """A table (a plane) drawn under the tendon robot's wall scene and the pick-and-place stays in
    the axes' box; a McKibben segment's legend writes every tension in one unit."""
    from tca_casadi.plotting.robot3d import save_robot_png
    sim = Simulation.from_file(SCENARIOS / "tendon_robot_wall.yaml",
                               ["obstacles=[{name: table, shape: plane, position: [0, 0, -130 mm], normal: [0, 0, 1]}]"])
    figure = save_robot_png(sim.solve(warn=False), None)
    ax = figure.axes[0]
    assert any(line.get_label() == "table" for line in ax.get_lines()) and _inside(ax) is None
    matplotlib.pyplot.close(figure)
    solution = Simulation.from_file(SCENARIOS / "bending_module_mckibben.yaml").solve(warn=False)
    figure = save_robot_png(solution, None)
    forces = [line.get_label().rsplit(", ", 1)[1].rstrip(")") for line in figure.axes[0].get_lines()
              if line.get_label().startswith("segment.pam")]
    units = {text.split(" ")[-1] for text in forces if text != "slack"}
    assert len(forces) == 3 and len(units) == 1, forces
    matplotlib.pyplot.close(figure)


def test_voltage_and_current_drives_get_their_own_traces():
    """A TCA on a voltage drive and one on a current drive (a resistance that rises with
    temperature): the figure has a voltage and a current panel, and the traces, computed from the
    thermal model's power and R(T), give back the drives' values (3 V, then 4 V; 150 mA)."""
    overrides = ["tca_types.nylon.resistance=20 ohm", "tca_types.nylon.resistance_temperature_coefficient=0.002",
                 "bending.tca2.drive={kind: voltage, value: 3 V}", "bending.tca3.drive={kind: current, value: 150 mA}",
                 "timeline=[{at: 2 s, set: {bending.tca2.drive.value: 4 V}}]", "duration=4"]
    figure, sim = _figure("bending_module_heating.yaml", overrides, 0.5)
    names = [ax.get_ylabel() for ax in figure.axes]
    assert names[:4] == ["temperature [degC]", "electrical power [mW]", "voltage [V]", "current [mA]"]
    voltage, current = figure.axes[2], figure.axes[3]
    (v,) = [l for l in voltage.get_lines() if l.get_label() == "bending.tca2"]
    (i,) = [l for l in current.get_lines() if l.get_label() == "bending.tca3"]
    t = np.asarray(v.get_xdata())
    np.testing.assert_allclose(v.get_ydata(), np.where(t < 2, 3.0, 4.0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(i.get_ydata(), 150.0, rtol=0, atol=1e-9)
    assert _colours(voltage)["bending.tca2"] == _colours(figure.axes[0])["bending.tca2"]
    matplotlib.pyplot.close(figure)

"""Figures checked where eyes are not needed (issue 35): one colour per actuator in every panel
of timeseries.png, every event named, the energy account drawn for a dynamic run and no panel
spent on what a run does not have."""
import matplotlib
import pytest

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.plotting.timeseries import event_labels, save_timeseries_png
from tca_casadi.studies.timeline import TimeSimulation


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

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

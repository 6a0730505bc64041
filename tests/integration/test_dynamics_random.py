"""Rod dynamics on random robots (trees, connectors with mass, TCAs and tendons on any route,
point loads and masses, gravity in any direction): every actuator ramps over 10 steps from
t = 0 (TCAs 15 degC hotter, tendons pulled 30 % harder); with the energy-conserving midpoint
rule the energy account closes, with BDF2 every step balances globally with the inertial loads.
(A sudden step instead closes the account only to 1e-4-1e-3, at any step size and mesh: it puts
energy into the modes no step resolves.)"""
import pytest

from random_robots import random_robot
from tca_casadi import Simulation
from tca_casadi.discretisation.dynamics import time_scale
from tca_casadi.time_simulation.timeline import TimeSimulation


def _stepped(seed, integrator):
    """A random robot (no distributed loads: the energy account counts point loads' work), its
    actuators ramped over the first 10 of 40 steps of a fifth of its shortest time scale."""
    scenario = random_robot(seed)
    scenario["loads"] = [load for load in scenario["loads"] if load["kind"] != "distributed"]
    changes = {}
    for module in scenario["modules"]:
        for actuator in module["actuators"]:
            key = f"{module['name']}.{actuator['name']}"
            if actuator["kind"] == "tca":
                changes[f"{key}.temperature"] = actuator["temperature"] + 15.0
            else:
                changes[f"{key}.tension"] = 1.3 * actuator["tension"]
    sim = Simulation.from_file(scenario)
    step = 0.2 * min(time_scale(m) for m in sim.robot.modules)
    scenario.update(dynamics={"enabled": True, "integrator": integrator, "balance_every": 1}, duration=40 * step,
                    timeline=[{"at": 0.0, "set": changes, "ramp": 10 * step}])
    timed = TimeSimulation(Simulation.from_file(scenario), dt=step)
    return timed, timed.run()


@pytest.mark.parametrize("seed", [3, 7, 11, 19])
def test_random_robots_keep_their_energy_account_and_balance(seed):
    timed, series = _stepped(seed, "midpoint")
    assert series.completed, series.message
    report = timed.report(series)["dynamics"]
    assert report["peak_tip_speed"] > 0
    assert report["energy_balance_relative"] < 1e-4, report
    _, series = _stepped(seed, "bdf2")
    assert series.completed, series.message
    assert max(s.balance.relative for s in series.solutions) < 1e-6

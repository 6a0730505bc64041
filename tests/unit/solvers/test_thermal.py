"""The thermal integrator against closed forms: a power step landing at its time, a linear
ramp, a voltage step's steady state with R(T), the heat balance."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.model.thermal import ThermalLaw
from tca_casadi.solvers.thermal import Drive, Schedule, integrate

LAW = ThermalLaw(heat_capacity=0.137, conductance=0.00707, resistance=12.0, resistance_coefficient=0.0)
AMBIENT = 25.0


def test_a_power_step_lands_at_its_time_and_follows_the_exponential():
    P, t_step = 0.3, 2.0
    outputs = np.linspace(0.0, 60.0, 601)
    history = integrate([LAW], [Drive("power", Schedule((0.0, t_step, t_step), (0.0, 0.0, P)))],
                        AMBIENT, [AMBIENT], outputs)
    after = np.clip(outputs - t_step, 0.0, None)
    rise = P / LAW.conductance
    expected = AMBIENT + rise * (1.0 - np.exp(-after / LAW.time_constant))
    assert_allclose(history.temperature[:, 0], expected, rtol=0, atol=1e-6 * rise)
    assert np.all(history.temperature[outputs <= t_step, 0] == AMBIENT)     # nothing before the step
    assert_allclose(history.power[:, 0], np.where(outputs >= t_step, P, 0.0), rtol=0, atol=0)


def test_a_linear_ramp():
    k, tau, G = 0.01, LAW.time_constant, LAW.conductance          # P = k t [W]
    outputs = np.linspace(0.0, 30.0, 301)
    history = integrate([LAW], [Drive("power", Schedule((0.0, 30.0), (0.0, 30.0 * k)))], AMBIENT, [AMBIENT], outputs)
    expected = AMBIENT + (k / G) * (outputs - tau * (1.0 - np.exp(-outputs / tau)))
    assert_allclose(history.temperature[:, 0], expected, rtol=0, atol=1e-6 * (expected[-1] - AMBIENT))
    assert_allclose(history.power[:, 0], k * outputs, rtol=0, atol=1e-15)


@pytest.mark.parametrize("alpha", [0.0, 4e-3])
def test_voltage_step_reaches_the_closed_form_steady_state_and_balances_heat(alpha):
    law = ThermalLaw(0.137, 0.00707, resistance=12.0, resistance_coefficient=alpha, reference_temperature=25.0)
    outputs = np.linspace(0.0, 30 * law.time_constant, 401)
    history = integrate([law, LAW], [Drive("voltage", Schedule.constant(2.0)), Drive("power", Schedule.constant(0.1))],
                        AMBIENT, [AMBIENT, 40.0], outputs)
    steady = law.steady_temperature("voltage", 2.0, AMBIENT)
    assert_allclose(history.temperature[-1, 0], steady, rtol=1e-8, atol=0)
    assert_allclose(history.temperature[-1, 1], LAW.steady_temperature("power", 0.1, AMBIENT), rtol=1e-8, atol=0)
    balance = history.heat_balance_residual()
    assert balance.shape == (outputs.size, 2)
    assert np.all(np.max(np.abs(balance), axis=0) <= 1e-6 * history.energy_in[-1])


def test_pi_setpoint_settles_without_error_and_respects_the_power_limit():
    """From ambient to 80 degC with a 1 W limit (saturated at first), then down to 60 degC: no
    steady-state error, the power never above the limit nor below zero, no wind-up (the power
    leaves the limit as soon as the temperature passes the setpoint)."""
    drive = Drive("setpoint", Schedule((0.0, 150.0, 150.0), (80.0, 80.0, 60.0)),
                  proportional=0.05, integral=0.005, max_power=1.0)
    outputs = np.linspace(0.0, 300.0, 3001)
    history = integrate([LAW], [drive], AMBIENT, [(AMBIENT, 0.0)], outputs)
    T, P = history.temperature[:, 0], history.power[:, 0]
    assert np.all(P <= 1.0) and np.all(P >= 0.0)
    assert P[0] == 1.0                                               # saturated at the start
    at_150, at_300 = np.searchsorted(outputs, 150.0), -1
    assert_allclose(T[at_150 - 1], 80.0, rtol=0, atol=1e-6)          # settled before the setpoint change
    assert_allclose(T[at_300], 60.0, rtol=0, atol=1e-6)
    assert_allclose(P[at_300], LAW.conductance * (60.0 - AMBIENT), rtol=0, atol=1e-8)   # P = G (T_set - T_amb)
    above = np.flatnonzero(T > 80.0 + 1e-9)
    assert above.size == 0 or P[above[0]] < 1.0                      # off the limit once past the setpoint
    assert T.max() < 80.0 + 1.0                                      # no wind-up overshoot


def test_setpoint_initial_state_is_its_steady_state():
    drive = Drive("setpoint", Schedule.constant(60.0), proportional=0.05, integral=0.005, max_power=1.0)
    T0, I0 = drive.initial_state(LAW, AMBIENT)
    history = integrate([LAW], [drive], AMBIENT, [(T0, I0)], np.linspace(0.0, 50.0, 11))
    assert_allclose(history.temperature[:, 0], 60.0, rtol=0, atol=1e-9)
    weak = Drive("setpoint", Schedule.constant(140.0), proportional=0.05, integral=0.005, max_power=0.5)
    T0, _ = weak.initial_state(LAW, AMBIENT)                         # 0.5 W holds only T_amb + P/G
    assert_allclose(T0, AMBIENT + 0.5 / LAW.conductance, rtol=1e-15, atol=0)


def test_step_response_of_a_first_order_lag():
    """10-90 % rise tau ln 9 and 2 % settling tau ln 50 of 1 - exp(-t/tau) after an event at 1 s."""
    from tca_casadi.time_simulation.timeline import step_response
    tau = LAW.time_constant
    t = np.linspace(0.0, 30 * tau, 30001)
    y = 25.0 + 50.0 * (1.0 - np.exp(-np.clip(t - 1.0, 0.0, None) / tau))
    response = step_response(t, y, 1.0, t[-1])
    assert_allclose(response["rise_time"], tau * np.log(9.0), rtol=1e-6, atol=0)
    assert_allclose(response["settling_time"], tau * np.log(50.0), rtol=1e-6, atol=0)
    flat = step_response(t, np.full_like(t, 3.0), 1.0, t[-1])
    assert flat["rise_time"] is None and flat["settling_time"] is None


def test_two_coupled_tcas_follow_their_two_modes():
    """Identical TCAs coupled by Gc, only the first heated (P from t = 0): the sum of their
    rises relaxes with G/C, their difference with (G + 2 Gc)/C; the heat each passes to the
    other cancels in total and every TCA's own balance holds."""
    from tca_casadi.solvers.thermal import steady_state
    P, Gc, C, G = 0.3, 0.004, LAW.heat_capacity, LAW.conductance
    outputs = np.linspace(0.0, 120.0, 241)
    drives = [Drive("power", Schedule((0.0, 0.0), (0.0, P))), Drive("power", Schedule.constant(0.0))]
    coupling = [[0.0, Gc], [Gc, 0.0]]
    initial = steady_state([LAW, LAW], drives, AMBIENT, coupling)
    assert_allclose(initial[:, 0], AMBIENT, rtol=0, atol=1e-12)        # the value before t = 0: no power
    history = integrate([LAW, LAW], drives, AMBIENT, initial, outputs, coupling)
    total = (P / G) * (1.0 - np.exp(-outputs * G / C))
    difference = P / (G + 2 * Gc) * (1.0 - np.exp(-outputs * (G + 2 * Gc) / C))
    expected = AMBIENT + 0.5 * np.stack([total + difference, total - difference], axis=1)
    assert_allclose(history.temperature, expected, rtol=0, atol=1e-6 * P / G)
    assert_allclose(history.energy_exchanged.sum(axis=1), 0.0, rtol=0, atol=1e-12)
    assert history.energy_exchanged[-1, 0] > 0.1                       # heat did flow from the heated one
    assert np.max(np.abs(history.heat_balance_residual())) <= 1e-6 * history.energy_in[-1, 0]


@pytest.mark.parametrize("max_power", [1.0, 0.3])
def test_coupled_steady_state_is_steady(max_power):
    """A voltage-driven TCA with R(T) beside a PI setpoint at 70 degC: the steady state holds
    for 60 s to 1e-8 degC; the setpoint is held while its power limit allows (1 W), else the
    controller sits at its limit (0.3 W) below the setpoint."""
    from tca_casadi.solvers.thermal import steady_state
    warm = ThermalLaw(0.137, 0.00707, resistance=12.0, resistance_coefficient=4e-3)
    drives = [Drive("voltage", Schedule.constant(2.0)),
              Drive("setpoint", Schedule.constant(70.0), proportional=0.05, integral=0.005, max_power=max_power)]
    coupling = [[0.0, 0.003], [0.003, 0.0]]
    initial = steady_state([warm, LAW], drives, AMBIENT, coupling)
    history = integrate([warm, LAW], drives, AMBIENT, initial, np.linspace(0.0, 60.0, 7), coupling)
    assert_allclose(history.temperature, np.broadcast_to(initial[:, 0], (7, 2)), rtol=0, atol=1e-8)
    needed = LAW.conductance * (70.0 - AMBIENT) + 0.003 * (70.0 - initial[0, 0])
    if needed <= max_power:
        assert_allclose(initial[1, 0], 70.0, rtol=0, atol=1e-12)
    else:
        assert initial[1, 0] < 70.0 - 1.0
        assert_allclose(history.power[:, 1], max_power, rtol=0, atol=1e-12)


def test_fixed_steps_converge_at_the_order_of_dop853():
    """A voltage step with R(T) at t = 16 s (a breakpoint: the pieces are stepped separately):
    halving the fixed step (16, 8, 4 s) divides the error at 80 s by about 2^8, the order of DOP853 (a
    drive evaluated across its step would drop it to 1)."""
    law = ThermalLaw(0.137, 0.00707, resistance=12.0, resistance_coefficient=4e-3)
    drive = Drive("voltage", Schedule((0.0, 16.0, 16.0), (0.5, 0.5, 3.0)))
    outputs = np.array([0.0, 80.0])
    start = drive.initial_state(law, AMBIENT)
    exact = integrate([law], [drive], AMBIENT, [start], outputs, rtol=1e-13, atol=1e-13).temperature[-1, 0]
    errors = [abs(integrate([law], [drive], AMBIENT, [start], outputs, step=h).temperature[-1, 0] - exact)
              for h in (16.0, 8.0, 4.0)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] > 1e-11                                          # still above the reference's error
    assert np.all((orders > 7.5) & (orders < 9.0)), (errors, orders)


def test_zero_order_hold_is_the_exact_step_of_the_coupled_model():
    """Three coupled TCAs with different constants and powers held over 0.7 s: the matrix
    exponential's step against DOP853 at 1e-12, and against the closed form of one uncoupled
    TCA, T_amb + P/G + (T0 - T_amb - P/G) exp(-h G/C)."""
    from tca_casadi.solvers.thermal import zero_order_hold
    laws = [ThermalLaw(0.12, 0.007), ThermalLaw(0.2, 0.004), ThermalLaw(0.05, 0.009)]
    coupling = np.array([[0, 0.002, 0.0], [0.002, 0, 0.001], [0.0, 0.001, 0]])
    T0, P, h = np.array([40.0, 25.0, 31.0]), np.array([0.3, 0.0, 0.12]), 0.7
    Phi, Gamma, offset = zero_order_hold(laws, 22.0, h, coupling)
    drives = [Drive("power", Schedule.constant(p)) for p in P]
    reference = integrate(laws, drives, 22.0, T0, [0.0, h], coupling, rtol=1e-13, atol=1e-13).temperature[-1]
    assert_allclose(Phi @ T0 + Gamma @ P + offset, reference, rtol=0, atol=1e-10)
    Phi, Gamma, offset = zero_order_hold(laws[:1], 22.0, h)
    C, G = laws[0].heat_capacity, laws[0].conductance
    closed = 22.0 + P[0] / G + (T0[0] - 22.0 - P[0] / G) * np.exp(-h * G / C)
    assert_allclose(Phi @ T0[:1] + Gamma @ P[:1] + offset, [closed], rtol=0, atol=1e-12)

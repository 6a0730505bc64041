"""Rod dynamics (issue 16) against Euler-Bernoulli, conservation of energy and the global
balance with inertia, and the integrators' order in time."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.model.dynamics import KelvinVoigt
from tca_casadi.solvers.dynamics import RodDynamics
from tca_casadi.studies.spectrum import dominant_frequencies

CANTILEVER = SCENARIOS / "analytic" / "released_cantilever.yaml"
E, D, L, RHO = 1e6, 5e-3, 0.2, 1000.0
EI, RHO_A = E * np.pi * D ** 4 / 64, RHO * np.pi * D ** 2 / 4
#: Euler-Bernoulli cantilever frequencies [Hz]
F1, F2 = (beta ** 2 * np.sqrt(EI / (RHO_A * L ** 4)) / (2 * np.pi) for beta in (1.8751, 4.6941))


def released(integrator, step, periods, damping=None, overrides=()):
    """Release the held cantilever; ``(t, tip x, energies (n, 2), worst balance)`` over
    ``periods`` first-mode periods at ``step`` [s] (the parameters after the release from the
    first step on)."""
    sim = Simulation.from_file(CANTILEVER, list(overrides))
    static = sim.solve(warn=False)
    dynamics = RodDynamics(sim, integrator, damping)
    state = dynamics.start(static)
    params = sim.params.copy()
    params[sim.robot.layout["hold.force"]] = 0.0
    state.params = params                              # released at t = 0+
    t, tip, energies, balance = [0.0], [static.tip_position[0]], [dynamics.energies(state, params)], 0.0
    for _ in range(int(round(periods / F1 / step))):
        state, solution = dynamics.step(params, step)
        assert state is not None, solution.message
        balance = max(balance, solution.balance.relative)
        t.append(state.t)
        tip.append(dynamics.tip_position(state)[0])
        energies.append(dynamics.energies(state, params))
    return np.array(t), np.array(tip), np.array(energies), balance


def test_free_vibration_matches_euler_bernoulli():
    """Implicit midpoint at T1/200 over 10 periods: the tip's spectrum has the first two
    cantilever modes within 0.5 % and 1 % of Euler-Bernoulli's; every step balances globally
    with the sections' inertia to 1e-9."""
    t, tip, _, balance = released("midpoint", 1 / F1 / 200, 10)
    f1, f2 = dominant_frequencies(t, tip, count=2)
    assert abs(f1 / F1 - 1) < 0.005, (f1, F1)
    assert abs(f2 / F2 - 1) < 0.01, (f2, F2)
    assert balance < 1e-8                                                   # the solver's tolerance


def test_midpoint_conserves_energy_over_100_periods():
    t, _, energies, _ = released("midpoint", 1 / F1 / 20, 100)
    total = energies.sum(axis=1)
    assert np.max(np.abs(total - total[0])) < 1e-6 * total[0]              # the issue asks for 1 %
    assert np.max(energies[:, 0]) > 0.9 * total[0]                          # it did swing: kinetic at the crossings


@pytest.mark.parametrize("integrator", ["bdf2", "midpoint"])
def test_the_first_mode_frequency_converges_at_order_two_in_time(integrator):
    """The first mode's frequency over 10 periods at steps T1/20, T1/40, T1/80 against T1/320:
    the error falls fourfold per halving (midpoint: the phase error -(omega h)^2 / 24 of its
    rotation per step)."""
    T1 = 1 / F1
    frequency = {n: dominant_frequencies(*released(integrator, T1 / n, 10)[:2], count=1)[0] for n in (20, 40, 80, 320)}
    errors = [abs(frequency[n] - frequency[320]) for n in (20, 40, 80)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 1.8) & (orders < 2.4)), (errors, orders)


def _peaks(t, x):
    """Times and heights of the positive maxima of x (parabolas through three samples)."""
    step, out = t[1] - t[0], []
    for k in range(1, len(x) - 1):
        if x[k] > x[k - 1] and x[k] >= x[k + 1] and x[k] > 0:
            a, b, c = x[k - 1], x[k], x[k + 1]
            shift = 0.5 * (a - c) / (a - 2 * b + c)
            out.append((t[k] + shift * step, b - 0.25 * (a - c) * shift))
    return np.array(out).T


def test_kelvin_voigt_damping_decays_the_first_mode_at_its_predicted_rate():
    """Stiffness-proportional Kelvin-Voigt damping with zeta = 2 % at the first mode: the tip's
    peaks decay as exp(-zeta omega_1 t) within 2 % (midpoint: no numerical damping), and the
    total energy never grows."""
    damping = KelvinVoigt.with_ratio(0.02, F1, E)
    t, tip, energies, _ = released("midpoint", 1 / F1 / 100, 10, damping)
    times, heights = _peaks(t, tip)
    rate = -np.polyfit(times, np.log(heights), 1)[0]
    assert abs(rate / (0.02 * 2 * np.pi * F1) - 1) < 0.02, rate
    total = energies.sum(axis=1)
    assert np.all(np.diff(total) <= 1e-12 * total[0])


def test_a_damped_run_settles_on_the_static_equilibrium():
    """From the held shape, the hold force halved at t = 0+, heavy damping (zeta = 0.3), BDF2:
    after 8 periods the tip is the static equilibrium under the halved force to 1e-8 m."""
    damping = KelvinVoigt.with_ratio(0.3, F1, E)
    sim = Simulation.from_file(CANTILEVER)
    dynamics = RodDynamics(sim, "bdf2", damping)
    state = dynamics.start(sim.solve(warn=False))
    params = sim.params.copy()
    params[sim.robot.layout["hold.force"]] *= 0.5
    state.params = params
    for _ in range(8 * 20):
        state, solution = dynamics.step(params, 1 / F1 / 20)
    settled = Simulation.from_file(CANTILEVER, ["hold.force=[5 uN, 0, 0]"]).solve(warn=False)
    assert_allclose(dynamics.tip_position(state), settled.tip_position, rtol=0, atol=1e-8)
    swing = 0.87e-3 * 2 * np.pi * F1                  # the released swing's peak tip speed [m/s]
    assert np.max(np.abs(state.nodes[0][1][0:3])) < 1e-5 * swing          # at rest


@pytest.mark.parametrize("step", [1e-5, 1e-6, 1e-7])
def test_tiny_steps_converge_and_balance(step):
    """The bending module, TCA 2 stepped from 25 to 35 degC, 20 BDF2 steps of 1e-5, 1e-6 and
    1e-7 s (the small end of the step range): every step converges and the tip starts to move.
    The global balance (inertial loads included) holds to 1e-4 only: in 20 such steps the
    disturbance travels about 1 mm, far less than an interval (7.5 mm), and the balance measures
    that unresolved wave front (8.5e-6 at 1e-5 s; 1.5e-9 in the free-vibration test)."""
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml", ["bending.tca2.temperature=25",
                                                                   "bending.tca3.temperature=25"])
    static = sim.solve(warn=False)
    dynamics = RodDynamics(sim, "bdf2")
    state = dynamics.start(static)
    params = sim.params.copy()
    params[sim.robot.layout["bending.tca2.temperature"]] = 35.0
    state.params = params
    for _ in range(20):
        state, solution = dynamics.step(params, step)
        assert state is not None, solution.message
        assert solution.balance.relative < 1e-4
    assert np.linalg.norm(dynamics.tip_position(state) - static.tip_position) > 0

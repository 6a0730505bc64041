"""The lumped thermal law against its closed forms."""
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tca_casadi.model.thermal import ThermalLaw, conductance, heat_capacity


def test_time_constant_depends_on_the_radius_not_the_length():
    """tau = rho c r / (2 h area_factor): a 0.4 mm fibre in still air, about 15 s."""
    for length in (0.05, 0.5):
        law = ThermalLaw(heat_capacity(4e-4, length, 1140.0, 1700.0), conductance(4e-4, length, 25.0, 1.0))
        assert_allclose(law.time_constant, 1140.0 * 1700.0 * 4e-4 / (2 * 25.0), rtol=1e-14, atol=0)
    assert_allclose(heat_capacity(4e-4, 0.1, 1140.0, 1700.0), 1140.0 * 1700.0 * math.pi * 1.6e-7 * 0.1,
                    rtol=1e-14, atol=0)


@pytest.mark.parametrize("alpha", [0.0, 4e-3, -1e-3])
def test_voltage_steady_state_is_the_root_of_the_heat_balance(alpha):
    law = ThermalLaw(0.05, 0.004, resistance=12.0, resistance_coefficient=alpha, reference_temperature=20.0)
    T = law.steady_temperature("voltage", 2.5, 25.0)
    balance = 2.5 ** 2 / law.resistance_at(T) - law.conductance * (T - 25.0)
    assert abs(balance) <= 1e-12 * 2.5 ** 2 / law.resistance
    assert T > 25.0
    if alpha == 0.0:
        assert_allclose(T, 25.0 + 2.5 ** 2 / (12.0 * 0.004), rtol=1e-14, atol=0)


def test_current_and_power_steady_states():
    law = ThermalLaw(0.05, 0.004, resistance=12.0, resistance_coefficient=4e-3, reference_temperature=25.0)
    T = law.steady_temperature("current", 0.1, 25.0)
    assert_allclose(0.01 * law.resistance_at(T), law.conductance * (T - 25.0), rtol=1e-13, atol=0)
    assert_allclose(law.steady_temperature("power", 0.2, 25.0), 75.0, rtol=1e-15, atol=0)
    with pytest.raises(ValueError, match="no steady state"):
        law.steady_temperature("current", 10.0, 25.0)       # I^2 R0 alpha > G: thermal runaway


def test_power_of_each_drive():
    law = ThermalLaw(0.05, 0.004, resistance=10.0, resistance_coefficient=0.01, reference_temperature=25.0)
    assert_allclose(law.power("voltage", 2.0, 125.0), 4.0 / 20.0, rtol=1e-15, atol=0)
    assert_allclose(law.power("current", 0.1, 125.0), 0.01 * 20.0, rtol=1e-15, atol=0)
    assert_allclose(law.power("power", 0.3, np.array([25.0, 80.0])), [0.3, 0.3], rtol=0, atol=0)

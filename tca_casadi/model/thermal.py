"""The lumped (first-order) thermal model of an electrically heated TCA.

One temperature per TCA, the fibre's:

    C dT/dt = P(t, T) - G (T - T_amb) - sum_j G_j (T - T_j)

``C`` [J/K] the fibre's heat capacity, ``G`` [W/K] its conductance to the surroundings
(convection), ``G_j`` [W/K] optional conductances to neighbouring TCAs of the same module (heat
through the body). The electrical power ``P`` [W] is given (``power`` drive, what PWM averages
to), or follows from a voltage ``V`` or a current ``I`` and the resistance
``R(T) = R_0 (1 + alpha_R (T - T_0))``: ``P = V^2 / R(T)`` or ``P = I^2 R(T)``.

From the fibre's geometry (radius ``r``, length ``l``) and material (density ``rho``, specific
heat ``c``, convection coefficient ``h``, and ``area_factor``, the exposed fraction of the
fibre's own lateral surface: less than 1 when coils touch or the TCA lies in a channel)::

    C = rho c pi r^2 l            (mass times specific heat; rho enters once)
    G = h area_factor 2 pi r l    (lateral area, the ends neglected)
    tau = C / G = rho c r / (2 h area_factor)

so the time constant depends on the fibre's radius, not its length (the area-to-volume ratio
``2 / r`` must not be dropped: without it tau comes out in days).
"""
from dataclasses import dataclass
import math

import numpy as np

#: nylon 6,6 TCA fibre in still air: density [kg/m^3], specific heat [J/(kg K)] and natural
#: convection coefficient [W/(m^2 K)] (see the README's thermal section for the sources)
NYLON_DENSITY = 1140.0
NYLON_SPECIFIC_HEAT = 1700.0
STILL_AIR_CONVECTION = 25.0


def heat_capacity(fiber_radius, fiber_length, density=NYLON_DENSITY, specific_heat=NYLON_SPECIFIC_HEAT):
    """``C = rho c pi r^2 l`` [J/K] of a fibre of radius [m] and length [m]."""
    return density * specific_heat * math.pi * fiber_radius ** 2 * fiber_length


def conductance(fiber_radius, fiber_length, convection_coefficient=STILL_AIR_CONVECTION, area_factor=1.0):
    """``G = h area_factor 2 pi r l`` [W/K]: convection from the exposed lateral surface."""
    return convection_coefficient * area_factor * 2.0 * math.pi * fiber_radius * fiber_length


@dataclass(frozen=True)
class ThermalLaw:
    """Heat capacity, conductance and electrical resistance of one TCA (SI, degC)."""
    heat_capacity: float                 # C [J/K]
    conductance: float                   # G [W/K]
    resistance: float = float("nan")     # R_0 [ohm] at reference_temperature
    resistance_coefficient: float = 0.0  # alpha_R [1/K]
    reference_temperature: float = 25.0  # T_0 [degC]

    @property
    def time_constant(self):
        """``C / G`` [s]."""
        return self.heat_capacity / self.conductance

    def resistance_at(self, temperature):
        """``R(T) = R_0 (1 + alpha_R (T - T_0))`` [ohm]."""
        return self.resistance * (1.0 + self.resistance_coefficient * (np.asarray(temperature) - self.reference_temperature))

    def power(self, kind, value, temperature):
        """Electrical power [W] of a ``power`` [W], ``voltage`` [V] or ``current`` [A] drive
        of ``value`` at fibre ``temperature`` [degC]."""
        if kind == "power":
            return np.asarray(value, float) + 0.0 * np.asarray(temperature, float)
        if kind == "voltage":
            return np.asarray(value, float) ** 2 / self.resistance_at(temperature)
        if kind == "current":
            return np.asarray(value, float) ** 2 * self.resistance_at(temperature)
        raise ValueError(f"unknown drive kind {kind!r}")

    def rate(self, temperature, power, ambient, exchange=0.0):
        """``dT/dt`` [K/s]; ``exchange`` [W]: heat flowing to neighbours, ``sum G_j (T - T_j)``."""
        return (power - self.conductance * (temperature - ambient) - exchange) / self.heat_capacity

    def steady_temperature(self, kind, value, ambient):
        """The steady state of a constant drive [degC], in closed form: ``P = G (T - T_amb)``
        (power), or the root above ambient of the quadratic ``V^2 = G (T - T_amb) R(T)``
        (voltage) or ``I^2 R(T) = G (T - T_amb)`` (current, only while ``I^2 R_0 alpha_R < G``:
        beyond, resistive heating outruns convection and there is no steady state)."""
        G, R0, alpha, T0 = self.conductance, self.resistance, self.resistance_coefficient, self.reference_temperature
        if kind == "power":
            return ambient + value / G
        if kind == "voltage":          # G R0 (1 + alpha (T - T0)) (T - T_amb) = V^2, in x = T - T_amb
            a = G * R0 * alpha
            b = G * R0 * (1.0 + alpha * (ambient - T0))
            c = -value ** 2
        elif kind == "current":        # G x = I^2 R0 (1 + alpha (T_amb - T0) + alpha x)
            slope = G - value ** 2 * R0 * alpha
            if slope <= 0:
                raise ValueError("no steady state: resistive heating grows faster than convection")
            return ambient + value ** 2 * R0 * (1.0 + alpha * (ambient - T0)) / slope
        else:
            raise ValueError(f"unknown drive kind {kind!r}")
        return ambient - 2 * c / (b + math.sqrt(b * b - 4 * a * c))    # the root x >= 0, no cancellation


def thermal_law(tca_type, fiber_length):
    """The :class:`ThermalLaw` of a TCA of ``tca_type`` (the scenario's ``TcaType``) whose fibre
    is ``fiber_length`` [m] long: ``thermal.heat_capacity`` / ``conductance`` where given, else
    from the fibre (:func:`heat_capacity`, :func:`conductance`)."""
    thermal = tca_type.thermal
    C = thermal.heat_capacity
    if C is None:
        C = heat_capacity(tca_type.fiber_radius, fiber_length, thermal.density, thermal.specific_heat)
    G = thermal.conductance
    if G is None:
        G = conductance(tca_type.fiber_radius, fiber_length, thermal.convection_coefficient, thermal.area_factor)
    resistance = float("nan") if tca_type.resistance is None else tca_type.resistance
    return ThermalLaw(C, G, resistance, tca_type.resistance_temperature_coefficient, tca_type.reference_temperature)

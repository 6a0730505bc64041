"""The time stage (``tca-casadi simulate``): a scenario's timeline run in time, on top of the
solvers. ``timeline`` (:class:`TimeSimulation`: events, drives, the thermal model, the run),
``heating`` (:class:`TimeSeries`, the result; the quasi-static shape followed from one output
time to the next), ``motion`` (rod dynamics: implicit steps and the energy account) and
``spectrum`` (the frequencies in a sampled signal)."""
from .heating import TimeSeries, follow_parameters, follow_temperatures
from .motion import ENERGY_COLUMNS, EnergyAccount, follow_dynamics
from .spectrum import dominant_frequencies
from .timeline import TimeSimulation, simulate, step_response

__all__ = ["TimeSimulation", "simulate", "step_response", "TimeSeries", "follow_parameters", "follow_temperatures",
           "EnergyAccount", "ENERGY_COLUMNS", "follow_dynamics", "dominant_frequencies"]

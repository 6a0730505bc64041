"""Calibration from measurements (``tca-casadi fit``): least squares over chosen parameters
(:class:`Fit`, ``least_squares``), heating curves for a TCA type's thermal constants
(``thermal``), and the result type :class:`FitResult`."""
from .least_squares import Fit, FitModel, Measurements, read_measurements, synthetic_measurements, write_measurements
from .result import FitResult, FittedParameter

__all__ = ["Fit", "FitModel", "FitResult", "FittedParameter", "Measurements", "read_measurements",
           "synthetic_measurements", "write_measurements"]

"""Sweeps: one or more parameters followed along a path of values by continuation (``tca-casadi
sweep``, :class:`Sweep`), with exact sensitivities, fold detection and pseudo-arclength steps;
the result type :class:`SweepResult`."""
from .result import SweepResult, bending_angle, find_events
from .run import Sweep, SweepPoint

__all__ = ["Sweep", "SweepPoint", "SweepResult", "bending_angle", "find_events"]

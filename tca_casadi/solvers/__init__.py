"""Solvers behind one interface: ``solver.solve(params, initial=None) -> Solution``."""
from .collocation import CollocationSolver

__all__ = ["CollocationSolver"]

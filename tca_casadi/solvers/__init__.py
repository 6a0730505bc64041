"""Solvers behind one interface: ``solver.solve(params, initial=None) -> Solution``."""
from .collocation import CollocationSolver
from .shooting import ShootingSolver

__all__ = ["CollocationSolver", "ShootingSolver"]

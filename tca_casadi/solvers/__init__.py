"""Solvers behind one interface: ``solver.solve(params, initial=None) -> Solution``. The
shooting solver (and scipy.integrate with it) is imported on first use: most commands never
shoot."""
from .._lazy import lazy_getattr
from .collocation import CollocationSolver

__getattr__ = lazy_getattr(__name__, {"ShootingSolver": ".shooting"})
__all__ = ["CollocationSolver", "ShootingSolver"]

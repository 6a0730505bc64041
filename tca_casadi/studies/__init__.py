"""Studies built on the solvers: solver comparison (check)."""
from .compare import CheckReport, check, compare_solutions

__all__ = ["CheckReport", "check", "compare_solutions"]

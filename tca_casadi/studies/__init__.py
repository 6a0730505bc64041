"""Studies built on the solvers: solver comparison (check), continuation (sweep), inverse statics."""
from .compare import CheckReport, check, compare_solutions
from .inverse import InverseResult, InverseStatics, Target
from .parameters import StudyParameter, resolve_parameter
from .sweep import Sweep
from .sweep_result import SweepResult, bending_angle

__all__ = ["CheckReport", "check", "compare_solutions", "Sweep", "SweepResult", "StudyParameter",
           "resolve_parameter", "bending_angle", "InverseStatics", "InverseResult", "Target"]

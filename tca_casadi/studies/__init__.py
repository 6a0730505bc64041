"""Studies built on the solvers, one subpackage per capability: ``sweep`` (continuation along a
path of values), ``inverse`` (inverse statics), ``batch`` (studies of many samples, on Dask or
local processes), ``fit`` (calibration from measurements), ``sequence`` (steps and the objects
picked and placed); ``compare`` (the collocation/shooting cross-check) and ``parameters`` (a
study's parameters and the units they are shown in) serve them all."""
from .compare import CheckReport, check, compare_solutions
from .inverse import InverseResult, InverseStatics, Target
from .parameters import StudyParameter, resolve_parameter
from .sweep import Sweep, SweepResult, bending_angle

__all__ = ["CheckReport", "check", "compare_solutions", "Sweep", "SweepResult", "StudyParameter",
           "resolve_parameter", "bending_angle", "InverseStatics", "InverseResult", "Target"]

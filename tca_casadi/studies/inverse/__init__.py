"""Inverse statics (``tca-casadi inverse``): the temperatures (or other inputs) that bring a
point of the robot to a target pose (:class:`InverseStatics`; reduced least squares by default,
full-space IPOPT on request), targets read from Python, the scenario or a CSV path
(:class:`Target`), and the result type :class:`InverseResult`."""
from .result import InverseResult, write_path_results
from .statics import InverseStatics
from .targets import Target, TargetLayout, read_targets

__all__ = ["InverseStatics", "InverseResult", "Target", "TargetLayout", "read_targets", "write_path_results"]

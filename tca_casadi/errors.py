"""Exceptions and warnings of tca_casadi.

Bad user input raises :class:`ScenarioError` (the CLI turns it into one line and exit code 2).
Algorithmic failure is *not* an exception: a :class:`~tca_casadi.solution.Solution` carries
``converged=False`` with a status and message. :class:`SolverError` exists for callers who prefer
an exception (``Solution.raise_if_failed()``) and keeps the failed solution.
"""


class TcaError(Exception):
    """Base class of every error this package raises on purpose."""


class ScenarioError(TcaError, ValueError):
    """A scenario (file, dict or override) is invalid. The message names key path and line."""


class ModelError(TcaError):
    """A scenario is valid but asks the model for something it cannot represent."""


class SolverError(TcaError):
    """A solve did not converge; ``.solution`` holds the failed (unconverged) result."""

    def __init__(self, message, solution=None):
        super().__init__(message)
        self.solution = solution


class PhysicsWarning(UserWarning):
    """A converged result that leaves the model's range (compression, fit range, slack)."""


class OutputError(ScenarioError):
    """Results cannot be written where asked (not a directory, not writable). Raised before any
    computing, and treated like bad input (exit code 2)."""

"""Exceptions and warnings of tca_casadi.

Bad user input raises :class:`ScenarioError` (the CLI turns it into one line and exit code 2).
Algorithmic failure is *not* an exception: a :class:`~tca_casadi.solution.Solution` carries
``converged=False`` with a status and message. :class:`SolverError` exists for callers who prefer
an exception (``Solution.raise_if_failed()``) and keeps the failed solution.

Messages name an option as the user gave it (:func:`flag`): ``--data`` when the command line
runs (:func:`command_line`), the keyword argument ``data`` from Python.
"""
import contextlib
import contextvars

#: which front end the user is calling through: ``"python"`` or ``"cli"``
_FRONT_END = contextvars.ContextVar("tca_casadi_front_end", default="python")


def flag(option, python=None):
    """An option in a message as the user gave it: ``option`` (``"--power-budget"``) on the
    command line, else ``python`` if given (``"allow_code=True"``), else the keyword argument
    (``"power_budget"``)."""
    if _FRONT_END.get() == "cli":
        return option
    return python if python is not None else option.lstrip("-").replace("-", "_")


@contextlib.contextmanager
def command_line():
    """Within it, messages name options as the command line spells them (:func:`flag`)."""
    token = _FRONT_END.set("cli")
    try:
        yield
    finally:
        _FRONT_END.reset(token)


class TcaError(Exception):
    """Base class of every error this package raises on purpose."""


class ScenarioError(TcaError, ValueError):
    """A scenario (file, dict or override) is invalid. The message names key path and line."""


class ModelError(ScenarioError):
    """A scenario is valid but asks the model for something it cannot represent (the midpoint
    rule with contact, the dynamics of a massless rod, a plan through a resistance that changes
    with temperature); bad input all the same (the command line's exit code 2)."""


class SolverError(TcaError):
    """A solve did not converge; ``.solution`` holds the failed (unconverged) result."""

    def __init__(self, message, solution=None):
        super().__init__(message)
        self.solution = solution


class PhysicsWarning(UserWarning):
    """Something a result's user must know: it did not converge, or it leaves the model's range
    (compression, fit range, slack), or its accuracy or balance is not what was asked, or a
    tolerance was floored. Recorded in ``Solution.warnings`` (``str(w)`` is the text, ``w.kind``
    one of :data:`WARNING_KINDS`) and issued by :meth:`Simulation.solve` and ``check``."""

    def __init__(self, kind, message):
        if kind not in WARNING_KINDS:
            raise ValueError(f"unknown warning kind {kind!r}")
        super().__init__(message)
        self.kind = kind
        self.message = message

    def __str__(self):
        return self.message

    def __repr__(self):
        return f"PhysicsWarning({self.kind!r}, {self.message!r})"

    def __eq__(self, other):
        return isinstance(other, PhysicsWarning) and (self.kind, self.message) == (other.kind, other.message)

    def __hash__(self):
        return hash((self.kind, self.message))

    def as_dict(self):
        return {"kind": self.kind, "message": self.message}


#: the kinds of :class:`PhysicsWarning`
WARNING_KINDS = ("not_converged", "compression", "fit_range", "slack", "global_balance", "accuracy",
                 "mesh_limit", "tolerance_floor", "grasp", "sequence", "stress", "penetration", "slipping")


class OutputError(ScenarioError):
    """Results cannot be written where asked (not a directory, not writable). Raised before any
    computing, and treated like bad input (exit code 2)."""


class ResourceError(TcaError):
    """A run needs more of the machine than it has (memory): said in one line with what was
    too big and what to change (exit code 1); no result files are written."""

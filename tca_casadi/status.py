"""One status type for every solver and study: Newton, IPOPT, shooting, continuation, inverse.

Following scipy's ``OptimizeResult``: ``success``, an integer ``status`` whose meaning is in
:data:`MESSAGES`, ``nit``, the residual reached and the tolerance it was judged against, and
timings. The algorithm's own words (IPOPT's return status, scipy's message) are kept in
``detail``; they never decide success, the residual does.
"""
from dataclasses import asdict, dataclass, replace
from enum import IntEnum


class Status(IntEnum):
    """Why an algorithm stopped (0 is success)."""
    CONVERGED = 0
    MAX_ITERATIONS = 1
    ABOVE_TOLERANCE = 2
    ALGORITHM_FAILED = 3
    SINGULAR = 4
    NOT_FINITE = 5
    NO_DESCENT = 6
    INTEGRATION_FAILED = 7
    STALLED = 8
    NO_EQUILIBRIUM = 9
    CYCLING = 10


#: what each status means
MESSAGES = {
    Status.CONVERGED: "converged: the max scaled residual meets the tolerance",
    Status.MAX_ITERATIONS: "stopped at the iteration limit",
    Status.ABOVE_TOLERANCE: "stopped with the max scaled residual above the tolerance",
    Status.ALGORITHM_FAILED: "the algorithm reported failure",
    Status.SINGULAR: "singular Jacobian",
    Status.NOT_FINITE: "the residual is not finite",
    Status.NO_DESCENT: "no descent along the Newton step",
    Status.INTEGRATION_FAILED: "the integration of a shot failed",
    Status.STALLED: "continuation stalled before the requested parameters",
    Status.NO_EQUILIBRIUM: "no equilibrium at the answer",
    Status.CYCLING: "the semismooth steps went round without cutting the residual (contacts switching back and forth)",
}


@dataclass(frozen=True)
class SolveStatus:
    """How one solve ended.

    Attributes
    ----------
    status : Status
        Why it stopped; ``success`` is ``status == Status.CONVERGED``.
    algorithm : str
        ``"IPOPT"``, ``"Newton"``, ``"pseudo-arclength corrector"``, ``"scipy root (hybr)"``,
        ``"least squares (dogbox)"``, ...
    nit : int
        Iterations (function evaluations for scipy's MINPACK root).
    residual : float
        Max scaled residual reached (dimensionless; ``inf`` if none).
    tolerance : float
        The tolerance the residual was judged against.
    solve_time_s, build_time_s : float
        Wall time of the solve and of building the solver [s].
    detail : str
        The algorithm's own report and notes (continuation steps, refinements).
    """
    status: Status
    algorithm: str
    nit: int = 0
    residual: float = float("nan")
    tolerance: float = float("nan")
    solve_time_s: float = 0.0
    build_time_s: float = 0.0
    detail: str = ""

    @classmethod
    def judged(cls, algorithm, residual, tolerance, failure=None, **fields):
        """``CONVERGED`` when ``residual <= tolerance`` and no ``failure`` (a :class:`Status`)
        was reported, else ``failure`` or ``ABOVE_TOLERANCE``."""
        residual = float(residual)
        if failure is None or failure == Status.CONVERGED:
            failure = Status.CONVERGED if residual <= tolerance else Status.ABOVE_TOLERANCE
        return cls(Status(failure), algorithm, residual=residual, tolerance=float(tolerance), **fields)

    @property
    def success(self):
        return self.status == Status.CONVERGED

    @property
    def message(self):
        """One line: algorithm, meaning of the status, residual against tolerance, detail."""
        text = f"{self.algorithm}: {MESSAGES[self.status]} (max scaled residual {self.residual:.2e}"
        text += f", tolerance {self.tolerance:.0e}, {self.nit} iterations)"
        return text + (f"; {self.detail}" if self.detail else "")

    def noted(self, note):
        """A copy with ``note`` appended to ``detail``."""
        return replace(self, detail=f"{self.detail}; {note}" if self.detail else note)

    def replace(self, **changes):
        return replace(self, **changes)

    def as_dict(self):
        """JSON-ready: the fields, the status as an integer, ``success`` and ``message``."""
        out = asdict(self)
        out.update(status=int(self.status), success=self.success, message=self.message)
        return out


__all__ = ["MESSAGES", "SolveStatus", "Status"]

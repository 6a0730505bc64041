"""What every result offers (issue 35): ``success``, ``status``, ``message`` and ``result`` (the
:class:`~tca_casadi.status.SolveStatus`), a short ``repr`` (what it is, whether it succeeded,
its headline numbers: a few lines, never the arrays), an HTML repr for notebooks, and
``plot()``: the matplotlib figure the command line saves for it.

A result class mixes in :class:`ResultAPI` (its dataclass with ``repr=False``, so that the
mixin's repr is the one used) and provides ``result``, ``summary()`` (the headline) and
``figure()``; ``message`` is its own where it has one, else the status's.
"""
import html

from .status import MESSAGES, SolveStatus, Status

#: the repr shows at most this many lines of the summary, each at most this wide
REPR_LINES = 10
REPR_WIDTH = 160


def status_of(success, algorithm, detail="", failure=Status.ABOVE_TOLERANCE, **fields):
    """A :class:`SolveStatus` for a result judged as a whole (a sweep completed, a check agreed):
    ``CONVERGED`` when ``success``, else ``failure``."""
    return SolveStatus(Status.CONVERGED if success else failure, algorithm, detail=detail, **fields)


class ResultAPI:
    """``success``, ``status``, a short ``repr``, ``_repr_html_`` and ``plot()`` from the class's
    ``result``, ``summary()`` and ``figure()`` (module docstring)."""

    @property
    def success(self):
        """Whether it did what was asked (the :class:`SolveStatus`'s judgement)."""
        return bool(self.result.success)

    @property
    def status(self):
        """Why it ended (:class:`~tca_casadi.status.Status`; 0 is success)."""
        return self.result.status

    def _headline(self):
        """The summary's first :data:`REPR_LINES` lines, each clipped to :data:`REPR_WIDTH`."""
        lines = self.summary().splitlines()
        shown = [line if len(line) <= REPR_WIDTH else line[:REPR_WIDTH - 3] + "..." for line in lines[:REPR_LINES]]
        if len(lines) > REPR_LINES:
            shown.append(f"... ({len(lines) - REPR_LINES} more lines: print(result.summary()))")
        return shown

    def __repr__(self):
        state = "success" if self.success else f"no success: {MESSAGES[Status(self.status)]}"
        return "\n".join([f"<{type(self).__name__}: {state}>"] + ["  " + line for line in self._headline()])

    def _repr_html_(self):
        state = "success" if self.success else f"no success: {MESSAGES[Status(self.status)]}"
        colour = "#1a7f37" if self.success else "#cf222e"
        body = html.escape("\n".join(self._headline()))
        return (f"<div><b>{type(self).__name__}</b> <span style='color:{colour}'>{html.escape(state)}</span>"
                f"<pre style='margin:0.3em 0'>{body}</pre></div>")

    def plot(self):
        """The figure the command line saves for this result (a matplotlib Figure, open: show
        it, save it or close it)."""
        return self.figure()

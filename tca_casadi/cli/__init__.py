"""Command line: ``tca-casadi validate|solve|check|sweep|inverse|sequence|simulate|plan|study|fit SCENARIO ...``.

Exit codes: 0 success, 1 the solver did not converge (``check``: the solvers disagree),
2 bad input (one line on stderr). ``sweep``: 1 when the run stopped before the stop value;
``inverse``: 1 when a target is unreachable (the closest pose is still written); ``study``: 1
when some samples did not converge (they are rows with their reason); ``fit``: 1 when the least
squares did not converge.

One module per stage of the command line: :mod:`.parser` (every command's options),
:mod:`.run` (running one), :mod:`.common` (what they share), and the commands by what they
compute: :mod:`.statics` (validate, solve, check, sweep, inverse), :mod:`.sequence`,
:mod:`.time` (simulate), :mod:`.plan`, :mod:`.study`, :mod:`.fit`.
"""
from .run import main
from .parser import build_parser

__all__ = ["build_parser", "main"]

"""Running one command: exit codes, one-line errors, interrupts."""
import logging
import signal
import sys

from ..errors import ScenarioError, TcaError, command_line
from .fit import _fit
from .parser import build_parser
from .plan import _plan
from .sequence import _sequence
from .statics import _check, _inverse, _solve, _sweep, _validate
from .study import _study
from .time import _simulate


def main(argv=None):
    """Run one command; the exit code (0, 1, 2, or 130 when interrupted). Run as the program
    (``argv`` None), an interrupt ends the process at once with status 130 (see
    :func:`_exit_interrupted`), whatever the parent did with SIGINT (a shell's background job
    starts with it ignored)."""
    if argv is None:
        _take_interrupts()
    try:
        return _run(argv)
    except Exception:
        # a Ctrl-C that lands inside CasADi's argument conversion comes back as another error
        # (SWIG tries the next overload and reports none matched: NotImplementedError)
        if not _INTERRUPTS:
            raise
        return _interrupted(argv)


def _run(argv):
    """:func:`main`'s command, its errors reported in one line."""
    try:
        args = build_parser().parse_args(argv)
        logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                            format="%(levelname)s %(name)s: %(message)s")
        with command_line():                    # messages name options as --flags
            return COMMANDS[args.command](args)
    except ScenarioError as exc:
        print("\n".join(f"error: {line}" for line in str(exc).splitlines()), file=sys.stderr)
        return 2
    except TcaError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except (MemoryError, RuntimeError) as exc:
        from ..resources import is_out_of_memory, memory_limit
        if not is_out_of_memory(exc):
            raise
        print(f"error: out of memory ({memory_limit()}): the problem is too large for "
              "this machine; lower solver.max_intervals or solver.intervals, the number of samples, steps or output "
              "times; no result was written", file=sys.stderr)
        return 1
    except BrokenPipeError:            # the reader left (``| head``): not an error of ours
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        return _interrupted(argv)
    except SystemError as exc:
        # a Ctrl-C that lands inside a C extension's callback (numpy converting a CasADi
        # matrix) comes back as a SystemError caused by the KeyboardInterrupt
        if not isinstance(exc.__cause__ or exc.__context__, KeyboardInterrupt):
            raise
        return _interrupted(argv)


def _interrupted(argv):
    """The one-line report of an interrupt; status 130 (the process ends at once when run as
    the program)."""
    if argv is None:                     # a second Ctrl-C must not break the one-line report
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    print("interrupted: no result of this run was written (the output directory keeps what it held; "
          "a study goes on from its solved rows with --resume)", file=sys.stderr)
    if argv is None:
        _exit_interrupted()
    return 130


#: the Ctrl-Cs this process took (run as the program)
_INTERRUPTS = []


def _take_interrupts():
    """Ctrl-C raises KeyboardInterrupt in this process, even where the parent ignored SIGINT
    (Python keeps an inherited ``SIG_IGN``), and is remembered (:data:`_INTERRUPTS`)."""
    def interrupt(number, frame):
        _INTERRUPTS.append(number)
        signal.default_int_handler(number, frame)
    signal.signal(signal.SIGINT, interrupt)


def _exit_interrupted():
    """Exit with status 130 now. A Ctrl-C that lands during some extension imports (seen during
    casadi's, about 0.8 s after start) leaves CPython 3.11 treating the interrupt as unhandled
    even though we caught it: at exit it kills itself with SIGINT (status -2, not 130).
    ``os._exit`` after flushing avoids that; result files are written atomically, so nothing is
    left half-written."""
    import os
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(130)


COMMANDS = {"validate": _validate, "solve": _solve, "check": _check, "sweep": _sweep,
            "inverse": _inverse, "sequence": _sequence, "simulate": _simulate, "plan": _plan, "study": _study,
            "fit": _fit}

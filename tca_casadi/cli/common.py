"""What the commands share: output directories, progress, quantities on the command line."""
import sys

from ..errors import ScenarioError
from ..output import ResultSet, default_directory


def _view(args):
    from ..plotting.robot3d import view_of
    return view_of(getattr(args, "view", None), getattr(args, "projection", None))


def _vtk_files(args, name):
    """``(files, stale)`` of a command's VTK output: the frames and ``NAME.pvd`` with ``--vtk``,
    else the same as files an earlier run may have left."""
    files = ["vtk_*.vtu", f"{name}.pvd", f"{name}_names.json"]
    return (files, []) if args.vtk else ([], files)


def _results(args, sim, command, files, stale=(), default=None):
    """The :class:`~tca_casadi.output.ResultSet` of a command's output directory (``-o``, else
    ``results/<scenario name>[/default]``): prepared on entering, made visible on leaving."""
    directory = args.output or default_directory(sim.scenario.name, *([default] if default else []))
    return ResultSet(directory, command, files, stale, argv=sys.argv[1:], scenario=str(args.scenario))


def _median(values):
    import statistics
    return statistics.median(values)


def _quantities(values, kind, option):
    """SI values of command-line numbers or quantities with units (``'12 mm'``) of ``kind``;
    a bad one is a ScenarioError naming ``option``."""
    from ..units import to_si
    try:
        return [to_si(_number(v), kind) for v in values]
    except ValueError as exc:
        raise ScenarioError(f"{option}: {exc}") from None


def _number(text):
    """A plain number where the text is one; else the text (a value with a unit)."""
    try:
        return float(text)
    except ValueError:
        return text


def _with_progress(run, label, quiet=False):
    """Call ``run(progress=...)`` with a rich progress bar on stderr (none if quiet or not a TTY,
    where a long run says once, from its first steps, how long it will take: :class:`_Pace`)."""
    if quiet or not sys.stderr.isatty():
        return run(progress=_Pace(label))
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
    columns = (TextColumn(f"{label} "), BarColumn(), TextColumn("{task.percentage:>5.1f}%"),
               TextColumn("{task.description}"), TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task("", total=1.0)
        return run(progress=lambda fraction, text: bar.update(task, completed=fraction, description=text))


class _Pace:
    """A progress callback that, once a run has gone on for :data:`PACE_AFTER` seconds since its
    first progress (the build and first solve left out), prints one line to stderr if at its
    pace so far it still has more than :data:`LONG_RUN` seconds to go."""

    def __init__(self, label):
        import time
        self.label, self.clock, self.first, self.said = label, time.perf_counter, None, False

    def __call__(self, fraction, text=""):
        if self.said:
            return
        now = self.clock()
        if self.first is None:
            self.first = (now, fraction)
            return
        (_, done), elapsed = self.first, now - self.first[0]
        if elapsed < PACE_AFTER or fraction <= done:
            return
        self.said = True
        left = (1.0 - fraction) * elapsed / (fraction - done)
        if left > LONG_RUN:
            print(f"{self.label}: {100 * fraction:.2g} % done; about {_duration(left)} to go at this pace "
                  "(Ctrl-C stops it)", file=sys.stderr, flush=True)


def _duration(seconds):
    """``3 h 20 min``, ``12 min``, ``45 s``."""
    if seconds >= 3600 * 48:
        return f"{seconds / 86400:.3g} days"
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60)} min"
    if seconds >= 60:
        return f"{int(seconds // 60)} min"
    return f"{seconds:.0f} s"


def _kelvin(value):
    """A temperature difference [K] from a number or ``"0.5 K"`` (degC steps are kelvin)."""
    from ..units import temperature_difference
    return temperature_difference(value)


def _vary_spec(text, option):
    """``(path, spec)`` of ``PATH=LO:HI[:N]`` (--vary) or ``PATH=normal:MEAN:STD`` /
    ``PATH=uniform:LO:HI`` (--monte-carlo)."""
    path, sep, rest = text.partition("=")
    parts = rest.split(":")
    if not sep or not path.strip():
        raise ScenarioError(f"{option} {text!r}: give PATH=" + ("LO:HI[:N]" if option == "--vary" else "normal:MEAN:STD"))
    path = path.strip()
    if option == "--vary":
        if len(parts) not in (2, 3) or not all(p.strip() for p in parts):
            raise ScenarioError(f"--vary {text!r}: give PATH=LO:HI or PATH=LO:HI:N")
        spec = {"range": [_number(parts[0]), _number(parts[1])]}
        if len(parts) == 3:
            try:
                spec["points"] = int(parts[2])
            except ValueError:
                raise ScenarioError(f"--vary {text!r}: N = {parts[2]!r} is not a whole number") from None
        return path, spec
    if len(parts) != 3 or parts[0] not in ("normal", "uniform"):
        raise ScenarioError(f"--monte-carlo {text!r}: give PATH=normal:MEAN:STD or PATH=uniform:LO:HI")
    if parts[0] == "normal":
        return path, {"normal": {"mean": _number(parts[1]), "std": _number(parts[2])}}
    return path, {"uniform": [_number(parts[1]), _number(parts[2])]}


#: seconds of progress a run is timed over before it may say how long it will take ...
PACE_AFTER = 3.0


#: ... which it says when that is more than this [s]
LONG_RUN = 120.0

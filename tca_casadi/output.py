"""Where results are written, and how: the output stage.

* Every file is written **atomically**: to a temporary file in the same directory, flushed to
  disk, then renamed over the target (``os.replace``), so a process killed at any moment leaves
  either the previous complete file or the new complete one, never a truncated one.
* An output directory is **prepared before any computing**: created, checked to be a writable
  directory, and checked that none of the files about to be written is a directory. Files of an
  earlier run that this run will not write again (a ``robot.png`` when ``--no-plot`` is given) are
  removed, so that a directory never mixes results of two runs.
* The default directory is ``results/<scenario name>`` with the name reduced to a safe file name:
  a scenario file never chooses where files are written outside the output directory.
"""
import json
import os
import re
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .errors import OutputError
from .text import clip

#: characters kept in a directory name derived from a scenario name
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")


def safe_name(name, fallback="scenario"):
    """A file name made from ``name``: letters, digits, ``. _ -`` only, no leading dot, at most
    64 characters (``"../../x"`` -> ``"x"``, ``"/etc"`` -> ``"etc"``)."""
    text = _UNSAFE.sub("_", str(name)).strip("._-")[:64].strip("._-")
    return text or fallback


def default_directory(scenario_name, *parts):
    """``results/<safe scenario name>/<parts...>``."""
    return Path("results", safe_name(scenario_name), *parts)


def prepare_directory(directory, files=(), stale=()):
    """Create ``directory`` and check that ``files`` (names) can be written into it; remove the
    ``stale`` names (files of an earlier run that this run will not rewrite). Raises
    :class:`OutputError` (one line) before any computing is done."""
    directory = Path(directory)
    label = clip(directory)
    try:
        if directory.exists() and not directory.is_dir():
            raise OutputError(f"{label}: exists and is not a directory (give -o a directory)")
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=directory, prefix=".write-test-"):
            pass
    except OutputError:
        raise
    except (OSError, ValueError) as exc:    # permissions, a file in the path, NUL, too long
        raise OutputError(f"{label}: cannot write results there "
                          f"({getattr(exc, 'strerror', None) or exc})") from None
    for name in files:
        if (directory / name).is_dir():
            raise OutputError(f"{label}: {name} is a directory; cannot write the result file {name}")
    leftovers = [".write-test-*"] + [f".{Path(name).stem}.*{Path(name).suffix}" for name in files]
    for pattern in list(stale) + leftovers:     # and temporary files of a run that was killed
        for path in directory.glob(pattern):
            if path.is_file():
                path.unlink()
    return directory


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path`` (same suffix) to write to; on success it replaces
    ``path`` atomically, on failure it is removed."""
    path = Path(path)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(handle)
    try:
        yield Path(temporary)
        with open(temporary, "rb+") as stream:
            os.fsync(stream.fileno())
        os.replace(temporary, path)
    except BaseException:
        if os.path.exists(temporary):
            os.unlink(temporary)
        raise


def write_text(path, text):
    """Write ``text`` to ``path`` atomically; return ``path``."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path, data):
    """Write ``data`` as indented JSON atomically; return ``path``."""
    return write_text(path, json.dumps(data, indent=2))


def write_csv(path, header, rows, comments=()):
    """Write a CSV (``header`` list, ``rows`` of lists) atomically, after ``comments`` as ``#``
    lines; return ``path``."""
    import csv
    with atomic_path(path) as temporary, open(temporary, "w", newline="", encoding="utf-8") as handle:
        for line in comments:
            handle.write(f"# {line}\n")
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)
    return Path(path)


def save_figure(figure, path, **options):
    """``figure.savefig`` atomically (the format from the suffix); return ``path``."""
    path = Path(path)
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip(".") or None, **options)
    return path

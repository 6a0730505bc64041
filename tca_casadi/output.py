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
* A run's files are made visible **together** (:class:`ResultSet`): they are written into a
  hidden sibling directory, which is then exchanged with the output directory in one atomic
  step (Linux ``renameat2(RENAME_EXCHANGE)``; elsewhere two renames); what else the output
  directory held (other commands' results, subdirectories, your own files) is moved across. A
  run killed at any moment leaves the output directory with the previous run's complete set or
  the new run's complete set, never a mix; ``run_<command>.json`` says which run it is.
"""
import json
import os
import re
import shutil
import sys
import tempfile
import time
import uuid
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
    os.chmod(temporary, 0o666 & ~_umask())          # as an ordinary new file (mkstemp makes it private)
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


# ----------------------------------------------------------------------------- a run's file set
#: the hidden sibling directories of a run: ``.<output name>.tca-run-<id>``
RUN_PREFIX = ".tca-run-"
#: inside a swapped-out (old) directory: it is the old set, its other entries still to move back
SWAPPED = ".tca-swapped-out"


class ResultSet:
    """The files one run of ``command`` writes into ``directory``, made visible together.

    ``files``: the names (or glob patterns) this run may write; ``stale``: those of an earlier
    run's files that this run will not write again (``robot.png`` with ``--no-plot``): together
    the command's set; everything else the directory holds is kept. Use as a context manager: :meth:`prepare` on entry (checks, before any
    computing), write into :attr:`staging`, :meth:`commit` on a normal exit, :meth:`discard` on
    an exception (the output directory is then as it was). Where the directory cannot be
    swapped (it is the working directory or holds it, or its parent is not writable), the files
    are written in place, each atomically, and the old set's files removed first."""

    def __init__(self, directory, command, files, stale=(), argv=None, scenario=None):
        self.directory = Path(directory)
        self.command, self.files, self.stale = command, list(files), list(stale)
        self.owned = self.files + self.stale + [self.manifest_name]
        self.argv, self.scenario = argv, scenario
        self.run_id = uuid.uuid4().hex[:12]
        self.staging = None
        self.started = time.time()

    @property
    def manifest_name(self):
        return f"run_{self.command}.json"

    # ------------------------------------------------------------------ before
    def prepare(self):
        """Check that the output can be written (OutputError, one line, before any computing),
        finish or clean up what a killed run left, and make the staging directory; returns it."""
        directory, label = self.directory, clip(self.directory)
        try:
            if directory.exists() and not directory.is_dir():
                raise OutputError(f"{label}: exists and is not a directory (give -o a directory)")
            directory.parent.mkdir(parents=True, exist_ok=True)
            recover(directory)
        except OutputError:
            raise
        except (OSError, ValueError) as exc:        # permissions, a file in the path, NUL, too long
            raise OutputError(f"{label}: cannot write results there ({getattr(exc, 'strerror', None) or exc})") from None
        if self._swappable():
            try:
                self.staging = Path(tempfile.mkdtemp(dir=directory.parent, prefix=f".{directory.name}{RUN_PREFIX}"))
                mode = directory.stat().st_mode & 0o7777 if directory.exists() else 0o777 & ~_umask()
                os.chmod(self.staging, mode)             # the directory it replaces keeps its mode
            except (OSError, ValueError):
                self.staging = None
        try:
            if self.staging is None:                    # in place: the checks and removals as before
                self.staging = prepare_directory(directory, [n for n in self.files if not _is_pattern(n)], self.stale)
            elif directory.exists():
                _check_writable(directory)
            for name in self.owned:
                if not _is_pattern(name) and (directory / name).is_dir():
                    raise OutputError(f"{label}: {name} is a directory; cannot write the result file {name}")
        except OutputError:
            self.discard()
            raise
        return self.staging

    def _swappable(self):
        """True where the directory may be exchanged: not the working directory nor one holding
        it, not a mount point, in a writable parent."""
        try:
            here, target = Path.cwd().resolve(), self.directory.resolve()
            return target != here and target not in here.parents and os.access(target.parent, os.W_OK) \
                and not (target.exists() and os.path.ismount(target))
        except (OSError, ValueError):
            return False

    @property
    def in_place(self):
        return self.staging is not None and self.staging.resolve() == self.directory.resolve()

    # ------------------------------------------------------------------ after
    def commit(self):
        """Make this run's files the directory's result set (with ``run_<command>.json``)."""
        if self.in_place:
            written = sorted(self._old_set(self.staging) - {self.manifest_name})
        else:
            written = sorted(p.name for p in self.staging.iterdir() if not p.name.startswith("."))
        write_json(self.staging / self.manifest_name, self.manifest(written))
        if self.in_place:
            return
        if not self.directory.exists():
            os.rename(self.staging, self.directory)
            return
        old_set = sorted(self._old_set(self.directory))
        write_json(self.directory / SWAPPED, old_set)      # travels with the old directory
        old = self.staging
        try:
            _exchange(self.staging, self.directory)
        except OSError:
            os.unlink(self.directory / SWAPPED)
            raise
        _move_back(old, self.directory, set(old_set))
        shutil.rmtree(old, ignore_errors=True)

    def discard(self):
        """Forget this run's files (an exception ended it): the output directory is untouched."""
        if self.staging is not None and not self.in_place:
            shutil.rmtree(self.staging, ignore_errors=True)

    def manifest(self, files):
        from . import __version__
        return {"command": self.command, "run_id": self.run_id, "files": [f for f in files if f != self.manifest_name],
                "started": _stamp(self.started), "finished": _stamp(time.time()),
                "argv": self.argv if self.argv is not None else sys.argv[1:], "scenario": self.scenario,
                "tca_casadi": __version__}

    def final(self, paths):
        """``paths`` written into the staging directory, as they are named after the commit."""
        return [self.directory / Path(p).relative_to(self.staging) for p in paths]

    def _old_set(self, directory):
        """Names in ``directory`` that belong to this command's set (its owned names and
        patterns, and what its manifest lists)."""
        names = set()
        for pattern in self.owned:
            names |= {p.name for p in directory.glob(pattern)}
        try:
            listed = json.loads((directory / self.manifest_name).read_text())["files"]
            names |= {name for name in listed if isinstance(name, str) and (directory / name).exists()}
        except (OSError, ValueError, KeyError, TypeError):
            pass
        return names

    def __enter__(self):
        self.prepare()
        return self

    def __exit__(self, kind, error, trace):
        if kind is not None:
            self.discard()
            return False
        try:
            self.commit()
        except OSError as exc:
            self.discard()
            raise OutputError(f"{clip(self.directory)}: could not put the results in place "
                              f"({exc.strerror or exc})") from None
        return False


def _umask():
    """The process's umask (read from /proc where it can be, which changes nothing)."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _is_pattern(name):
    return any(ch in name for ch in "*?[")


def _stamp(seconds):
    return time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(seconds))


def _check_writable(directory):
    try:
        with tempfile.NamedTemporaryFile(dir=directory, prefix=".write-test-"):
            pass
    except (OSError, ValueError) as exc:
        raise OutputError(f"{clip(directory)}: cannot write results there "
                          f"({getattr(exc, 'strerror', None) or exc})") from None


def _exchange(a, b):
    """Swap the directories ``a`` and ``b`` atomically (``renameat2`` with ``RENAME_EXCHANGE``);
    where that is not available, ``b`` is renamed aside and ``a`` into its place."""
    import ctypes
    import errno
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        renameat2 = None
    if renameat2 is not None:
        at_fdcwd, rename_exchange = -100, 2
        if renameat2(at_fdcwd, os.fsencode(str(a)), at_fdcwd, os.fsencode(str(b)), rename_exchange) == 0:
            return
        if ctypes.get_errno() not in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()), str(b))
    aside = Path(f"{a}.aside")
    os.rename(b, aside)
    os.rename(a, b)
    os.rename(aside, a)


def _move_back(old, directory, owned):
    """Move every entry of the swapped-out ``old`` directory that is not in ``owned`` (the old
    result set) into ``directory``."""
    for entry in old.iterdir():
        if entry.name in owned or entry.name.startswith((SWAPPED, ".write-test-")):
            continue
        target = directory / entry.name
        if not target.exists():
            os.rename(entry, target)


def recover(directory):
    """Finish what a run killed during its commit left beside ``directory``: the swapped-out old
    directory's other entries are moved back, and staging directories of killed runs removed."""
    directory = Path(directory)
    stray = directory / SWAPPED
    if stray.exists():
        stray.unlink()
    for sibling in directory.parent.glob(f".{glob_escape(directory.name)}{RUN_PREFIX}*"):
        if not sibling.is_dir():
            continue
        if (sibling / SWAPPED).exists() and directory.is_dir():
            try:
                owned = set(json.loads((sibling / SWAPPED).read_text()))
            except (OSError, ValueError, TypeError):
                owned = set()
            _move_back(sibling, directory, owned)
        shutil.rmtree(sibling, ignore_errors=True)


def glob_escape(name):
    """``name`` with glob's special characters escaped."""
    return re.sub(r"([*?\[])", r"[\1]", name)

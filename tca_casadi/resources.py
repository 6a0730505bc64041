"""What a run needs of the machine: the memory available, sizes refused before a run starts,
and running out of memory turned into one line that says what was too big and what to change."""
import os
from contextlib import contextmanager

from .errors import ResourceError


def cache_root():
    """Where the project keeps what it computed once per machine (compiled Functions, unit
    conversions): ``$TCA_CASADI_CACHE`` or ``~/.cache/tca_casadi``."""
    from pathlib import Path
    return Path(os.environ.get("TCA_CASADI_CACHE") or Path.home() / ".cache" / "tca_casadi")


def available_memory():
    """Bytes of memory available to this process (Linux ``MemAvailable``, else the physical
    memory; at most what an address-space limit, ``ulimit -v``, leaves), or None when unknown."""
    found = None
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    found = int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    if found is None:
        try:
            found = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):
            pass
    limit = _address_space_left()
    if limit is not None:
        found = limit if found is None else min(found, limit)
    return found


def _address_space_left():
    """Bytes of address space this process may still map under ``RLIMIT_AS``, or None."""
    try:
        import resource
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft == resource.RLIM_INFINITY:
            return None
        with open("/proc/self/statm") as handle:
            used = int(handle.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        return max(soft - used, 0)
    except (ImportError, OSError, ValueError, IndexError):
        return None


def readable_bytes(count):
    """``1.5 GB``, ``320 MB``, ``12 kB``."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if count >= size:
            return f"{count / size:.3g} {unit}"
    return f"{int(count)} B"


def is_out_of_memory(error):
    """True for Python's MemoryError (numpy's ArrayMemoryError included) and for a C++
    ``std::bad_alloc`` that CasADi passes on as a RuntimeError."""
    return isinstance(error, MemoryError) or (isinstance(error, RuntimeError) and "bad_alloc" in str(error))


@contextmanager
def memory_guard(what, advice):
    """Run the block; if it runs out of memory, raise :class:`ResourceError` ``"out of memory
    while {what}; {advice}"`` instead (one line)."""
    try:
        yield
    except (MemoryError, RuntimeError) as error:
        if not is_out_of_memory(error):
            raise
        raise ResourceError(f"out of memory while {what} ({memory_limit()}); {advice}") from None


def memory_limit():
    """What memory this process may have, for messages: its address-space limit (``ulimit -v``)
    where one is set, else the memory available on the machine."""
    try:
        import resource
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft != resource.RLIM_INFINITY:
            return f"this process may use at most {readable_bytes(soft)}: ulimit -v"
    except (ImportError, OSError, ValueError):
        pass
    available = available_memory()
    return f"{readable_bytes(available)} available" if available else "memory unknown"

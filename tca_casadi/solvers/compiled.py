"""CasADi Functions compiled to machine code (``solver.jit: true``), kept on disk.

CasADi evaluates an expanded (SX) Function in its virtual machine; the same Function generated as
C and compiled (``gcc -O1``) evaluates about six times faster (the bending module's residual:
0.032 ms against 0.0055 ms). Compiling takes seconds (1.7 s for the bending module's residual,
10 s for the arm's), so each compiled Function is kept in a cache directory under the hash of its
serialized form: the same structure compiles once per machine. Only numeric evaluation uses the
compiled code; everything symbolic (sensitivities, IPOPT) keeps the original Function.
"""
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

from ..errors import TcaError

#: compiler flags: -O1 gives most of -O2's speed at a fraction of its compile time
FLAGS = ("-O1", "-shared", "-fPIC")
#: generated code larger than this [bytes] compiles at -O0 where :func:`compiled` is asked to:
#: the arm's Jacobian (4.7 MB of C) takes over 4 minutes at -O1 and 20 s at -O0 (and still
#: evaluates twice as fast as CasADi's virtual machine)
OPTIMISED_BYTES = 1_000_000


def cache_directory():
    """Where compiled Functions are kept: ``$TCA_CASADI_CACHE`` or ``~/.cache/tca_casadi``,
    in a ``jit`` subdirectory."""
    from ..resources import cache_root
    return cache_root() / "jit"


def compiler():
    """The C compiler to use (``$CC``, else ``gcc`` or ``cc`` on the PATH)."""
    for name in (os.environ.get("CC"), "gcc", "cc"):
        if name and shutil.which(name):
            return shutil.which(name)
    raise TcaError("solver.jit: true needs a C compiler (gcc or cc on the PATH, or $CC); set solver.jit: false")


def has_compiler():
    """Whether :func:`compiler` finds a C compiler (``solver.jit: auto`` compiles only then)."""
    try:
        return bool(compiler())
    except TcaError:
        return False


def compiled(function, directory=None, sources=(), defines=(), optimised_bytes=None):
    """``function`` (a CasADi Function) as compiled code: an external Function with the same
    inputs and outputs, loaded from the cache (compiled there first if missing); the arguments
    as :func:`compiled_library`'s."""
    library = compiled_library(function, directory, sources, defines, optimised_bytes)
    return ca.external(function.name(), str(library))


def compiled_library(function, directory=None, sources=(), defines=(), optimised_bytes=None):
    """The path of the cached library of ``function``, compiled there first if missing.
    ``sources``: paths of further C files compiled into the same library (e.g. :mod:`.native`'s
    chord steps), with the preprocessor ``defines`` (``"NAME=VALUE"``); ``optimised_bytes``:
    generated code larger than this compiles without optimisation (-O0)."""
    library = library_of(function, directory, sources, defines)
    if not library.exists():
        library.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=library.parent) as work:
            source = Path(work) / f"{function.name()}.c"
            generator = ca.CodeGenerator(source.name, {"with_header": False})
            generator.add(function)
            generator.generate(f"{work}{os.sep}")
            built = Path(work) / library.name
            # -Bsymbolic: the sources call this library's residual, never a same-named one loaded before
            linking = ("-Wl,-Bsymbolic",) if sources else ()
            flags = FLAGS
            if optimised_bytes is not None and source.stat().st_size > optimised_bytes:
                flags = ("-O0",) + FLAGS[1:]
            command = [compiler(), *flags, *linking, *(f"-D{d}" for d in defines), "-o", str(built), str(source),
                       *(str(s) for s in sources), "-lm"]
            result = subprocess.run(command, capture_output=True, text=True)
            if result.returncode != 0:
                raise TcaError(f"solver.jit: compiling {function.name()} failed: {result.stderr.strip()[:300]}")
            os.replace(built, library)           # atomic: a concurrent process sees all or nothing
    return library


def library_of(function, directory=None, sources=(), defines=()):
    """The cached library's path of :func:`compiled`'s arguments: named by a hash of the
    Function's serialized form, the extra sources' text and the defines."""
    directory = Path(directory or cache_directory())
    digest = hashlib.sha256(function.serialize().encode())
    for path in sources:
        digest.update(Path(path).read_bytes())
    for define in defines:
        digest.update(define.encode())
    return directory / f"{function.name()}_{digest.hexdigest()[:20]}.so"

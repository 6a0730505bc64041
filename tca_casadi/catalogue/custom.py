"""A user's own law from a Python entry point, declared: its types live in ``muscle_types`` with
``kind: custom`` (its ``parameters`` are NLP parameters), and loading the entry point into a
CasADi Function (:func:`residual_function`) is here, where the scenario's checks and the law
(:mod:`tca_casadi.model.laws.custom`) both find it; the entry point runs only when a scenario
that allows code is checked or built."""
import functools
import importlib
import math
import sys
from typing import Optional

from .base import Declaration


class Custom(Declaration):
    """A law from an entry point: ``entry_point: "module:function"`` builds the residual
    ``r(stroke, force, input, reference_length, **parameters)`` from CasADi symbols."""
    KIND = "custom"
    INPUT = ("input", "dimensionless", 0.0)
    OPTIONS = {"entry_point": (str, ...), "folder": (Optional[str], None), "parameters": (dict[str, float], {}),
               "scale": ("dimensionless", 1.0), "min_input": ("dimensionless", -math.inf),
               "max_input": ("dimensionless", math.inf)}
    RANGE_KEYS = ("min_input", "max_input")

    @classmethod
    def parameter_entries(cls, config):
        """``[(key, unit kind, value)]`` of the type's NLP parameters."""
        return [(f"parameters.{key}", "dimensionless", value) for key, value in config.parameters.items()]

    @classmethod
    def range_of(cls, config):
        return (config.min_input, config.max_input)

    @classmethod
    def code_problem(cls, config):
        try:
            residual_function(config.entry_point, tuple(config.parameters), config.folder)
        except EntryPointError as error:
            return str(error)
        return None

    @classmethod
    def validate_type(cls, config):
        if ":" not in config.entry_point:
            raise ValueError(f"entry_point {config.entry_point!r} must read 'module:function'")
        if not config.scale > 0:
            raise ValueError(f"scale {config.scale:g} must be positive")
        if not config.min_input < config.max_input:
            raise ValueError("need min_input < max_input")


def describe_entry_point(entry_point, folder=None):
    """What importing ``entry_point`` would run, found without running anything: ``"it would
    import module 'muscle_laws' (/path/muscle_laws.py) and call linear_muscle"``. A top-level
    module is located by ``importlib.util.find_spec`` (which executes nothing), else in
    ``folder``."""
    import importlib.util
    from pathlib import Path
    module_name, _, name = entry_point.partition(":")
    top = module_name.split(".")[0]
    where = None
    try:
        spec = importlib.util.find_spec(top) if top else None
        where = spec.origin if spec is not None else None
    except (ImportError, ValueError):
        pass
    if where is None and folder is not None:
        for candidate in (Path(folder) / f"{top}.py", Path(folder) / top / "__init__.py"):
            if candidate.is_file():
                where = str(candidate)
                break
    found = f" ({_shown(where)})" if where else " (not found on the Python path or beside the scenario)"
    return f"it would import module {module_name!r}{found} and call {name or '?'}"


def _shown(path):
    """A path relative to the working directory when it lies below it, else absolute."""
    import os
    here = os.getcwd()
    relative = os.path.relpath(path, here)
    return path if relative.startswith("..") or here == os.path.dirname(here) else relative


class EntryPointError(ValueError):
    """The entry point cannot be imported or does not build a scalar CasADi expression."""


@functools.lru_cache(maxsize=32)
def residual_function(entry_point, parameter_names, folder=None):
    """The CasADi Function ``(stroke, force, input, l*, *parameters) -> r`` of an entry point
    (``EntryPointError`` with a one-line reason when it cannot be made)."""
    import casadi as ca
    function = load_entry_point(entry_point, folder)
    symbols = [ca.SX.sym(name) for name in ("stroke", "force", "input", "reference_length")]
    values = {name: ca.SX.sym(name) for name in parameter_names}
    try:
        out = function(*symbols, **values)
    except Exception as error:           # the user's code: any failure is a bad entry point
        raise EntryPointError(f"{entry_point} failed when called with CasADi symbols: "
                              f"{type(error).__name__}: {error}") from None
    if isinstance(out, (int, float)):
        out = ca.SX(out)
    if not isinstance(out, (ca.SX, ca.MX, ca.DM)):
        raise EntryPointError(f"{entry_point} returned {type(out).__name__}, not a CasADi expression "
                              "(build it with casadi operations on the arguments)")
    if out.shape != (1, 1):
        raise EntryPointError(f"{entry_point} returned shape {out.shape}, expected a scalar (1, 1)")
    try:
        return ca.Function("custom_law", symbols + list(values.values()), [ca.SX(out)])
    except Exception as error:
        raise EntryPointError(f"{entry_point}: {error}".splitlines()[0]) from None


def load_entry_point(entry_point, folder=None):
    """The function ``module:function`` names, imported from the Python path or ``folder``."""
    module_name, _, name = entry_point.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if folder is None or error.name != module_name.split(".")[0]:
            raise EntryPointError(f"cannot import {module_name!r}: {error}") from None
        sys.path.insert(0, str(folder))
        try:
            module = importlib.import_module(module_name)
        except ImportError as inner:
            raise EntryPointError(f"cannot import {module_name!r} (looked on the Python path and in "
                                  f"{folder}): {inner}") from None
        finally:
            sys.path.remove(str(folder))
    except Exception as error:
        raise EntryPointError(f"cannot import {module_name!r}: {type(error).__name__}: {error}") from None
    function = getattr(module, name, None)
    if not callable(function):
        raise EntryPointError(f"module {module_name!r} has no function {name!r}")
    return function


DECLARATION = Custom

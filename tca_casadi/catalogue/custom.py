"""A user's own law from a Python entry point, declared: its types live in ``muscle_types`` with
``kind: custom`` (its ``parameters`` are NLP parameters); the law is
:mod:`tca_casadi.model.laws.custom`, which imports the entry point only when a robot is built."""
import math
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


DECLARATION = Custom

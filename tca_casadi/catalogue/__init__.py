"""The actuator-law catalogue: what each kind of actuator declares, and nothing else (no law
math, no CasADi). The scenario's schema and checks read it; each law in
:mod:`tca_casadi.model.laws` inherits its entry's declarations. The TCA is an entry like the
others (its types in ``tca_types``, the others' in ``muscle_types``).

A new muscle: its declarations here (a module defining ``DECLARATION``, a subclass of
:class:`~tca_casadi.catalogue.base.Declaration`), its law in :mod:`tca_casadi.model.laws` (a module
defining ``LAW``, a class inheriting that declaration).
"""
import functools
import importlib
import pkgutil

from .base import Declaration, Heated, LawParameter


@functools.lru_cache(maxsize=1)
def declarations():
    """``{kind: declaration}`` of every entry of the catalogue, in name order."""
    out = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        declaration = getattr(importlib.import_module(f"{__name__}.{info.name}"), "DECLARATION", None)
        if declaration is not None:
            out[declaration.KIND] = declaration
    return out


def muscle_declarations():
    """``{kind: declaration}`` of the entries whose types live in ``muscle_types``."""
    return {kind: d for kind, d in declarations().items() if d.TYPES_KEY == "muscle_types"}


def thermal_kinds():
    """Actuator kinds heated by a drive in ``simulate`` (``tca`` and the ``THERMAL`` muscles)."""
    return tuple(kind for kind, d in declarations().items() if d.THERMAL)


__all__ = ["Declaration", "Heated", "LawParameter", "declarations", "muscle_declarations", "thermal_kinds"]

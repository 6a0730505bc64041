"""Actuator laws behind one interface (:mod:`.base`): the TCA (:mod:`.tca`), the displacement
tendon (:mod:`.tendon`) and the muscles of ``muscle_types``: each file of this package that
defines ``LAW`` (:mod:`.sma`, :mod:`.mckibben`, :mod:`.custom`) is one muscle kind, found
here by :func:`muscles`; what each declares is its :mod:`tca_casadi.catalogue` entry's."""
import functools
import importlib
import pkgutil

from ...catalogue import thermal_kinds


@functools.lru_cache(maxsize=1)
def laws():
    """``{kind: law class}`` of every law file in this package defining ``LAW`` (the TCA's
    and the muscles'), in name order."""
    out = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        law = getattr(module, "LAW", None)
        if law is not None:
            out[law.KIND] = law
    return out


def muscles():
    """``{kind: law class}`` of the muscles of ``muscle_types`` (every law but the TCA's)."""
    return {kind: law for kind, law in laws().items() if law.TYPES_KEY == "muscle_types"}


def law_of(kind):
    """The law class of actuator ``kind`` (``tca`` or a muscle's)."""
    return laws()[kind]


def muscle_module(kind):
    """The module of the law of ``kind`` (for its ``thermal_law``, if it has one)."""
    return importlib.import_module(laws()[kind].__module__)


__all__ = ["laws", "muscles", "law_of", "muscle_module", "thermal_kinds"]

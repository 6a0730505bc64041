"""Actuator laws behind one interface (:mod:`.base`): the TCA (:mod:`.tca`), the displacement
tendon (:mod:`.tendon`) and the muscles of ``muscle_types``: each file of this package that
defines ``MUSCLE`` (:mod:`.sma`, :mod:`.mckibben`, :mod:`.custom`) is one muscle kind, found
here by :func:`muscles`; nothing else needs to know it exists."""
import functools
import importlib
import pkgutil


@functools.lru_cache(maxsize=1)
def muscles():
    """``{kind: law class}`` of every muscle file in this package, in name order."""
    out = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        module = importlib.import_module(f"{__name__}.{info.name}")
        law = getattr(module, "MUSCLE", None)
        if law is not None:
            out[law.KIND] = law
    return out


def muscle_module(kind):
    """The module of muscle ``kind`` (for its ``thermal_law``, if it has one)."""
    return importlib.import_module(muscles()[kind].__module__)


def thermal_kinds():
    """Actuator kinds heated by a drive in ``simulate``: ``tca`` and the ``THERMAL`` muscles."""
    return ("tca",) + tuple(kind for kind, law in muscles().items() if law.THERMAL)


__all__ = ["muscles", "muscle_module", "thermal_kinds"]

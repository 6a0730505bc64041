"""Names of a package imported on first use (PEP 562), so that importing the package is cheap."""
import importlib


def lazy_getattr(package, names):
    """A module ``__getattr__`` for ``package`` that imports ``names[name]`` (a relative module
    name) on first access of ``name`` and caches it in the package."""
    module = importlib.import_module(package)

    def __getattr__(name):
        if name in names:
            value = getattr(importlib.import_module(names[name], package), name)
            setattr(module, name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    return __getattr__

"""The physics, written once: rotations, sections, TCA law, routes, rod equations, the robot."""
from .._lazy import lazy_getattr

_LAZY = {"Robot": ".robot", "TcaLaw": ".laws.tca"}
__all__ = list(_LAZY)
__getattr__ = lazy_getattr(__name__, _LAZY)

"""The physics, written once: rotations, sections, TCA law, routes, rod equations, the robot."""
from .robot import Robot
from .tca_law import TcaLaw

__all__ = ["Robot", "TcaLaw"]

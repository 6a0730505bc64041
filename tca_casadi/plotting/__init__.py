"""Drawings (matplotlib is imported lazily, with the Agg backend when no display is set)."""
from .robot3d import draw_robot, save_robot_png

__all__ = ["draw_robot", "save_robot_png"]

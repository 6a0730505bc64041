"""Targets of inverse statics: a pose for a point of the robot, read from Python, the scenario or
a CSV path, and the layout of the target vector the inverse NLP takes as a parameter."""
from dataclasses import dataclass
from typing import Optional

import numpy as np

from ...errors import ScenarioError, flag


@dataclass
class Target:
    """A target pose [m]: ``position``; optionally ``direction`` (the point's tangent, unit) or
    ``orientation`` (quaternion [w, x, y, z] of the point's frame); ``point``: 'tip' or a module."""
    position: np.ndarray
    direction: Optional[np.ndarray] = None
    orientation: Optional[np.ndarray] = None
    point: str = "tip"

    @classmethod
    def create(cls, position, direction=None, orientation=None, point="tip"):
        """Validated target; :class:`ScenarioError` names what is wrong."""
        position = _finite_vector(position, 3, "target position")
        if direction is not None and orientation is not None:
            raise ScenarioError("give a target direction or a target orientation, not both")
        if direction is not None:
            direction = _unit(_finite_vector(direction, 3, "target direction"), "target direction")
        if orientation is not None:
            orientation = _unit(_finite_vector(orientation, 4, "target orientation"), "target orientation")
        return cls(position, direction, orientation, point)


def _finite_vector(value, size, what):
    try:
        array = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ScenarioError(f"{what}: expected {size} numbers, got {value!r}") from None
    if array.size != size:
        raise ScenarioError(f"{what}: expected {size} numbers, got {array.size}")
    if not np.all(np.isfinite(array)):
        raise ScenarioError(f"{what}: {array.tolist()} is not finite (NaN or inf)")
    return array


def _unit(vector, what):
    norm = np.linalg.norm(vector)
    if norm == 0:
        raise ScenarioError(f"{what} must not be zero")
    return vector / norm

class TargetLayout:
    """The inverse NLP's target parameter vector, written down once:
    ``[position (3), direction (3), R_target (9, column-major), weights (3: position, direction,
    rotation), select (n_modules: 1 for the module whose end is the target point)]``."""

    def __init__(self, n_modules):
        sizes = [("position", 3), ("direction", 3), ("rotation", 9), ("weights", 3), ("select", n_modules)]
        self.slices, start = {}, 0
        for name, size in sizes:
            self.slices[name] = slice(start, start + size)
            start += size
        self.size = start

    def unpack(self, vector):
        """``{name: part}`` of a vector (numbers or a CasADi symbol); ``rotation`` as 3 x 3."""
        import casadi as ca
        parts = {name: vector[part] for name, part in self.slices.items()}
        parts["rotation"] = ca.reshape(parts["rotation"], 3, 3)
        return parts

    def pack(self, position, direction, rotation, weights, select):
        out = np.zeros(self.size)
        for name, value in (("position", position), ("direction", direction),
                            ("rotation", np.asarray(rotation).ravel(order="F")), ("weights", weights),
                            ("select", select)):
            out[self.slices[name]] = value
        return out


def read_targets(path, point="tip"):
    """Targets from a CSV with columns x, y, z [m] and optionally dx, dy, dz (a direction) or
    qw, qx, qy, qz (an orientation); header names may carry units (``x [m]``). Read by
    :func:`tca_casadi.tables.read_table` (one-line errors for any bad file)."""
    from ...tables import name_of, read_table
    table = read_table(path, f"inverse {flag('--path')}", "targets file", required=("x", "y", "z"))
    columns = {name_of(name).lower(): k for k, name in enumerate(table.header)}
    targets = []
    for k in range(len(table.rows)):
        try:
            targets.append(Target.create(_take(table, k, columns, "xyz"), _take(table, k, columns, ("dx", "dy", "dz")),
                                         _take(table, k, columns, ("qw", "qx", "qy", "qz")), point))
        except ScenarioError as exc:
            message = str(exc)
            raise ScenarioError(message if message.startswith(f"inverse {flag('--path')}") else f"{table.where(k)}: {message}") from None
    if not targets:
        raise ScenarioError(f"inverse {flag('--path')}: {path}: no targets (a header x, y, z, then one row per target)")
    return targets


def _take(table, k, columns, keys):
    """The numbers of ``keys`` in row ``k`` of ``table``, or None when any is absent or empty."""
    if not all(key in columns and table.rows[k][columns[key]].strip() for key in keys):
        return None
    return [table.number(k, columns[key]) for key in keys]

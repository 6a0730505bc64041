"""Sequences (``tca-casadi sequence``): the scenario's steps solved one after the other
(:func:`run_sequence`, the result type :class:`SequenceResult`) and the objects the robot picks
and places along them (``objects``: :class:`ObjectTracker`)."""
from .objects import ObjectPose, ObjectTracker, object_poses
from .steps import SequenceResult, run_sequence

__all__ = ["run_sequence", "SequenceResult", "ObjectPose", "ObjectTracker", "object_poses"]

"""Objects a robot picks and places (``objects:`` in a scenario): where each one is at each step
of a sequence.

An object rests at its scenario pose until its ``held`` parameter is set. From then on it is
carried: it turns with the holders' common parent (the gripper's base frame) and its centre
keeps, in that frame, the offset it had from the grasp point (the mean of its holders' tips)
when it was picked, so that picking it moves it not at all. Picking is checked: the grasp point must lie
inside the object's box when the holders close on it. When ``held`` is cleared the object is put
down on its support plane (the height it rested at) below the grasp point, keeping only its
rotation about the vertical. Falling and contact forces are not simulated. A contact object
(``contact: true``, a free rigid body) is where its solution puts it (``solution.bodies``).
"""
from dataclasses import dataclass

import numpy as np

from ...errors import ScenarioError

#: margin [m] around an object's box within which a grasp point still counts as on the object
GRASP_MARGIN = 0.5e-3


@dataclass
class ObjectPose:
    """An object's box: ``center`` (3,) [m], ``rotation`` (3, 3) object-to-global, ``size``
    (3,) edge lengths [m], ``held``."""
    name: str
    size: np.ndarray
    center: np.ndarray
    rotation: np.ndarray
    held: bool

    def corners(self):
        """The 8 corners (3, 8) [m], global frame."""
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]).T
        return self.center[:, None] + self.rotation @ (signs * self.size[:, None] / 2)

    def edges(self):
        """The 12 edges as pairs of corner indices."""
        return [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]

    def contains(self, point, margin=GRASP_MARGIN):
        local = self.rotation.T @ (np.asarray(point) - self.center)
        return bool(np.all(np.abs(local) <= self.size / 2 + margin))


def _yaw_rotation(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class ObjectTracker:
    """Follows the scenario's objects through the solutions of a sequence (:meth:`advance`)."""

    def __init__(self, scenario, robot):
        index = {m.name: k for k, m in enumerate(scenario.modules)}
        self.robot = robot
        self.holders = {o.name: [index[h] for h in o.held_by] for o in scenario.objects}
        self.poses = {o.name: ObjectPose(o.name, np.array(o.size), np.array(o.position), _yaw_rotation(o.yaw), False)
                      for o in scenario.objects}
        self.support = {o.name: float(o.position[2]) for o in scenario.objects}
        #: contact objects (free rigid bodies): their pose is the solution's, not tracked here
        self.free = {o.name for o in scenario.objects if o.contact}
        self._relative = {}            # name -> object rotation in the carrier's tip frame
        self._offset = {}              # name -> its centre less the grasp point, in that frame, when picked

    @property
    def names(self):
        return list(self.poses)

    # ------------------------------------------------------------------ geometry of a solution
    def grasp_point(self, solution, name):
        """Mean of the holders' tip positions [m]."""
        return np.mean([solution.modules[m].tip_position for m in self.holders[name]], axis=0)

    def opening(self, solution, name):
        """Distance between the first two holders' tips [m] (None with a single holder)."""
        holders = self.holders[name]
        if len(holders) < 2:
            return None
        return float(np.linalg.norm(solution.modules[holders[0]].tip_position
                                    - solution.modules[holders[1]].tip_position))

    def carrier_rotation(self, solution, name):
        """Rotation of the frame a held object turns with: the holders' common parent's tip
        (the gripper base), else the first holder's tip."""
        parents = {self.robot.modules[m].parent for m in self.holders[name]}
        carrier = parents.pop() if len(parents) == 1 and None not in parents else self.holders[name][0]
        return solution.modules[carrier].tip_rotation

    def held_in(self, solution, name):
        """Whether ``solution``'s parameters hold the object (``NAME.held`` >= 1/2); a contact
        object: whether something grips it."""
        if name in self.free:
            return any(b.name == name and b.grip_force > 0 for b in solution.bodies)
        return bool(solution.parameters[solution.parameter_names[f"{name}.held"]][0] >= 0.5)

    def _solved_pose(self, solution, name):
        """A contact object's pose in ``solution`` (the solved free body)."""
        body = next((b for b in solution.bodies if b.name == name), None)
        if body is None:
            return self.poses[name]
        return ObjectPose(name, self.poses[name].size, body.position, body.rotation, body.grip_force > 0)

    # ------------------------------------------------------------------ stepping
    def poses_in(self, solution):
        """Poses drawn for ``solution`` with the current attachments (no state change): carried
        objects follow the grasp point, the others stay where they are."""
        out = {}
        for name, pose in self.poses.items():
            if name in self.free:
                out[name] = self._solved_pose(solution, name)
            elif pose.held:
                out[name] = self._carried(solution, name, pose)
            else:
                out[name] = pose
        return out

    def advance(self, solution, step_name):
        """Update every object after a step's ``solution``: pick (checked), carry, or put down.
        Raises ScenarioError when a step holds an object its holders do not close on."""
        for name, pose in list(self.poses.items()):
            if name in self.free:
                self.poses[name] = self._solved_pose(solution, name)
                continue
            holding = self.held_in(solution, name)
            grasp = self.grasp_point(solution, name)
            if holding and not pose.held:
                if not pose.contains(grasp):
                    local = pose.rotation.T @ (grasp - pose.center)
                    raise ScenarioError(
                        f"step {step_name!r}: holds {name!r} but the grasp point is "
                        f"{np.linalg.norm(local) * 1e3:.2f} mm from its centre, outside its "
                        f"{' x '.join(f'{e * 1e3:g}' for e in pose.size)} mm box (offset in the "
                        f"object's frame {np.round(local * 1e3, 2).tolist()} mm)")
                carrier = self.carrier_rotation(solution, name)
                self._relative[name] = carrier.T @ pose.rotation
                self._offset[name] = carrier.T @ (pose.center - grasp)
                pose = ObjectPose(name, pose.size, pose.center, pose.rotation, True)
            if holding:
                pose = self._carried(solution, name, pose)
            elif pose.held:                    # let go where the holders are now, on its support
                carried = self._carried(solution, name, pose)
                axis = carried.rotation[:, 0]
                yaw = np.arctan2(axis[1], axis[0])
                pose = ObjectPose(name, pose.size, np.array([carried.center[0], carried.center[1], self.support[name]]),
                                  _yaw_rotation(yaw), False)
            self.poses[name] = pose
        return dict(self.poses)

    def _carried(self, solution, name, pose):
        """The pose of a held object in ``solution``: turned with the carrier's frame, its
        centre at the grasp point plus the offset it was picked with."""
        carrier = self.carrier_rotation(solution, name)
        centre = self.grasp_point(solution, name) + carrier @ self._offset.get(name, np.zeros(3))
        return ObjectPose(name, pose.size, centre, carrier @ self._relative[name], True)

    def grip_angle(self, solution, name):
        """Angle [deg] between the holders' closing direction (tip to tip) and the object's
        long axis: 90 when the gripper pinches across the object."""
        holders = self.holders[name]
        if len(holders) < 2:
            return None
        across = solution.modules[holders[0]].tip_position - solution.modules[holders[1]].tip_position
        pose = self.poses[name]
        long_axis = pose.rotation[:, int(np.argmax(pose.size))]
        cosine = abs(across @ long_axis) / max(np.linalg.norm(across), 1e-15)
        return float(np.degrees(np.arccos(min(1.0, cosine))))


def object_poses(scenario, robot, solution):
    """The scenario's objects as drawn with one solution: picked up where its parameters hold
    them and the grasp closes on them, else resting where the scenario puts them."""
    from ...errors import ScenarioError
    tracker = ObjectTracker(scenario, robot)
    try:
        return list(tracker.advance(solution, "solve").values())
    except ScenarioError:
        return list(tracker.poses.values())

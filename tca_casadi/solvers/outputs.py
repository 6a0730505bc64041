"""What a solve keeps of its answer where it builds no :class:`~tca_casadi.solution.Solution`
(issue 36): a dynamic run's steps between its balance checks, a study's samples between its
checks. Read like a Solution by the tables, the energy account and the rows."""
import functools
from dataclasses import dataclass, field

import numpy as np

from ..model.rotations import rotation_numpy, rotations_of
from ..solution import ReadsItsStatus, TipOfModules, body_columns


@dataclass
class Centreline:
    """A module's centreline at a step's nodes, its tip appended: arc lengths ``s`` (n,) [m],
    positions ``p`` (3, n) [m], unit quaternions ``h`` (4, n), quadrature weights (n,) [m];
    the rotations ``R`` (3, 3, n) computed when first read."""
    s: np.ndarray
    p: np.ndarray
    h: np.ndarray
    weights: np.ndarray

    @functools.cached_property
    def R(self):
        return rotations_of(self.h)

    @property
    def tip_position(self):
        return self.p[:, -1]

    @property
    def tip_rotation(self):
        return self.R[:, :, -1] if "R" in self.__dict__ else rotation_numpy(self.h[:, -1])

    @property
    def base_rotation(self):
        return self.R[:, :, 0] if "R" in self.__dict__ else rotation_numpy(self.h[:, 0])


@dataclass
class ActuatorState:
    """An actuator's tension [N], length and stroke [m] at a step."""
    tension: float
    length: float
    stroke: float


@dataclass
class StepOutputs(TipOfModules, ReadsItsStatus):
    """What a dynamic run keeps of each step in place of its :class:`Solution` (built only when
    asked, issue 36): the robot parameters, per module its :class:`Centreline`, per actuator
    key its :class:`ActuatorState`, the point loads' markers (as ``Solution.loads``) and the
    index of the tip's module. Read like a Solution by the energy account, the tables and the
    objects' tracking."""
    parameters: np.ndarray
    modules: list
    actuators: dict
    loads: list
    tip_module: int
    converged: bool = True
    #: the parameters' slices by name (as a Solution's); the free bodies' BodyResult s (with
    #: free bodies: each step's, from its Solution)
    parameter_names: dict = field(default_factory=dict)
    bodies: list = field(default_factory=list)
    #: with obstacles: the normal force [N] and the gap [m] at each contact candidate
    #: (``robot.contacts``), and per obstacle the nearest approach over the nodes [m]
    contact_forces: np.ndarray = None
    contact_gaps: np.ndarray = None
    clearance: dict = field(default_factory=dict)
    obstacles: list = field(default_factory=list)
    #: with friction: the closed contacts (ContactResult s, as a Solution's)
    contacts: list = None
    #: with free bodies: the normal force [N] and the gap [m] of each grip candidate
    #: (``robot.grips``), and per body its pose, velocity [m/s] and body-frame angular velocity
    #: [rad/s] (12, bodies) (:meth:`DynamicSolver.body_values`)
    grip_forces: np.ndarray = None
    grip_gaps: np.ndarray = None
    body_motion: np.ndarray = None
    #: a study's sample: its solve's SolveStatus and the solver's variables (an Iterate: the
    #: next sample's warm start)
    result: object = None
    iterate: object = None
    #: no global balance is computed here (a Solution's is)
    balance = None

    def contact_columns(self):
        """Per obstacle ``{"NAME.normal_force [N]", "NAME.clearance [m]"}`` (as a Solution's;
        the clearance here is the nearest node's, not searched between nodes); per free body its
        :func:`~tca_casadi.solution.body_columns` and velocity ``NAME.vx|vy|vz [m/s]``."""
        out = {}
        for k, name in enumerate(self.clearance):
            out[f"{name}.normal_force [N]"] = float(sum(f for f, c in zip(self.contact_forces, self.obstacles) if c == k))
            out[f"{name}.clearance [m]"] = self.clearance[name]
        out.update(body_columns(self.bodies))
        for body, motion in zip(self.bodies, () if self.body_motion is None else self.body_motion.T):
            out.update({f"{body.name}.v{axis} [m/s]": float(v) for axis, v in zip("xyz", motion[6:9])})
        return out

    def body_velocity(self, k=0):
        """The velocity [m/s] (3,) of free body ``k`` (``robot.bodies`` order)."""
        return self.body_motion[6:9, k]

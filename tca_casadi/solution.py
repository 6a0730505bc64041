"""The result of a solve: status, per-module arrays, tip pose, actuator table; JSON/NPZ export.

Arrays are shaped ``(3, n)`` (rotations ``(3, 3, n)``), SI units, global frame unless named
``*_body``. The JSON keys follow SPEC section 8.
"""
import functools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Optional

import numpy as np

from .results import ResultAPI
from .errors import SolverError
from .model.rotations import matrix_to_quaternion
from .status import SolveStatus
from .text import signed, unit_text


@dataclass
class ModuleResult:
    """Arrays of one module at its nodes (arc lengths ``s`` nondecreasing; a breakpoint where the
    strain jumps appears twice)."""
    name: str
    s: np.ndarray             # (n,) [m]
    p: np.ndarray             # (3, n) [m]
    h: np.ndarray             # (4, n) non-unit quaternion
    R: np.ndarray             # (3, 3, n)
    u: np.ndarray             # (3, n) [1/m] body frame
    v: np.ndarray             # (3, n) [-] body frame
    force: np.ndarray         # (3, n) [N] internal force, global frame
    moment: np.ndarray        # (3, n) [N m] internal moment, global frame
    base_reaction: dict       # {'force': (3,), 'moment': (3,)} on the module's base, global frame
    outline: np.ndarray = None  # (3, k) body-frame outline of the body's cross-section [m]
    weights: np.ndarray = None  # (n,) [m] quadrature weights of the solver: integral f ds = weights @ f

    @property
    def tip_position(self):
        return self.p[:, -1]

    @property
    def tip_rotation(self):
        return self.R[:, :, -1]

    @property
    def base_rotation(self):
        return self.R[:, :, 0]


@dataclass
class ActuatorResult:
    """One actuator's table row (SI, temperature degC) and its path (3, n) in the global frame
    (``path_of``: the path, or a function of nothing that makes it, called when ``path`` is first
    read: most solves never draw it)."""
    key: str
    kind: str
    temperature: Optional[float]
    reference_temperature: Optional[float]
    tension: float
    length: float
    reference_length: float
    free_stroke: Optional[float]
    path_of: object = field(repr=False, compare=False)
    control: str = "temperature"          # temperature (TCA) | tension | displacement (tendon)
    tension_only: bool = False
    displacement: Optional[float] = None  # q [m], displacement-controlled tendons
    slack_length: Optional[float] = None  # [m] tension_only actuators (0 when taut)
    pressure: Optional[float] = None      # [Pa] McKibben muscles
    input: Optional[float] = None         # a custom law's input (SI)
    heated: bool = False                  # its law calls the input active (heated, pressurised)
    at_corner: bool = False               # tension_only, taut with no tension (see assemble.CORNER)

    @functools.cached_property
    def path(self):
        """The path (3, n) [m] through the actuator's span in the global frame."""
        return self.path_of() if callable(self.path_of) else self.path_of

    @property
    def stroke(self):
        return self.length - self.reference_length

    @property
    def slack(self):
        return bool(self.slack_length)

    def as_dict(self):
        return {"kind": self.kind, "control": self.control, "temperature": self.temperature,
                "displacement": self.displacement, "pressure": self.pressure, "input": self.input,
                "tension": self.tension,
                "length": self.length, "reference_length": self.reference_length,
                "stroke": self.stroke, "free_stroke": self.free_stroke,
                "tension_only": self.tension_only, "slack_length": self.slack_length}


#: a grip whose rod point moved more than this over its body during a solve slid [m] (a
#: sticking grip's point creeps by ~1e-8 m over a continuation as the contact normal turns)
SLID = 1e-6


@dataclass
class ContactResult:
    """One closed contact (a candidate whose normal force is not zero; issue 17): where, the
    obstacle's outward normal, the forces [N] and the gap [m] (global frame, SI). Frictionless
    contacts carry no tangential force; ``friction_margin = friction f_n - |f_t|`` [N];
    ``sliding``: on Coulomb's cone, sliding over the body or obstacle (``contact.friction_law:
    coulomb``), ``slip`` [m] how far over the last step; ``slid`` [m] (grips) how far its rod
    point moved over the body since the state the solve started from (Coulomb: the grasp slid)."""
    module: str
    s: float
    obstacle: str
    position: np.ndarray      # (3,) the outline point in contact
    normal: np.ndarray        # (3,) the obstacle's outward normal (the force on the rod is along it)
    normal_force: float
    tangential_force: np.ndarray
    gap: float
    friction: float
    sliding: bool = False
    slip: float = 0.0
    slid: float = 0.0
    #: (3,) [m] the rod's material point the friction force acts at (anchored where the contact
    #: touched at the solve's start: :mod:`~tca_casadi.model.history`); None: ``position``
    held_at: Optional[np.ndarray] = None
    #: (3,) [m] the point of the body or obstacle the friction history anchors it to (where
    #: ``held_at`` was at the solve's start, carried with the body); None: no friction history.
    #: ``held_at - anchored_at`` is its slip over the solve (a time step)
    anchored_at: Optional[np.ndarray] = None

    @property
    def force(self):
        """The total force on the rod (3,) [N]."""
        return self.normal_force * self.normal + self.tangential_force

    @property
    def friction_margin(self):
        from .model.friction import cone_margin
        return cone_margin(self.friction, self.normal_force, self.tangential_force)

    @property
    def needed_friction(self):
        """``|f_t| / f_n``: the friction this contact needs to stick."""
        return float(np.linalg.norm(self.tangential_force) / self.normal_force) if self.normal_force > 0 else 0.0

    @property
    def slipping(self):
        """It needs more friction than it has (sticking), or it slides or slid (Coulomb)."""
        return self.sliding or self.slid > SLID or self.friction_margin < 0

    def as_dict(self):
        return {"module": self.module, "s": self.s, "obstacle": self.obstacle,
                "position": np.asarray(self.position).tolist(), "normal": np.asarray(self.normal).tolist(),
                "normal_force": self.normal_force, "tangential_force": np.asarray(self.tangential_force).tolist(),
                "gap": self.gap, "friction": self.friction, "friction_margin": self.friction_margin,
                "needed_friction": self.needed_friction, "slipping": self.slipping, "sliding": self.sliding,
                "slip": self.slip, "slid": self.slid,
                "held_at": None if self.held_at is None else np.asarray(self.held_at).tolist()}


#: a contact object's table columns (:meth:`Solution.contact_columns`), in order
BODY_COLUMNS = ("grip_force [N]", "friction_margin [N]", "support_force [N]", "x [m]", "y [m]", "z [m]")


def body_columns(bodies):
    """Per free body (its :class:`BodyResult`) the table columns of :data:`BODY_COLUMNS`, named
    ``NAME.COLUMN``: what holds it and how high it is."""
    out = {}
    for body in bodies:
        values = (body.grip_force, body.friction_margin, float(np.linalg.norm(body.support_force)),
                  *(float(x) for x in body.position))
        out.update({f"{body.name}.{key}": value for key, value in zip(BODY_COLUMNS, values)})
    return out


@dataclass
class SupportCorners:
    """A body's eight corners against its support (global frame, SI): ``positions`` (8, 3),
    ``normal_forces`` (8,) and ``tangential_forces`` (8, 3) on the body, ``gaps`` (8,) to the
    plane, ``sliding`` (8,) on Coulomb's cone; ``normal`` (3,) the plane's outward normal."""
    positions: np.ndarray
    normal_forces: np.ndarray
    tangential_forces: np.ndarray
    gaps: np.ndarray
    sliding: np.ndarray
    normal: np.ndarray
    force_scale: float

    @property
    def pressed(self):
        """(8,) bool: the corners the support pushes on."""
        from .model.contact import CLOSED
        return self.normal_forces > CLOSED * self.force_scale

    @property
    def forces(self):
        """(8, 3) the support's force on the body at each corner [N]."""
        return self.normal_forces[:, None] * self.normal[None, :] + self.tangential_forces

    @property
    def centre_of_pressure(self):
        """Where the support's normal force acts (3,) [m] (the corners' mean when it carries none)."""
        total = float(self.normal_forces.sum())
        if total <= 0:
            return self.positions.mean(axis=0)
        return (self.normal_forces[:, None] * self.positions).sum(axis=0) / total

    def needed_friction(self):
        """The friction the support's resultant needs to hold the body without sliding,
        ``|F_t| / F_n`` (0 when it carries nothing)."""
        total = float(self.normal_forces.sum())
        return float(np.linalg.norm(self.tangential_forces.sum(axis=0))) / total if total > 0 else 0.0

    def as_list(self):
        """The pressed corners, as JSON: position, normal and tangential force, gap, sliding."""
        return [{"corner": j, "position": self.positions[j].tolist(), "normal_force": float(self.normal_forces[j]),
                 "tangential_force": self.tangential_forces[j].tolist(), "gap": float(self.gaps[j]),
                 "sliding": bool(self.sliding[j])} for j in np.flatnonzero(self.pressed)]


@dataclass
class BodyResult:
    """A free rigid body at equilibrium (a contact object, issue 17): its pose, what the rods'
    contacts put on it (``contact_force`` [N], ``contact_moment`` about its centre [N m]), its
    support's reaction (the sum of its corners' forces ``support_force``, acting at the centre
    of pressure ``support_point`` with the couple ``support_moment``; per corner ``corners``), its
    ``weight`` and the residual of its equilibrium (all global frame, SI). ``grip_force`` [N]:
    the sum of its closed grips' normal forces; ``friction_margin`` [N]: the smallest of theirs;
    ``slipping``: some grip needs more friction than the body has, or slides;
    ``support_slipping``: the support needs more friction than it has, or a corner slides."""
    name: str
    position: np.ndarray
    rotation: np.ndarray
    grips: list                       # ContactResult of its closed grips
    contact_force: np.ndarray
    contact_moment: np.ndarray
    weight: np.ndarray
    support_force: np.ndarray
    support_moment: np.ndarray
    support_point: np.ndarray
    support_gap: float
    support_friction: float
    residual_force: np.ndarray
    residual_moment: np.ndarray
    corners: Optional[SupportCorners] = None

    @classmethod
    def of(cls, body, r, R, weight, forces, grips, corners, inertial=None):
        """From the pose ``(r, R)``, ``weight`` (3,), the rods' ``forces`` ``[(point, force on the
        rod)]``, the closed ``grips``, the support's :class:`SupportCorners` (or None) and, in
        dynamics, the body's d'Alembert force and moment ``inertial`` (in the residual)."""
        from .model.bodies import body_equilibrium
        r, R, weight = np.asarray(r, float).ravel(), np.asarray(R, float), np.asarray(weight, float).ravel()
        forces = [(np.asarray(point, float).ravel(), np.asarray(on_rod, float).ravel()) for point, on_rod in forces]
        zero = np.zeros(3)
        force, moment = body_equilibrium(r, zero, forces)            # what the grips put on it
        support = [] if corners is None else list(zip(corners.positions, corners.forces))
        residual_force, residual_moment = body_equilibrium(r, weight, forces, support, inertial)
        if corners is None:
            return cls(body.name, r, R, grips, force, moment, weight, zero, zero, r, np.inf, 0.0, residual_force,
                       residual_moment)
        point = corners.centre_of_pressure
        reaction, couple = body_equilibrium(point, zero, [], support)
        return cls(body.name, r, R, grips, force, moment, weight, reaction, couple, point,
                   float(corners.gaps.min()), body.support_friction, residual_force, residual_moment, corners)

    @property
    def grip_force(self):
        return float(sum(c.normal_force for c in self.grips))

    @property
    def friction_margin(self):
        """The smallest friction margin of its grips [N] (NaN when nothing grips it)."""
        return float(min(c.friction_margin for c in self.grips)) if self.grips else float("nan")

    @property
    def needed_friction(self):
        return float(max(c.needed_friction for c in self.grips)) if self.grips else 0.0

    @property
    def slipping(self):
        return any(c.slipping for c in self.grips)

    @property
    def support_needed_friction(self):
        """The friction its support needs to hold it (:meth:`SupportCorners.needed_friction`)."""
        return self.corners.needed_friction() if self.corners is not None else 0.0

    @property
    def support_slipping(self):
        """It slides on its support: a pressed corner slides, or (sticking) the support needs
        more friction than it has."""
        if self.corners is None or not self.resting:
            return False
        return bool(np.any(self.corners.sliding & self.corners.pressed)) or \
            self.support_needed_friction > self.support_friction

    @property
    def resting(self):
        """True while its support pushes on it."""
        return bool(np.linalg.norm(self.support_force) > 1e-6 * max(np.linalg.norm(self.weight), 1e-300))

    def as_dict(self):
        from .model.rotations import matrix_to_quaternion
        return {"name": self.name, "position": self.position.tolist(),
                "quaternion": np.asarray(matrix_to_quaternion(self.rotation), float).ravel().tolist(),
                "rotation": self.rotation.tolist(), "grip_force": self.grip_force,
                "friction_margin": self.friction_margin, "needed_friction": self.needed_friction,
                "slipping": self.slipping, "resting": self.resting,
                "contact_force": self.contact_force.tolist(), "contact_moment": self.contact_moment.tolist(),
                "weight": self.weight.tolist(), "support_force": self.support_force.tolist(),
                "support_moment": self.support_moment.tolist(), "support_point": self.support_point.tolist(),
                "support_gap": self.support_gap, "support_friction": self.support_friction,
                "support_needed_friction": self.support_needed_friction, "support_slipping": self.support_slipping,
                "support_corners": self.corners.as_list() if self.corners is not None else [],
                "residual_force": self.residual_force.tolist(), "residual_moment": self.residual_moment.tolist()}


class ReadsItsStatus:
    """``status``, ``message``, ``max_residual``, ``iterations`` and the timings of a result
    read from its ``result`` (:class:`~tca_casadi.status.SolveStatus`)."""

    @property
    def status(self):
        """The integer :class:`~tca_casadi.status.Status`."""
        return self.result.status

    @property
    def message(self):
        return self.result.message

    @property
    def max_residual(self):
        return self.result.residual

    @property
    def iterations(self):
        return self.result.nit

    @property
    def solve_time_s(self):
        return self.result.solve_time_s

    @property
    def build_time_s(self):
        return self.result.build_time_s


class TipOfModules:
    """The tip of a result with ``modules`` (each with ``tip_position`` and ``tip_rotation``)
    and the index ``tip_module`` of the tip's module."""

    @property
    def tip_position(self):
        return self.modules[self.tip_module].tip_position

    @property
    def tip_rotation(self):
        return self.modules[self.tip_module].tip_rotation


@dataclass(frozen=True, repr=False)
class Iterate:
    """A solver's own variables at a Solution: studies and the time simulation hand it back to
    the solver's methods (warm starts, linearisations, continuation) and never interpret it.

    Attributes
    ----------
    method : str
        The solver that made it (``collocation``, ``shooting``, ``collocation-dynamics``).
    w : ndarray or None
        The collocation NLP's scaled variables (n,), or None (shooting).
    z : ndarray or None
        The shooting unknowns, or None (collocation).
    contact : ndarray
        The contact block in physical units (both solvers: the other's warm start).
    """
    method: str = ""
    w: Optional[np.ndarray] = None
    z: Optional[np.ndarray] = None
    contact: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def values(self):
        """The solver's vector: ``w`` (collocation) or ``z`` (shooting); None if neither."""
        return self.w if self.w is not None else self.z

    def fits(self, method, size):
        """Whether a solver of ``method`` with ``size`` variables can start from it."""
        return self.method == method and self.w is not None and self.w.size == size


@dataclass(repr=False)
class Solution(TipOfModules, ReadsItsStatus, ResultAPI):
    """An equilibrium (or a failed attempt: ``converged`` is False, never hidden).

    ``result`` (:class:`~tca_casadi.status.SolveStatus`) says how the solve ended; ``converged``,
    ``status``, ``message``, ``max_residual``, ``iterations`` and the timings read it.
    ``warnings`` are :class:`~tca_casadi.errors.PhysicsWarning` objects."""
    result: SolveStatus
    method: str
    modules: list
    actuators: dict
    warnings: list = field(default_factory=list)
    parameters: Optional[np.ndarray] = None
    parameter_names: Optional[dict] = None
    iterate: Iterate = field(default_factory=Iterate, repr=False)   # the solver's variables
    scenario_name: str = ""
    tip_module: int = -1      # index of the module whose tip is "the tip" (Robot.tip_index)
    balance: Optional[object] = None   # model.balance.GlobalBalance of the whole robot
    loads: list = field(default_factory=list)   # point loads and masses: {name, kind, position, force}
    accuracy: Optional[object] = None  # solvers.accuracy.AccuracyEstimate (cold collocation solves)
    contacts: list = field(default_factory=list)   # ContactResult of every closed contact
    #: per obstacle, the body's nearest approach on a fine sampling: {name: {gap, module, s}}
    clearance: dict = field(default_factory=dict)
    obstacles: list = field(default_factory=list)  # the fixed shapes (model.obstacles), for drawings
    #: per contact candidate, True on the closed side of its complementarity's corner
    contact_pattern: tuple = ()
    bodies: list = field(default_factory=list)     # BodyResult of every free body (contact objects)

    # ------------------------------------------------------------------ status
    @property
    def converged(self):
        return self.result.success

    def figure(self):
        """``robot.png``'s figure: the robot drawn in 3D."""
        from .plotting import save_robot_png
        return save_robot_png(self, None)

    def warning_texts(self, kind=None):
        """The warnings' texts (of one ``kind`` if given)."""
        return [str(w) for w in self.warnings if kind is None or w.kind == kind]

    # ------------------------------------------------------------------ tip
    @property
    def tip_quaternion(self):
        return matrix_to_quaternion(self.tip_rotation)

    @property
    def tensions(self):
        """``{MODULE.ACTUATOR: tension [N]}``."""
        return {key: a.tension for key, a in self.actuators.items()}

    def contact_columns(self):
        """Per obstacle, table columns ``{"NAME.normal_force [N]": total normal force on it,
        "NAME.clearance [m]": the body's nearest approach}`` (sweep and sequence tables)."""
        out = {}
        for name, nearest in self.clearance.items():
            out[f"{name}.normal_force [N]"] = sum(c.normal_force for c in self.contacts if c.obstacle == name)
            out[f"{name}.clearance [m]"] = nearest["gap"]
        out.update(body_columns(self.bodies))
        return out

    @property
    def penetration(self):
        """How deep [m] the body cuts into any obstacle (0 when clear), on a fine sampling."""
        gaps = [c["gap"] for c in self.clearance.values()]
        return float(max(0.0, -min(gaps))) if gaps else 0.0

    def raise_if_failed(self):
        """Raise :class:`SolverError` (keeping this solution) unless converged."""
        if not self.converged:
            raise SolverError(f"{self.method} did not converge: {self.message}", self)
        return self

    # ------------------------------------------------------------------ export
    def to_dict(self):
        """JSON-ready dict with the keys of SPEC section 8 (SI units)."""
        return {
            "scenario": self.scenario_name,
            "converged": bool(self.converged),
            "status": int(self.status),
            "message": self.message,
            "result": self.result.as_dict(),
            "method": self.method,
            "max_residual": float(self.max_residual),
            "iterations": int(self.iterations),
            "solve_time_s": float(self.solve_time_s),
            "build_time_s": float(self.build_time_s),
            "tip": _pose(self.tip_position, self.tip_rotation),
            "modules": {m.name: {"tip": _pose(m.tip_position, m.tip_rotation),
                                 "base_reaction": _listify(m.base_reaction)} for m in self.modules},
            "actuators": {key: a.as_dict() for key, a in self.actuators.items()},
            "parameters": ({name: np.atleast_1d(self.parameters[sl]).tolist()
                            for name, sl in self.parameter_names.items()}
                           if self.parameter_names is not None else {}),
            "global_balance": self.balance.as_dict() if self.balance is not None else None,
            "accuracy": self.accuracy.as_dict() if self.accuracy is not None else None,
            "contacts": [c.as_dict() for c in self.contacts],
            "clearance": self.clearance,
            "penetration": self.penetration,
            "objects": [b.as_dict() for b in self.bodies],
            "warnings": self.warning_texts(),
            "warning_kinds": [w.kind for w in self.warnings],
        }

    def save(self, directory):
        """Write ``solution.json`` and ``arrays.npz`` into ``directory``; return their paths."""
        from .output import atomic_path, write_json
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        json_path = write_json(directory / "solution.json", self.to_dict())
        npz_path = directory / "arrays.npz"
        with atomic_path(npz_path) as temporary, open(temporary, "wb") as stream:
            np.savez(stream, **self.arrays())
        return json_path, npz_path

    def arrays(self):
        """Flat ``{name: array}``: ``MODULE/s``, ``MODULE/p``, ... and ``ACTUATOR/path``."""
        out = {}
        for m in self.modules:
            for name in ("s", "p", "h", "R", "u", "v", "force", "moment"):
                out[f"{m.name}/{name}"] = getattr(m, name)
        for key, a in self.actuators.items():
            out[f"{key}/path"] = a.path
        return out

    def summary(self):
        """A few lines for the terminal."""
        state = "converged" if self.converged else "NOT CONVERGED"
        tip = self.tip_position * 1e3
        lines = [f"{self.scenario_name}: {state} ({self.method}, {self.result.algorithm}, {self.iterations} iterations, "
                 f"residual {self.max_residual:.1e}, solve {self.solve_time_s * 1e3:.1f} ms, "
                 f"build {self.build_time_s * 1e3:.0f} ms)",
                 f"  tip position [mm]: {signed(tip[0])} {signed(tip[1])} {signed(tip[2])}",
                 f"  {'actuator':<22}{'T [degC]':>9}{'q [mm]':>8}{'F [mN]':>11}{'stroke [mm]':>13}"
                 f"{'free [mm]':>11}{'slack [mm]':>12}"]
        extra = [(name, label, scale) for name, label, scale in
                 (("pressure", "P [kPa]", 1e-3), ("input", "input", 1.0))
                 if any(getattr(a, name) is not None for a in self.actuators.values())]
        lines[-1] += "".join(f"{label:>11}" for _, label, _ in extra)
        for key, a in self.actuators.items():
            temp = f"{a.temperature:9.1f}" if a.temperature is not None else f"{'-':>9}"
            pull = f"{a.displacement * 1e3:8.3f}" if a.displacement is not None else f"{'-':>8}"
            free = f"{a.free_stroke * 1e3:11.4f}" if a.free_stroke is not None else f"{'-':>11}"
            slack = f"{a.slack_length * 1e3:12.4f}" if a.slack_length is not None else f"{'-':>12}"
            more = "".join(f"{getattr(a, name) * scale:11.5g}" if getattr(a, name) is not None else f"{'-':>11}"
                           for name, _, scale in extra)
            lines.append(f"  {key:<22}{temp}{pull}{a.tension * 1e3:11.4f}{a.stroke * 1e3:13.4f}{free}{slack}{more}")
        if self.clearance:
            lines.append(f"  {'contact':<22}{'s [mm]':>9}{'f_n [mN]':>11}{'|f_t| [mN]':>11}{'gap [' + unit_text('um') + ']':>10}"
                         "  position [mm]")
            for c in self.contacts:
                where = " ".join(signed(x * 1e3) for x in c.position)
                state = " SLIDING" if c.sliding else (" SLIPPING" if c.slipping else "")
                lines.append(f"  {c.module + ' / ' + c.obstacle:<22}{c.s * 1e3:9.3f}{c.normal_force * 1e3:11.4f}"
                             f"{np.linalg.norm(c.tangential_force) * 1e3:11.4f}{c.gap * 1e6:10.4f}  {where}{state}")
            if not self.contacts:
                nearest = min(self.clearance.items(), key=lambda item: item[1]["gap"])
                lines.append(f"  no contact; nearest obstacle {nearest[0]!r} {nearest[1]['gap'] * 1e3:.4g} mm away")
        for body in self.bodies:          # contact objects: where they are, what holds them
            at = " ".join(signed(x * 1e3) for x in body.position)
            held = (f"grip {body.grip_force * 1e3:.4g} mN, needs friction {body.needed_friction:.3g} of "
                    f"{body.grips[0].friction:.3g}{', SLIPPING' if body.slipping else ''}" if body.grips else "not gripped")
            rests = f"; its support carries {np.linalg.norm(body.support_force) * 1e3:.4g} mN" if body.resting else ""
            lines.append(f"  object {body.name} at [{at}] mm: {held}{rests}")
        lines += [f"  warning: {w}" for w in self.warnings]
        if not self.converged and not self.warning_texts("not_converged"):
            lines.append(f"  message: {self.message}")
        return "\n".join(lines)


def _pose(position, rotation):
    return {"position": np.asarray(position).tolist(),
            "quaternion": matrix_to_quaternion(rotation).tolist(),
            "rotation_matrix": np.asarray(rotation).tolist()}


def _listify(d):
    return {k: np.asarray(v).tolist() for k, v in d.items()}

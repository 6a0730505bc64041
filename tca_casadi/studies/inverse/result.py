"""The answer of inverse statics and its files (``inverse.json``, the forward solution,
``inverse.png``; ``inverse_path.csv`` for a path of targets)."""
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ...text import signed
from ...results import ResultAPI
from ...status import Status

#: what an iteration is, per method
ITERATIONS = {"reduced": "least-squares iterations", "ipopt": "IPOPT iterations"}
from .targets import Target


@dataclass(repr=False)
class InverseResult(ResultAPI):
    """The answer to one query (SI, temperatures degC). ``temperatures`` holds every varied
    input (TCA and SMA temperatures, McKibben pressures...), each in its ``units`` entry."""
    target: Target
    temperatures: dict                 # {path: value}: the varied inputs
    position: np.ndarray               # achieved position of the target point [m]
    rotation: np.ndarray               # achieved frame (3, 3)
    position_error: float              # [m]
    angle_error: Optional[float]       # [rad] (direction or orientation), None if not asked
    reachable: bool
    converged: bool
    objective: float
    forward: object                    # Solution at the temperatures (independent forward solve)
    verification_difference: float     # |forward point - reported point| [m]
    solve_time_s: float
    iterations: int
    starts: int
    message: str
    w: np.ndarray = field(repr=False, default=None)
    tau: np.ndarray = field(repr=False, default=None)
    method: str = "reduced"            # 'reduced' (least squares) or 'ipopt' (full space)
    result: Optional[object] = None    # SolveStatus of the optimisation that gave the answer
    units: dict = field(default_factory=dict)   # {path: unit} of the inputs (default degC)
    #: the inputs' StudyParameters, which say the unit each is shown in (the one its bounds were given in)
    parameters: list = field(default_factory=list)

    @property
    def verified(self):
        return self.verification_difference <= 1e-6

    def to_dict(self):
        angle = None if self.angle_error is None else float(np.degrees(self.angle_error))
        return {"reachable": bool(self.reachable), "converged": bool(self.converged),
                "message": self.message,
                "target": {"position": self.target.position.tolist(), "point": self.target.point,
                           "direction": None if self.target.direction is None else self.target.direction.tolist(),
                           "orientation": None if self.target.orientation is None else self.target.orientation.tolist()},
                "temperatures": {k: float(v) for k, v in self.temperatures.items()},
                "achieved": {"position": self.position.tolist(), "rotation_matrix": self.rotation.tolist()},
                "position_error": float(self.position_error), "angle_error_deg": angle,
                "verification_difference": float(self.verification_difference),
                "verified": bool(self.verified), "objective": float(self.objective),
                "solve_time_s": float(self.solve_time_s), "iterations": int(self.iterations),
                "starts": int(self.starts), "method": self.method,
                "result": None if self.result is None else self.result.as_dict()}

    @property
    def success(self):
        """Reached, converged and verified by an independent forward solve."""
        return bool(self.reachable and self.converged and self.verified)

    @property
    def status(self):
        if self.success:
            return Status.CONVERGED
        return self.result.status if self.result is not None and not self.result.success else Status.ABOVE_TOLERANCE

    def figure(self):
        """``inverse.png``'s figure: the robot, the target and the point reached."""
        from ...plotting import save_robot_png
        state = "reached" if self.reachable else f"UNREACHABLE, {self.position_error * 1e3:.3g} mm away"
        return save_robot_png(self.forward, None, title=f"inverse statics: target {state}",
                              extra_points=[(self.target.position, "target", "magenta"), (self.position, "reached", "blue")])

    def save(self, directory, plot=True):
        """Write ``inverse.json``, the forward ``solution.json`` + ``arrays.npz`` and, with
        ``plot``, ``inverse.png`` (the robot, the target and the reached point)."""
        from pathlib import Path

        from ...output import write_json
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        path = write_json(directory / "inverse.json", self.to_dict())
        written = [path, *self.forward.save(directory)]
        if plot:
            from ...plotting import save_robot_png
            state = "reached" if self.reachable else f"UNREACHABLE, {self.position_error * 1e3:.3g} mm away"
            written.append(save_robot_png(
                self.forward, directory / "inverse.png", title=f"inverse statics: target {state}",
                extra_points=[(self.target.position, "target", "magenta"),
                              (self.position, "reached", "blue")]))
        return written

    def summary(self):
        state = "REACHED" if self.reachable else "UNREACHABLE"
        lines = [f"inverse: {state} ({self.message})",
                 "  target [mm]:   " + " ".join(signed(v * 1e3) for v in self.target.position),
                 "  achieved [mm]: " + " ".join(signed(v * 1e3) for v in self.position),
                 f"  position error {self.position_error * 1e3:.4g} mm"
                 + ("" if self.angle_error is None else f", angle error {np.degrees(self.angle_error):.4g} deg"),
                 f"  forward check: {self.verification_difference:.2e} m "
                 f"({'verified' if self.verified else 'NOT VERIFIED'})",
                 f"  {self.solve_time_s * 1e3:.0f} ms, {self.iterations} {ITERATIONS[self.method]}, {self.starts} start(s)"]
        shown = {p.path: p for p in self.parameters}
        for path, value in self.temperatures.items():
            parameter = shown.get(path)
            value, unit = (parameter.shown(value), parameter.shown_unit) if parameter else (value, self.units.get(path, "degC"))
            lines.append(f"  {path:<28}{value:9.3f} {unit}")
        return "\n".join(lines)


def write_path_results(path, results):
    """One row per target: target, temperatures, achieved position, errors, status, time."""
    from ...output import write_csv
    temperature_names = list(results[0].temperatures)
    header = (["row", "target_x [m]", "target_y [m]", "target_z [m]"]
              + [f"{name} [{results[0].units.get(name, 'degC')}]" for name in temperature_names]
              + ["x [m]", "y [m]", "z [m]", "position_error [m]", "angle_error [deg]",
                 "reachable", "verified", "solve_time [s]", "iterations"])
    rows = []
    for index, r in enumerate(results):
        angle = "" if r.angle_error is None else f"{np.degrees(r.angle_error):.8g}"
        rows.append([index, *(f"{v:.10g}" for v in r.target.position),
                     *(f"{r.temperatures[n]:.8g}" for n in temperature_names),
                     *(f"{v:.10g}" for v in r.position), f"{r.position_error:.4g}", angle,
                     int(r.reachable), int(r.verified), f"{r.solve_time_s:.4g}", r.iterations])
    return write_csv(path, header, rows)

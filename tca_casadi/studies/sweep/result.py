"""The result of a sweep: the accepted points, the events along the branch, a CSV table."""
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...model.rotations import matrix_to_quaternion
from ...output import write_csv, write_json
from ...results import ResultAPI, status_of
from ...status import Status
from ...text import signed


@dataclass(repr=False)
class SweepResult(ResultAPI):
    """``points`` (list of SweepPoint, in branch order), ``events`` (dicts: kind, between,
    values, message), ``completed`` (reached the stop value), ``message``, ``method``
    ('natural' or 'arclength'), ``total_time_s``."""
    parameters: list
    points: list
    events: list
    completed: bool
    message: str
    method: str
    total_time_s: float

    @property
    def solutions(self):
        return [p.solution for p in self.points]

    @property
    def values(self):
        """(n_points, k) swept values."""
        return np.array([p.values for p in self.points])

    @property
    def tip_positions(self):
        """(n_points, 3) [m]."""
        return np.array([p.solution.tip_position for p in self.points])

    def tensions(self, key):
        """(n_points,) tension [N] of actuator ``key`` ('MODULE.NAME')."""
        return np.array([p.solution.actuators[key].tension for p in self.points])

    # ------------------------------------------------------------------ table
    def rows(self):
        """One dict per point; keys are CSV headers with units."""
        return [self._row(i, point) for i, point in enumerate(self.points)]

    def _row(self, index, point):
        solution = point.solution
        row = {"step": index, "lambda [-]": point.lam}
        row.update({p.si_label: v for p, v in zip(self.parameters, point.values)})
        row.update({"converged": bool(solution.converged), "iterations": solution.iterations,
                    "substeps": point.substeps, "solve_time [s]": solution.solve_time_s})
        for axis, value in zip("xyz", solution.tip_position):
            row[f"tip_{axis} [m]"] = value
        for axis, value in zip("wxyz", matrix_to_quaternion(solution.tip_rotation)):
            row[f"tip_q{axis} [-]"] = value
        row["bending_angle [deg]"] = np.degrees(bending_angle(solution))
        for key, actuator in solution.actuators.items():
            row[f"{key}.tension [N]"] = actuator.tension
            row[f"{key}.stroke [m]"] = actuator.stroke
            if actuator.slack_length is not None:
                row[f"{key}.slack_length [m]"] = actuator.slack_length
            if actuator.free_stroke is not None:
                row[f"{key}.free_stroke [m]"] = actuator.free_stroke
        row.update(solution.contact_columns())
        for j, p in enumerate(self.parameters):
            for axis, value in zip("xyz", point.tip_derivative[:, j]):
                row[f"dtip_{axis}/d{p.path} [m/{p.unit}]"] = value
        row["jacobian_det_sign"] = point.det_sign
        row["jacobian_sigma_min [-]"] = point.sigma_min
        return row

    def to_csv(self, path):
        rows = self.rows()
        header = list(rows[0]) if rows else ["step"]
        return write_csv(path, header, [[_format(row.get(k, "")) for k in header] for row in rows])

    def to_dict(self):
        return {"method": self.method, "completed": self.completed, "message": self.message,
                "total_time_s": self.total_time_s, "points": len(self.points),
                "parameters": [p.si_label for p in self.parameters], "events": self.events}

    def save(self, directory, plots=True, robots=5):
        """Write ``sweep.csv``, ``sweep.json`` (status and events) and, with ``plots``,
        ``sweep.png`` and ``sweep_robots.png``; return the paths."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        written = [self.to_csv(directory / "sweep.csv"), write_json(directory / "sweep.json", self.to_dict())]
        if plots and self.points:
            from ...plotting.sweep_plots import plot_sweep, plot_sweep_robots
            written.append(plot_sweep(self, directory / "sweep.png"))
            written.append(plot_sweep_robots(self, directory / "sweep_robots.png", robots))
        return written

    @property
    def result(self):
        """:class:`SolveStatus` of the whole sweep: success when it reached the stop value."""
        return status_of(self.completed, f"continuation ({self.method})", self.message, Status.STALLED,
                         nit=len(self.points), solve_time_s=self.total_time_s)

    def figure(self):
        """``sweep.png``'s figure."""
        from ...plotting.sweep_plots import plot_sweep
        return plot_sweep(self, None)

    def summary(self):
        state = "completed" if self.completed else "STOPPED"
        lines = [f"sweep ({self.method}): {state}, {len(self.points)} points in "
                 f"{self.total_time_s:.2f} s: {self.message}"]
        if self.points:
            first, last = self.points[0], self.points[-1]
            move = (last.solution.tip_position - first.solution.tip_position) * 1e3
            lines.append("  tip moved [mm]: " + " ".join(signed(v) for v in move))
        lines += [f"  event: {event['message']}" for event in self.events]
        return "\n".join(lines)


def bending_angle(solution):
    """Angle [rad] between the base tangent (first module) and the tip tangent."""
    (a1, a2, a3), (b1, b2, b3) = solution.modules[0].base_rotation[:, 2].tolist(), solution.tip_rotation[:, 2].tolist()
    return math.atan2(math.hypot(a2 * b3 - a3 * b2, a3 * b1 - a1 * b3, a1 * b2 - a2 * b1), a1 * b1 + a2 * b2 + a3 * b3)


def _format(value):
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.12g}"
    return value


# ---------------------------------------------------------------------- events
def _contact_changes(a, b):
    """``[(kind, text)]``: (module, obstacle) pairs in contact at ``b`` and not at ``a``
    ("touch") or the reverse ("release")."""
    before = {(c.module, c.obstacle) for c in a.contacts}
    after = {(c.module, c.obstacle) for c in b.contacts}
    out = [("touch", f"{module} touches {obstacle}") for module, obstacle in sorted(after - before)]
    return out + [("release", f"{module} leaves {obstacle}") for module, obstacle in sorted(before - after)]


def find_events(robot, points, parameters):
    """Events between consecutive points: a TCA tension changing sign or leaving the law's fit
    range, a tension-only actuator going slack or becoming taut, a module touching an obstacle
    or leaving it, the Jacobian's determinant changing sign, a fold (lam turning back,
    arclength)."""
    events = []
    if len(points) < 2:
        return events
    far = max(points, key=lambda p: abs(p.lam - points[0].lam))
    slope = (far.values - points[0].values) / (far.lam - points[0].lam)

    def event(kind, lam, text):
        values = points[0].values + (lam - points[0].lam) * slope
        where = ", ".join(p.describe(v) for p, v in zip(parameters, values))
        events.append({"kind": kind, "lambda": float(lam),
                       "values": {p.path: float(v) for p, v in zip(parameters, values)},
                       "message": f"{text} near {where}"})

    at = {id(p): robot.at(p.solution.parameters) for p in points}     # laws at each point's parameters
    for index, (a, b) in enumerate(zip(points[:-1], points[1:])):
        def between(fraction, a=a, b=b):
            return a.lam + fraction * (b.lam - a.lam)
        for actuator in robot.unknowns:
            ra, rb = (p.solution.actuators[actuator.key] for p in (a, b))
            if actuator.tension_only and ra.slack != rb.slack:
                event("slack" if rb.slack else "taut", between(0.5),
                      f"{actuator.key} {'goes slack' if rb.slack else 'becomes taut'}")
            fa, fb = ra.tension, rb.tension
            if not actuator.is_muscle:
                continue
            if not actuator.tension_only and (fa * fb < 0 or (fa != 0 and fb == 0)):
                event("tension_sign", between(fa / (fa - fb)),
                      f"{actuator.key} tension changes sign ({fa * 1e3:.4g} -> {fb * 1e3:.4g} mN)")
            k = robot.actuators.index(actuator)
            la, lb = (at[id(p)].actuators[k].law.monotone_limit for p in (a, b))
            if (fa - la) * (fb - lb) < 0:
                limit = 0.5 * (la + lb)
                event("fit_range", between((fa - la) / ((fa - la) - (fb - lb))),
                      f"{actuator.key} tension crosses the fit's monotone limit {limit * 1e3:.4g} mN")
        for kind, text in _contact_changes(a.solution, b.solution):
            event(kind, between(0.5), text)
        if a.lam_rate * b.lam_rate < 0:
            event("fold", _turning_lambda(points, index),
                  "fold (turning point): the branch turns back; the Jacobian is singular there")
        elif a.det_sign * b.det_sign < 0:
            event("singular_jacobian", between(0.5), "the Jacobian's determinant changes sign: "
                  "a fold or a bifurcation lies between these points")
    return events


def _turning_lambda(points, index):
    """lam at the turn between points ``index`` and ``index + 1``: the vertex of the parabola
    ``lam(sigma)`` through three points around it (sigma: arclength in (w, lam))."""
    trio = points[index:index + 3] if index + 2 < len(points) else points[max(index - 1, 0):index + 2]
    a, b = points[index], points[index + 1]
    if len(trio) < 3:
        return a.lam + a.lam_rate / (a.lam_rate - b.lam_rate) * (b.lam - a.lam)
    steps = [np.linalg.norm(np.r_[q.w - p.w, q.lam - p.lam]) for p, q in zip(trio[:-1], trio[1:])]
    sigma = np.r_[0.0, np.cumsum(steps)]
    coefficients = np.polyfit(sigma, [p.lam for p in trio], 2)
    if coefficients[0] == 0:
        return b.lam
    return float(np.polyval(coefficients, -coefficients[1] / (2 * coefficients[0])))

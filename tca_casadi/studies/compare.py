"""Cross-check: the same scenario solved by collocation and by shooting, and the difference.

Positions are compared at identical arc lengths (the shooting solver also samples at the
collocation nodes), so no interpolation error enters the comparison.
"""
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..model.rotations import rotation_angle
from ..results import ResultAPI, status_of

#: default agreement tolerances: tip, centerline and slack lengths [m]; tensions relative to
#: the larger of the two, floored at 1e-6 of the robot's largest tension (and 1e-9 N), so that
#: a slack actuator's ~1e-12 N is compared absolutely, not relatively
POSITION_TOLERANCE = 1e-6
TENSION_TOLERANCE = 1e-5
TENSION_FLOOR = 1e-9
TENSION_FLOOR_FRACTION = 1e-6


@dataclass(repr=False)
class CheckReport(ResultAPI):
    """Differences between two solutions of one scenario (SI units)."""
    scenario: str
    methods: tuple
    converged: dict
    tip_position_difference: float
    tip_rotation_difference: float
    max_centerline_distance: float
    tension_differences: dict = field(default_factory=dict)
    slack_differences: dict = field(default_factory=dict)
    solve_times_s: dict = field(default_factory=dict)
    position_tolerance: float = POSITION_TOLERANCE
    tension_tolerance: float = TENSION_TOLERANCE
    accuracy: dict = field(default_factory=dict)     # method -> its error estimate (if any)
    warnings: dict = field(default_factory=dict)     # method -> [PhysicsWarning text, ...]
    #: per closed contact (in either solution) "MODULE s=... mm / OBSTACLE": both total contact
    #: forces (3,) [N], absolute and relative difference (relative as tensions are)
    contact_differences: dict = field(default_factory=dict)
    #: per free body its position difference [m]
    body_differences: dict = field(default_factory=dict)
    #: where the second solve started: ``reference`` (continuation from the unloaded state, an
    #: independent solve) or ``collocation`` (its solution: robots with free bodies)
    shooting_start: str = "reference"

    @property
    def worst_relative_tension(self):
        return max((d["relative"] for d in self.tension_differences.values()), default=0.0)

    @property
    def worst_relative_contact(self):
        return max((d["relative"] for d in self.contact_differences.values()), default=0.0)

    @property
    def agree(self):
        """Both converged, positions within the position tolerance, tensions within theirs."""
        return (all(self.converged.values())
                and self.tip_position_difference <= self.position_tolerance
                and self.max_centerline_distance <= self.position_tolerance
                and self.worst_relative_tension <= self.tension_tolerance
                and self.worst_relative_contact <= self.tension_tolerance
                and max(self.slack_differences.values(), default=0.0) <= self.position_tolerance
                and max(self.body_differences.values(), default=0.0) <= self.position_tolerance)

    @property
    def result(self):
        """:class:`SolveStatus` of the check: success when both solvers converged and agree."""
        return status_of(self.agree, "check (collocation against shooting)",
                         f"tip {self.tip_position_difference:.1e} m, worst tension {self.worst_relative_tension:.1e}")

    @property
    def message(self):
        return self.result.message

    def figure(self):
        """The differences against their tolerances (bars, log scale)."""
        from ..plotting.robot3d import _pyplot, finish
        plt = _pyplot()
        fig, ax = plt.subplots(figsize=(6.4, 3.2))
        names = ["tip [m]", "centerline [m]"] + [f"{k} [rel]" for k in self.tension_differences]
        values = [self.tip_position_difference, self.max_centerline_distance] + [d["relative"] for d in self.tension_differences.values()]
        limits = [self.position_tolerance] * 2 + [self.tension_tolerance] * len(self.tension_differences)
        ax.bar(range(len(values)), [max(v, 1e-18) for v in values], color=["tab:green" if v <= lim else "tab:red"
                                                                           for v, lim in zip(values, limits)])
        ax.scatter(range(len(limits)), limits, marker="_", s=400, color="black", label="tolerance")
        ax.set_yscale("log")
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=7)
        ax.set_title(f"check of {self.scenario}: {'agree' if self.agree else 'DISAGREE'}", fontsize=10)
        ax.legend(fontsize=7)
        return finish(plt, fig, None)

    def to_dict(self):
        data = asdict(self)
        data["agree"] = self.agree
        return data

    def save(self, path):
        from ..output import write_json
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        return write_json(path, self.to_dict())

    def summary(self):
        a, b = self.methods
        verdict = "AGREE" if self.agree else "DISAGREE"
        lines = [f"{self.scenario}: {a} vs {b}: {verdict} (tolerances: position "
                 f"{self.position_tolerance:.0e} m, tension {self.tension_tolerance:.0e} relative)",
                 f"  converged: {a} {self.converged[a]}, {b} {self.converged[b]}",
                 f"  tip position difference   {self.tip_position_difference:.3e} m",
                 f"  tip rotation difference   {self.tip_rotation_difference:.3e} rad",
                 f"  max centerline distance   {self.max_centerline_distance:.3e} m"]
        for key, d in self.tension_differences.items():
            lines.append(f"  {key:<24} {d[a] * 1e3:+.6f} mN vs {d[b] * 1e3:+.6f} mN  "
                         f"(relative {d['relative']:.2e})")
        for key, d in self.slack_differences.items():
            lines.append(f"  {key:<24} slack length difference {d:.3e} m")
        for key, d in self.contact_differences.items():
            lines.append(f"  contact {key}: |f| {np.linalg.norm(d[a]) * 1e3:.6f} mN vs "
                         f"{np.linalg.norm(d[b]) * 1e3:.6f} mN (relative {d['relative']:.2e})")
        for key, d in self.body_differences.items():
            lines.append(f"  {key:<24} position difference {d:.3e} m")
        for method, estimate in self.accuracy.items():
            lines.append(f"  {method} error estimate: tip {estimate['tip_error_estimate']:.1e} m, tensions "
                         f"{estimate['tension_error_estimate']:.1e} ({'met' if estimate['met'] else 'NOT met'}; "
                         f"{'+'.join(map(str, estimate['intervals']))} intervals)")
        lines.append("  solve time: " + ", ".join(f"{k} {v:.3f} s" for k, v in self.solve_times_s.items()))
        if self.shooting_start != "reference":
            lines.append(f"  {b} started from the {self.shooting_start} solution at its parameters (free bodies "
                         "have no rest pose to start from; friction's history is the path's); it converged on its "
                         "own equations")
        lines += [f"  warning ({method}): {text}" for method, texts in self.warnings.items() for text in texts]
        return "\n".join(lines)


def compare_solutions(first, second, position_tolerance=POSITION_TOLERANCE,
                      tension_tolerance=TENSION_TOLERANCE):
    """:class:`CheckReport` of two solutions of the same robot."""
    a, b = first.method, second.method
    distance = 0.0
    for ma, mb in zip(first.modules, second.modules):
        distance = max(distance, _centerline_distance(ma, mb))
    tensions, slack = {}, {}
    largest = max((abs(x.tension) for x in first.actuators.values()), default=0.0)
    floor = max(TENSION_FLOOR, TENSION_FLOOR_FRACTION * largest)
    for key, actuator in first.actuators.items():
        other = second.actuators[key]
        ta, tb = actuator.tension, other.tension
        tensions[key] = {a: ta, b: tb, "absolute": abs(ta - tb),
                         "relative": abs(ta - tb) / max(abs(ta), abs(tb), floor)}
        if actuator.slack_length is not None:
            slack[key] = abs(actuator.slack_length - other.slack_length)
    contacts = _contact_differences(first, second, floor)
    bodies = {f"object {body.name}": float(np.linalg.norm(np.asarray(body.position) - np.asarray(other.position)))
              for body, other in zip(first.bodies, second.bodies)}
    return CheckReport(
        contact_differences=contacts, body_differences=bodies,
        scenario=first.scenario_name, methods=(a, b),
        converged={a: bool(first.converged), b: bool(second.converged)},
        tip_position_difference=float(np.linalg.norm(first.tip_position - second.tip_position)),
        tip_rotation_difference=rotation_angle(first.tip_rotation, second.tip_rotation),
        max_centerline_distance=distance, tension_differences=tensions, slack_differences=slack,
        solve_times_s={a: first.solve_time_s, b: second.solve_time_s},
        position_tolerance=position_tolerance, tension_tolerance=tension_tolerance,
        accuracy={s.method: s.accuracy.as_dict() for s in (first, second) if s.accuracy is not None},
        warnings={s.method: s.warning_texts() for s in (first, second)})


def _contact_differences(first, second, floor):
    """Per closed contact of either solution (matched by module, arc length and what it
    touches; absent: zero force) both forces (3,) [N] and their absolute and relative
    difference (relative to the larger, floored at ``floor`` [N] as tensions are)."""
    def forces(solution):
        return {(c.module, round(c.s, 12), c.obstacle): np.asarray(c.force, float) for c in solution.contacts}
    fa, fb = forces(first), forces(second)
    out = {}
    for key in sorted(set(fa) | set(fb)):
        va, vb = fa.get(key, np.zeros(3)), fb.get(key, np.zeros(3))
        difference = float(np.linalg.norm(va - vb))
        out[f"{key[0]} s={key[1] * 1e3:.4g} mm / {key[2]}"] = {
            first.method: va.tolist(), second.method: vb.tolist(), "absolute": difference,
            "relative": difference / max(float(np.linalg.norm(va)), float(np.linalg.norm(vb)), floor)}
    return out


def _centerline_distance(ma, mb):
    """Largest distance between the two centerlines at the arc lengths both sampled."""
    worst, used = 0.0, 0
    for k, s in enumerate(ma.s):
        match = np.flatnonzero(np.abs(mb.s - s) <= 1e-12 * max(1.0, abs(s)))
        if match.size:
            worst = max(worst, float(np.min(np.linalg.norm(mb.p[:, match] - ma.p[:, k:k + 1], axis=0))))
            used += 1
    if used == 0:
        raise ValueError(f"module {ma.name}: the two solutions share no arc length to compare at")
    return worst


def solve_by_shooting(simulation, collocation):
    """``(solution, start)``: ``simulation`` solved by shooting from the unloaded reference state
    (``start`` ``"reference"``: continuation, independent of collocation) or, for a robot with
    free bodies or friction, at ``collocation``'s parameters from its solution
    (``"collocation"``): a free body has no rest pose to continue from (without its weight
    nothing holds it where it is), and with friction the equilibrium depends on the path, which
    the parameters' contact history records as collocation left it; shooting then converges on
    its own equations."""
    robot = simulation.robot
    if (robot.bodies or robot.path_dependent) and collocation.converged:
        solver = simulation.solver("shooting")
        return solver.solve(collocation.parameters, collocation), "collocation"
    return simulation.solve(method="shooting", warn=False), "reference"


def check(simulation, position_tolerance=POSITION_TOLERANCE, tension_tolerance=TENSION_TOLERANCE):
    """Solve ``simulation`` by collocation and (independently, from a cold start) by shooting.
    The solutions' warnings are in the report (not issued). The shooting solver is built after
    the collocation solve, on the robot it leaves (with the contact candidates it localised), so
    that both solve for forces at the same points."""
    collocation = simulation.solve(method="collocation", warn=False)
    shooting_solver = simulation.solver("shooting")
    shooting_solver.sample_s = [m.s for m in collocation.modules]
    shooting, start = solve_by_shooting(simulation, collocation)
    report = compare_solutions(collocation, shooting, position_tolerance, tension_tolerance)
    report.shooting_start = start
    return report, collocation, shooting

"""Sequences (``sequence:`` in a scenario, ``tca-casadi sequence``): named steps, each setting
values by dotted path on top of the previous ones, each solved from the previous step's
solution. A large change inside a step (a temperature jump) is followed by predictor-corrector
continuation from the previous parameters, so a step never jumps branches. Scenario objects
are picked, carried and put down as the steps set their ``held`` flags (:mod:`.objects`); with
``check=True`` every step is also solved by shooting and compared.
"""
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...errors import PhysicsWarning, ScenarioError
from ...results import ResultAPI, status_of
from ...solvers.continuation import walk_branch
from ...solvers.strategy import failure_text
from ..compare import compare_solutions, solve_by_shooting
from ...model.history import carried_history
from ...solvers.assemble import record_slides
from .objects import ObjectTracker
from ..sweep.result import bending_angle

#: a grasp closes "across" the object when the tip-to-tip direction is this close to 90 deg
#: from the object's long axis [deg]
GRIP_ANGLE_TOLERANCE = 15.0


@dataclass(repr=False)
class SequenceResult(ResultAPI):
    """The steps' names and solutions, in order; ``frames`` (lam, solution) between steps when
    asked for (for animations)."""
    names: list
    solutions: list
    transitions: list = field(default_factory=list)   # per step: [(lam, Solution), ...] from the previous
    total_time_s: float = 0.0
    objects: list = field(default_factory=list)       # per step: {name: ObjectPose} after the step
    transition_objects: list = field(default_factory=list)  # per step: [{name: ObjectPose}, ...] per frame
    openings: list = field(default_factory=list)      # per step: gripper opening [m] or None
    checks: list = field(default_factory=list)        # per step: CheckReport (check=True)
    warnings: list = field(default_factory=list)
    stage: list = field(default_factory=list)         # per step: how an external stage moved the base ("" if not)

    @property
    def converged(self):
        return all(s.converged for s in self.solutions)

    @property
    def agree(self):
        """Every step agrees with shooting (None when not checked)."""
        return all(c.agree for c in self.checks) if self.checks else None

    def rows(self):
        out = []
        for index, (name, solution) in enumerate(zip(self.names, self.solutions)):
            row = {"step": index, "name": name, "converged": bool(solution.converged),
                   "solve_time [s]": solution.solve_time_s}
            for axis, value in zip("xyz", solution.tip_position):
                row[f"tip_{axis} [m]"] = value
            row["tip_yaw [deg]"] = tip_yaw(solution)
            base = solution.modules[0].p[:, 0]
            for axis, value in zip("xyz", base):
                row[f"base_{axis} [m]"] = value
            row["base_moved_by"] = "external stage" if self.stage and self.stage[index] else ""
            row["bending_angle [deg]"] = np.degrees(bending_angle(solution))
            if self.openings and self.openings[index] is not None:
                row["gripper_opening [m]"] = self.openings[index]
            for name, pose in (self.objects[index] if self.objects else {}).items():
                row[f"{name}.held"] = int(pose.held)
                for axis, value in zip("xyz", pose.center):
                    row[f"{name}.{axis} [m]"] = value
            for key, actuator in solution.actuators.items():
                if actuator.temperature is not None:
                    row[f"{key}.temperature [degC]"] = actuator.temperature
                row[f"{key}.tension [N]"] = actuator.tension
            row.update(solution.contact_columns())
            if self.checks:
                row["shooting_tip_difference [m]"] = self.checks[index].tip_position_difference
                row["shooting_centerline_difference [m]"] = self.checks[index].max_centerline_distance
                row["shooting_tension_difference [-]"] = self.checks[index].worst_relative_tension
                row["shooting_contact_difference [-]"] = self.checks[index].worst_relative_contact
            out.append(row)
        return out

    def to_csv(self, path):
        from ...output import write_csv
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        rows = self.rows()
        header = list(rows[0])
        return write_csv(path, header, [[f"{v:.10g}" if isinstance(v, float) else v
                                         for v in (row.get(k, "") for k in header)] for row in rows])

    @property
    def result(self):
        """:class:`SolveStatus` of the sequence: success when every step converged (and, when
        checked, agreed with shooting)."""
        failed = [name for name, s in zip(self.names, self.solutions) if not s.converged]
        detail = f"not converged: {', '.join(failed)}" if failed else ("" if self.agree is not False else
                                                                       "a step disagrees with shooting")
        return status_of(self.converged and self.agree is not False, "sequence", detail,
                         nit=len(self.solutions), solve_time_s=self.total_time_s)

    @property
    def message(self):
        return self.result.message

    def figure(self):
        """The robot at the last step (each step's PNG is ``save_step_pngs``')."""
        from ...plotting import save_robot_png
        objects = self.objects[-1].values() if self.objects else ()
        return save_robot_png(self.solutions[-1], None, objects=objects, title=self.names[-1])

    def summary(self):
        state = "all converged" if self.converged else "NOT ALL CONVERGED"
        lines = [f"sequence: {len(self.solutions)} steps, {state}, {self.total_time_s:.2f} s"]
        if self.checks:
            worst = max(c.max_centerline_distance for c in self.checks)
            lines[0] += (f"; shooting {'AGREES' if self.agree else 'DISAGREES'} on every step" if self.agree
                         else "; shooting DISAGREES on some step") + f" (worst centerline {worst:.1e} m)"
        for index, (name, solution) in enumerate(zip(self.names, self.solutions)):
            tip = solution.tip_position * 1e3
            flag = "" if solution.converged else "  NOT CONVERGED"
            extra = ""
            if self.openings and self.openings[index] is not None:
                extra += f"  opening {self.openings[index] * 1e3:6.2f} mm"
            for pose in (self.objects[index] if self.objects else {}).values():
                c = pose.center * 1e3
                extra += f"  {pose.name} {'held' if pose.held else 'rests'} at {c[0]:+.1f} {c[1]:+.1f} {c[2]:+.1f}"
            for body in solution.bodies:             # contact objects: what holds them
                if body.grips:
                    extra += (f"  grip {body.grip_force * 1e3:.3g} mN, needs friction {body.needed_friction:.3g}"
                              + (" SLIPPING" if body.slipping else ""))
            if self.stage and self.stage[index]:
                extra += f"  ({self.stage[index]})"
            lines.append(f"  {name:<28} tip [mm] {tip[0]:+8.3f} {tip[1]:+8.3f} {tip[2]:+8.3f}  "
                         f"yaw {tip_yaw(solution):+7.2f} deg{extra}{flag}")
        lines += [f"  warning: {w}" for w in self.warnings]
        lines += [f"  warning: step {name!r}: {w}" for name, solution in zip(self.names, self.solutions)
                  for w in solution.warnings if w.kind in ("slipping", "penetration", "not_converged")]
        return "\n".join(lines)


def tip_yaw(solution):
    """Rotation [deg] of the tip frame about the global z axis (its x axis's heading)."""
    x_axis = solution.tip_rotation[:, 0]
    return float(np.degrees(np.arctan2(x_axis[1], x_axis[0])))


def run_sequence(sim, steps=None, frames_per_step=0, progress=None, check=False):
    """Solve ``steps`` (default the scenario's ``sequence:``) in order on ``sim``.

    ``frames_per_step``: also keep that many intermediate solutions of each transition (equal
    steps in the continuation parameter), for animations. ``check``: solve every step by
    shooting too (each shot started from the previous step's shooting solution, independent of
    collocation; with friction or free objects, whose equilibria depend on the path, from the
    step's collocation solution) and compare. ``progress(fraction, text)``."""
    steps = steps if steps is not None else (sim.scenario.sequence or [])
    if not steps:
        raise ScenarioError("the scenario has no sequence: steps (a list of {name, set: {PATH: value}})")
    started = time.perf_counter()
    result = SequenceResult([], [])
    tracker = ObjectTracker(sim.scenario, sim.robot)
    previous = sim.solve(method="collocation", warn=False)
    shot = solve_by_shooting(sim, previous)[0] if check else None
    for index, step in enumerate(steps):
        name, values = (step.name, step.set) if hasattr(step, "name") else (step["name"], step.get("set", {}))
        before = sim.params.copy()
        for path, value in values.items():
            sim.set(path, value)
        solution, transition = _solve_step(sim, before, previous, frames_per_step)
        result.stage.append(stage_motion(sim.robot, before, sim.params))
        result.names.append(name)
        result.solutions.append(solution)
        result.transitions.append(transition)
        result.transition_objects.append([tracker.poses_in(s) for _, s in transition])
        _track_objects(result, tracker, solution, name)
        if check:
            shot = _check_step(sim, result, solution, shot)
        previous = solution if solution.converged else previous
        if progress is not None:
            progress((index + 1) / len(steps), name)
    result.total_time_s = time.perf_counter() - started
    return result


def stage_motion(robot, before, after):
    """How a step moved the robot's base, as text (``""`` if it did not): the base is carried by
    an external stage (a positioner), not by any actuator of the robot."""
    moved = after[robot.layout["base.position"]] - before[robot.layout["base.position"]]
    turned = np.any(after[robot.layout["base.quaternion"]] != before[robot.layout["base.quaternion"]])
    parts = []
    if np.any(moved):
        parts.append("moves the base by [" + ", ".join(f"{v * 1e3:+.3g}" for v in moved) + "] mm")
    if turned:
        parts.append("turns the base")
    return ("external stage " + " and ".join(parts)) if parts else ""


def _track_objects(result, tracker, solution, name):
    """Objects and gripper opening after a step; a warning when a grasp is not across the object."""
    newly_held = [n for n in tracker.names if tracker.held_in(solution, n) and not tracker.poses[n].held
                  and n not in tracker.free]        # a contact object's grasp is solved, not guessed
    result.objects.append(tracker.advance(solution, name))
    result.openings.append(tracker.opening(solution, tracker.names[0]) if tracker.names else None)
    for object_name in newly_held:
        angle = tracker.grip_angle(solution, object_name)
        if angle is not None and abs(angle - 90.0) > GRIP_ANGLE_TOLERANCE:
            result.warnings.append(PhysicsWarning("grasp", f"step {name!r}: the gripper closes on {object_name!r} "
                                                  f"at {angle:.1f} deg to its long axis, not across it (90 deg)"))


def _check_step(sim, result, solution, shot):
    """Shooting at this step's parameters from the previous shooting solution (with friction or
    free objects: from this step's collocation solution); the comparison."""
    shooting = sim.solver("shooting")
    shooting.sample_s = [m.s for m in solution.modules]
    # at the parameters this step's collocation solution was found at: with friction the history
    # carried after it (where each contact sticks now) is the next step's, not this one's
    params = solution.parameters
    if sim.robot.path_dependent:
        # with friction the equilibrium depends on the path: a jump from the previous step's shot
        # may land on another (a lifted gripper leaving its object behind is one); collocation
        # followed the step's path, so shooting starts where it ended and converges on its own
        other = shooting.solve(params, initial=solution)
        result.checks.append(compare_solutions(solution, other))
        return other
    other = shooting.solve(params, initial=shot if shot is not None and shot.converged else None)
    if not other.converged:
        result.warnings.append(PhysicsWarning("sequence", f"step {result.names[-1]!r}: shooting did not converge "
                                              "from the previous step's shooting solution; started it from this "
                                              "step's collocation solution"))
        other = shooting.solve(params, initial=solution)
    result.checks.append(compare_solutions(solution, other))
    return other


def _solve_step(sim, before, previous, frames):
    """From ``previous`` (at parameters ``before``) to the current parameters, by continuation."""
    solver = sim.solver("collocation")
    if previous.iterate.w is None or previous.iterate.w.size != solver.nlp.scale.size:
        return sim.solve(method="collocation", warn=False), []          # the structure changed: start afresh
    sim.params = carried_history(sim.robot, sim.params, previous)       # contact objects' grips
    before = carried_history(sim.robot, before, previous)
    targets = np.linspace(0, 1, frames + 2)[1:] if frames else [1.0]
    walk = walk_branch(solver, previous, before, sim.params, targets=targets)
    if not walk.completed and sim.robot.path_dependent:
        # a grasp's state depends on its path (friction): a solve from the reference state
        # would teleport the objects; the step is reported stalled where it stopped
        return sim.strategy.stalled(solver, walk.point.solution, before, sim.params, walk.point.lam, 1e-4,
                                    failure_text(walk.failure), walk.iterations, 0.0,
                                    origin="the previous step"), walk.reached
    if not walk.completed:
        return sim.solve(method="collocation", warn=False), walk.reached         # from the reference state
    record_slides(sim.robot, before, walk.point.solution)
    sim.last = walk.point.solution
    return walk.point.solution, walk.reached[:-1] if frames else []

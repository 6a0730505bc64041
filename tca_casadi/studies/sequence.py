"""Sequences (``sequence:`` in a scenario, ``tca-casadi sequence``): named steps, each setting
values by dotted path on top of the previous ones, each solved from the previous step's
solution. A large change inside a step (a temperature jump) is followed by predictor-corrector
continuation from the previous parameters, so a step never jumps branches.
"""
import csv
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ScenarioError
from ..solvers.continuation import BranchFollower
from .sweep_result import bending_angle


@dataclass
class SequenceResult:
    """The steps' names and solutions, in order; ``frames`` (lam, solution) between steps when
    asked for (for animations)."""
    names: list
    solutions: list
    transitions: list = field(default_factory=list)   # per step: [(lam, Solution), ...] from the previous
    total_time_s: float = 0.0

    @property
    def converged(self):
        return all(s.converged for s in self.solutions)

    def rows(self):
        out = []
        for index, (name, solution) in enumerate(zip(self.names, self.solutions)):
            row = {"step": index, "name": name, "converged": bool(solution.converged),
                   "solve_time [s]": solution.solve_time_s}
            for axis, value in zip("xyz", solution.tip_position):
                row[f"tip_{axis} [m]"] = value
            row["bending_angle [deg]"] = np.degrees(bending_angle(solution))
            for key, actuator in solution.actuators.items():
                if actuator.temperature is not None:
                    row[f"{key}.temperature [degC]"] = actuator.temperature
                row[f"{key}.tension [N]"] = actuator.tension
            out.append(row)
        return out

    def to_csv(self, path):
        rows = self.rows()
        with Path(path).open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            for row in rows:
                writer.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in row.items()})
        return Path(path)

    def summary(self):
        state = "all converged" if self.converged else "NOT ALL CONVERGED"
        lines = [f"sequence: {len(self.solutions)} steps, {state}, {self.total_time_s:.2f} s"]
        for name, solution in zip(self.names, self.solutions):
            tip = solution.tip_position * 1e3
            flag = "" if solution.converged else "  NOT CONVERGED"
            lines.append(f"  {name:<24} tip [mm] {tip[0]:+8.3f} {tip[1]:+8.3f} {tip[2]:+8.3f}{flag}")
        return "\n".join(lines)


def run_sequence(sim, steps=None, frames_per_step=0, progress=None):
    """Solve ``steps`` (default the scenario's ``sequence:``) in order on ``sim``.

    ``frames_per_step``: also keep that many intermediate solutions of each transition (equal
    steps in the continuation parameter), for animations. ``progress(fraction, text)``."""
    steps = steps if steps is not None else (sim.scenario.sequence or [])
    if not steps:
        raise ScenarioError("the scenario has no sequence: steps (a list of {name, set: {PATH: value}})")
    started = time.perf_counter()
    result = SequenceResult([], [])
    previous = sim.solve(method="collocation")
    for index, step in enumerate(steps):
        name, values = (step.name, step.set) if hasattr(step, "name") else (step["name"], step.get("set", {}))
        before = sim.params.copy()
        for path, value in values.items():
            sim.set(path, value)
        solution, transition = _solve_step(sim, before, previous, frames_per_step)
        result.names.append(name)
        result.solutions.append(solution)
        result.transitions.append(transition)
        previous = solution if solution.converged else previous
        if progress is not None:
            progress((index + 1) / len(steps), name)
    result.total_time_s = time.perf_counter() - started
    return result


def _solve_step(sim, before, previous, frames):
    """From ``previous`` (at parameters ``before``) to the current parameters, by continuation."""
    solver = sim.solver("collocation")
    if previous.raw.get("w") is None or previous.raw["w"].size != solver.nlp.scale.size:
        return sim.solve(method="collocation"), []          # the structure changed: start afresh
    follower = BranchFollower(solver, before, sim.params - before)
    point = follower.point(0.0, previous)
    transition = []
    targets = np.linspace(0, 1, frames + 2)[1:] if frames else [1.0]
    for target in targets:
        point, _, _, failure = follower.advance(point, float(target), float(target - point.lam), 1.0, 1e-4)
        if failure is not None:
            solution = sim.solve(method="collocation")            # from the reference state
            return solution, transition
        transition.append((float(target), point.solution))
    sim.last = point.solution
    return point.solution, transition[:-1] if frames else []

"""What a study's worker does (in this process, a pool process or a Dask worker alike): solve a
chunk of samples of one structure in order, each warm-started from the last converged one, and
return one row per sample.

A :class:`Chunk` carries everything a fresh process needs: the scenario as a plain mapping, the
structural values of its group, the mesh the parent fixed for that structure and the samples.
Each process builds a structure's model and NLP once (kept in :data:`_PREPARED`) and reuses it
for every chunk of that structure it is given.
"""
import os
import socket
import time
from dataclasses import dataclass, field

import numpy as np

from ...errors import TcaError
from ...model.rotations import matrix_to_quaternion
from ...solution import BODY_COLUMNS
from ..sweep.result import bending_angle

#: prepared structures kept per process
PREPARED = 4
#: a sample's row comes with its Solution's global balance every this many samples of a chunk
#: (its first and its last too); the others' rows come from the solve's outputs alone, with the
#: balance NaN (a Solution costs about 0.25 ms a sample on the bending module, a third of it)
BALANCE_EVERY = 25
_PREPARED = {}


@dataclass
class Chunk:
    """Samples of one structure for one worker: ``ids`` (k,), ``values`` (k, p) of the parameter
    ``paths`` (in their units); the group's ``structure`` overrides ``{path: value}``; ``key``
    names the prepared structure (scenario, structure and mesh)."""
    key: str
    raw: dict
    structure: dict
    meshes: tuple
    degree: int
    paths: list
    ids: list
    values: list
    outputs: list = field(default_factory=list)
    #: the user allowed the scenario's custom laws' code (workers rebuild it from ``raw``)
    allow_code: bool = False
    #: ``solver.jit: auto`` decided to compile (a study of :data:`AUTO_JIT_SAMPLES` or more)
    compiled: bool = False
    #: the id of the sample just before this chunk's first in its group's order (None: the
    #: group's first): a serial run starts the chunk from that sample's answer where it has it
    after: int = None


def solve_chunk(chunk, progress=None):
    """Rows (list of dicts, one per sample, in the chunk's order) of ``chunk``; ``progress(row)``
    is called after each sample. A sample whose solve fails or raises is a row with
    ``converged`` False and the reason in ``message``, never left out. The global balance is
    checked (``balance [-]``) at every :data:`BALANCE_EVERY`-th sample and the chunk's last (at
    every sample where outputs are asked for, or the robot has contact or friction); the others'
    is NaN."""
    return solve_chunk_from(chunk, progress)[0]


def solve_chunk_from(chunk, progress=None, start=None):
    """``(rows, last)``: :func:`solve_chunk`'s rows, its first sample warm-started from
    ``start`` (the answer at the sample ``chunk.after``, from the chunk before it in a serial
    run; None: cold, from the reference state), and the last converged answer (or ``start``)."""
    from ..parameters import resolve_parameters
    sim, base = _prepared(chunk)
    parameters = resolve_parameters(sim.robot, base, chunk.paths)
    where = f"{socket.gethostname()}:{os.getpid()}"
    rows, previous, last = [], start, len(chunk.ids) - 1
    for k, (sample, values) in enumerate(zip(chunk.ids, chunk.values)):
        started = time.perf_counter()
        # a Solution with its global balance every BALANCE_EVERY samples and at the chunk's last;
        # the others' rows come from their outputs (issue 36), unless outputs are asked for
        lean = not chunk.outputs and k % BALANCE_EVERY != 0 and k != last
        try:
            params = base.copy()
            for parameter, value in zip(parameters, values):
                params = parameter.with_value(params, value)
            solution = sim.solve_near(previous, params, lean=lean)
            row = solution_row(sim, solution, chunk.outputs)
            previous = solution if solution.converged else previous
        except TcaError as exc:
            row = failure_row(sim, chunk.outputs, "error", str(exc))
        except (RuntimeError, ArithmeticError, ValueError) as exc:     # a solver that broke: a row too
            row = failure_row(sim, chunk.outputs, "error", f"{type(exc).__name__}: {exc}")
        row.update({"sample": int(sample), "wall_time [s]": time.perf_counter() - started, "worker": where})
        rows.append(row)
        if progress is not None:
            progress(row)
    return rows, previous


def _prepared(chunk):
    """``(Simulation, nominal parameter vector)`` of the chunk's structure on the parent's mesh,
    built once per process."""
    if chunk.key in _PREPARED:
        return _PREPARED[chunk.key]
    from ...simulation import Simulation
    sim = Simulation.from_file(chunk.raw, chunk.structure, allow_code=chunk.allow_code)
    if chunk.meshes is not None:
        sim.use_meshes(chunk.meshes, chunk.degree)
        sim.solver().compile_when_auto = chunk.compiled
    _PREPARED[chunk.key] = (sim, sim.params.copy())
    while len(_PREPARED) > PREPARED:
        _PREPARED.pop(next(iter(_PREPARED)))
    return _PREPARED[chunk.key]


def solution_row(sim, solution, outputs=()):
    """The result columns of one solved sample (units in the names). An unconverged solve keeps
    its status and message; its shape columns are NaN (never a shape that is not one)."""
    row = {"converged": bool(solution.converged), "status": solution.status.name.lower(),
           "iterations": int(solution.iterations or 0), "solve_time [s]": float(solution.solve_time_s or 0.0),
           "message": "" if solution.converged else solution.message}
    if not solution.converged:
        row.update(_empty_columns(sim, outputs))
        return row
    for axis, value in zip("xyz", solution.tip_position):
        row[f"tip_{axis} [m]"] = float(value)
    for axis, value in zip("wxyz", matrix_to_quaternion(solution.tip_rotation)):
        row[f"tip_q{axis} [-]"] = float(value)
    row["bending_angle [deg]"] = float(np.degrees(bending_angle(solution)))
    for key, actuator in solution.actuators.items():
        row[f"{key}.tension [N]"] = float(actuator.tension)
        row[f"{key}.stroke [m]"] = float(actuator.stroke)
    row.update({name: float(value) for name, value in solution.contact_columns().items()})
    for name in outputs:
        label, value = OUTPUTS[output_kind(name)][1](solution, name)
        row[label] = float(value)
    row["balance [-]"] = float(solution.balance.relative) if solution.balance is not None else float("nan")
    return row


def failure_row(sim, outputs, status, message):
    """The row of a sample that raised (bad parameter values, a solver error)."""
    row = {"converged": False, "status": status, "iterations": 0, "solve_time [s]": 0.0, "message": message}
    row.update(_empty_columns(sim, outputs))
    return row


def _empty_columns(sim, outputs):
    names = [f"tip_{a} [m]" for a in "xyz"] + [f"tip_q{a} [-]" for a in "wxyz"] + ["bending_angle [deg]"]
    for actuator in sim.robot.actuators:
        names += [f"{actuator.key}.tension [N]", f"{actuator.key}.stroke [m]"]
    for shape in sim.robot.obstacles:
        names += [f"{shape.name}.normal_force [N]", f"{shape.name}.clearance [m]"]
    for body in sim.robot.bodies:
        names += [f"{body.name}.{key}" for key in BODY_COLUMNS]
    names += [output_label(name) for name in outputs] + ["balance [-]"]
    return {name: float("nan") for name in names}


# ---------------------------------------------------------------------- requested outputs
def _module_end(solution, name):
    module, what = name.rsplit(".", 1)
    result = next(m for m in solution.modules if m.name == module)
    return f"{name} [m]", result.tip_position["xyz".index(what[-1])]


def _actuator_value(solution, name):
    key, what = name.rsplit(".", 1)
    value = getattr(solution.actuators[key], what)
    return f"{name} [m]", np.nan if value is None else value


#: requested outputs: kind -> (description, (solution, name) -> (label, value))
OUTPUTS = {
    "module_end": ("MODULE.tip_x|tip_y|tip_z: a module's end [m]", _module_end),
    "actuator": ("ACTUATOR.length|free_stroke|slack_length: an actuator's [m] (e.g. bending.tca1.length)",
                 _actuator_value),
    "max_residual": ("max_residual: the largest scaled residual [-]",
                     lambda solution, name: ("max_residual [-]", solution.max_residual)),
}


def output_kind(name):
    """The :data:`OUTPUTS` kind of a requested output name (None if it is not one)."""
    if name == "max_residual":
        return "max_residual"
    stem, _, what = name.rpartition(".")
    if what in ("tip_x", "tip_y", "tip_z") and stem:
        return "module_end"
    if what in ("length", "free_stroke", "slack_length") and stem:
        return "actuator"
    return None


def output_label(name):
    return "max_residual [-]" if name == "max_residual" else f"{name} [m]"

"""Studies at scale (``tca-casadi study``, ``tc.Study``): one scenario solved at many samples of
its parameters, serially, on a pool of processes or on a Dask cluster.

    study = tc.Study(sim, vary={"bending.tca1.temperature": [25, 125, 5],
                                "bending.tca2.temperature": [25, 125, 5]})
    result = study.run()                      # or run(workers=2), run(scheduler="tcp://...")
    result.frame                              # pandas DataFrame, one row per sample

**Plan.** The :mod:`.design` gives the samples in a locality-preserving order. Paths that are
NLP parameters (temperatures, loads, moduli, TCA geometry: :mod:`~tca_casadi.studies.parameters`) only change the
parameter vector; any other scenario path changes the structure, so the samples are grouped by
their structural values and each group's model is built once per process. Each group's mesh is
fixed in this process by one accuracy-controlled solve at the scenario's own values (refined
there if the scenario asks for it) and used by every worker, so a sample's answer does not
depend on where it ran.

**Chunks.** A group's ordered samples are cut into chunks (about four per worker, at most
:data:`MAX_CHUNK`); a worker solves a chunk's first sample cold (continuation from the reference
state; serially, warm from the chunk before it where that ended on the sample before) and each
next one warm from the last converged one; a warm solve that fails falls back to
continuation (:meth:`Simulation.solve`). Rows stream back as chunks finish; with an output
directory they are appended to ``study_rows.jsonl`` at once, and ``resume`` skips the samples
found there.
"""
import hashlib
import json
import time
from pathlib import Path

import numpy as np

from ...errors import ScenarioError, flag
from .design import Axis, build_design, rows_design
from .executors import describe, executor_of, run_dask, run_processes, run_serial
from ..parameters import check_range, resolve_parameter, shown_as_given
from .worker import OUTPUTS, Chunk, failure_row, output_kind, solve_chunk

#: samples per chunk at most
MAX_CHUNK = 500
#: ``solver.jit: auto`` compiles a study of at least this many samples (:attr:`Study.compiles`)
AUTO_JIT_SAMPLES = 5000
#: chunks per worker (load balance against one cold start per chunk)
CHUNKS_PER_WORKER = 4
#: the file rows stream into (deleted once the study's results are written)
PARTIAL = "study_rows.jsonl"


class Study:
    """A batch of solves of ``sim``'s scenario.

    Parameters
    ----------
    sim : Simulation
    vary : dict, optional
        ``{PATH: spec}``; a spec is ``[lo, hi]`` or ``[lo, hi, N]`` (a range; N values on a
        grid), ``{"normal": {"mean": m, "std": s}}``, ``{"uniform": [lo, hi]}`` (Monte Carlo
        axes) or ``{"values": [...]}``; numbers in the path's unit or strings with units.
    outputs : list of str, optional
        Further columns (:data:`~tca_casadi.studies.batch.worker.OUTPUTS`).
    design : str, optional
        grid | sobol | latin | random (default grid, random with a distribution).
    samples : int, optional
        Points of a sampling design (default 256).
    seed : int
        Seed of sobol, latin and random designs.
    rows : dict or str or Path, optional
        Explicit samples: ``{PATH: values}`` or a CSV whose columns are paths (a unit in
        brackets allowed: ``bending.tca1.temperature [degC]``); instead of ``vary``.
    """

    def __init__(self, sim, vary=None, outputs=(), design=None, samples=None, seed=0, rows=None):
        self.sim, self.outputs, self.seed = sim, list(outputs), int(seed)
        self.kinds = {}                  # path -> StudyParameter, or None for a structural path
        self.units = {}                  # structural path -> SI unit symbol, where given with one
        self.given = {}                  # path -> its first value as given ("0.5mm"): the unit to show it in
        self._meshes = {}                # structure -> (meshes, degree), fixed in this process
        self.nominal = None              # the Simulation solved at the scenario's own values
        if rows is not None and vary:
            raise ScenarioError("study: give varied paths or rows, not both")
        if rows is not None:
            table = read_rows(rows) if not isinstance(rows, dict) else rows
            self.kinds = {path: self._kind(path, list(values)[:1]) for path, values in table.items()}
            converted = {path: [self._si(path, v) for v in values] for path, values in table.items()}
            self.axes = [Axis(path, "values", values=values) for path, values in converted.items()]
            self.design = rows_design(converted, seed)
        else:
            self.axes = [self._axis(path, spec) for path, spec in (vary or {}).items()]
            self.design = build_design(self.axes, design, samples, seed)
        for name in self.outputs:
            if output_kind(name) is None:
                raise ScenarioError(f"study: unknown output {name!r}; outputs: "
                                    + "; ".join(text for text, _ in OUTPUTS.values()))
        self._check_bounds()
        self.structural = [p for p in self.design.paths if self.kinds[p] is None]
        self.parameters = [p for p in self.design.paths if self.kinds[p] is not None]

    # ------------------------------------------------------------------ axes
    def _kind(self, path, probe):
        """The StudyParameter of a parameter path, None for a structural one; ScenarioError for
        a path that is neither."""
        try:
            return resolve_parameter(self.sim.robot, self.sim.params, path)
        except ScenarioError:
            pass
        raw = self._raw()
        from ...scenario.loader import validate
        from ...scenario.overrides import apply_overrides
        from ...scenario.sources import SourceMap
        try:
            validate(apply_overrides(raw, {path: _plain(probe[0]) if len(probe) else 0}), SourceMap("<study>"))
        except ScenarioError as exc:
            text = str(exc).splitlines()[0].replace("<study>: ", "")
            raise ScenarioError(f"study: {path!r} is neither a parameter nor a scenario value ({text}); "
                                "`tca-casadi validate` lists the parameters") from None
        return None

    def _axis(self, path, spec):
        if isinstance(spec, (list, tuple)):
            if len(spec) not in (2, 3):
                raise ScenarioError(f"vary {path}: a range is [lo, hi] or [lo, hi, N], not {list(spec)!r}")
            spec = {"range": list(spec[:2]), "points": spec[2] if len(spec) == 3 else None}
        if not isinstance(spec, dict) or len(set(spec) & {"range", "normal", "uniform", "values"}) != 1:
            raise ScenarioError(f"vary {path}: give [lo, hi], [lo, hi, N], {{normal: {{mean, std}}}}, "
                                f"{{uniform: [lo, hi]}} or {{values: [...]}}, not {spec!r}")
        first = (spec.get("range") or spec.get("uniform") or spec.get("values")
                 or [spec["normal"].get("mean") if isinstance(spec.get("normal"), dict) else None])
        self.kinds[path] = self._kind(path, [first[0]])
        self.given[path] = first[0]
        si = lambda value, what="value": self._si(path, value, what)     # noqa: E731
        if "range" in spec or "uniform" in spec:
            bounds = spec.get("range") or spec.get("uniform")
            if not isinstance(bounds, (list, tuple)) or len(bounds) != 2:
                raise ScenarioError(f"vary {path}: a range is two values [lo, hi], not {bounds!r}")
            points = spec.get("points")
            if points is not None and (not float(points).is_integer() or int(points) < 1):
                raise ScenarioError(f"vary {path}: {points} points; give a whole number of at least 1")
            return Axis(path, "range" if "range" in spec else "uniform", si(bounds[0], "low"), si(bounds[1], "high"),
                        points=None if points is None else int(points))
        if "normal" in spec:
            normal = spec["normal"]
            if not isinstance(normal, dict) or set(normal) != {"mean", "std"}:
                raise ScenarioError(f"vary {path}: normal takes {{mean, std}}, not {normal!r}")
            mean, std = si(normal["mean"], "mean"), _difference(self, path, normal["std"])
            return Axis(path, "normal", mean=mean, std=std)
        return Axis(path, "values", values=[si(v) for v in spec["values"]])

    def shown(self, path):
        """``(factor, unit)``: a column of ``path`` (SI) times ``factor`` is in ``unit``, the unit its
        values were given in (else the scenario's, else a readable one; temperatures in degC)."""
        from ...units import in_unit, unit_given, unit_text, ureg
        parameter = self.kinds.get(path)
        if parameter is not None:
            axis = next((a for a in self.axes if a.path == path), None)
            values = [v for v in ([axis.low, axis.high, axis.mean] + list(axis.values or [])
                                  if axis is not None else []) if v is not None]
            parameter = shown_as_given(parameter, self.sim.scenario, self.given.get(path), values=values)
            return (1.0 if parameter.kind == "temperature" else in_unit(1.0, parameter.kind, parameter.display),
                    parameter.shown_unit)
        unit = unit_given(str(self.given.get(path, "")))
        if unit is None or path not in self.units:
            return 1.0, self.units.get(path, "SI")
        try:
            return float(ureg.Quantity(1.0, self.units[path]).to(unit).magnitude), unit_text(unit)
        except Exception:                              # (pint's many errors): shown as stored
            return 1.0, self.units[path]

    def _si(self, path, value, what="value"):
        parameter = self.kinds[path]
        if parameter is not None:
            return float(parameter.to_si(value, what))
        return _plain(value, self.units, path)

    def _raw(self):
        scenario = self.sim.scenario
        return scenario._raw if scenario._raw is not None else scenario.model_dump(mode="json")

    def _check_bounds(self):
        """A range that leaves what the scenario can hold (a TCA type's temperature range, a
        modulus that is not positive) is bad input before anything is solved."""
        for axis in self.axes:
            parameter = self.kinds.get(axis.path)
            if parameter is None or axis.kind not in ("range", "uniform", "values"):
                continue
            ends = axis.values if axis.kind == "values" else [axis.low, axis.high]
            check_range(self.sim.robot, parameter, *ends, params=self.sim.params)

    # ------------------------------------------------------------------ plan
    def groups(self):
        """``[(structure {path: value}, positions (k,) into the design)]`` in first-seen order."""
        columns = [self.design.paths.index(p) for p in self.structural]
        out = {}
        for position, values in enumerate(self.design.values):
            key = tuple(float(values[c]) for c in columns)
            out.setdefault(key, []).append(position)
        return [(dict(zip(self.structural, key)), np.array(positions)) for key, positions in out.items()]

    def chunks(self, workers=1):
        """The :class:`Chunk` s, each group's samples cut into about ``CHUNKS_PER_WORKER`` per
        worker (serial: :data:`MAX_CHUNK`)."""
        raw, out = self._raw(), []
        columns = [self.design.paths.index(p) for p in self.parameters]
        for structure, positions in self.groups():
            meshes, degree = self._mesh(structure)
            size = MAX_CHUNK if workers == 1 else max(1, min(MAX_CHUNK, -(-len(positions) // (CHUNKS_PER_WORKER * workers))))
            key = hashlib.sha256(json.dumps([raw, structure, repr(meshes), degree], sort_keys=True,
                                            default=str).encode()).hexdigest()[:16]
            for start in range(0, len(positions), size):
                part = positions[start:start + size]
                out.append(Chunk(key, raw, structure, meshes, degree, self.parameters,
                                 [int(i) for i in self.design.ids[part]],
                                 self.design.values[np.ix_(part, columns)].tolist(), self.outputs,
                                 self.sim.scenario._allow_code, self.compiles,
                                 int(self.design.ids[positions[start - 1]]) if start else None))
        return out

    @property
    def compiles(self):
        """Whether the workers run compiled (``solver.jit``): always with ``true``; with ``auto``
        for a study of :data:`AUTO_JIT_SAMPLES` samples or more where a C compiler is found (a
        compile of seconds, kept on disk, against about 3 ms saved per sample)."""
        from ...solvers.compiled import has_compiler
        jit = self.sim.scenario.solver.jit
        return jit is True or (jit == "auto" and self.design.size >= AUTO_JIT_SAMPLES and has_compiler())

    def _mesh(self, structure):
        """``(meshes, degree)`` of a structure: its collocation solver's after one cold,
        accuracy-controlled solve at the scenario's values (None for shooting)."""
        key = json.dumps(structure, sort_keys=True)
        if key not in self._meshes:
            from ...simulation import Simulation
            sim = self.sim if not structure else Simulation.from_file(self._raw(), structure,
                                                                      allow_code=self.sim.scenario._allow_code)
            if sim.method != "collocation":
                self._meshes[key] = (None, None)
            else:
                nominal = Simulation(sim.scenario) if sim is self.sim else sim
                nominal.solve(warn=False)
                solver = nominal.solver()
                self._meshes[key] = (tuple(solver.nlp.meshes), solver.degree)
                if not structure:
                    self.nominal = nominal
        return self._meshes[key]

    def plan_hash(self):
        """A digest of everything that fixes the rows (for ``resume``)."""
        text = json.dumps([self._raw(), self.design.paths, self.design.values.tolist(), self.design.ids.tolist(),
                           self.outputs], sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    # ------------------------------------------------------------------ run
    def run(self, executor=None, workers=None, scheduler=None, progress=None, directory=None, resume=False):
        """Solve every sample; a :class:`~tca_casadi.studies.batch.result.StudyResult`.

        ``executor``: None (serial, or from ``workers`` / ``scheduler``), an int (that many
        processes), a Dask address or ``Client``. ``progress(fraction, text)`` after every
        sample (serial) or chunk. ``directory``: rows are appended to ``study_rows.jsonl``
        there as they finish; ``resume`` first reads the rows of an interrupted run of the same
        study from it and solves only the rest."""
        if isinstance(executor, int):
            workers = executor
        elif executor is not None:
            scheduler = executor
        kind, target = executor_of(workers, scheduler)
        started = time.perf_counter()
        stream = _Stream(directory, self.plan_hash(), resume, self.design.size)
        rows = dict(stream.rows)
        cluster = _dask_workers(target) if kind == "dask" else None
        count = {"serial": 1, "processes": target}.get(kind) or cluster or 2
        todo = [c for c in (_without(c, rows) for c in self.chunks(count)) if c.ids]
        total, resumed = self.design.size, len(rows)
        clock = {"start": time.perf_counter()}

        def report():
            if progress is not None:
                done = len(rows)
                elapsed = time.perf_counter() - clock["start"]
                rate = (done - resumed) / elapsed if elapsed > 0 else 0.0
                eta = (total - done) / rate if rate > 0 else float("nan")
                progress(done / total, f"{done}/{total} samples, {rate:.0f}/s, ETA {eta:.0f} s")

        def finished(chunk, chunk_rows):
            for row in chunk_rows:
                rows[row["sample"]] = row
            stream.write(chunk_rows)
            report()

        def lost(chunk, reason):
            sim = self.sim
            finished(chunk, [dict(failure_row(sim, self.outputs, "lost", reason), sample=i, worker="",
                                  **{"wall_time [s]": 0.0}) for i in chunk.ids])

        def sample_done(row):
            rows[row["sample"]] = row
            stream.write([row])
            report()

        if kind == "serial":
            run_serial(todo, lambda chunk, chunk_rows: None, sample_done)
        elif kind == "processes":
            run_processes(todo, finished, target, lost)
        else:
            run_dask(todo, finished, target, lost)
        from .result import StudyResult
        return StudyResult.from_rows(self, [rows[i] for i in sorted(rows)], {
            "ran_on": describe(kind, target), "workers": target if kind != "dask" else cluster,
            "wall_time_s": time.perf_counter() - started, "resumed_samples": resumed,
            "compiled": self.compiles}, stream)

    def local_sensitivities(self):
        """``d tip / d value`` [m per unit] (3, p) of the parameter paths at the scenario's own
        values (the implicit function theorem on the collocation system), or None."""
        if self.structural or not self.parameters:
            return None
        self._mesh({})
        nominal = self.nominal
        solution = nominal.last if nominal is not None else None
        if solution is None or not solution.converged or solution.iterate.w is None:
            return None
        resolved = [resolve_parameter(nominal.robot, nominal.params, p) for p in self.parameters]
        linear = nominal.solver().linearise(solution.iterate.w, nominal.params)
        directions = np.column_stack([p.vector(nominal.params.size) for p in resolved])
        return linear.tip_derivative(directions)


class _Stream:
    """Rows appended to ``directory/study_rows.jsonl`` as they finish (first line: the plan's
    digest), and read back for ``resume``."""

    def __init__(self, directory, digest, resume, size):
        self.path = None if directory is None else Path(directory) / PARTIAL
        self.rows = {}
        if self.path is None:
            return
        if resume and self.path.exists():
            from ...tables import read_json_lines
            records = read_json_lines(self.path, f"study {flag('--resume')}")
            header = records[0] if records and isinstance(records[0], dict) else {}
            if header.get("plan") != digest:
                raise ScenarioError(f"study {flag('--resume')}: {self.path} holds rows of another study (its plan differs); "
                                    f"run without {flag('--resume')} to start again")
            for row in records[1:]:
                if not isinstance(row, dict) or not isinstance(row.get("sample"), int):
                    raise ScenarioError(f"study {flag('--resume')}: {self.path}: a row without its sample number; the file "
                                        f"is damaged (delete it, or run without {flag('--resume')})")
                self.rows[row["sample"]] = row
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.path.write_text(json.dumps({"plan": digest, "samples": size}) + "\n")

    def write(self, rows):
        if self.path is None or not rows:
            return
        with open(self.path, "a") as stream:
            stream.write("".join(json.dumps(row, default=float) + "\n" for row in rows))
            stream.flush()

    def close(self):
        """Delete the partial file (the study's results are written)."""
        if self.path is not None and self.path.exists():
            self.path.unlink()


def _without(chunk, rows):
    """The chunk minus the samples already in ``rows``."""
    keep = [k for k, i in enumerate(chunk.ids) if i not in rows]
    chunk.ids, chunk.values = [chunk.ids[k] for k in keep], [chunk.values[k] for k in keep]
    return chunk


def _dask_workers(target):
    """The number of workers of the Dask cluster at ``target`` (ScenarioError if it does not
    answer)."""
    from .executors import connect
    client, owned = connect(target)
    try:
        return len(client.scheduler_info().get("workers", {})) or None
    finally:
        if owned:
            client.close()


def _plain(value, units=None, path=None):
    """A structural value: a number as is, a string with a unit in SI base units (whose symbol
    is recorded in ``units[path]``)."""
    if isinstance(value, (int, float, np.floating, np.integer)):
        return float(value)
    from ...units import ureg
    try:
        quantity = ureg.Quantity(str(value)).to_base_units()
    except Exception as exc:                       # pint's many parse errors
        raise ScenarioError(f"study: cannot read {value!r} as a number with a unit ({exc})") from None
    if units is not None and not quantity.dimensionless:
        units[path] = f"{quantity.units:~}".replace(" ", "")
    return float(quantity.magnitude)


def _difference(study, path, value):
    """A standard deviation in the path's unit (a temperature's in kelvin = degC steps)."""
    parameter = study.kinds[path]
    if parameter is not None and parameter.kind == "temperature" and isinstance(value, str):
        from ...units import temperature_difference
        try:
            return temperature_difference(value)
        except ValueError as exc:
            raise ScenarioError(f"study: {path} std {value!r}: {exc}") from None
    return study._si(path, value, "std")


def read_rows(path):
    """``{PATH: values}`` from a CSV whose header names scenario paths (``[unit]`` suffixes are
    dropped: the values are in the path's unit); read by :func:`tca_casadi.tables.read_table`."""
    from ...tables import name_of, read_table
    table = read_table(path, f"study {flag('--rows')}", "samples file")
    return {name_of(name): table.column(k) for k, name in enumerate(table.header)}


__all__ = ["Study", "read_rows", "solve_chunk"]

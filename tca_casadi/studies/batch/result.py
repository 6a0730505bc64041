"""The result of a study: one row per sample as a pandas DataFrame, what the samples span, how
sensitive the tip is to each input, and the files (``study.parquet``, ``study.csv``,
``study.json``, plots).

**First-order sensitivity indices** ``S_i = Var(E[Y | X_i]) / Var(Y)`` from any design with
independent inputs (Sobol, Latin, random, Monte Carlo, grids): ``X_i`` is cut into ``B`` bins of
equal count (``B ~ sqrt(n)``, 5 to 50; a grid axis's own levels), the variance of the bins' means over the variance of ``Y`` is
the correlation ratio ``eta^2``, and its bias ``(B - 1) / (n - 1)`` (what bins of pure noise give)
is removed: ``S = (eta^2 - b) / (1 - b)``, clipped to [0, 1] (a full grid has no such bias: each
level averages the other inputs exactly, so ``S = eta^2`` there). ``local``: the exact derivatives of
the tip at the scenario's own values (implicit function theorem on the collocation system).
"""
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ...results import ResultAPI, status_of
from ...output import atomic_path, write_json
from .worker import BALANCE_EVERY

TIP = ["tip_x [m]", "tip_y [m]", "tip_z [m]"]
#: the columns that come first, in this order
LEADING = ["sample"]
TRAILING = ["balance [-]", "message", "wall_time [s]", "worker"]


class StudyResult(ResultAPI):
    """``frame``: a pandas DataFrame, one row per sample in the design's order (inputs with
    units, ``converged``, ``status``, iterations, solve time, tip pose, every tension and stroke,
    requested outputs, the message of a failure); ``info``: counts, throughput, wall time and
    where it ran; ``inputs``: the input columns' names."""

    def __init__(self, frame, info, inputs, study=None):
        self.frame, self.info, self.inputs, self.study = frame, info, inputs, study

    @classmethod
    def from_rows(cls, study, rows, run_info, stream=None):
        pd = _pandas()
        labels = [input_label(study, path) for path in study.design.paths]
        values = {int(i): v for i, v in zip(study.design.ids, study.design.values)}
        records = []
        for row in rows:
            record = {"sample": int(row["sample"])}
            record.update({label: float(v) for label, v in zip(labels, values[int(row["sample"])])})
            record.update({k: v for k, v in row.items() if k != "sample"})
            records.append(record)
        frame = pd.DataFrame.from_records(records)
        if len(frame):
            middle = [c for c in frame.columns if c not in LEADING + labels + TRAILING]
            frame = frame[LEADING + labels + middle + [c for c in TRAILING if c in frame.columns]]
        converged = int(frame["converged"].sum()) if len(frame) else 0
        checked = frame.loc[frame["converged"], "balance [-]"].dropna() if len(frame) else frame
        wall = run_info["wall_time_s"]
        solved = len(frame) - run_info.get("resumed_samples", 0)
        info = {"scenario": study.sim.scenario.name, "samples": len(frame), "converged": converged,
                "failed": len(frame) - converged, "design": study.design.kind, "seed": study.seed,
                "varied": [a.describe() for a in study.axes], "structural_paths": study.structural,
                "structure_groups": len(study.groups()), "outputs": study.outputs,
                "samples_per_second": solved / wall if wall > 0 else None,
                "balance_checked": len(checked), "balance_worst": float(checked.max()) if len(checked) else None,
                **run_info,
                "finished": datetime.now(timezone.utc).isoformat(timespec="seconds")}
        result = cls(frame, info, labels, study)
        result._stream = stream
        return result

    # ------------------------------------------------------------------ analysis
    @property
    def converged(self):
        """The rows of converged samples."""
        return self.frame[self.frame["converged"]] if len(self.frame) else self.frame

    def tips(self):
        """Tip positions (n, 3) [m] of the converged samples."""
        return self.converged[TIP].to_numpy(float)

    def workspace_hull(self):
        """The convex hull of the converged tips: ``{"points", "volume [m^3]", "area [m^2]",
        "vertices" (k, 3), "dimension"}``; a workspace that lies in a plane (or a line) has
        dimension 2 (1) and the area (length) of its hull in that plane."""
        from scipy.spatial import ConvexHull
        tips = self.tips()
        out = {"points": int(len(tips)), "volume [m^3]": 0.0, "area [m^2]": 0.0, "vertices": np.zeros((0, 3))}
        if len(tips) < 2:
            out["dimension"] = 0
            return out
        centred = tips - tips.mean(axis=0)
        _, singular, axes = np.linalg.svd(centred, full_matrices=False)
        scale = max(singular[0], 1e-300)
        dimension = int(np.sum(singular > 1e-9 * scale)) if singular[0] > 0 else 0
        out["dimension"] = dimension
        if dimension == 3 and len(tips) >= 4:
            hull = ConvexHull(tips)
            out.update({"volume [m^3]": float(hull.volume), "area [m^2]": float(hull.area),
                        "vertices": tips[hull.vertices]})
        elif dimension == 2 and len(tips) >= 3:
            plane = centred @ axes[:2].T
            hull = ConvexHull(plane)
            out.update({"area [m^2]": float(hull.volume), "vertices": tips[hull.vertices]})
        elif dimension >= 1:
            line = centred @ axes[0]
            out.update({"length [m]": float(np.ptp(line)), "vertices": tips[[np.argmin(line), np.argmax(line)]]})
        return out

    def sensitivity(self, method="sobol", outputs=TIP):
        """First-order sensitivity indices (``sobol``, the module docstring) of ``outputs`` to each
        input, a DataFrame (inputs x outputs); ``local``: ``d tip / d input`` [m per unit] at the
        scenario's values."""
        import pandas as pd
        if method == "local":
            derivative = self.study.local_sensitivities() if self.study is not None else None
            if derivative is None:
                raise ValueError("local sensitivities need parameter paths only and a converged nominal solve")
            columns = [f"d{c.split(' ')[0]}/d" for c in TIP]
            return pd.DataFrame(derivative.T, index=self.study.parameters, columns=columns)
        if method != "sobol":
            raise ValueError(f"method {method!r}: sobol or local")
        data = self.converged
        sampled = self.info["design"] != "grid"
        table = {column: [first_order_index(data[label].to_numpy(float), data[column].to_numpy(float),
                                            corrected=sampled) for label in self.inputs] for column in outputs}
        return pd.DataFrame(table, index=self.inputs)

    @property
    def result(self):
        """:class:`SolveStatus` of the study: success when every sample converged (a failed
        sample is a row, never absent)."""
        info = self.info
        return status_of(info["failed"] == 0, f"study ({info['design']})",
                         f"{info['failed']} of {info['samples']} samples failed" if info["failed"] else "",
                         nit=int(info["samples"]), solve_time_s=float(info["wall_time_s"]))

    @property
    def message(self):
        return self.result.message

    def figure(self):
        """``study_workspace.png``'s figure (the tip of every converged sample)."""
        from ...plotting.study_plots import plot_workspace
        return plot_workspace(self, None)

    def summary(self):
        info = self.info
        rate = info.get("samples_per_second")
        lines = [f"study of {info['scenario']}: {info['samples']} samples ({info['design']}), "
                 f"{info['converged']} converged, {info['failed']} failed, in {info['wall_time_s']:.2f} s"
                 + (f" ({rate:.0f} samples/s)" if rate else "") + f" on {info['ran_on']}"
                 + (", compiled (solver.jit)" if info.get("compiled") else "")]
        tips = self.tips()
        if len(tips):
            low, high = tips.min(axis=0) * 1e3, tips.max(axis=0) * 1e3
            lines.append("  tip range [mm]: " + ", ".join(f"{a} {lo:.3f} to {hi:.3f}"
                                                          for a, lo, hi in zip("xyz", low, high)))
            if any(a.distribution for a in self.study.axes) if self.study is not None else False:
                mean, std = tips.mean(axis=0) * 1e3, tips.std(axis=0, ddof=1) * 1e3 if len(tips) > 1 else np.zeros(3)
                lines.append("  tip mean +- std [mm]: " + ", ".join(f"{a} {m:.3f} +- {s:.3f}"
                                                                    for a, m, s in zip("xyz", mean, std)))
        if info.get("balance_checked") is not None and info["converged"]:
            worst = info["balance_worst"]
            lines.append(f"  global balance checked at {info['balance_checked']} of {info['converged']} converged samples "
                         f"(every {BALANCE_EVERY}th of a chunk and its last)"
                         + (f": worst {worst:.1e} of the forces in play" if worst is not None else ""))
        failed = self.frame[~self.frame["converged"]] if len(self.frame) else self.frame
        for _, row in failed.head(3).iterrows():
            lines.append(f"  failed: sample {row['sample']}: {row['status']}: {str(row['message'])[:160]}")
        return "\n".join(lines)

    # ------------------------------------------------------------------ files
    def to_dict(self):
        out = dict(self.info)
        if len(self.converged) >= 2:
            hull = self.workspace_hull()
            out["workspace"] = {k: v for k, v in hull.items() if k != "vertices"}
        return out

    def save(self, directory, plots=True, color=None, finish=True):
        """Write ``study.parquet``, ``study.csv``, ``study.json`` and, with ``plots``, the
        figures (:mod:`tca_casadi.plotting.study_plots`); the paths written. ``finish``: then
        delete the rows journal of the run (:meth:`finish`; the CLI does it once the files are
        in place)."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        written = []
        with atomic_path(directory / "study.parquet") as temporary:
            self.frame.to_parquet(temporary, index=False)
        written.append(directory / "study.parquet")
        with atomic_path(directory / "study.csv") as temporary:
            self.frame.to_csv(temporary, index=False, float_format="%.12g")
        written.append(directory / "study.csv")
        written.append(write_json(directory / "study.json", self.to_dict()))
        if plots:
            from ...plotting.study_plots import save_study_plots
            written += save_study_plots(self, directory, color)
        if finish:
            self.finish()
        return written

    def finish(self):
        """Delete the run's rows journal (``study_rows.jsonl``): its rows are in the results."""
        if getattr(self, "_stream", None) is not None:
            self._stream.close()


def _pandas():
    try:
        import pandas
    except ImportError:
        from ...errors import TcaError
        raise TcaError("studies need pandas and pyarrow: pip install 'tca_casadi[studies]'") from None
    return pandas


def input_label(study, path):
    """An input column's name: ``path [unit]`` (a structural path's in SI base units: the
    unit its values were given in, converted, else ``SI``)."""
    parameter = study.kinds.get(path)
    return parameter.si_label if parameter is not None else f"{path} [{study.units.get(path, 'SI')}]"


def first_order_index(x, y, bins=None, corrected=True):
    """First-order sensitivity index of ``y`` to ``x`` (module docstring): the correlation
    ratio over ``bins`` equal-count bins of x (default ``sqrt(n)``, 5 to 50; x's own levels when
    it has no more), bias-corrected for sampled designs (``corrected``; a full grid's levels
    average the other inputs exactly: no bias)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    n = x.size
    if n < 10 or np.var(y) == 0 or np.ptp(x) == 0:
        return float("nan")
    bins = bins or int(np.clip(round(np.sqrt(n)), 5, 50))
    levels, which = np.unique(x, return_inverse=True)
    if levels.size <= bins:                   # a grid axis: its own levels are the bins
        bins = levels.size
        groups = [y[which == k] for k in range(bins)]
    else:
        groups = np.array_split(y[np.argsort(x, kind="stable")], bins)
    means = np.array([g.mean() for g in groups])
    sizes = np.array([g.size for g in groups])
    eta2 = float(np.sum(sizes * (means - y.mean()) ** 2) / np.sum((y - y.mean()) ** 2))
    if not corrected:
        return float(np.clip(eta2, 0.0, 1.0))
    bias = (bins - 1) / (n - 1)
    return float(np.clip((eta2 - bias) / (1 - bias), 0.0, 1.0))

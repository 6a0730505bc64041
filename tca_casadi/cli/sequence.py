"""``sequence``: the scenario's steps in order, their drawings and animation."""
from pathlib import Path

from ..output import write_json
from .common import _results, _view, _vtk_files, _with_progress


def _sequence(args):
    from ..plotting.animation import save_animation, save_step_pngs
    from ..simulation import Simulation
    from ..studies.sequence.steps import run_sequence
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    frames = 0 if args.no_animation else max(args.frames, 0)
    stale = ["step_*.png"] + (["sequence.gif", "sequence.mp4"] if args.no_animation else []) + \
        ([] if args.check else ["sequence_check.json"])
    vtk, vtk_stale = _vtk_files(args, "sequence")
    view = _view(args)
    with _results(args, sim, "sequence", ["sequence.csv", "sequence_check.json", "sequence.gif", "sequence.mp4"] + vtk,
                  stale=stale + vtk_stale, default="sequence") as run:
        result = _with_progress(lambda progress: run_sequence(sim, frames_per_step=frames, progress=progress,
                                                              check=args.check), "steps", args.quiet)
        output = run.staging
        written = [result.to_csv(output / "sequence.csv"), *save_step_pngs(result, output, **view)]
        if args.check:
            reports = {name: report.to_dict() for name, report in zip(result.names, result.checks)}
            written.append(write_json(output / "sequence_check.json", reports))
        if not args.no_animation:
            written += _with_progress(lambda progress: save_animation(result, output, progress=progress, **view),
                                      "animation", args.quiet)
        if args.vtk:
            from ..vtk_files import write_series
            written += write_series([(float(k), solution, result.objects[k] if result.objects else ())
                                     for k, solution in enumerate(result.solutions)], output, "sequence")
    print(result.summary())
    print(f"wrote {len(written)} files to {run.directory}: sequence.csv, step PNGs"
          + ("" if args.no_animation else ", " + ", ".join(p.name for p in written if p.suffix in (".gif", ".mp4")))
          + (", VTK frames (sequence.pvd)" if args.vtk else ""))
    return 0 if result.converged and result.agree is not False else 1

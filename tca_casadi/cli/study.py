"""``study``: many samples of a scenario (serially, on processes or on Dask)."""
from pathlib import Path

from ..errors import ScenarioError
from .common import _results, _vary_spec, _with_progress


def _study(args):
    from ..simulation import Simulation
    from ..studies.batch.study import Study
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    vary = dict(_vary_spec(text, "--vary") for text in args.vary)
    for text in args.monte_carlo:
        path, spec = _vary_spec(text, "--monte-carlo")
        if path in vary:
            raise ScenarioError(f"--monte-carlo {path}: already varied by --vary")
        vary[path] = spec
    study = Study(sim, vary=vary, outputs=args.outputs, design=args.design, samples=args.samples,
                  seed=args.seed, rows=args.rows)
    plots = ["study_workspace.png", "study_monte_carlo.png", "study_response.png"]
    with _results(args, sim, "study", ["study.parquet", "study.csv", "study.json"] + plots, stale=plots,
                  default="study") as run:
        # the rows journal (study_rows.jsonl) lives in the output directory itself, so that
        # --resume finds the rows of a run that was killed; it goes once the results are in place
        result = _with_progress(lambda progress: study.run(workers=args.workers, scheduler=args.scheduler,
                                                           progress=progress, directory=run.directory,
                                                           resume=args.resume), "study", quiet=args.quiet)
        written = result.save(run.staging, plots=not args.no_plot, color=args.color, finish=False)
    result.finish()
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.info["failed"] == 0 else 1

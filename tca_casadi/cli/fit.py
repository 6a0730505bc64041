"""``fit``: calibration from measurements."""
from pathlib import Path

from ..errors import ScenarioError
from .common import _kelvin, _number, _results, _with_progress


def _fit(args):
    from ..simulation import Simulation
    from ..studies.fit.least_squares import Fit
    from ..units import to_si
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    sigmas = {}
    for text in args.sigma:
        kind, sep, value = text.partition("=")
        if not sep or kind not in ("length", "force", "temperature"):
            raise ScenarioError(f"--sigma {text!r}: give length=VALUE, force=VALUE or temperature=VALUE "
                                "(e.g. length=0.1mm)")
        try:
            sigmas[kind] = to_si(_number(value), kind) if kind != "temperature" else _kelvin(_number(value))
        except ValueError as exc:
            raise ScenarioError(f"--sigma {text!r}: {exc}") from None
        if not sigmas[kind] > 0:
            raise ScenarioError(f"--sigma {text!r}: give a positive value")
    bounds = {}
    for text in args.bounds:
        path, sep, rest = text.partition("=")
        parts = rest.split(":")
        if not sep or len(parts) != 2 or not all(p.strip() for p in parts):
            raise ScenarioError(f"--bounds {text!r}: give PATH=LO:HI")
        bounds[path.strip()] = (_number(parts[0]), _number(parts[1]))
    fit = Fit(sim, args.data, args.params, bounds=bounds, sigmas=sigmas, absolute_sigma=args.absolute_sigma,
              starts=args.starts, holdout=args.holdout, seed=args.seed)
    plots = ["fit.png", "fit_parameters.png"]
    if args.profile is not None and args.profile not in args.params:
        raise ScenarioError(f"--profile {args.profile}: not one of the fitted parameters (--param)")
    with _results(args, sim, "fit", ["fit.json", "fitted.yaml"] + plots, stale=plots if args.no_plot else [],
                  default="fit") as run:
        result = _with_progress(fit.run, "fit", quiet=args.quiet)
        if args.profile is not None:
            result.profile = fit.profile(result, args.profile)
        written = result.save(run.staging, plots=not args.no_plot)
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.converged else 1

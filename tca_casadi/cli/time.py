"""``simulate``: the robot in time (heating, dynamics, the closed loop)."""
from pathlib import Path

from ..errors import ScenarioError
from ..output import write_json
from .common import _results, _view, _vtk_files, _with_progress


def _simulate(args):
    from ..simulation import Simulation
    from ..time_simulation.timeline import TimeSimulation
    from ..units import to_si
    from ..control.mpc import mpc_drives
    overrides = list(args.overrides) + ([] if args.timeline is None else _timeline_overrides(args.timeline))
    sim = Simulation.from_file(Path(args.scenario), overrides, allow_code=args.allow_code)
    try:
        duration = None if args.duration is None else to_si(args.duration, "time")
        dt = to_si(args.dt, "time")
    except ValueError as exc:
        raise ScenarioError(f"--duration/--dt: {exc}") from None
    if mpc_drives(sim.scenario):
        return _closed_loop(args, sim, overrides, duration)
    if args.plant_overrides:
        raise ScenarioError("--plant-set makes the plant of a closed loop differ from its model; this scenario has "
                            "no mpc drive")
    timed = TimeSimulation(sim, duration=duration, dt=dt)
    plots = ["timeseries.png"]
    movies = ["simulate.gif", "simulate.mp4"]
    vtk, vtk_stale = _vtk_files(args, "simulate")
    view = _view(args)
    frames = []
    with _results(args, sim, "simulate", ["timeseries.csv", "simulation.json"] + plots + movies + vtk,
                  stale=(plots if args.no_plot else []) + (movies if args.no_animation else []) + vtk_stale,
                  default="simulate") as run:
        output = run.staging
        series = _with_progress(timed.run, "simulate", quiet=args.quiet)
        written = [series.to_csv(output / "timeseries.csv"),
                   write_json(output / "simulation.json", timed.report(series))]
        if not args.no_plot and series.solutions:
            from ..plotting.timeseries import save_timeseries_png
            from ..plotting.timeseries import event_labels
            written.append(save_timeseries_png(series, output / "timeseries.png", event_labels(sim.scenario.timeline)))
        print(timed.summary(series))
        if not args.no_animation and series.solutions:
            from ..plotting.animation import save_time_animation
            moving = {"fps": 20, "max_frames": 200} if sim.scenario.dynamics.enabled else {}   # motion: finer in time
            paths, speed_up = _with_progress(lambda progress: save_time_animation(series, output, progress=progress,
                                                                                  **moving, **view), "animation",
                                             quiet=args.quiet)
            written += paths
            print(f"animation at {'real time' if speed_up == 1 else f'{speed_up}x real time'}")
        if args.vtk and series.solutions:
            from ..vtk_files import write_series
            objects = series.objects or [()] * len(series.solutions)
            frames = write_series(zip(series.t, series.solutions, objects), output, "simulate")
    grids = [p for p in frames if p.suffix == ".vtu"]
    print("wrote " + ", ".join(str(p) for p in run.final(written + [p for p in frames if p.suffix != ".vtu"]))
          + (f" and {len(grids)} VTK grids (vtk_*.vtu, {len(series.solutions)} frames)" if frames else ""))
    return 0 if series.completed else 1


def _closed_loop(args, sim, overrides, duration):
    """``simulate`` of a scenario with mpc drives: the closed loop (:class:`ClosedLoop`),
    timeseries.csv (with the controller's solve time per period), simulation.json and
    timeseries.png (inputs, temperatures, distance to the target)."""
    from ..control.mpc import ClosedLoop
    from ..plotting.plan_plots import save_plan_png
    if args.vtk:
        raise ScenarioError("--vtk: a closed loop (an mpc drive) keeps the plant's tip and temperatures, not its "
                            "shapes; run simulate --timeline with the applied powers for VTK frames")
    loop = ClosedLoop(Path(args.scenario), overrides, args.plant_overrides, duration=duration,
                      allow_code=args.allow_code)
    with _results(args, sim, "simulate", ["timeseries.csv", "simulation.json", "timeseries.png"],
                  stale=(["timeseries.png"] if args.no_plot else []) + ["simulate.gif", "simulate.mp4"],
                  default="simulate") as run:
        result = _with_progress(loop.run, "closed loop", quiet=args.quiet)
        written = [result.to_csv(run.staging / "timeseries.csv"),
                   write_json(run.staging / "simulation.json", result.report())]
        if not args.no_plot:
            written.append(save_plan_png(result, run.staging / "timeseries.png"))
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.completed and result.reached else 1


def _timeline_overrides(path):
    """``--set`` overrides from a ``--timeline`` file: its ``timeline`` (and ``duration``)."""
    import json

    from ..scenario.yaml_safe import parse_yaml
    from ..tables import read_text
    data, _ = parse_yaml(read_text(path, "--timeline", "timeline YAML"), str(path))
    if not isinstance(data, dict) or not isinstance(data.get("timeline"), list):
        raise ScenarioError(f"--timeline {path}: expected a mapping with a 'timeline' list (and optionally a 'duration')")
    extra = set(data) - {"timeline", "duration"}
    if extra:
        raise ScenarioError(f"--timeline {path}: unknown key(s) {', '.join(sorted(map(str, extra)))}; "
                            "a timeline file holds 'timeline' and 'duration'")
    out = [f"timeline={json.dumps(data['timeline'])}"]
    if "duration" in data:
        out.append(f"duration={json.dumps(data['duration'])}")
    return out

"""``plan``: optimal heating schedules."""
import math
from pathlib import Path

from ..errors import ScenarioError
from .common import _quantities, _results, _with_progress


def _plan(args):
    from ..control import Plan
    from ..simulation import Simulation
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    from ..control.plan import read_path
    if args.objective == "track":
        if args.path is None or args.target_position is not None:
            raise ScenarioError("plan --objective track follows a --path CSV (and takes no --target-position)")
        target = read_path(args.path)
    else:
        if args.target_position is None or args.path is not None:
            raise ScenarioError(f"plan --objective {args.objective} needs --target-position X Y Z "
                                "(a --path is for --objective track)")
        target = _quantities(args.target_position, "length", "--target-position")
    options = {name: _quantities([getattr(args, name)], kind, f"--{name.replace('_', '-')}")[0]
               for name, kind in (("horizon", "time"), ("by", "time"), ("tolerance", "length"),
                                  ("power_budget", "power"))
               if getattr(args, name) is not None}
    if args.bounds is not None:
        options["bounds"] = list(args.bounds)             # each in its drive's unit (Plan converts)
    if args.angle_tolerance is not None:
        options["angle_tolerance"] = _quantities([args.angle_tolerance], "angle", "--angle-tolerance")[0]
    planner = Plan(sim, target, objective=args.objective, nodes=args.nodes, vary=args.vary, point=args.point,
                   direction=args.target_direction, **options)
    movies = ["plan.gif", "plan.mp4"]
    with _results(args, sim, "plan", ["plan.csv", "plan.json", "plan_timeline.yaml", "plan.png"] + movies,
                  stale=(["plan.png"] if args.no_plot else []) + ([] if args.animation else movies),
                  default="plan") as run:
        result = _with_progress(planner.solve, "plan", quiet=args.quiet)
        written = result.save(run.staging, plot=not args.no_plot)
        if args.animation and all(map(math.isfinite, result.tips.ravel())):      # no equilibrium: nothing to draw
            from ..plotting.animation import save_plan_animation
            paths, speed_up = _with_progress(
                lambda progress: save_plan_animation(result, planner.solutions(result), run.staging, max_frames=60,
                                                     progress=progress),
                "animation", quiet=args.quiet)
            written += paths
            print(f"animation at {'real time' if speed_up == 1 else f'{speed_up}x real time'}")
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.converged and result.reached else 1

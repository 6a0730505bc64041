"""``validate``, ``solve``, ``check``, ``sweep`` and ``inverse``: equilibria."""
import json
from pathlib import Path

from .common import _median, _number, _quantities, _results, _view, _vtk_files, _with_progress


def _validate(args):
    from ..model import Robot
    from ..scenario import load_scenario
    scenario = load_scenario(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    robot = Robot.from_scenario(scenario)
    print(f"{args.scenario}: valid scenario {scenario.name!r}: {len(robot.modules)} module(s), "
          f"{len(robot.tcas)} TCA(s), {_other_muscles(robot)}"
          f"{sum(a.kind == 'tendon' for a in robot.actuators)} tendon(s), "
          f"{len(scenario.loads)} load(s), {len(scenario.objects)} object(s); tip: "
          f"{robot.modules[robot.tip_index].name}")
    import numpy as np
    from ..model.history import history_names_of
    history = history_names_of(robot)
    names = [name for name in robot.layout.names() if name not in history]
    print(f"parameters ({len(names)}: --set or sweep them without rebuilding the model):")
    from ..scenario.written import written_value
    from ..units import UNIT_OF, unit_given
    for name in names:
        value = np.atleast_1d(robot.values[robot.layout[name]])
        text = f"{value[0]:.6g}" if value.size == 1 else "[" + ", ".join(f"{v:.6g}" for v in value) + "]"
        written = written_value(scenario, name) if value.size == 1 else None
        given = f"  ({written} as written)" if unit_given(written) and unit_given(written) != \
            UNIT_OF[robot.layout.kind(name)] else ""
        print(f"  {name:<44} {text} {UNIT_OF[robot.layout.kind(name)]}{given}")
    if history:
        kinds = sorted({".".join(name.split(".")[0:1] + ["NAME"] + name.split(".")[2:3]) for name in history})
        print(f"contact history ({len(history)} parameters {', '.join(k + '.*' for k in kinds)}: friction's anchors, "
              "each solve copies them from the solution it starts from)")
    _print_thermal(scenario, robot)
    return 0


def _other_muscles(robot):
    """``"3 sma muscle(s), "`` for every muscle kind but the TCA ("" if none)."""
    kinds = [a.kind for a in robot.muscles if a.kind != "tca"]
    return "".join(f"{kinds.count(k)} {k} muscle(s), " for k in dict.fromkeys(kinds))


def _print_thermal(scenario, robot):
    """Each TCA's lumped thermal model (heat capacity, conductance, time constant)."""
    from ..catalogue import thermal_kinds
    if robot.thermal_actuators:
        print(f"thermal (ambient {scenario.ambient_temperature:g} degC):")
    for actuator in robot.thermal_actuators:
        law = actuator.thermal_law(scenario)
        resistance = "" if law.resistance != law.resistance else f", R0 {law.resistance:.4g} ohm"
        print(f"  {actuator.key:<28} C {law.heat_capacity:.4g} J/K, G {law.conductance:.4g} W/K, "
              f"tau {law.time_constant:.3g} s{resistance}")
    if scenario.dynamics.enabled:
        from ..discretisation.dynamics import time_scale
        damping = scenario.dynamics.damping
        text = "undamped" if damping is None else (
            f"eta {damping.viscosity:g} Pa s" if damping.viscosity is not None else
            f"zeta {damping.ratio:g} at {damping.frequency:g} Hz")
        scales = ", ".join(f"{m.name} {time_scale(m):.3g} s" for m in robot.modules if m.weight_density > 0)
        print(f"dynamics ({scenario.dynamics.integrator}, {text}): time scale sqrt(rho A L^4 / EI): {scales}")
    for module in scenario.modules:
        if module.thermal_coupling is not None:
            names = [a.name for a in module.actuators if a.kind in thermal_kinds()]
            pairs = module.thermal_coupling.between or [(a, b) for i, a in enumerate(names) for b in names[i + 1:]]
            print(f"  {module.name}: {module.thermal_coupling.conductance:.4g} W/K between "
                  + ", ".join(f"{a}-{b}" for a, b in pairs))


def _solve(args):
    from ..simulation import Simulation
    sim = Simulation.from_file(Path(args.scenario), args.overrides, method=args.method, allow_code=args.allow_code)
    vtk, vtk_stale = _vtk_files(args, "solution")
    view = _view(args)
    with _results(args, sim, "solve", ["solution.json", "arrays.npz", "robot.png"] + vtk,
                  stale=(["robot.png"] if args.no_plot else []) + vtk_stale) as run:
        solution = sim.solve(warn=False)          # its warnings are in the summary and solution.json
        written = list(solution.save(run.staging))
        from ..studies.sequence.objects import object_poses
        objects = object_poses(sim.scenario, sim.robot, solution)
        if not args.no_plot:
            from ..plotting import save_robot_png
            written.append(save_robot_png(solution, run.staging / "robot.png", objects=objects, **view))
        if args.vtk:
            from ..vtk_files import write_series
            written += write_series([(0.0, solution, objects)], run.staging, "solution")
    if args.json:
        print(json.dumps(solution.to_dict(), indent=2))
    else:
        print(solution.summary())
        print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if solution.converged else 1


def _check(args):
    from ..simulation import Simulation
    from ..studies import check
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    with _results(args, sim, "check", ["check.json"]) as run:
        report, _, _ = check(sim, args.position_tolerance, args.tension_tolerance)
        path = report.save(run.staging / "check.json")
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(report.summary())
        print(f"wrote {run.final([path])[0]}")
    return 0 if report.agree else 1


def _sweep(args):
    from ..simulation import Simulation
    from ..studies import Sweep
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    sweep = Sweep(sim, args.params, _number(args.start), _number(args.stop), args.steps,
                  arclength=args.arclength, min_step=args.min_step)
    plots = ["sweep.png", "sweep_robots.png"]
    with _results(args, sim, "sweep", ["sweep.csv", "sweep.json"] + plots, stale=plots if args.no_plot else [],
                  default="sweep") as run:
        result = _with_progress(sweep.run, "sweep", quiet=args.quiet)
        written = result.save(run.staging, plots=not args.no_plot)
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.completed else 1


def _inverse(args):
    from ..simulation import Simulation
    from ..studies.inverse import InverseStatics, Target, read_targets, write_path_results
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    tolerance = None if args.tolerance is None else _quantities([args.tolerance], "length", "--tolerance")[0]
    solver = InverseStatics.from_scenario(sim, vary=args.vary, bounds=args.bounds, tolerance=tolerance,
                                          starts=args.starts, method=args.method)
    files = ["inverse_path.csv"] if args.path is not None else ["inverse.json", "solution.json",
                                                                 "arrays.npz", "inverse.png"]
    run = _results(args, sim, "inverse_path" if args.path is not None else "inverse", files,
                   stale=["inverse.png"] if args.no_plot and args.path is None else [], default="inverse")
    if args.path is not None:
        targets = read_targets(args.path, args.point or "tip")
        with run:
            results = _with_progress(lambda progress: solver.track(targets, progress), "inverse", args.quiet)
            written = write_path_results(run.staging / "inverse_path.csv", results)
        reached = sum(r.reachable for r in results)
        print(f"inverse path: {reached}/{len(results)} targets reached; "
              f"median {_median([r.solve_time_s for r in results]) * 1e3:.0f} ms per target")
        print(f"wrote {run.final([written])[0]}")
        return 0 if reached == len(results) else 1
    if args.target_position is None:
        target = solver.scenario_target(args.point)
    else:
        position = _quantities(args.target_position, "length", "--target-position")
        target = Target.create(position, args.target_direction, args.target_orientation, args.point or "tip")
    with run:
        result = solver.solve(target)
        written = result.save(run.staging, plot=not args.no_plot)
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.reachable and result.verified else 1

"""Command line: ``tca-casadi validate|solve|check|sweep|inverse|sequence|simulate|plan|study|fit SCENARIO ...``.

Exit codes: 0 success, 1 the solver did not converge (``check``: the solvers disagree),
2 bad input (one line on stderr). ``sweep``: 1 when the run stopped before the stop value;
``inverse``: 1 when a target is unreachable (the closest pose is still written); ``study``: 1
when some samples did not converge (they are rows with their reason); ``fit``: 1 when the least
squares did not converge.
"""
import argparse
import math
import json
import logging
import signal
import sys
from pathlib import Path

from .errors import ScenarioError, TcaError
from .output import ResultSet, default_directory, write_json


def _scenario_arguments(parser):
    parser.add_argument("scenario", help="scenario YAML file")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                        help="override a scenario value by dotted path, e.g. bending.tca2.temperature=100 "
                             "(repeatable)")
    parser.add_argument("--allow-code", action="store_true",
                        help="run the Python module that a custom muscle law's entry_point names (a scenario "
                             "with one is refused without this; allow only code you trust)")


def _output_arguments(parser, default, plots):
    """``-o/--output``, ``--no-plot`` (what ``plots`` names) and ``--quiet``."""
    parser.add_argument("-o", "--output", type=Path, default=None,
                        help=f"output directory (default: results/<scenario name>/{default})")
    parser.add_argument("--no-plot", action="store_true", help=f"do not draw {plots}")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def _view_arguments(parser):
    """``--view AZIMUTH,ELEVATION`` and ``--projection xy|xz|yz`` of the robot drawings."""
    parser.add_argument("--view", default=None, metavar="AZ,EL",
                        help="camera of the robot drawings: azimuth,elevation [deg], e.g. -60,20")
    parser.add_argument("--projection", default=None, choices=["xy", "xz", "yz"],
                        help="draw the robot projected onto a coordinate plane (orthographic) instead")


def _view(args):
    from .plotting.robot3d import view_of
    return view_of(getattr(args, "view", None), getattr(args, "projection", None))


def build_parser():
    parser = argparse.ArgumentParser(
        prog="tca-casadi",
        description="Shape and motion of soft robots driven by TCAs and tendons (Cosserat rods, "
                    "CasADi collocation + Newton/IPOPT).")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    validate = commands.add_parser("validate", help="check a scenario file and print what it holds")
    _scenario_arguments(validate)

    solve = commands.add_parser("solve", help="solve one equilibrium; write JSON, NPZ and a PNG")
    _scenario_arguments(solve)
    solve.add_argument("-o", "--output", type=Path, default=None,
                       help="output directory (default: results/<scenario name>)")
    solve.add_argument("--json", action="store_true", help="print solution.json to stdout")
    solve.add_argument("--no-plot", action="store_true", help="do not draw robot.png")
    _view_arguments(solve)
    solve.add_argument("--vtk", action="store_true", help="also VTK files for ParaView: vtk_NNNN_rods.vtu, _actuators.vtu, _surfaces.vtu, solution.pvd (the frames in time) and solution_names.json")
    solve.add_argument("--method", choices=["collocation", "shooting"], default=None,
                       help="solver (default: the scenario's, collocation)")

    check = commands.add_parser("check", help="solve by collocation and by shooting; report the difference")
    _scenario_arguments(check)
    check.add_argument("-o", "--output", type=Path, default=None,
                       help="output directory for check.json (default: results/<scenario name>)")
    check.add_argument("--position-tolerance", type=float, default=1e-6, metavar="M",
                       help="allowed tip and centerline difference [m] (default 1e-6)")
    check.add_argument("--tension-tolerance", type=float, default=1e-5, metavar="REL",
                       help="allowed relative tension difference (default 1e-5)")
    check.add_argument("--json", action="store_true", help="print check.json to stdout")

    sweep = commands.add_parser("sweep", help="continuation over parameters; write sweep.csv and plots")
    _scenario_arguments(sweep)
    sweep.add_argument("--param", dest="params", action="append", required=True, metavar="PATH",
                       help="parameter to move (repeatable; all move together), e.g. "
                            "bending.tca2.temperature, cable.tension, payload.force.x, gravity.magnitude")
    sweep.add_argument("--from", dest="start", required=True, metavar="VALUE",
                       help="start value, in the parameter's unit (degC, N, m/s^2) or with a unit ('5 mN')")
    sweep.add_argument("--to", dest="stop", required=True, metavar="VALUE", help="stop value")
    sweep.add_argument("--steps", type=int, default=51, help="number of points, ends included (default 51)")
    sweep.add_argument("--arclength", action="store_true",
                       help="pseudo-arclength continuation: follow the branch through folds")
    sweep.add_argument("--min-step", type=float, default=1e-4, metavar="FRACTION",
                       help="smallest step, as a fraction of the range, before a run stops (default 1e-4)")
    _output_arguments(sweep, "sweep", "sweep.png and sweep_robots.png")

    inverse = commands.add_parser("inverse", help="inverse statics: TCA temperatures (or other muscles' inputs) for a target tip pose")
    _scenario_arguments(inverse)
    inverse.add_argument("--target-position", nargs=3, metavar=("X", "Y", "Z"),
                         help="target position [m] (or with units, '12 mm'); default: the scenario's inverse.target")
    where = inverse.add_mutually_exclusive_group()
    where.add_argument("--target-direction", nargs=3, type=float, metavar=("DX", "DY", "DZ"),
                       help="also aim the point's tangent along this direction")
    where.add_argument("--target-orientation", nargs=4, type=float, metavar=("QW", "QX", "QY", "QZ"),
                       help="also match this orientation (quaternion) of the point's frame")
    inverse.add_argument("--point", default=None, help="'tip' (default) or a module name (its end)")
    inverse.add_argument("--vary", action="append", default=None, metavar="PATH",
                         help="input to vary: a TCA or SMA temperature, a McKibben pressure... "
                              "(repeatable; default: every muscle's)")
    inverse.add_argument("--bounds", nargs=2, metavar=("LO", "HI"),
                         help="bounds of the inputs, in their units (degC, Pa; default: each TCA or SMA "
                              "type's reference to max temperature, 0 to a McKibben type's max_pressure)")
    inverse.add_argument("--tolerance", default=None, metavar="M",
                         help="position error under which the target counts as reached (default 0.1 mm)")
    inverse.add_argument("--starts", type=int, default=None, help="initial temperature sets tried (default 4)")
    inverse.add_argument("--method", choices=["ipopt", "reduced"], default=None,
                         help="reduced (default): least squares over the temperatures with the equilibrium "
                              "solved and differentiated exactly; ipopt: the full-space NLP (slower)")
    inverse.add_argument("--path", type=Path, default=None, metavar="CSV",
                         help="a CSV of targets (x, y, z [m], optional dx, dy, dz or qw..qz): one answer per row")
    _output_arguments(inverse, "inverse", "inverse.png")

    sequence = commands.add_parser("sequence", help="solve the scenario's sequence: steps; table, PNGs, animation")
    _scenario_arguments(sequence)
    sequence.add_argument("-o", "--output", type=Path, default=None,
                          help="output directory (default: results/<scenario name>/sequence)")
    sequence.add_argument("--frames", type=int, default=6,
                          help="intermediate frames per transition in the animation (default 6)")
    sequence.add_argument("--no-animation", action="store_true", help="no GIF/MP4")
    _view_arguments(sequence)
    sequence.add_argument("--vtk", action="store_true", help="also VTK files for ParaView (a frame per step): vtk_NNNN_rods.vtu, _actuators.vtu, _surfaces.vtu, sequence.pvd (the frames in time) and sequence_names.json")
    sequence.add_argument("--check", action="store_true",
                          help="also solve every step by shooting and compare (as `check` does); "
                               "writes sequence_check.json")
    sequence.add_argument("--quiet", action="store_true", help="no progress bars")

    simulate = commands.add_parser("simulate", help="run the scenario's timeline in time: heated TCAs, the shape "
                                   "at every output time; timeseries.csv, simulation.json, timeseries.png")
    _scenario_arguments(simulate)
    simulate.add_argument("-o", "--output", type=Path, default=None,
                          help="output directory (default: results/<scenario name>/simulate)")
    simulate.add_argument("--duration", default=None, help="[s] (units allowed: '30 s'); default the scenario's")
    simulate.add_argument("--dt", default="0.1", help="output step [s] (default 0.1); with dynamics, the time step")
    _view_arguments(simulate)
    simulate.add_argument("--vtk", action="store_true", help="also VTK files for ParaView (a frame per output time): vtk_NNNN_rods.vtu, _actuators.vtu, _surfaces.vtu, simulate.pvd (the frames in time) and simulate_names.json")
    simulate.add_argument("--timeline", type=Path, default=None, metavar="YAML",
                          help="a file with a timeline (and optionally a duration) that replaces the scenario's, "
                               "e.g. a plan's plan_timeline.yaml")
    simulate.add_argument("--plant-set", dest="plant_overrides", action="append", default=[], metavar="PATH=VALUE",
                          help="with an mpc drive: make the simulated plant differ from the controller's model, "
                               "e.g. 'materials.ecoflex30.youngs_modulus=0.1375 MPa' (repeatable)")
    simulate.add_argument("--no-plot", action="store_true", help="no timeseries.png")
    simulate.add_argument("--no-animation", action="store_true",
                          help="no simulate.gif / simulate.mp4 (the robot in time, with a clock)")
    simulate.add_argument("--quiet", action="store_true", help="no progress bar")

    plan = commands.add_parser("plan", help="optimal heating schedule: the TCA powers over time that bring the tip "
                               "to a target fastest or with the least energy; plan.csv, plan.json, plan.png")
    _scenario_arguments(plan)
    plan.add_argument("--target-position", nargs=3, metavar=("X", "Y", "Z"),
                      help="target tip position [m] (or with units, '12 mm'); time and energy")
    plan.add_argument("--target-direction", nargs=3, type=float, metavar=("DX", "DY", "DZ"),
                      help="also aim the point's tangent along this direction (time and energy)")
    plan.add_argument("--angle-tolerance", default=None, metavar="ANGLE",
                      help="with --target-direction: the angle counted as reached [rad] (or with units, '0.5 deg'; default 1 deg)")
    plan.add_argument("--point", default="tip", help="'tip' (default) or a module name: the point (its end) to bring "
                                                      "to the target")
    plan.add_argument("--path", type=Path, default=None, metavar="CSV",
                      help="track: the tip path, a CSV with columns t [s], x, y, z [m] (units in the header)")
    plan.add_argument("--objective", choices=["time", "energy", "track"], default="time",
                      help="time (default): reach the target as early as the bounds allow and hold it; energy: "
                           "hold it from --by on with the least electrical energy; track: follow --path")
    plan.add_argument("--horizon", default="30", help="[s] from t = 0 (units allowed; default 30 s)")
    plan.add_argument("--nodes", type=int, default=60, help="time steps on the horizon (default 60)")
    plan.add_argument("--by", default=None, help="energy: the time [s] from which the target is held (default the "
                                                 "horizon's end)")
    plan.add_argument("--vary", action="append", default=None, metavar="PATH",
                      help="a heated TCA's drive value to plan (MODULE.TCA.drive.value; repeatable; default every "
                           "heated TCA's)")
    plan.add_argument("--bounds", nargs=2, metavar=("LO", "HI"),
                      help="bounds of the inputs, in their drives' units (W, V or A; units allowed, '3 V'; "
                           "default 0 to the value that holds each TCA at its type's max_temperature)")
    plan.add_argument("--tolerance", default=None, metavar="M",
                      help="distance from the target within which it counts as reached (default 0.1 mm)")
    plan.add_argument("--power-budget", default=None, metavar="W",
                      help="the heated TCAs' total power at every step at most this [W] (units allowed, '500 mW')")
    _output_arguments(plan, "plan", "plan.png")
    plan.add_argument("--animation", action="store_true",
                      help="also plan.gif (and plan.mp4 with ffmpeg): the robot at every node, with a clock")

    study = commands.add_parser("study", help="solve many samples (workspace maps, Monte Carlo, design sweeps) "
                                "serially, on local processes or a Dask cluster; study.parquet, study.csv, plots")
    _scenario_arguments(study)
    study.add_argument("--vary", action="append", default=[], metavar="PATH=LO:HI[:N]",
                       help="a range of a scenario path (N values on a grid; units allowed: 25degC:125degC:11)")
    study.add_argument("--monte-carlo", action="append", default=[], metavar="PATH=normal:MEAN:STD",
                       help="a distribution of a path: normal:MEAN:STD or uniform:LO:HI")
    study.add_argument("--rows", type=Path, default=None, metavar="CSV",
                       help="explicit samples: a CSV whose columns are scenario paths (instead of --vary)")
    study.add_argument("--design", choices=["grid", "sobol", "latin", "random"], default=None,
                       help="how ranges are sampled (default grid; random with --monte-carlo)")
    study.add_argument("--samples", type=int, default=None, help="points of a sobol/latin/random design (default 256)")
    study.add_argument("--seed", type=int, default=0, help="seed of sobol, latin and random designs (default 0)")
    study.add_argument("--outputs", nargs="+", default=[], metavar="NAME",
                       help="further columns: MODULE.tip_x|tip_y|tip_z, ACTUATOR.length|free_stroke|slack_length, "
                            "max_residual")
    where = study.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, metavar="K", help="a pool of K local processes")
    where.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="a Dask scheduler (tcp://host:8786; default $DASK_SCHEDULER_ADDRESS if set)")
    study.add_argument("--resume", action="store_true",
                       help="continue an interrupted study in the same output directory")
    study.add_argument("--color", default=None, metavar="COLUMN",
                       help="the column that colours the workspace plot (default the first input)")
    _output_arguments(study, "study", "the study PNGs")

    fit = commands.add_parser("fit", help="calibrate parameters to measurements (weighted least squares, exact "
                              "Jacobians); fit.json with intervals and correlations, fitted.yaml, plots")
    _scenario_arguments(fit)
    fit.add_argument("--data", required=True, type=Path, metavar="CSV",
                     help="one row per experiment: inputs by scenario path [unit], measured columns (tip_x [mm], "
                          "MODULE.tip_x, ACTUATOR.stroke, ACTUATOR.tension) and optional sigma_NAME columns")
    fit.add_argument("--param", dest="params", action="append", required=True, metavar="PATH",
                     help="a parameter to fit (any NLP parameter, e.g. materials.ecoflex30.youngs_modulus); repeatable")
    fit.add_argument("--bounds", action="append", default=[], metavar="PATH=LO:HI", help="bounds of a fitted parameter")
    fit.add_argument("--sigma", action="append", default=[], metavar="KIND=VALUE",
                     help="standard deviation of measurements without a sigma column: length=0.1mm, force=1mN, "
                          "temperature=0.5K (the defaults)")
    fit.add_argument("--absolute-sigma", action="store_true",
                     help="trust the sigmas (do not scale the covariance by the residual variance)")
    fit.add_argument("--starts", type=int, default=1, help="starting points in the bounds (default 1: the nominal)")
    fit.add_argument("--holdout", type=float, default=None, metavar="FRACTION",
                     help="leave this fraction of the experiments out of the fit and report their error")
    fit.add_argument("--seed", type=int, default=0, help="seed of --holdout and --starts (default 0)")
    fit.add_argument("--profile", default=None, metavar="PATH",
                     help="also the profile likelihood of this fitted parameter (its 95 %% interval, to compare "
                          "with the Wald interval)")
    _output_arguments(fit, "fit", "fit.png and fit_parameters.png")
    return parser


def main(argv=None):
    """Run one command; the exit code (0, 1, 2, or 130 when interrupted). Run as the program
    (``argv`` None), an interrupt ends the process at once with status 130 (see
    :func:`_exit_interrupted`), whatever the parent did with SIGINT (a shell's background job
    starts with it ignored)."""
    if argv is None:
        _take_interrupts()
    try:
        args = build_parser().parse_args(argv)
        logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                            format="%(levelname)s %(name)s: %(message)s")
        return COMMANDS[args.command](args)
    except ScenarioError as exc:
        print("\n".join(f"error: {line}" for line in str(exc).splitlines()), file=sys.stderr)
        return 2
    except TcaError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except (MemoryError, RuntimeError) as exc:
        from .resources import is_out_of_memory, memory_limit
        if not is_out_of_memory(exc):
            raise
        print(f"error: out of memory ({memory_limit()}): the problem is too large for "
              "this machine; lower solver.max_intervals or solver.intervals, the number of samples, steps or output "
              "times; no result was written", file=sys.stderr)
        return 1
    except BrokenPipeError:            # the reader left (``| head``): not an error of ours
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        if argv is None:                 # a second Ctrl-C must not break the one-line report
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        print("interrupted: no result of this run was written (the output directory keeps what it held; "
              "a study goes on from its solved rows with --resume)", file=sys.stderr)
        if argv is None:
            _exit_interrupted()
        return 130


def _take_interrupts():
    """Ctrl-C raises KeyboardInterrupt in this process, even where the parent ignored SIGINT
    (Python keeps an inherited ``SIG_IGN``)."""
    signal.signal(signal.SIGINT, signal.default_int_handler)


def _exit_interrupted():
    """Exit with status 130 now. A Ctrl-C that lands during some extension imports (seen during
    casadi's, about 0.8 s after start) leaves CPython 3.11 treating the interrupt as unhandled
    even though we caught it: at exit it kills itself with SIGINT (status -2, not 130).
    ``os._exit`` after flushing avoids that; result files are written atomically, so nothing is
    left half-written."""
    import os
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(130)


def _validate(args):
    from .model import Robot
    from .scenario import load_scenario
    scenario = load_scenario(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    robot = Robot.from_scenario(scenario)
    print(f"{args.scenario}: valid scenario {scenario.name!r}: {len(robot.modules)} module(s), "
          f"{len(robot.tcas)} TCA(s), {_other_muscles(robot)}"
          f"{sum(a.kind == 'tendon' for a in robot.actuators)} tendon(s), "
          f"{len(scenario.loads)} load(s), {len(scenario.objects)} object(s); tip: "
          f"{robot.modules[robot.tip_index].name}")
    import numpy as np
    from .model.history import history_names_of
    history = history_names_of(robot)
    names = [name for name in robot.layout.names() if name not in history]
    print(f"parameters ({len(names)}: --set or sweep them without rebuilding the model):")
    from .scenario.written import written_value
    from .units import UNIT_OF, unit_given
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
    from .model.laws import thermal_kinds
    if robot.thermal_actuators:
        print(f"thermal (ambient {scenario.ambient_temperature:g} degC):")
    for actuator in robot.thermal_actuators:
        law = actuator.thermal_law(scenario)
        resistance = "" if law.resistance != law.resistance else f", R0 {law.resistance:.4g} ohm"
        print(f"  {actuator.key:<28} C {law.heat_capacity:.4g} J/K, G {law.conductance:.4g} W/K, "
              f"tau {law.time_constant:.3g} s{resistance}")
    if scenario.dynamics.enabled:
        from .discretisation.dynamics import time_scale
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
    from .simulation import Simulation
    sim = Simulation.from_file(Path(args.scenario), args.overrides, method=args.method, allow_code=args.allow_code)
    vtk, vtk_stale = _vtk_files(args, "solution")
    view = _view(args)
    with _results(args, sim, "solve", ["solution.json", "arrays.npz", "robot.png"] + vtk,
                  stale=(["robot.png"] if args.no_plot else []) + vtk_stale) as run:
        solution = sim.solve(warn=False)          # its warnings are in the summary and solution.json
        written = list(solution.save(run.staging))
        from .studies.objects import object_poses
        objects = object_poses(sim.scenario, sim.robot, solution)
        if not args.no_plot:
            from .plotting import save_robot_png
            written.append(save_robot_png(solution, run.staging / "robot.png", objects=objects, **view))
        if args.vtk:
            from .vtk_files import write_series
            written += write_series([(0.0, solution, objects)], run.staging, "solution")
    if args.json:
        print(json.dumps(solution.to_dict(), indent=2))
    else:
        print(solution.summary())
        print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if solution.converged else 1


def _check(args):
    from .simulation import Simulation
    from .studies import check
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
    from .simulation import Simulation
    from .studies import Sweep
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
    from .simulation import Simulation
    from .studies.inverse import InverseStatics, Target, read_targets, write_path_results
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


def _sequence(args):
    from .plotting.animation import save_animation, save_step_pngs
    from .simulation import Simulation
    from .studies.sequence import run_sequence
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
            from .vtk_files import write_series
            written += write_series([(float(k), solution, result.objects[k] if result.objects else ())
                                     for k, solution in enumerate(result.solutions)], output, "sequence")
    print(result.summary())
    print(f"wrote {len(written)} files to {run.directory}: sequence.csv, step PNGs"
          + ("" if args.no_animation else ", " + ", ".join(p.name for p in written if p.suffix in (".gif", ".mp4")))
          + (", VTK frames (sequence.pvd)" if args.vtk else ""))
    return 0 if result.converged and result.agree is not False else 1


def _vtk_files(args, name):
    """``(files, stale)`` of a command's VTK output: the frames and ``NAME.pvd`` with ``--vtk``,
    else the same as files an earlier run may have left."""
    files = ["vtk_*.vtu", f"{name}.pvd", f"{name}_names.json"]
    return (files, []) if args.vtk else ([], files)


def _results(args, sim, command, files, stale=(), default=None):
    """The :class:`~tca_casadi.output.ResultSet` of a command's output directory (``-o``, else
    ``results/<scenario name>[/default]``): prepared on entering, made visible on leaving."""
    directory = args.output or default_directory(sim.scenario.name, *([default] if default else []))
    return ResultSet(directory, command, files, stale, argv=sys.argv[1:], scenario=str(args.scenario))


def _median(values):
    import statistics
    return statistics.median(values)


def _quantities(values, kind, option):
    """SI values of command-line numbers or quantities with units (``'12 mm'``) of ``kind``;
    a bad one is a ScenarioError naming ``option``."""
    from .units import to_si
    try:
        return [to_si(_number(v), kind) for v in values]
    except ValueError as exc:
        raise ScenarioError(f"{option}: {exc}") from None


def _number(text):
    """A plain number where the text is one; else the text (a value with a unit)."""
    try:
        return float(text)
    except ValueError:
        return text


def _with_progress(run, label, quiet=False):
    """Call ``run(progress=...)`` with a rich progress bar on stderr (none if quiet or not a TTY,
    where a long run says once, from its first steps, how long it will take: :class:`_Pace`)."""
    if quiet or not sys.stderr.isatty():
        return run(progress=_Pace(label))
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
    columns = (TextColumn(f"{label} "), BarColumn(), TextColumn("{task.percentage:>5.1f}%"),
               TextColumn("{task.description}"), TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True), transient=True) as bar:
        task = bar.add_task("", total=1.0)
        return run(progress=lambda fraction, text: bar.update(task, completed=fraction, description=text))


class _Pace:
    """A progress callback that, once a run has gone on for :data:`PACE_AFTER` seconds since its
    first progress (the build and first solve left out), prints one line to stderr if at its
    pace so far it still has more than :data:`LONG_RUN` seconds to go."""

    def __init__(self, label):
        import time
        self.label, self.clock, self.first, self.said = label, time.perf_counter, None, False

    def __call__(self, fraction, text=""):
        if self.said:
            return
        now = self.clock()
        if self.first is None:
            self.first = (now, fraction)
            return
        (started, done), elapsed = self.first, now - self.first[0]
        if elapsed < PACE_AFTER or fraction <= done:
            return
        self.said = True
        left = (1.0 - fraction) * elapsed / (fraction - done)
        if left > LONG_RUN:
            print(f"{self.label}: {100 * fraction:.2g} % done; about {_duration(left)} to go at this pace "
                  "(Ctrl-C stops it)", file=sys.stderr, flush=True)


#: seconds of progress a run is timed over before it may say how long it will take ...
PACE_AFTER = 3.0
#: ... which it says when that is more than this [s]
LONG_RUN = 120.0


def _duration(seconds):
    """``3 h 20 min``, ``12 min``, ``45 s``."""
    if seconds >= 3600 * 48:
        return f"{seconds / 86400:.3g} days"
    if seconds >= 3600:
        return f"{int(seconds // 3600)} h {int(seconds % 3600 // 60)} min"
    if seconds >= 60:
        return f"{int(seconds // 60)} min"
    return f"{seconds:.0f} s"


def _simulate(args):
    from .simulation import Simulation
    from .studies.timeline import TimeSimulation
    from .units import to_si
    from .control.mpc import mpc_drives
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
            from .plotting.timeseries import save_timeseries_png
            from .plotting.timeseries import event_labels
            written.append(save_timeseries_png(series, output / "timeseries.png", event_labels(sim.scenario.timeline)))
        print(timed.summary(series))
        if not args.no_animation and series.solutions:
            from .plotting.animation import save_time_animation
            moving = {"fps": 20, "max_frames": 200} if sim.scenario.dynamics.enabled else {}   # motion: finer in time
            paths, speed_up = _with_progress(lambda progress: save_time_animation(series, output, progress=progress,
                                                                                  **moving, **view), "animation",
                                             quiet=args.quiet)
            written += paths
            print(f"animation at {'real time' if speed_up == 1 else f'{speed_up}x real time'}")
        if args.vtk and series.solutions:
            from .vtk_files import write_series
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
    from .control.mpc import ClosedLoop
    from .plotting.plan_plots import save_plan_png
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

    from .scenario.yaml_safe import parse_yaml
    from .tables import read_text
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


def _plan(args):
    from .control import Plan
    from .simulation import Simulation
    sim = Simulation.from_file(Path(args.scenario), args.overrides, allow_code=args.allow_code)
    from .control.plan import read_path
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
            from .plotting.animation import save_plan_animation
            paths, speed_up = _with_progress(
                lambda progress: save_plan_animation(result, planner.solutions(result), run.staging, max_frames=60,
                                                     progress=progress),
                "animation", quiet=args.quiet)
            written += paths
            print(f"animation at {'real time' if speed_up == 1 else f'{speed_up}x real time'}")
    print(result.summary())
    print("wrote " + ", ".join(str(p) for p in run.final(written)))
    return 0 if result.converged and result.reached else 1


def _study(args):
    from .simulation import Simulation
    from .studies.study import Study
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


def _fit(args):
    from .simulation import Simulation
    from .studies.fit import Fit
    from .units import to_si
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


def _kelvin(value):
    """A temperature difference [K] from a number or ``"0.5 K"`` (degC steps are kelvin)."""
    if isinstance(value, float):
        return value
    from .units import ureg
    try:
        return float(ureg.Quantity(value.replace("degC", "K")).to("K").magnitude)
    except Exception:                       # pint's parse and dimension errors
        raise ValueError(f"{value!r} is not a temperature difference (e.g. 0.5 K)") from None


def _vary_spec(text, option):
    """``(path, spec)`` of ``PATH=LO:HI[:N]`` (--vary) or ``PATH=normal:MEAN:STD`` /
    ``PATH=uniform:LO:HI`` (--monte-carlo)."""
    path, sep, rest = text.partition("=")
    parts = rest.split(":")
    if not sep or not path.strip():
        raise ScenarioError(f"{option} {text!r}: give PATH=" + ("LO:HI[:N]" if option == "--vary" else "normal:MEAN:STD"))
    path = path.strip()
    if option == "--vary":
        if len(parts) not in (2, 3) or not all(p.strip() for p in parts):
            raise ScenarioError(f"--vary {text!r}: give PATH=LO:HI or PATH=LO:HI:N")
        spec = {"range": [_number(parts[0]), _number(parts[1])]}
        if len(parts) == 3:
            try:
                spec["points"] = int(parts[2])
            except ValueError:
                raise ScenarioError(f"--vary {text!r}: N = {parts[2]!r} is not a whole number") from None
        return path, spec
    if len(parts) != 3 or parts[0] not in ("normal", "uniform"):
        raise ScenarioError(f"--monte-carlo {text!r}: give PATH=normal:MEAN:STD or PATH=uniform:LO:HI")
    if parts[0] == "normal":
        return path, {"normal": {"mean": _number(parts[1]), "std": _number(parts[2])}}
    return path, {"uniform": [_number(parts[1]), _number(parts[2])]}


COMMANDS = {"validate": _validate, "solve": _solve, "check": _check, "sweep": _sweep,
            "inverse": _inverse, "sequence": _sequence, "simulate": _simulate, "plan": _plan, "study": _study,
            "fit": _fit}

if __name__ == "__main__":
    sys.exit(main())

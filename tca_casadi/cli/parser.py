"""The command line's argument parser: every command and its options."""
import argparse
from pathlib import Path




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

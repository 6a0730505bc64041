"""Command line: ``tca-casadi validate|solve|check SCENARIO ...``.

Exit codes: 0 success, 1 the solver did not converge (``check``: the solvers disagree),
2 bad input (one line on stderr).
"""
import argparse
import json
import logging
import sys
from pathlib import Path

from .errors import ScenarioError, TcaError


def _scenario_arguments(parser):
    parser.add_argument("scenario", help="scenario YAML file")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="PATH=VALUE",
                        help="override a scenario value by dotted path, e.g. bending.tca2.temperature=100 "
                             "(repeatable)")


def build_parser():
    parser = argparse.ArgumentParser(
        prog="tca-casadi",
        description="Static shape of soft robots driven by TCAs and tendons (Cosserat rods, "
                    "CasADi collocation + IPOPT).")
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
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    try:
        return COMMANDS[args.command](args)
    except ScenarioError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except TcaError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def _validate(args):
    from .model import Robot
    from .scenario import load_scenario
    scenario = load_scenario(args.scenario, args.overrides)
    robot = Robot.from_scenario(scenario)
    print(f"{args.scenario}: valid scenario {scenario.name!r}: {len(robot.modules)} module(s), "
          f"{len(robot.tcas)} TCA(s), {len(robot.actuators) - len(robot.tcas)} tendon(s), "
          f"{len(scenario.loads)} load(s)")
    print("parameters (changeable without rebuilding): " + ", ".join(robot.layout.names()))
    return 0


def _solve(args):
    from .simulation import Simulation
    sim = Simulation.from_file(args.scenario, args.overrides, method=args.method)
    solution = sim.solve()
    output = args.output or Path("results") / sim.scenario.name
    json_path, npz_path = solution.save(output)
    written = [json_path, npz_path]
    if not args.no_plot:
        from .plotting import save_robot_png
        written.append(save_robot_png(solution, output / "robot.png"))
    if args.json:
        print(json.dumps(solution.to_dict(), indent=2))
    else:
        print(solution.summary())
        print("wrote " + ", ".join(str(p) for p in written))
    return 0 if solution.converged else 1


def _check(args):
    from .simulation import Simulation
    from .studies import check
    sim = Simulation.from_file(args.scenario, args.overrides)
    report, _, _ = check(sim, args.position_tolerance, args.tension_tolerance)
    path = report.save((args.output or Path("results") / sim.scenario.name) / "check.json")
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(report.summary())
        print(f"wrote {path}")
    return 0 if report.agree else 1


COMMANDS = {"validate": _validate, "solve": _solve, "check": _check}

if __name__ == "__main__":
    sys.exit(main())

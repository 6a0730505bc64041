"""Command line: ``tca-casadi validate|solve SCENARIO ...``.

Exit codes: 0 success, 1 the solver did not converge, 2 bad input (one line on stderr).
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
    solve.add_argument("--method", choices=["collocation"], default=None, help="solver (default: scenario's)")
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


COMMANDS = {"validate": _validate, "solve": _solve}

if __name__ == "__main__":
    sys.exit(main())

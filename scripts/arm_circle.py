"""The arm's worked example of ``plan`` (issue 32, docs/control.md): bend to a pose as fast as
possible, then make the tip go round a circle.

    python scripts/arm_circle.py               # 150 s, 2 s steps (about a minute)
    python scripts/arm_circle.py --quick       # 10 s steps (about 15 s)

The arm (``scenarios/arm.yaml``) with its bending module's three TCAs driven by power. The
circle is what the arm can do statically: the tip's poses under a heat pattern that turns
around the module once per ``period`` (TCA i at ``base + swing (1 + cos(theta - phi_i)) / 2``,
phi_i its route angle), reached after ``lead`` seconds from the straight arm. Two plans from
the same start: ``time`` to the circle's first point, and ``track`` of the whole path (held at
its first point before ``lead``: bend there, then go round). Writes the path
(``circle.csv``, the input of ``tca-casadi plan --objective track --path``) and each plan's
files into ``-o`` (default ``results/arm_circle``); prints each plan's summary.
"""
import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tca_casadi import Simulation  # noqa: E402
from tca_casadi.control import Plan  # noqa: E402

ARM = ROOT / "scenarios" / "arm.yaml"
#: the bending module's TCAs driven by power (from 25 degC, unheated)
DRIVES = [f"bending.tca{k}.drive={{kind: power, value: 0}}" for k in (1, 2, 3)]
ANGLES = np.radians([0.0, 120.0, 240.0])


def circle(sim, base=35.0, swing=30.0, period=120.0, lead=20.0, points=25):
    """``(times (m,) [s], tips (m, 3) [m])``: the tip's static poses under the turning heat
    pattern (module docstring), ``points`` per turn, from ``lead`` to ``lead + period``."""
    theta = np.linspace(0.0, 2.0 * np.pi, points)
    tips = []
    for angle in theta:
        temperatures = base + swing * 0.5 * (1.0 + np.cos(angle - ANGLES))
        for k, temperature in enumerate(temperatures, start=1):
            sim.set_parameter(f"bending.tca{k}.temperature", temperature)
        last = sim.solve(warm_start="last", refine=False, warn=False)      # along the circle
        if not last.converged:
            raise RuntimeError(f"no equilibrium on the circle at {np.degrees(angle):.0f} deg: {last.message}")
        tips.append(last.tip_position)
    return lead + period * theta / (2.0 * np.pi), np.array(tips)


def write_path(path, times, tips):
    """The path as ``plan --path`` reads it: ``t [s],x [mm],y [mm],z [mm]``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    rows = [f"{t:.6f},{x * 1e3:.9f},{y * 1e3:.9f},{z * 1e3:.9f}" for t, (x, y, z) in zip(times, tips)]
    path.write_text("t [s],x [mm],y [mm],z [mm]\n" + "\n".join(rows) + "\n")
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10 s steps and 13 poses on the circle")
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "results" / "arm_circle")
    args = parser.parse_args(argv)
    period, step = (120.0, 10.0) if args.quick else (120.0, 2.0)
    lead = 20.0
    sim = Simulation.from_file(ARM, DRIVES)
    times, tips = circle(sim, period=period, lead=lead, points=13 if args.quick else 25)
    written = write_path(args.output / "circle.csv", times, tips)
    print(f"circle: {len(times)} poses over {period:g} s from {lead:g} s, radius about "
          f"{np.mean(np.linalg.norm(tips[:, :2] - tips[:, :2].mean(axis=0), axis=1)) * 1e3:.2f} mm; wrote {written}")
    horizon = lead + period
    nodes = int(round(horizon / step))
    results = {}
    bend = Plan(Simulation.from_file(ARM, DRIVES), tips[0], objective="time", horizon=lead, nodes=int(lead / step))
    results["bend"] = bend.solve()
    track = Plan(Simulation.from_file(ARM, DRIVES), (times, tips), objective="track", horizon=horizon, nodes=nodes)
    results["track"] = track.solve()
    for name, plan in results.items():
        plan.save(args.output / name)
        print(plan.summary())
        print(f"wrote {args.output / name}")
    return results


if __name__ == "__main__":
    main()

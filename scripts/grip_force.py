"""The shipped gripper's grip force (issue 17): the normal force each fingertip presses on a
fixed bar of width 2-10 mm held between them, at finger TCA temperatures 25-125 degC.

The arm of ``scenarios/arm_pick_and_place.yaml`` hangs straight; a box obstacle ``bar`` (width
``w`` along x, the fingers' closing direction, 12 mm along y, 5 mm high) is centred between the
closed fingertips. The gripper is normally closed (heating its TCAs opens it) and its closed
tips are 4.6 mm apart, so a wider bar would cut the unloaded fingers, where a cold solve
starts: the script solves once cold with the bar parked far away and the fingers open (125
degC), moves the bar in (its position and size are NLP parameters: no rebuild) and cools the
fingers step by step, each solve warm-started from the last (Newton, then continuation where
a contact closes). A width's first step re-opens the gripper at 125 degC.

    python scripts/grip_force.py -o results/grip_force            # 9 widths x 11 temperatures
    python scripts/grip_force.py --quick -o /tmp/grip              # 2 x 3 (the test runs this)

Writes ``grip_force.csv`` (width, temperature, each finger's normal force, converged) and
``grip_force.png``.
"""
import argparse
import csv
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tca_casadi.simulation import Simulation  # noqa: E402

#: the closed fingertips' midpoint when the arm hangs straight [m]
TIPS = (0.0, 0.0, -0.0833)
FINGERS = ("finger_a", "finger_b")
PARKED = (0.0, 0.0, 1.0)


def gripper_with_bar(width):
    """The shipped arm with a box obstacle ``bar`` of ``width`` [m] parked far above it."""
    raw = yaml.safe_load((ROOT / "scenarios" / "arm_pick_and_place.yaml").read_text())
    for key in ("sequence", "objects"):
        raw.pop(key, None)
    raw["name"] = "gripper_grip_force"
    raw["obstacles"] = [{"name": "bar", "shape": "box", "size": [width, 0.012, 0.005], "position": list(PARKED)}]
    return raw


def set_fingers(sim, temperature):
    for finger in FINGERS:
        sim.set_parameter(f"{finger}.tca.temperature", temperature)


def grip_map(widths, temperatures, progress=print):
    """Rows ``{width_mm, temperature_degC, finger_a_N, finger_b_N, converged, solve_s}``."""
    sim = Simulation.from_file(gripper_with_bar(widths[0]))
    set_fingers(sim, 125.0)
    start = time.perf_counter()
    solution = sim.solve()
    progress(f"cold solve, bar parked, fingers open: {time.perf_counter() - start:.2f} s")
    rows = []
    for width in widths:
        set_fingers(sim, 125.0)
        sim.set_parameter("obstacles.bar.size", [width, 0.012, 0.005])
        sim.set_parameter("obstacles.bar.position", list(TIPS))
        solution = sim.solve(warm_start=solution)
        for temperature in sorted(temperatures, reverse=True):
            set_fingers(sim, temperature)
            start = time.perf_counter()
            trial = sim.solve(warm_start=solution)
            elapsed = time.perf_counter() - start
            force = {finger: sum(c.normal_force for c in trial.contacts if c.module == finger) for finger in FINGERS}
            rows.append({"width_mm": round(width * 1e3, 9), "temperature_degC": temperature,
                         "finger_a_N": force["finger_a"], "finger_b_N": force["finger_b"],
                         "converged": bool(trial.converged), "penetration_m": trial.penetration, "solve_s": elapsed})
            progress(f"w = {width * 1e3:4.1f} mm, T = {temperature:5.1f} degC: grip {force['finger_a'] * 1e3:7.4f} / "
                     f"{force['finger_b'] * 1e3:7.4f} mN{'' if trial.converged else '  NOT CONVERGED'} ({elapsed:.2f} s)")
            if trial.converged:
                solution = trial
    return rows


def write(rows, directory):
    directory.mkdir(parents=True, exist_ok=True)
    with open(directory / "grip_force.csv", "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    widths = sorted({row["width_mm"] for row in rows})
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(widths)))
    for width, color in zip(widths, colors):
        mine = sorted((row for row in rows if row["width_mm"] == width and row["converged"]),
                      key=lambda row: row["temperature_degC"])
        ax.plot([row["temperature_degC"] for row in mine], [row["finger_a_N"] * 1e3 for row in mine], "o-",
                color=color, markersize=3.5, label=f"{width:g} mm")
    ax.set_xlabel("finger TCA temperature [degC]")
    ax.set_ylabel("grip force per fingertip [mN]")
    ax.set_title("The shipped gripper's grip on a fixed bar (normal force, frictionless)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(title="bar width", fontsize=8, title_fontsize=8)
    fig.tight_layout()
    fig.savefig(directory / "grip_force.png", dpi=130)
    plt.close(fig)
    return directory / "grip_force.csv", directory / "grip_force.png"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", default="results/grip_force")
    parser.add_argument("--quick", action="store_true", help="2 widths x 3 temperatures")
    args = parser.parse_args(argv)
    if args.quick:
        widths, temperatures = [4e-3, 8e-3], [125.0, 75.0, 25.0]
    else:
        widths, temperatures = list(np.arange(2, 11) * 1e-3), list(np.arange(125.0, 24.0, -10.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = grip_map(widths, temperatures)
    paths = write(rows, Path(args.output))
    print("wrote " + ", ".join(map(str, paths)))
    return rows


if __name__ == "__main__":
    main()

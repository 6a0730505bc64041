"""Reproduce the paper's Figs. 3-5 (Sun & Zhao) from the shipped bending-module scenario.

    python scripts/paper_figures.py all -o results/figures      # or fig3 | fig4 | fig5
    python scripts/paper_figures.py fig4 --quick                # fewer points (smoke run)

Each figure writes a PNG and a CSV (columns with units) into the output directory:

* Fig. 3: a passive TCA's stretch against force, from the TCA law alone (25 degC), up to and
  beyond the fit's monotone limit sqrt(a0/a2).
* Fig. 4: TCAs 2 and 3 heated together from 25 to 125 degC, with and without the passive TCA 1;
  the bending magnitude (angle between the base and tip tangents) and their ratio.
* Fig. 5: all three TCAs at 75, 100 and 125 degC; the tip displacement against a horizontal
  (x) tip force: variable stiffness.
"""
import argparse
import csv
import sys
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tca_casadi import Simulation, Sweep  # noqa: E402
from tca_casadi.plotting.robot3d import _pyplot  # noqa: E402
from tca_casadi.studies import bending_angle  # noqa: E402

SCENARIO = ROOT / "scenarios" / "bending_module.yaml"
HEATED = ["bending.tca2.temperature", "bending.tca3.temperature"]


def write_csv(path, header, rows):
    with Path(path).open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows([[f"{v:.10g}" for v in row] for row in rows])
    return path


# ---------------------------------------------------------------------- Fig. 3
def fig3(output, points=81):
    """Stretch [m] of the passive TCA against its tension [N] (TCA law, no body)."""
    law = Simulation.from_file(SCENARIO).robot.tcas[0].law
    force = np.linspace(0.0, 1.4 * law.monotone_limit, points)
    stretch = law.stretch(force)
    rows = np.column_stack([force, stretch, stretch / law.reference_length, law.shear_modulus(force)])
    write_csv(output / "fig3_tca_passive.csv",
              ["force [N]", "stretch [m]", "strain [-]", "G_t [Pa]"], rows)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(force * 1e3, stretch * 1e3, "k-")
    ax.axvspan(law.monotone_limit * 1e3, force[-1] * 1e3, color="tab:red", alpha=0.1,
               label=f"beyond the fit's monotone range ({law.monotone_limit * 1e3:.0f} mN)")
    ax.set_xlabel("force [mN]"), ax.set_ylabel("stretch [mm]")
    ax.set_title(f"Fig. 3: passive TCA (l* = {law.reference_length * 1e3:.0f} mm), law alone", fontsize=10)
    ax.grid(True, alpha=0.3), ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(output / "fig3_tca_passive.png", dpi=120)
    plt.close(fig)
    return {"force": force, "stretch": stretch, "law": law}


# ---------------------------------------------------------------------- Fig. 4
def _without_tca1():
    raw = yaml.safe_load(SCENARIO.read_text())
    raw["modules"][0]["actuators"] = [a for a in raw["modules"][0]["actuators"] if a["name"] != "tca1"]
    raw.pop("sequence", None)          # its steps set TCA 1, which this robot does not have
    return raw


def heating_sweep(source, steps):
    result = Sweep(Simulation.from_file(source), HEATED, 25, 125, steps=steps).run()
    if not result.completed:
        raise RuntimeError(f"the heating sweep stopped: {result.message}")
    return result


def fig4(output, steps=41):
    """Bending angle [deg] with and without the passive TCA 1 and their ratio, 25-125 degC."""
    with_passive, without = heating_sweep(SCENARIO, steps), heating_sweep(_without_tca1(), steps)
    temperature = with_passive.values[:, 0]
    angle_with = np.degrees([bending_angle(s) for s in with_passive.solutions])
    angle_without = np.degrees([bending_angle(s) for s in without.solutions])
    ratio = np.divide(angle_without, angle_with, out=np.full_like(angle_with, np.nan), where=angle_with > 0)
    write_csv(output / "fig4_antagonism.csv",
              ["temperature [degC]", "angle_with_passive [deg]", "angle_without_passive [deg]", "ratio [-]"],
              np.column_stack([temperature, angle_with, angle_without, ratio]))
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
    top.plot(temperature, angle_with, "g.-", label="with the passive TCA 1")
    top.plot(temperature, angle_without, "r.-", label="without it")
    top.set_ylabel("bending angle [deg]"), top.legend(fontsize=8), top.grid(True, alpha=0.3)
    bottom.plot(temperature[1:], ratio[1:], "k.-")
    bottom.axhline(1.4, color="tab:red", linestyle=":", label="1.4 (the paper: > 40 % more)")
    bottom.set_ylabel("ratio without / with"), bottom.set_xlabel("temperature of TCAs 2 and 3 [degC]")
    bottom.legend(fontsize=8), bottom.grid(True, alpha=0.3)
    top.set_title("Fig. 4: antagonism of the passive TCA", fontsize=10)
    fig.tight_layout()
    fig.savefig(output / "fig4_antagonism.png", dpi=120)
    plt.close(fig)
    return {"temperature": temperature, "with": angle_with, "without": angle_without, "ratio": ratio}


# ---------------------------------------------------------------------- Fig. 5
def fig5(output, temperatures=(75, 100, 125), force="5 mN", steps=11):
    """Tip displacement [m] against a horizontal tip force [N], all three TCAs at each temperature."""
    curves = {}
    for temperature in temperatures:
        overrides = [f"bending.tca{k}.temperature={temperature}" for k in (1, 2, 3)]
        result = Sweep(Simulation.from_file(SCENARIO, overrides), ["tip_force.force.x"], 0, force,
                       steps=steps).run()
        if not result.completed:
            raise RuntimeError(f"the force sweep at {temperature} degC stopped: {result.message}")
        displacement = np.linalg.norm(result.tip_positions - result.tip_positions[0], axis=1)
        curves[temperature] = (result.values[:, 0], displacement)
    forces = curves[temperatures[0]][0]
    write_csv(output / "fig5_variable_stiffness.csv",
              ["force_x [N]"] + [f"tip_displacement_{t}degC [m]" for t in temperatures],
              np.column_stack([forces] + [curves[t][1] for t in temperatures]))
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    for temperature in temperatures:
        ax.plot(curves[temperature][0] * 1e3, curves[temperature][1] * 1e3, ".-", label=f"{temperature} degC")
    ax.set_xlabel("horizontal tip force [mN]"), ax.set_ylabel("tip displacement [mm]")
    ax.set_title("Fig. 5: variable stiffness (all three TCAs heated)", fontsize=10)
    ax.legend(fontsize=8), ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(output / "fig5_variable_stiffness.png", dpi=120)
    plt.close(fig)
    return {"force": forces, "displacement": {t: curves[t][1] for t in temperatures}}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("figure", choices=["fig3", "fig4", "fig5", "all"])
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "results" / "figures")
    parser.add_argument("--quick", action="store_true", help="fewer points (a smoke run)")
    args = parser.parse_args(argv)
    args.output.mkdir(parents=True, exist_ok=True)
    quick = args.quick
    if args.figure in ("fig3", "all"):
        fig3(args.output, points=21 if quick else 81)
    if args.figure in ("fig4", "all"):
        data = fig4(args.output, steps=11 if quick else 41)
        heated = data["temperature"] > 25
        print(f"Fig. 4: ratio without/with the passive TCA: min {np.nanmin(data['ratio'][heated]):.3f}, "
              f"max {np.nanmax(data['ratio'][heated]):.3f} over {data['temperature'][heated][0]:.1f}-125 degC")
    if args.figure in ("fig5", "all"):
        data = fig5(args.output, steps=5 if quick else 11)
        print("Fig. 5: tip displacement at the largest force [mm]: " + ", ".join(
            f"{t} degC: {d[-1] * 1e3:.3f}" for t, d in data["displacement"].items()))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()

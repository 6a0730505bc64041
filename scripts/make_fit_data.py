"""Make the shipped calibration example: measurements of the bending module made by the model
itself at known parameter values, with stated noise.

    python scripts/make_fit_data.py [-o data/bending_module_measurements.csv] [--experiments 50]

The true values differ from the scenario's (what a fit should recover); 50 experiments at Latin
hypercube temperatures of the three TCAs (25-125 degC); the tip measured with Gaussian noise of
0.05 mm on each coordinate (seed 7). Fit it with

    tca-casadi fit scenarios/bending_module.yaml --data data/bending_module_measurements.csv \
        --param materials.ecoflex30.youngs_modulus --param tca_types.nylon.fiber_radius \
        --param bending.tca1.route.radius --param tca_types.nylon.untwist.c1
"""
import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: the values the data are made at (the scenario has 0.125 MPa, 0.5 mm, 4 mm and 0.3338)
TRUTH = {"materials.ecoflex30.youngs_modulus": 0.14e6, "tca_types.nylon.fiber_radius": 0.52e-3,
         "bending.tca1.route.radius": 4.3e-3, "tca_types.nylon.untwist.c1": 0.32}
NOISE_MM = 0.05
SEED = 7


def make(experiments=50, seed=SEED):
    """The :class:`~tca_casadi.studies.fit.Measurements` of the example."""
    from scipy.stats import qmc

    import tca_casadi as tc
    from tca_casadi.studies.fit import synthetic_measurements
    sim = tc.Simulation.from_file(ROOT / "scenarios" / "bending_module.yaml")
    temperatures = 25 + 100 * qmc.LatinHypercube(3, seed=seed).random(experiments)
    inputs = {f"bending.tca{k + 1}.temperature": np.round(temperatures[:, k], 2) for k in range(3)}
    return synthetic_measurements(sim, TRUTH, inputs, ["tip_x", "tip_y", "tip_z"], {"length": NOISE_MM * 1e-3}, seed)


def main(argv=None):
    from tca_casadi.studies.fit import write_measurements
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "data" / "bending_module_measurements.csv")
    parser.add_argument("--experiments", type=int, default=50)
    args = parser.parse_args(argv)
    data = make(args.experiments)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    truth = ", ".join(f"{k} = {v:g}" for k, v in TRUTH.items())
    write_measurements(args.output, data, [
        "Synthetic measurements of the bending module (scenarios/bending_module.yaml), made by tca_casadi itself",
        f"(scripts/make_fit_data.py) at known parameter values: {truth} (SI).",
        f"{len(data.values)} experiments at Latin hypercube temperatures (25-125 degC, seed {SEED}); the tip measured",
        f"with Gaussian noise of {NOISE_MM} mm on each coordinate (seed {SEED}). Not an experiment: a test of the fit."])
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()

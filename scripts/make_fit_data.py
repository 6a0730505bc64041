"""Make the shipped calibration examples: measurements of the bending module made by the model
itself at known parameter values, with stated noise.

    python scripts/make_fit_data.py [-o data/bending_module_measurements.csv] [--experiments 50]
    python scripts/make_fit_data.py --heating [-o data/bending_module_heating_curve.csv]

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
#: the heating curve's thermal constants (the fibre gives C = 0.137 J/K, G = 7.07 mW/K: tau 19.4 s)
HEATING_TRUTH = {"tca_types.nylon.thermal.heat_capacity": 0.16, "tca_types.nylon.thermal.conductance": 0.0065}
NOISE_K = 0.3


def make(experiments=50, seed=SEED):
    """The :class:`~tca_casadi.studies.fit.least_squares.Measurements` of the example."""
    from scipy.stats import qmc

    import tca_casadi as tc
    from tca_casadi.studies.fit.least_squares import synthetic_measurements
    sim = tc.Simulation.from_file(ROOT / "scenarios" / "bending_module.yaml")
    temperatures = 25 + 100 * qmc.LatinHypercube(3, seed=seed).random(experiments)
    inputs = {f"bending.tca{k + 1}.temperature": np.round(temperatures[:, k], 2) for k in range(3)}
    return synthetic_measurements(sim, TRUTH, inputs, ["tip_x", "tip_y", "tip_z"], {"length": NOISE_MM * 1e-3}, seed)


def make_heating(seed=SEED):
    """The heating curve of ``scenarios/bending_module_heating.yaml``: TCA 2's temperature every
    second for 80 s at :data:`HEATING_TRUTH` with :data:`NOISE_K` of noise."""
    import tca_casadi as tc
    from tca_casadi.studies.fit.thermal import synthetic_heating_curve
    sim = tc.Simulation.from_file(ROOT / "scenarios" / "bending_module_heating.yaml")
    return synthetic_heating_curve(sim, HEATING_TRUTH, ["bending.tca2.temperature"], np.arange(0.0, 80.5, 1.0),
                                   NOISE_K, seed)


def main(argv=None):
    from tca_casadi.studies.fit.least_squares import write_measurements
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=None)
    parser.add_argument("--experiments", type=int, default=50)
    parser.add_argument("--heating", action="store_true", help="the heating curve instead")
    args = parser.parse_args(argv)
    if args.heating:
        from tca_casadi.studies.fit.thermal import write_heating_curve
        output = args.output or ROOT / "data" / "bending_module_heating_curve.csv"
        output.parent.mkdir(parents=True, exist_ok=True)
        truth = ", ".join(f"{k} = {v:g}" for k, v in HEATING_TRUTH.items())
        write_heating_curve(output, make_heating(), [
            "Synthetic heating curve of TCA 2 of scenarios/bending_module_heating.yaml (0.3 W from 1 s to 40 s),",
            f"made by tca_casadi itself (scripts/make_fit_data.py --heating) at known thermal constants: {truth}",
            f"(SI; time constant {HEATING_TRUTH['tca_types.nylon.thermal.heat_capacity'] / HEATING_TRUTH['tca_types.nylon.thermal.conductance']:.4g} s), "
            f"with Gaussian noise of {NOISE_K} K (seed {SEED}). Not an experiment: a test of the fit."])
        print(f"wrote {output}")
        return
    args.output = args.output or ROOT / "data" / "bending_module_measurements.csv"
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

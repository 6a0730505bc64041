"""Coverage of the fit's 95 % intervals on synthetic data: how often they hold the true values.

    python scripts/fit_coverage.py [--repetitions 100] [--quick]

Each repetition makes 10 experiments of the bending module (random temperatures of its three
TCAs) at known values of its modulus and fibre radius with 0.05 mm of Gaussian noise on the tip
(seed = the repetition), fits both parameters with the sigmas trusted, and counts the intervals
that hold the truth. Honest intervals hold it about 95 % of the time; the residuals' RMS is the
noise. ``--quick``: 10 repetitions (what the test runs is ``coverage(sim, 8)``).
"""
import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

TRUTH = {"materials.ecoflex30.youngs_modulus": 0.14e6, "tca_types.nylon.fiber_radius": 0.52e-3}
NOISE = 5e-5
TIP = ["tip_x", "tip_y", "tip_z"]


def coverage(sim, repetitions, experiments=10):
    """``(inside, intervals, residual scales)``: intervals holding the truth, intervals in all,
    and each fit's residual RMS over the noise."""
    from tca_casadi.studies.fit.least_squares import Fit, synthetic_measurements
    inside, scales = 0, []
    for seed in range(repetitions):
        rng = np.random.default_rng(seed)
        inputs = {f"bending.tca{k}.temperature": np.round(rng.uniform(25, 125, experiments), 1) for k in (1, 2, 3)}
        data = synthetic_measurements(sim, TRUTH, inputs, TIP, {"length": NOISE}, seed)
        result = Fit(sim, data, list(TRUTH), absolute_sigma=True).run()
        if not result.converged:
            raise RuntimeError(f"repetition {seed}: {result.message}")
        inside += sum(q.low <= value <= q.high for q, value in zip(result.parameters, TRUTH.values()))
        scales.append(float(np.sqrt(np.mean(result.residuals ** 2))) / NOISE)
    return inside, repetitions * len(TRUTH), scales


def main(argv=None):
    import tca_casadi as tc
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=100)
    parser.add_argument("--quick", action="store_true", help="10 repetitions")
    args = parser.parse_args(argv)
    sim = tc.Simulation.from_file(ROOT / "scenarios" / "bending_module.yaml")
    inside, total, scales = coverage(sim, 10 if args.quick else args.repetitions)
    print(f"95 % intervals holding the true value: {inside} of {total} ({100 * inside / total:.1f} %); "
          f"residual RMS / noise: mean {np.mean(scales):.3f}, range {min(scales):.3f} to {max(scales):.3f}")
    return inside, total


if __name__ == "__main__":
    main()

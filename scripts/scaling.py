"""How the core's cost grows with the mesh and with the robot (``bench.py --scaling``).

Two series, each point in a fresh process (its peak memory is its own):

* the bending module on 24, 48, ... 768 intervals (``solver.intervals``, no refinement);
* chains of 1, 2, 4, ... 16 bending modules, 6 intervals each (TCAs 2 and 3 at 50 degC).

Per point: the cold solve (build and continuation from the reference state), the warm solve
after +1 degC on TCA 2 of the first module (``Simulation.solve(warm_start=...)``, median of
5) with its Newton iterations (chord steps included) and the time per iteration, whether both
converged, the number of unknowns and the process's peak resident memory.
The exponents are the slopes of log(cost) against log(size) over the larger half of the
points (linear cost: 1).

    python scripts/scaling.py                  # both series, printed and in results/scaling.json
    python scripts/scaling.py --point intervals 192     # one point, JSON on stdout
"""
import argparse
import copy
import json
import resource
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
BENDING = ROOT / "scenarios" / "bending_module.yaml"
INTERVALS = (24, 48, 96, 192, 384, 768)
MODULES = (1, 2, 4, 8, 16)
QUICK = {"intervals": (24, 48, 96), "modules": (1, 2, 4)}


def chain(count):
    """A scenario dict: ``count`` bending modules in series (6 intervals each, TCAs 2 and 3 at
    50 degC), the tip probe on the last."""
    raw = yaml.safe_load(BENDING.read_text())
    module = raw["modules"][0]
    for actuator in module["actuators"][1:]:          # TCAs 2 and 3 at 50 degC: each module bends
        actuator["temperature"] = 50                  # about 20 deg, a chain of 16 does not coil up
    raw["modules"] = [dict(copy.deepcopy(module), name=f"bending{k}") for k in range(count)]
    raw["loads"] = [dict(raw["loads"][0], module=f"bending{count - 1}")]
    for key in ("inverse", "sequence"):
        raw.pop(key)
    raw["name"] = f"chain_{count}"
    raw["solver"] = {"intervals": 6, "refine": "off"}
    return raw


def scenario(kind, size):
    if kind == "modules":
        return chain(size), "bending0.tca2.temperature"
    raw = yaml.safe_load(BENDING.read_text())
    raw["solver"] = {"intervals": size, "refine": "off"}
    return raw, "bending.tca2.temperature"


def point(kind, size, repeats=5):
    """One point, measured in this process: ``{size, unknowns, cold_s, warm_s, converged,
    peak_rss_mb}``."""
    import tca_casadi as tc
    warnings.simplefilter("ignore")
    raw, path = scenario(kind, size)
    started = time.perf_counter()
    sim = tc.Simulation.from_file(raw)
    cold = sim.solve(warn=False)
    cold_s = time.perf_counter() - started
    times, iterations, warm = [], [], cold
    value = sim.get_parameter(path)
    for k in range(repeats):
        sim.set_parameter(path, value + 1.0 + 1e-3 * k)
        started = time.perf_counter()
        warm = sim.solve(warm_start=cold, warn=False)
        times.append(time.perf_counter() - started)
        iterations.append(warm.result.nit)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {"size": size, "unknowns": int(sim.solver().nlp.scale.size), "cold_s": cold_s,
            "warm_s": statistics.median(times), "warm_iterations": statistics.median(iterations),
            "warm_per_iteration_s": statistics.median(times) / max(statistics.median(iterations), 1),
            "converged": bool(cold.converged and warm.converged),
            "peak_rss_mb": peak}


def measure(kind, size, timeout=1800):
    """:func:`point` in a fresh process (None if it failed or ran out of time)."""
    try:
        run = subprocess.run([sys.executable, __file__, "--point", kind, str(size)], capture_output=True,
                             text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"size": size, "failed": f"more than {timeout} s"}
    if run.returncode != 0:
        return {"size": size, "failed": (run.stderr.strip().splitlines() or ["?"])[-1]}
    return json.loads(run.stdout.strip().splitlines()[-1])


def exponent(rows, key):
    """Slope of log(row[key]) against log(size) over the larger half of the converged rows."""
    good = [r for r in rows if r.get("converged") and r.get(key, 0) > 0]
    good = good[len(good) // 2:] if len(good) >= 4 else good
    if len(good) < 2:
        return None
    x, y = np.log([r["size"] for r in good]), np.log([r[key] for r in good])
    return float(np.polyfit(x, y, 1)[0])


def scaling(quick=False):
    """Both series and their exponents."""
    out = {}
    for kind in ("intervals", "modules"):
        sizes = QUICK[kind] if quick else (INTERVALS if kind == "intervals" else MODULES)
        rows = [measure(kind, size) for size in sizes]
        out[kind] = {"rows": rows, "exponents": {key: exponent(rows, key)
                                                 for key in ("cold_s", "warm_s", "warm_per_iteration_s",
                                                             "peak_rss_mb")}}
    return out


def print_scaling(result):
    for kind, label in (("intervals", "bending module, intervals"), ("modules", "chain of bending modules")):
        print(f"{label}:")
        print(f"  {'size':>6} {'unknowns':>9} {'cold [s]':>9} {'warm [ms]':>10} {'Newton its':>10} "
              f"{'per it [ms]':>11} {'peak [MB]':>10}")
        for row in result[kind]["rows"]:
            if "failed" in row:
                print(f"  {row['size']:>6}  failed: {row['failed']}")
                continue
            flag = "" if row["converged"] else "  NOT CONVERGED"
            print(f"  {row['size']:>6} {row['unknowns']:>9} {row['cold_s']:>9.3f} {1e3 * row['warm_s']:>10.2f} "
                  f"{row['warm_iterations']:>10.0f} {1e3 * row['warm_per_iteration_s']:>11.2f} "
                  f"{row['peak_rss_mb']:>10.0f}{flag}")
        exponents = result[kind]["exponents"]
        print("  exponents (larger half): " + ", ".join(
            f"{key.removesuffix('_s').removesuffix('_mb')} {value:.2f}" if value is not None
            else f"{key.removesuffix('_s').removesuffix('_mb')} -"
            for key, value in exponents.items()))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--point", nargs=2, metavar=("KIND", "SIZE"), help="one point (intervals|modules N)")
    parser.add_argument("--quick", action="store_true", help="the three smallest points of each series")
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "results" / "scaling.json")
    args = parser.parse_args(argv)
    if args.point:
        print(json.dumps(point(args.point[0], int(args.point[1]))))
        return 0
    result = scaling(args.quick)
    print_scaling(result)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Print the README's performance table (markdown) from ``results/bench.json`` (scripts/bench.py).

    python scripts/readme_table.py [results/bench.json]
"""
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NAMES = {"bending_module": "bending module", "twisting_module": "twisting module",
         "arm": "arm (bending + twisting)", "elastica": "elastica (P L^2/EI = 2)"}
HEADER = ["problem", "unknowns (intervals)", "build", "first cold solve, with error estimate",
          "cold solve, NLPs kept", "warm +1 degC (IPOPT)", "warm +1 degC (Newton, default)",
          "E +10 % (Newton, no rebuild)", "101-step sweep", "inverse (IPOPT)", "inverse (reduced, default)",
          "shooting, exact Jacobian", "shooting, finite differences", "tip error: collocation / shooting",
          "speed-up at equal accuracy (intervals)"]


def seconds(value):
    """``0.27 s`` from 0.1 s up, ``38.6 ms`` below."""
    if value is None:
        return "-"
    return f"{value:.2f} s" if value >= 0.1 else f"{value * 1e3:.1f} ms"


def row(r):
    errors = (f"{r['tip_error_collocation_m']:.1e} / {r['tip_error_shooting_m']:.1e} m"
              if "tip_error_shooting_m" in r else "-")
    speedup = (f"{r['speedup_equal_accuracy']:.0f}x ({r['intervals_equal_accuracy']})"
               if "speedup_equal_accuracy" in r else "-")
    cells = [NAMES.get(r["problem"], r["problem"]), f"{r['unknowns']} ({r['intervals']})"]
    cells += [seconds(r.get(key)) for key in ("build_s", "cold_s", "cold_kept_s", "warm_ipopt_s", "warm_newton_s",
                                              "design_newton_s", "sweep_s", "inverse_ipopt_s", "inverse_reduced_s",
                                              "shooting_s", "shooting_differences_s")]
    return cells + [errors, speedup]


def main(argv=None):
    path = Path((argv or sys.argv[1:] or [ROOT / "results" / "bench.json"])[0])
    data = json.loads(path.read_text())
    lines = ["| " + " | ".join(HEADER) + " |", "|" + "---|" * len(HEADER)]
    lines += ["| " + " | ".join(row(r)) + " |" for r in data["rows"]]
    print("\n".join(lines))
    checks = data.get("check", {})
    if checks:
        print("\n| scenario | collocation | shooting | tip difference |\n|---|---|---|---|")
        for name, c in checks.items():
            print(f"| `{name}` | {seconds(c['collocation_s'])} | {seconds(c['shooting_s'])} | "
                  f"{c['tip_difference_m']:.1e} m |")
    print(f"\nmeasured {data['machine']['date']} on {data['machine']['cpus']} CPUs, Python {data['machine']['python']}")


if __name__ == "__main__":
    main()

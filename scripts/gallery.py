"""The documentation's gallery, built from the shipped scenarios (issue 37).

Every scenario under ``scenarios/`` is solved the way ``tca-casadi solve`` solves it (its static
equilibrium: a timed or dynamic scenario's state at its start) and drawn as ``solve`` draws it;
each drawing goes to ``docs/images/gallery/NAME.png`` and one row per scenario (its title,
description, tip, convergence, global balance, the command) to ``docs/images/gallery/scenarios.json``.
The docs build (``docs/hooks.py``) writes the gallery page's scenario section from that file,
so the page lists exactly what was drawn; a test checks that every shipped scenario is in it.

    python scripts/gallery.py            # every shipped scenario (about 2 minutes)
    python scripts/gallery.py --quick    # one scenario into a temporary folder (the test's run)
"""
import argparse
import json
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
IMAGES = ROOT / "docs" / "images" / "gallery"
ROWS = IMAGES / "scenarios.json"


def shipped():
    """The shipped scenario files, sorted: the robots first, then the analytic references."""
    return sorted(SCENARIOS.glob("*.yaml")) + sorted((SCENARIOS / "analytic").glob("*.yaml"))


def name_of(path):
    """The gallery's name of a scenario file: its path under ``scenarios/`` without ``.yaml``."""
    return path.relative_to(SCENARIOS).with_suffix("").as_posix()


def draw(path, images):
    """Solve the scenario at ``path``, draw it into ``images`` and return its gallery row."""
    from tca_casadi import Simulation
    from tca_casadi.plotting import save_robot_png
    from tca_casadi.studies.sequence.objects import object_poses
    name = name_of(path)
    started = time.perf_counter()
    sim = Simulation.from_file(path, allow_code=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        solution = sim.solve(warn=False)
    image = images / f"{name.replace('/', '__')}.png"
    image.parent.mkdir(parents=True, exist_ok=True)
    save_robot_png(solution, image, objects=object_poses(sim.scenario, sim.robot, solution),
                   title=sim.scenario.name)
    return {"name": name, "scenario": f"scenarios/{name}.yaml", "title": sim.scenario.name,
            "description": " ".join(sim.scenario.description.split()),
            "image": image.name, "converged": bool(solution.converged),
            "tip_mm": [round(1e3 * float(v), 4) for v in solution.tip_position],
            "balance": float(solution.balance.relative) if solution.converged else None,
            "command": f"tca-casadi solve scenarios/{name}.yaml" + (" --allow-code" if "custom" in name else ""),
            "seconds": round(time.perf_counter() - started, 2)}


def build(paths, images, rows_file, progress=print):
    """Draw every scenario in ``paths``; write their rows (sorted by name) to ``rows_file``."""
    rows = []
    for path in paths:
        rows.append(draw(path, images))
        progress(f"{rows[-1]['name']}: {'converged' if rows[-1]['converged'] else 'NOT converged'} "
                 f"in {rows[-1]['seconds']} s")
    rows_file.parent.mkdir(parents=True, exist_ok=True)
    rows_file.write_text(json.dumps(rows, indent=1) + "\n")
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="one scenario into a temporary folder")
    args = parser.parse_args(argv)
    os.environ.setdefault("MPLBACKEND", "Agg")
    if args.quick:
        with tempfile.TemporaryDirectory() as work:
            rows = build([SCENARIOS / "bending_module.yaml"], Path(work), Path(work) / "scenarios.json")
            ok = (Path(work) / rows[0]["image"]).stat().st_size > 10_000 and rows[0]["converged"]
        return 0 if ok else 1
    rows = build(shipped(), IMAGES, ROWS)
    return 0 if all(r["converged"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())

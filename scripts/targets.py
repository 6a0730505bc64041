"""Issue 36's targets, each measured the way the issue states it (``bench.py --targets``).

Every row: what is measured, the measured value, the target and whether it is met. Whole
commands run in a fresh process (the command line's ``main``; the wall time and, where the
target names memory, that process's peak resident memory); ``solver.jit`` runs compile once before
the timed run (the compile is kept on disk, as a user's second run finds it).

    python scripts/bench.py --targets [--quick]       # results/bench_targets.json
"""
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
RANDOM_ROBOT = ROOT / "tests" / "data" / "robot_11_9_four_modules.yaml"
#: the build and 101-step sweep, in a fresh process, timed after the imports
SWEEP = """
import json, sys, time
started = time.perf_counter()
import tca_casadi as tc
from tca_casadi.simulation import Simulation
from tca_casadi.studies.sweep.run import Sweep
imported = time.perf_counter()
sim = Simulation.from_file(sys.argv[1], sys.argv[2:])
result = Sweep(sim, ["bending.tca2.temperature", "bending.tca3.temperature"], 25, 125, steps=101).run()
done = time.perf_counter()
print(json.dumps({"import_s": imported - started, "build_sweep_s": done - imported, "completed": result.completed}))
"""


#: a command in a fresh process that reports its own peak resident memory [kB] on stderr
MEASURED = ("import resource, sys\nfrom tca_casadi.cli import main\ncode = main(sys.argv[1:])\n"
            "print('PEAK_KB', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr)\nsys.exit(code)")


def _run(command):
    """``(wall seconds, peak resident memory of the command's process [MB], completed process)``."""
    started = time.perf_counter()
    process = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - started
    peaks = [line.split()[1] for line in process.stderr.splitlines() if line.startswith("PEAK_KB ")]
    return wall, (float(peaks[-1]) / 1024 if peaks else float("nan")), process


def _cli(*arguments):
    return [sys.executable, "-c", MEASURED, *map(str, arguments)]


def row(what, measured, target, unit, met, note="", profile=None):
    """A target's row; ``profile``: the code :func:`where_the_time_goes` runs for it when it is not met."""
    return {"what": what, "measured": measured, "target": target, "unit": unit, "met": bool(met), "note": note,
            "profile": profile}


#: a target's code run in a fresh process under :class:`stages.StageProfile` (its imports, in
#: "other", included): prints the report as JSON on a line of its own
PROFILED = """
import json, sys, time
started = time.perf_counter()
sys.path[:0] = [{scripts!r}]
import scipy.optimize, scipy.sparse.linalg, tca_casadi.cli, tca_casadi.simulation
from stages import StageProfile, with_imports
imported = time.perf_counter()
with StageProfile() as profile:
    exec(compile(sys.argv[1], "<target>", "exec"))
total = time.perf_counter() - started
print("STAGES " + json.dumps({{"total_s": total, "stages": with_imports(profile.report(total), imported - started, total)}}))
"""
#: each unmet target's run, as the profile repeats it (the code of :data:`PROFILED`)
PROFILES = {
    "sweep": ("from tca_casadi.simulation import Simulation\nfrom tca_casadi.studies.sweep.run import Sweep\n"
              f"sim = Simulation.from_file({str(SCENARIOS / 'bending_module.yaml')!r})\n"
              "Sweep(sim, ['bending.tca2.temperature', 'bending.tca3.temperature'], 25, 125, steps=101).run()"),
    "till": "from bench import till_arguments\nfrom tca_casadi.cli import main\n"
            "main(till_arguments({duration}, True) + ['-o', {folder!r}])",
    "dynamics": ("from bench import dynamics_rate\ndynamics_rate({name!r}, 0.002, 500, jit=True)"),     # the steps show
    "inverse": "from targets import inverse_arguments\nfrom tca_casadi.cli import main\n"
               "main(inverse_arguments({target!r}, {folder!r}))",
    "study": ("from tca_casadi.simulation import Simulation\nfrom tca_casadi.studies.batch.study import Study\n"
              f"sim = Simulation.from_file({str(SCENARIOS / 'bending_module.yaml')!r}, [{{jit!r}}])\n"
              "Study(sim, vary={{f'bending.tca{{k}}.temperature': [25, 125, {per_axis}] for k in (1, 2, 3)}}).run()"),
}


def where_the_time_goes(code):
    """``{"total_s", "stages"}``: :data:`PROFILED` of ``code`` in a fresh process."""
    command = [sys.executable, "-c", PROFILED.format(scripts=str(Path(__file__).parent)), code]
    process = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
    lines = [line for line in process.stdout.splitlines() if line.startswith("STAGES ")]
    if not lines:
        raise RuntimeError(f"the profiled run failed: {process.stderr[-2000:]}")
    return json.loads(lines[-1][len("STAGES "):])


def warm_solve(repeats):
    """The bending module after +1 degC on every TCA, from the previous point's solution and its
    factorised Jacobian (what a sweep or a time step does), with ``solver.jit``: Newton alone
    and with the point's Solution; uncompiled beside it."""
    sys.path.insert(0, str(Path(__file__).parent))
    from bench import median_time, nudge
    from tca_casadi.simulation import Simulation
    out = {}
    for jit in ("false", "true"):
        sim = Simulation.from_file(SCENARIOS / "bending_module.yaml", ["solver.algorithm=newton", f"solver.jit={jit}"])
        cold = sim.solve(warn=False)
        solver = sim.solver()
        square, w = solver.square, cold.iterate.w
        lu = square.factorise(square.evaluate(w, sim.params)[1])
        nudged = nudge(sim, sim.params)
        out[f"newton_{jit}_s"], _ = median_time(lambda: square.newton(w, nudged, solver.options.tolerance, lu=lu),
                                                repeats)
        out[f"solve_{jit}_s"], solved = median_time(lambda: solver.solve_newton(nudged, w, lu=lu), repeats)
        out[f"converged_{jit}"] = bool(solved.converged)
    return out


def build_and_sweep():
    """Build + 101-step sweep of the bending module in a fresh process (imports timed apart),
    uncompiled and with ``solver.jit`` (its compile done by an untimed first run)."""
    out = {}
    for jit in ("false", "true"):
        command = [sys.executable, "-c", SWEEP, str(SCENARIOS / "bending_module.yaml"), f"solver.jit={jit}"]
        if jit == "true":
            subprocess.run(command, check=True, capture_output=True)
        runs = [json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout) for _ in range(3)]
        out[jit] = {key: statistics.median(r[key] for r in runs) for key in ("import_s", "build_sweep_s")}
        out[jit]["completed"] = all(r["completed"] for r in runs)
    return out


def random_robot():
    """``tca-casadi solve`` on the random 4-module robot: wall time, peak memory, converged
    with its accuracy met."""
    with tempfile.TemporaryDirectory() as folder:
        wall, peak, process = _run(_cli("solve", RANDOM_ROBOT, "--no-plot", "-o", folder))
        report = json.loads((Path(folder) / "solution.json").read_text()) if process.returncode == 0 else {}
    accuracy = report.get("accuracy") or {}
    return {"wall_s": wall, "peak_mb": peak, "converged": bool(report.get("converged")),
            "accuracy_met": bool(accuracy.get("met")), "exit": process.returncode}


def inverse_arguments(target, folder):
    """The ``tca-casadi inverse`` arguments of :func:`arm_inverse`'s run to ``target`` (three
    coordinates [m], as text) into ``folder``."""
    return ["inverse", str(SCENARIOS / "arm.yaml"), "--target-position", *target, "--no-plot", "--quiet", "-o",
            str(folder)]


def arm_inverse():
    """``tca-casadi inverse`` on the arm (whole call, the median of 3): to the tip of the arm
    with its bending module's TCA 2 at 60 degC (a forward solve gives it, not timed)."""
    from tca_casadi.simulation import Simulation
    target = Simulation.from_file(SCENARIOS / "arm.yaml", ["bending.tca2.temperature=60"]).solve(warn=False).tip_position
    walls, reached = [], []
    for _ in range(3):
        with tempfile.TemporaryDirectory() as folder:
            wall, _, process = _run(_cli(*inverse_arguments([f"{x:.9f}" for x in target], folder)))
        walls.append(wall)
        reached.append("REACHED" in process.stdout)
    return {"wall_s": statistics.median(walls), "walls_s": walls, "exit": process.returncode, "reached": all(reached),
            "target": [f"{x:.9f}" for x in target]}


def targets(quick=False):
    """Every target's row (module docstring), and where a target is not met a profile by stage of
    its run (:func:`where_the_time_goes`, not in a ``quick`` run); ``quick``: the cheap ones,
    0.5 s of Till's rod."""
    sys.path.insert(0, str(Path(__file__).parent))
    scratch = tempfile.mkdtemp(prefix="tca_targets_")
    from bench import dynamics_rate, study_rates, till_cantilever, wall_pressing
    rows = []
    warm = warm_solve(5 if quick else 50)
    rows.append(row("bending module: warm solve after +1 degC, from the previous point's factors (solver.jit)",
                    warm["solve_true_s"] * 1e3, 0.5, "ms", warm["converged_true"] and warm["solve_true_s"] <= 5e-4,
                    f"Newton alone {warm['newton_true_s'] * 1e3:.3f} ms; uncompiled {warm['solve_false_s'] * 1e3:.2f} ms"))
    sweep = build_and_sweep()
    for jit in ("false", "true"):
        r = sweep[jit]
        rows.append(row(f"bending module: build + 101-step sweep, in a fresh process after its imports"
                        f"{' (solver.jit)' if jit == 'true' else ''}", r["build_sweep_s"], 0.3, "s",
                        r["completed"] and r["build_sweep_s"] <= 0.3, f"imports {r['import_s']:.2f} s before it",
                        PROFILES["sweep"] if jit == "false" else None))
    duration = 0.5 if quick else 25.0
    till = till_cantilever(duration, jit=True)
    rows.append(row(f"Till's steel cantilever, dt 2 ms, {duration:g} s, whole simulate call (solver.jit)",
                    till["real_time_factor"], 20.0, "x real time", till["real_time_factor"] >= 20,
                    f"{till['wall_s']:.2f} s; first mode {till['first_mode_hz']:.3f} Hz",
                    PROFILES["till"].format(duration=duration, folder=scratch)))
    for name, goal in ((("bending module", 20.0),) if quick else (("bending module", 20.0), ("arm", 2.0))):
        rate = dynamics_rate(name, 0.002, 5 if quick else 50, jit=True)
        rows.append(row(f"{name}: BDF2 dynamics at dt 2 ms (solver.jit)", rate["real_time_factor"], goal,
                        "x real time", (rate["real_time_factor"] or 0) >= goal,
                        f"{rate['step_s'] * 1e3:.2f} ms per step" if rate["step_s"] else rate.get("message", ""),
                        PROFILES["dynamics"].format(name=name)))
    wall = wall_pressing(5 if quick else 50)
    rows.append(row("bending module pressing on a wall (issue 33): BDF2 at dt 2 ms, real-time factor against "
                    "the same run without the wall", wall["ratio"], 0.5, "ratio", (wall["ratio"] or 0) >= 0.5,
                    f"{wall['wall']['step_s'] * 1e3:.2f} ms per step on the wall ({wall['wall']['unknowns']} unknowns), "
                    f"{wall['no_wall']['step_s'] * 1e3:.2f} ms without ({wall['no_wall']['unknowns']})"
                    if wall["ratio"] else "a run failed"))
    if not quick:
        robot = random_robot()
        rows.append(row("random 4-module robot (robot_11_9): tca-casadi solve, whole call", robot["wall_s"], 10.0, "s",
                        robot["wall_s"] <= 10 and robot["converged"] and robot["accuracy_met"],
                        f"converged {robot['converged']}, accuracy met {robot['accuracy_met']}"))
        rows.append(row("random 4-module robot (robot_11_9): peak memory", robot["peak_mb"], 500.0, "MB",
                        robot["peak_mb"] <= 500))
        inverse = arm_inverse()
        rows.append(row("arm: tca-casadi inverse, whole call (median of 3)", inverse["wall_s"], 2.0, "s",
                        inverse["wall_s"] <= 2 and inverse["reached"],
                        f"reached {inverse['reached']}; runs " + ", ".join(f"{w:.2f}" for w in inverse["walls_s"]) + " s",
                        PROFILES["inverse"].format(target=inverse["target"], folder=scratch)))
        studies = study_rates(22, 2)
        rows.append(row("bending module temperature box: study samples per second per core (serial)",
                        studies["serial_samples_per_s"], 1000.0, "samples/s", studies["serial_samples_per_s"] >= 1000,
                        f"{studies['samples']} samples", PROFILES["study"].format(jit="solver.jit=auto", per_axis=22)))
        study_rates(3, 1, ["solver.jit=true"])           # its compile, kept on disk, not timed
        compiled = study_rates(22, 1, ["solver.jit=true"])
        rows.append(row("bending module temperature box: study samples per second per core (serial, solver.jit)",
                        compiled["serial_samples_per_s"], 1000.0, "samples/s",
                        compiled["serial_samples_per_s"] >= 1000, f"{compiled['samples']} samples",
                        PROFILES["study"].format(jit="solver.jit=true", per_axis=22)))
    for r in rows:                        # where the time goes, where a target is not met
        if not r["met"] and r["profile"] and not quick:
            r["stages"] = where_the_time_goes(r["profile"])
    shutil.rmtree(scratch, ignore_errors=True)
    return rows


def print_targets(rows):
    from stages import print_stages
    width = max(len(r["what"]) for r in rows)
    for r in rows:
        value = r["measured"]
        shown = "n/a" if value is None or not np.isfinite(value) else f"{value:.3g}"
        print(f"{r['what']:<{width}}  {shown:>8} {r['unit']:<11} target {r['target']:g}  "
              f"{'met' if r['met'] else 'NOT MET'}{'  (' + r['note'] + ')' if r['note'] else ''}")
    for r in rows:
        if r.get("stages"):
            print_stages(f"where the time goes (not met): {r['what']}, profiled in a fresh process, imports "
                         f"included ({r['stages']['total_s']:.2f} s)", r["stages"]["stages"])

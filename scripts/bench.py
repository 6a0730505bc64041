"""Speed and accuracy benchmark: collocation (IPOPT and the Newton fast path) against the
shooting solver, measured in the same run.

    python scripts/bench.py                 # full run (a few minutes), writes results/bench.json
    python scripts/bench.py --quick         # smoke run: 1 repeat, fewer problems and steps

For each problem it reports the median over repeats of: the NLP build; a cold solve
(continuation from the reference state); a warm re-solve after +1 degC on every TCA (+1 % load
where there is no TCA), by IPOPT and by Newton; a 101-step sweep 25 -> 125 degC (the load from
0 to its value where there is no TCA); an inverse query (full-space IPOPT and reduced, targets
from forward solves at random temperatures); the shooting solver's cold solve; the tip error of
each against a reference on a much finer mesh (64 intervals, degree 5); and the cold
collocation time on the coarsest mesh at least as accurate as shooting (the speed ratio at
equal accuracy). Shooting is timed twice in the same run: with its exact Jacobian (variational
equations, the default) and with forward differences (the method before), both on the CasADi
right-hand sides.

Also: the CLI's start-up (``tca-casadi --help`` and ``validate`` of the bending module, each a
fresh process, median of 5) and ``tca-casadi check`` on every shipped scenario (collocation and
shooting time, one run each).
"""
import argparse
import json
import platform
import statistics
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tca_casadi import InverseStatics, Simulation, Sweep, Target  # noqa: E402

SCENARIOS = ROOT / "scenarios"


def arm_source():
    """The arm's chain without its gripper: the bending module with the twisting module below
    (the README's "arm (bending + twisting)" row; the gripper's sequence is timed separately)."""
    bending, twisting = (yaml.safe_load((SCENARIOS / f"{n}.yaml").read_text())
                         for n in ("bending_module", "twisting_module"))
    raw = dict(bending, name="arm_bending_twisting", loads=[], modules=bending["modules"] + twisting["modules"])
    raw.pop("inverse", None)
    raw["solver"] = {"intervals": "auto", "degree": 4}
    return raw


PROBLEMS = {
    "bending_module": lambda: SCENARIOS / "bending_module.yaml",
    "twisting_module": lambda: SCENARIOS / "twisting_module.yaml",
    "arm": arm_source,
    "elastica": lambda: SCENARIOS / "analytic" / "tip_load.yaml",
}


def median_time(function, repeats):
    """(median seconds, last result) of ``repeats`` calls."""
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def first_solves(source, repeats):
    """Medians of a fresh build and of the first cold solve on it (with the error estimate: it
    builds the degree d+1 solver and any refined one), nothing kept from an earlier repeat.
    Returns ``(build_s, cold_s, simulation, solution)`` of the last repeat."""
    from tca_casadi.solvers.collocation import clear_built_solvers
    builds, colds = [], []
    for _ in range(repeats):
        clear_built_solvers()
        start = time.perf_counter()
        sim = _built(source)
        builds.append(time.perf_counter() - start)
        start = time.perf_counter()
        cold = sim.solve(warn=False)
        colds.append(time.perf_counter() - start)
    return statistics.median(builds), statistics.median(colds), sim, cold


def nudge(sim, params):
    """+1 degC on every TCA, +1 % on every load/tension."""
    out = params.copy()
    for name in sim.robot.layout.names():
        slot = sim.robot.layout[name]
        if name.endswith(".temperature"):
            out[slot] += 1.0
        elif name.endswith((".tension", ".force", ".moment", ".mass")):
            out[slot] *= 1.01
    return out


def redesign(sim, params):
    """+10 % on every material's Young's modulus (a design change: an NLP parameter)."""
    out = params.copy()
    for name in sim.robot.layout.names():
        if name.endswith(".youngs_modulus"):
            out[sim.robot.layout[name]] *= 1.10
    return out


def sweep_paths(sim):
    tcas = [a.parameter for a in sim.robot.tcas]
    if tcas:
        return tcas, 25.0, 125.0
    name = next(n for n in sim.robot.layout.names() if n.endswith(".force"))
    component = int(np.argmax(np.abs(sim.get_parameter(name))))
    return [f"{name}[{component}]"], 0.0, float(sim.get_parameter(name)[component])


def bench_problem(name, source, repeats, steps, shooting_repeats, inverse_queries):
    row = {"problem": name}
    row["build_s"], row["cold_s"], sim, cold = first_solves(source, repeats)
    row["cold_kept_s"], _ = median_time(lambda: sim.solve(warn=False), repeats)   # every NLP kept
    row["cold_converged"] = bool(cold.converged)
    solver = sim.solver()                          # the mesh the cold solve refined to, if it did
    row["unknowns"] = int(solver.nlp.w.numel())
    row["intervals"] = "+".join(map(str, cold.accuracy.intervals)) if cold.accuracy else "-"
    nudged = nudge(sim, sim.params)
    row["warm_ipopt_s"], warm = median_time(lambda: solver.solve_ipopt(nudged, cold), max(repeats, 5))
    row["warm_newton_s"], fast = median_time(lambda: solver.solve_newton(nudged, cold.iterate.w), max(repeats, 5))
    row["warm_newton_equals_ipopt_m"] = float(np.max(np.abs(fast.tip_position - warm.tip_position)))
    stiffer = redesign(sim, sim.params)
    row["design_newton_s"], designed = median_time(lambda: solver.solve_newton(stiffer, cold.iterate.w),
                                                   max(repeats, 5))
    row["design_converged"] = bool(designed.converged)
    paths, start, stop = sweep_paths(sim)
    row["sweep_steps"] = steps
    row["sweep_s"], sweep = median_time(lambda: Sweep(sim, paths, start, stop, steps=steps).run(), repeats)
    row["sweep_completed"] = bool(sweep.completed)
    reference = Simulation.from_file(source, ["solver.intervals=64", "solver.degree=5", "solver.refine=off"]).solve(warn=False)
    row["tip_error_collocation_m"] = float(np.linalg.norm(cold.tip_position - reference.tip_position))
    if sim.robot.tcas and inverse_queries:
        row.update(bench_inverse(sim, inverse_queries))
    if shooting_repeats:
        row["shooting_s"], shot = median_time(lambda: sim.solve(method="shooting", warn=False), shooting_repeats)
        row["shooting_differences_s"], _ = median_time(lambda: _shooting_by_differences(source), shooting_repeats)
        row["tip_error_shooting_m"] = float(np.linalg.norm(shot.tip_position - reference.tip_position))
        row["speedup_cold"] = row["shooting_s"] / row["cold_s"]
        row.update(equal_accuracy(source, reference, row["tip_error_shooting_m"], repeats))
        row["speedup_equal_accuracy"] = row["shooting_s"] / row["cold_equal_accuracy_s"]
    return row


def equal_accuracy(source, reference, shooting_error, repeats):
    """Cold collocation time on the coarsest mesh at least as accurate as shooting (tip error
    at most max(shooting's, 1e-12) m against the fine reference; 1e-12 is the floor the
    reference itself and the solver tolerance allow)."""
    threshold = max(shooting_error, 1e-12)
    for intervals in (4, 6, 8, 12, 16, 24, 32, 48):
        sim = Simulation.from_file(source, [f"solver.intervals={intervals}", "solver.refine=off"])
        solution = sim.solve(warn=False)
        error = float(np.linalg.norm(solution.tip_position - reference.tip_position))
        if error <= threshold:
            break
    seconds, _ = median_time(lambda: sim.solve(warn=False), repeats)
    return {"intervals_equal_accuracy": intervals, "tip_error_equal_accuracy_m": error,
            "cold_equal_accuracy_s": seconds}


def _shooting_by_differences(source):
    """A cold shooting solve with the forward-difference Jacobian (the previous method)."""
    from tca_casadi.solvers import ShootingSolver
    sim = Simulation.from_file(source)
    sim.strategy.use_solver(ShootingSolver(sim.robot, sim.scenario.solver, jacobian="differences"), "shooting")
    return sim.solve(method="shooting", warn=False)


def startup(repeats=5):
    """Median wall time [s] of ``tca-casadi --help`` and of ``validate`` on the bending module,
    each in a fresh Python process."""
    commands = {"startup_help_s": ["--help"],
                "startup_validate_s": ["validate", str(SCENARIOS / "bending_module.yaml")]}
    out = {}
    for name, argv in commands.items():
        out[name], _ = median_time(lambda: subprocess.run([sys.executable, "-m", "tca_casadi.cli", *argv],
                                                          check=True, capture_output=True), repeats)
    return out


#: the heating/cooling cycle of ``simulate``'s benchmark: 0.5 W on TCAs 2 and 3 from 1 s to 30 s
CYCLE = ["bending.tca2.drive={kind: power, value: 0}", "bending.tca3.drive={kind: power, value: 0}", "duration=60",
         "timeline=[{at: 1 s, set: {bending.tca2.drive.value: 0.5 W, bending.tca3.drive.value: 0.5 W}},"
         " {at: 30 s, set: {bending.tca2.drive.value: 0, bending.tca3.drive.value: 0}}]"]


def simulate_cycle(dt, repeats, jit=False):
    """Median wall time [s] of the bending module's 60 s heating/cooling cycle at output step
    ``dt`` (the NLP built, compiled with ``jit``, and the t = 0 state solved before timing; the
    thermal integration and every output time's equilibrium timed), and the real-time factor."""
    from tca_casadi.time_simulation.timeline import TimeSimulation
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml", CYCLE + [f"solver.jit={str(jit).lower()}"])
    sim.solve(warn=False)
    seconds, series = median_time(lambda: TimeSimulation(sim, dt=dt).run(), repeats)
    suffix = "_jit" if jit else ""
    return {"simulate_dt_s": dt, "simulate_outputs": int(len(series.t)), f"simulate{suffix}_s": seconds,
            f"simulate{suffix}_real_time_factor": 60.0 / seconds, f"simulate{suffix}_completed": bool(series.completed)}


#: dynamics benchmarks: scenario, overrides (no connector mass: rigid inertias are not modelled yet)
DYNAMIC_PROBLEMS = {"bending module": ("bending_module", ["bending.tca2.temperature=25", "bending.tca3.temperature=25"]),
                    "arm": ("arm", ["finger_a.connector.mass=0"])}


def dynamics_rate(name, dt, steps, jit=False, problem=None):
    """Real-time factor (simulated seconds per wall second) of BDF2 dynamics: the median step time
    (what ``simulate`` does per step: Newton and the step's outputs; the Solutions with their
    global balance are built every ``dynamics.balance_every`` steps only) over ``steps`` steps of
    ``dt`` after a TCA's temperature steps by 10 degC (the static start, the dynamic NLP's build
    and any compile not timed); ``jit``: with ``solver.jit``; ``problem``: ``(scenario,
    overrides)`` instead of ``DYNAMIC_PROBLEMS[name]``."""
    from tca_casadi.solvers.dynamics import RodDynamics
    scenario, overrides = problem or DYNAMIC_PROBLEMS[name]
    sim = Simulation.from_file(SCENARIOS / f"{scenario}.yaml", overrides + [f"solver.jit={str(jit).lower()}"])
    static = sim.solve(warn=False)
    dynamics = RodDynamics(sim.robot, sim.solver("collocation"), "bdf2")
    state = dynamics.start(static)
    params = sim.params.copy()
    key = sim.robot.tcas[0].parameter
    params[sim.robot.layout[key]] += 10.0
    state.params = params
    times, iterations = [], []
    for _ in range(steps):
        started = time.perf_counter()
        state = dynamics.advance(params, dt)
        if state is None:
            return {"dt_s": dt, "step_s": None, "real_time_factor": None, "message": dynamics.last_status.message}
        dynamics.outputs(state)
        times.append(time.perf_counter() - started)
        iterations.append(state.status.nit)
    step = float(np.median(times))
    return {"dt_s": dt, "jit": jit, "step_s": step, "real_time_factor": dt / step,
            "newton_iterations": float(np.median(iterations)), "unknowns": int(dynamics.solver.nlp.scale.size)}


#: the bending module pressing on a wall (issue 33): TCA 2 and 3 at 100 degC bend it into a wall
#: 12 mm from its axis; its dynamics starts there
WALL = ["bending.tca2.temperature=100", "bending.tca3.temperature=100",
        "obstacles=[{name: wall, shape: plane, position: [-12 mm, 0, 0], normal: [1, 0, 0]}]"]


def wall_pressing(steps=50, dt=0.002):
    """Issue 33's contact benchmark: BDF2 at ``dt`` of the bending module pressed on a wall
    (:data:`WALL`, a +10 degC step on TCA 2 from its static equilibrium there) against the same
    run without the wall: both real-time factors (:func:`dynamics_rate`'s median step) and their
    ratio (the goal: at least 0.5)."""
    wall, free = (dynamics_rate(name, dt, steps, problem=("bending_module", overrides))
                  for name, overrides in (("bending module on a wall", WALL), ("bending module, no wall", WALL[:2])))
    ratio = (wall["real_time_factor"] / free["real_time_factor"]
             if wall["real_time_factor"] and free["real_time_factor"] else None)
    return {"wall": wall, "no_wall": free, "ratio": ratio}


def first_mode(t, x):
    """Frequency [Hz] of ``x(t)`` from its upward crossings of its mean (linear interpolation
    between samples; the first and last crossings span whole periods)."""
    x = np.asarray(x, float) - np.mean(x)
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    if len(up) < 2:
        return None
    crossings = t[up] - x[up] * (t[up + 1] - t[up]) / (x[up + 1] - x[up])
    return float((len(crossings) - 1) / (crossings[-1] - crossings[0]))


def till_arguments(duration, jit):
    """The ``tca-casadi`` arguments of :func:`till_cantilever`'s run (its output folder apart)."""
    return ["simulate", str(SCENARIOS / "analytic" / "steel_cantilever.yaml"), "--dt", "0.002", "--set",
            f"duration={duration}", "--set", f"solver.jit={str(jit).lower()}", "--no-plot", "--no-animation", "--quiet"]


def till_cantilever(duration, jit=False):
    """The whole ``tca-casadi simulate`` call (a fresh process: import, build, static start, every
    BDF2 step of 2 ms, the CSV and JSON; no plot or animation) on John Till's steel cantilever
    (``scenarios/analytic/steel_cantilever.yaml``) for ``duration`` [s]: the wall time, the
    real-time factor and the first mode's frequency from the tip's crossings of its mean, beside
    Euler-Bernoulli's 5.596 Hz; ``jit``: with ``solver.jit`` (its compile, kept on disk, done
    by a first run that is not timed)."""
    import tempfile
    command = [sys.executable, "-m", "tca_casadi.cli", *till_arguments(duration, jit)]
    with tempfile.TemporaryDirectory() as folder:
        if jit:
            subprocess.run(command + ["-o", folder], check=True, capture_output=True)
        started = time.perf_counter()
        subprocess.run(command + ["-o", folder], check=True, capture_output=True)
        wall = time.perf_counter() - started
        data = np.genfromtxt(Path(folder) / "timeseries.csv", delimiter=",", names=True)
    return {"duration_s": duration, "jit": jit, "wall_s": wall, "real_time_factor": duration / wall,
            "first_mode_hz": first_mode(data["t_s"], data["tip_x_m"]), "euler_bernoulli_hz": 5.596}


def till_stages(duration):
    """Where the time of Till's cantilever goes (:mod:`stages`): the run of ``duration`` [s]
    in-process (BDF2, 2 ms; the scenario, the NLP and the static start before it, timed apart),
    by stage, with each stage's time per step."""
    from stages import StageProfile
    from tca_casadi.time_simulation.timeline import TimeSimulation
    started = time.perf_counter()
    sim = Simulation.from_file(SCENARIOS / "analytic" / "steel_cantilever.yaml", [f"duration={duration}"])
    run = TimeSimulation(sim, dt=0.002)
    setup = time.perf_counter() - started
    with StageProfile() as profile:
        started = time.perf_counter()
        series = run.run()
        total = time.perf_counter() - started
    return {"duration_s": duration, "steps": len(series.t) - 1, "setup_s": setup, "run_s": total,
            "stages": profile.report(total)}


def warm_stages(repeats=200):
    """Where a warm Newton solve of the bending module after +1 degC goes (:mod:`stages`):
    ``repeats`` solves alternating between the two temperatures, each from the other's solution."""
    from stages import StageProfile
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml", ["solver.algorithm=newton"])
    base = sim.solve(warn=False)
    solver = sim.solver("collocation")
    points = [sim.params.copy(), nudge(sim, sim.params)]
    last = solver.solve(points[1], base)
    with StageProfile() as profile:
        started = time.perf_counter()
        for k in range(repeats):
            last = solver.solve(points[k % 2], last)
        total = time.perf_counter() - started
    return {"repeats": repeats, "solve_s": total / repeats, "converged": bool(last.converged),
            "stages": profile.report(total)}


def print_till(runs):
    for r in runs:
        print(f"dynamics, Till's steel cantilever (BDF2, 2 ms, {r['duration_s']:g} s, whole simulate call"
              f"{', solver.jit' if r['jit'] else ''}): {r['wall_s']:.2f} s, {r['real_time_factor']:.2f}x real time; "
              f"first mode {r['first_mode_hz']:.3f} Hz (Euler-Bernoulli {r['euler_bernoulli_hz']:.3f} Hz)")


def control_rates(quick=False):
    """Heating schedules and the closed loop (issue 32): the minimum-time plan of the bending
    module (TCA 2 by power, to the pose 60 degC holds, 60 nodes on 30 s; quick: 10) and of the
    arm (its bending module's TCAs by power, to the pose of TCA 2 at 60 degC; 60 nodes; skipped
    when quick), each from a fresh build, wall time and evaluations; and the closed loop of
    ``scenarios/bending_module_mpc.yaml`` at a 0.5 s period (its 10 s horizon in 10 steps; 30 s,
    quick: 5 s) with its controller's solve times."""
    from tca_casadi.control import ClosedLoop, Plan
    out = {}
    heating = SCENARIOS / "bending_module_heating.yaml"
    cases = {"bending module": (heating, [], ["bending.tca2.temperature=60"])}
    if not quick:
        drives = [f"bending.tca{k}.drive={{kind: power, value: 0}}" for k in (1, 2, 3)]
        cases["arm"] = (SCENARIOS / "arm.yaml", drives + [f"bending.tca{k}.temperature=25" for k in (1, 2, 3)],
                        ["bending.tca2.temperature=60", "bending.tca1.temperature=25", "bending.tca3.temperature=25"])
    for name, (source, overrides, at) in cases.items():
        target = Simulation.from_file(source, overrides + at).solve(warn=False).tip_position
        started = time.perf_counter()
        plan = Plan(Simulation.from_file(source, overrides), target, horizon=30.0, nodes=10 if quick else 60).solve()
        out[f"plan {name}"] = {"nodes": len(plan.t) - 1, "wall_s": time.perf_counter() - started,
                               "evaluations": plan.result.nit, "reached_at_s": plan.reached_at_s,
                               "converged": plan.converged}
    loop = ClosedLoop(SCENARIOS / "bending_module_mpc.yaml", [f"duration={5 if quick else 30}",
                                                             "bending.tca2.drive.mpc.period=0.5 s"]).run()
    report = loop.report()
    out["mpc bending module"] = {key: report[key] for key in ("periods", "reached_at_s", "solve_time_median_s",
                                                              "solve_time_max_s", "solve_time_fraction_of_period")}
    return out


def print_control(rates):
    for name, r in rates.items():
        if name.startswith("plan"):
            print(f"{name}: {r['nodes']} nodes, {r['wall_s']:.2f} s ({r['evaluations']} evaluations), reached at "
                  f"{r['reached_at_s']} s, {'converged' if r['converged'] else 'NOT CONVERGED'}")
        else:
            print(f"{name}: {r['periods']} periods of 0.5 s, controller solve median {r['solve_time_median_s'] * 1e3:.0f} ms, "
                  f"max {r['solve_time_max_s'] * 1e3:.0f} ms ({r['solve_time_fraction_of_period']:.0%} of the period)")


def study_rates(per_axis, design_per_length, overrides=()):
    """Samples per second of ``tca-casadi study`` on the bending module: the temperature box of
    its three TCAs (``per_axis``^3 grid samples, 25-125 degC) serially and on a pool of 2
    processes (their start-up, the NLP builds and the nominal solve included: the wall time of
    ``Study.run``), and a design study with rebuilt geometry (5 module lengths x
    ``design_per_length`` temperatures, one NLP build per length); ``overrides``: scenario
    settings for the temperature box (e.g. ``solver.jit=true``)."""
    from tca_casadi.studies.batch.study import Study
    vary = {f"bending.tca{k}.temperature": [25, 125, per_axis] for k in (1, 2, 3)}
    out = {"samples": per_axis ** 3}
    for label, workers in (("serial", None), ("processes_2", 2)):
        sim = Simulation.from_file(SCENARIOS / "bending_module.yaml", list(overrides))
        result = Study(sim, vary=vary).run(workers=workers)
        out[f"{label}_samples_per_s"] = result.info["samples_per_second"]
        out[f"{label}_wall_s"] = result.info["wall_time_s"]
        out[f"{label}_converged"] = int(result.info["converged"])
    out["parallel_efficiency"] = out["processes_2_samples_per_s"] / (2 * out["serial_samples_per_s"])
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    design = Study(sim, vary={"bending.length": {"values": [f"{v} mm" for v in (35, 40, 45, 50, 55)]},
                              "bending.tca2.temperature": [25, 125, design_per_length]}).run()
    out.update({"design_samples": int(design.info["samples"]), "design_samples_per_s": design.info["samples_per_second"],
                "design_converged": int(design.info["converged"])})
    return out


MUSCLES = {"sma": ("bending_module_sma", "bending.sma1.temperature", 25.0, 110.0),
           "mckibben": ("bending_module_mckibben", "segment.pam1.pressure", 0.0, 400e3),
           "custom": ("bending_module_custom", "bending.m1.input", 0.0, 2.0)}


def muscle_rates(repeats, steps):
    """The other muscles' example robots: build, cold solve, a warm Newton solve after a 1 %
    change of the input, a natural-continuation sweep of the input over its range, and the
    collocation/shooting check."""
    from tca_casadi.solvers.collocation import clear_built_solvers
    out = {}
    for kind, (name, path, start, stop) in MUSCLES.items():
        source = SCENARIOS / f"{name}.yaml"
        row = {}
        row["build_s"], row["cold_s"], sim, cold = first_solves(source, repeats)
        solver = sim.solver()
        slot = sim.robot.layout[path]
        nudged = sim.params.copy()
        nudged[slot] = nudged[slot] * 1.01 + 0.01 * (stop - start) * (nudged[slot] == 0)
        row["warm_newton_s"], warm = median_time(lambda: solver.solve_newton(nudged, cold.iterate.w), max(repeats, 5))
        row["warm_converged"] = bool(warm.converged)
        row["sweep_steps"] = steps
        row["sweep_s"], sweep = median_time(lambda: Sweep(sim, [path], start, stop, steps=steps).run(), repeats)
        row["sweep_completed"] = bool(sweep.completed)
        row.update(check_times([name])[name])
        out[kind] = row
        clear_built_solvers()
    return out


CONTACT = {"tendon robot": ("tendon_robot", "tendon_robot_wall", "body.t1.displacement"),
           "propped cantilever": (None, "analytic/propped_cantilever", "gravity")}


def contact_rates(repeats):
    """Solve times with contact against without: build, cold (continuation from the reference
    state, localisation, error estimate) and a warm solve after a 1 % change of the load
    (``Simulation.solve`` from the last answer)."""
    out = {}
    for label, (plain, touching, path) in CONTACT.items():
        for key, name in (("without", plain), ("with", touching)):
            if name is not None:
                out[f"{label} {key} contact"] = contact_row(
                    SCENARIOS / f"{name}.yaml", repeats,
                    lambda sim, path=path: sim.set_parameter(path, sim.get_parameter(path) * 1.01))
    out.update(grasp_rates(repeats))
    out.update(friction_rates(repeats))
    return out


def contact_row(source, repeats, load, warm_from=None):
    """One contact row: build and cold medians of ``source``, then ``load(sim)`` and the median
    warm solve from the cold answer (or from ``warm_from(sim, cold)``), with the unknowns and
    the closed contacts counted."""
    from tca_casadi.solvers.collocation import clear_built_solvers
    row = {}
    row["build_s"], row["cold_s"], sim, cold = first_solves(source, repeats)
    start = cold if warm_from is None else warm_from(sim, cold)
    load(sim)
    row["warm_s"], warm = median_time(lambda: sim.solve(warm_start=start, warn=False), max(repeats, 5))
    row["converged"] = bool(cold.converged and start.converged and warm.converged)
    row["contacts"] = len(warm.contacts)
    row["unknowns"] = int(sim.solver().nlp.w.numel())
    clear_built_solvers()
    return row


def friction_rates(repeats):
    """Friction against an obstacle: the propped cantilever (``scenarios/analytic/
    propped_cantilever.yaml``) with a frictionless knife edge and with ``friction: 0.5`` on
    Coulomb's cone: build, cold, and the warm solve that pushes the tip sideways by 6 mN (the
    frictional tip slides along the edge)."""
    import yaml
    with open(SCENARIOS / "analytic" / "propped_cantilever.yaml") as handle:
        raw = yaml.safe_load(handle)
    raw["loads"] = [{"name": "side", "kind": "point", "module": "rod", "at": "end", "force": [0, 0, 0]}]
    out = {}
    for key, mu in (("without", 0.0), ("with", 0.5)):
        raw["obstacles"][0]["friction"] = mu
        raw["contact"] = {"friction_law": "coulomb"}
        out[f"propped cantilever pushed sideways, {key} friction"] = contact_row(
            raw, repeats, lambda sim: sim.set_parameter("side.force", [0, 6e-3, 0]))
    return out


def grasp_rates(repeats):
    """The free-body pinch (``scenarios/analytic/free_pinch.yaml``) with and without its block
    and table: build, cold, and the warm solve that lifts the squeezed block 1 mm (the grips
    stick where they closed; without the block, the same squeeze and lift)."""
    import yaml
    with open(SCENARIOS / "analytic" / "free_pinch.yaml") as handle:
        with_block = yaml.safe_load(handle)
    without = {k: v for k, v in with_block.items() if k not in ("objects", "obstacles")}

    def squeezed(sim, cold):
        sim.set_parameter("squeeze_left.force", [2e-3, 0, 0])
        sim.set_parameter("squeeze_right.force", [-2e-3, 0, 0])
        return sim.solve(warm_start=cold, warn=False)
    return {f"free pinch {key} block": contact_row(raw, repeats, lambda sim: sim.set_parameter("base.position",
                                                                                               [0, 0, 1e-3]), squeezed)
            for key, raw in (("without", without), ("with", with_block))}


def print_contact(rates):
    for label, r in rates.items():
        print(f"{label}: {r['unknowns']} unknowns, build {r['build_s']:.3f} s, cold {r['cold_s'] * 1e3:.1f} ms, "
              f"warm {r['warm_s'] * 1e3:.2f} ms, {r['contacts']} contact(s){'' if r['converged'] else ' NOT CONVERGED'}")


def check_times(names):
    """``tca-casadi check`` on shipped scenarios: collocation and shooting seconds, agreement."""
    from tca_casadi.studies import check
    out = {}
    for name in names:
        report, _, _ = check(Simulation.from_file(SCENARIOS / f"{name}.yaml", allow_code=True))
        out[name] = {"collocation_s": report.solve_times_s["collocation"], "shooting_s": report.solve_times_s["shooting"],
                     "agree": report.agree, "tip_difference_m": report.tip_position_difference}
    return out


def _built(source):
    sim = Simulation.from_file(source, allow_code=True)
    sim.solver()
    return sim


def bench_inverse(sim, queries):
    """Median time of cold inverse queries (targets: forward tips at random temperatures in
    25-125 degC, seed 0), per method; the first query (which also solves the cached start
    equilibria) is reported separately."""
    paths = [a.parameter for a in sim.robot.tcas]
    forward, rng, targets = Simulation.from_file(sim.scenario.model_dump(mode="json")), np.random.default_rng(0), []
    for _ in range(queries + 1):
        for path, value in zip(paths, rng.uniform(25, 125, len(paths))):
            forward.set_parameter(path, value)
        targets.append(Target.create(forward.solve(warn=False).tip_position))
    out = {}
    for method in ("ipopt", "reduced"):
        inverse = InverseStatics(sim, bounds=(25, 125), method=method)
        results = [inverse.solve(t) for t in targets]
        out[f"inverse_{method}_first_s"] = results[0].solve_time_s
        out[f"inverse_{method}_s"] = statistics.median(r.solve_time_s for r in results[1:])
        out[f"inverse_{method}_reached"] = f"{sum(r.reachable for r in results)}/{len(results)}"
    return out


COLUMNS = [("problem", "{}"), ("unknowns", "{}"), ("intervals", "{}"), ("build_s", "{:.3f}"), ("cold_s", "{:.4f}"),
           ("cold_kept_s", "{:.4f}"),
           ("warm_ipopt_s", "{:.4f}"), ("warm_newton_s", "{:.4f}"), ("design_newton_s", "{:.4f}"), ("sweep_s", "{:.3f}"),
           ("inverse_ipopt_s", "{:.3f}"), ("inverse_reduced_s", "{:.3f}"), ("shooting_s", "{:.3f}"),
           ("shooting_differences_s", "{:.3f}"),
           ("speedup_cold", "{:.0f}x"), ("tip_error_collocation_m", "{:.1e}"),
           ("tip_error_shooting_m", "{:.1e}"), ("intervals_equal_accuracy", "{}"),
           ("tip_error_equal_accuracy_m", "{:.1e}"), ("speedup_equal_accuracy", "{:.0f}x")]


def table(rows):
    header = [name for name, _ in COLUMNS]
    lines = [" | ".join(header), " | ".join("---" for _ in header)]
    for row in rows:
        lines.append(" | ".join(fmt.format(row[name]) if name in row else "-" for name, fmt in COLUMNS))
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description="tca_casadi speed and accuracy benchmark")
    parser.add_argument("--quick", action="store_true", help="smoke run: 1 repeat, the bending module only")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "results" / "bench.json")
    parser.add_argument("--muscles", action="store_true", help="only the other muscles' rows (results/bench_muscles.json)")
    parser.add_argument("--contact", action="store_true", help="only the contact rows (results/bench_contact.json)")
    parser.add_argument("--control", action="store_true",
                        help="only the heating-schedule and closed-loop rows (results/bench_control.json)")
    parser.add_argument("--dynamics", action="store_true",
                        help="only the dynamics rows: Till's steel cantilever and the BDF2 step rates "
                             "(results/bench_dynamics.json)")
    parser.add_argument("--scaling", action="store_true",
                        help="only the growth with the mesh and the robot (scripts/scaling.py; results/bench_scaling.json)")
    parser.add_argument("--targets", action="store_true",
                        help="only issue 36's targets, each measured as the issue states it, met or not "
                             "(scripts/targets.py; results/bench_targets.json)")
    args = parser.parse_args(argv)
    if args.targets:
        from targets import print_targets, targets
        return _only(args, "targets", targets(args.quick), print_targets)
    if args.scaling:
        from scaling import print_scaling, scaling
        return _only(args, "scaling", scaling(args.quick), print_scaling)
    if args.dynamics:
        return _dynamics_only(args)
    if args.control:
        return _only(args, "control", control_rates(args.quick), print_control)
    if args.muscles:
        return _muscles_only(args)
    if args.contact:
        return _contact_only(args)
    if args.quick:
        plan = {"bending_module": (1, 11, 1, 2)}
    else:
        r = args.repeats
        plan = {"bending_module": (r, 101, r, 10), "twisting_module": (r, 101, 1, 10),
                "arm": (max(1, r // 2), 101, 1, 1), "elastica": (r, 101, r, 0)}
    rows = []
    for name, (repeats, steps, shooting_repeats, queries) in plan.items():
        print(f"benchmarking {name} ...", file=sys.stderr, flush=True)
        rows.append(bench_problem(name, PROBLEMS[name](), repeats, steps, shooting_repeats, queries))
    machine = {"date": date.today().isoformat(), "cpus": _cpus(), "python": platform.python_version(),
               "platform": platform.platform()}
    started = startup(1 if args.quick else 5)
    cycle = simulate_cycle(1.0 if args.quick else 0.1, 1 if args.quick else 5)
    if not args.quick:                     # the compiled residual (its one-time compile not timed)
        cycle.update(simulate_cycle(0.1, 5, jit=True))
    motion = dynamics_rates(args.quick)
    studies = study_rates(4, 4) if args.quick else study_rates(22, 20)
    muscles = muscle_rates(1, 11) if args.quick else muscle_rates(args.repeats, 35)
    checks = check_times(["bending_module"] if args.quick else
                         ["bending_module", "twisting_module", "tendon_robot", "tendon_robot_two_segments",
                          "arm", "arm_pick_and_place", "analytic/pure_moment", "analytic/tip_load",
                          "analytic/tendon_arc"])
    print(table(rows))
    print(f"start-up: --help {started['startup_help_s']:.3f} s, validate {started['startup_validate_s']:.3f} s")
    for name, c in checks.items():
        print(f"check {name}: collocation {c['collocation_s']:.3f} s, shooting {c['shooting_s']:.3f} s, "
              f"{'agree' if c['agree'] else 'DISAGREE'} (tip {c['tip_difference_m']:.1e} m)")
    print(f"simulate: 60 s heating/cooling cycle of the bending module at dt {cycle['simulate_dt_s']:g} s "
          f"({cycle['simulate_outputs']} outputs): {cycle['simulate_s']:.2f} s, "
          f"{cycle['simulate_real_time_factor']:.0f}x real time" + (
              f"; with solver.jit {cycle['simulate_jit_s']:.2f} s, {cycle['simulate_jit_real_time_factor']:.0f}x"
              if "simulate_jit_s" in cycle else ""))
    print_dynamics(motion)
    print(f"study: bending module temperature box, {studies['samples']} samples: serial "
          f"{studies['serial_samples_per_s']:.0f} samples/s, 2 processes {studies['processes_2_samples_per_s']:.0f} "
          f"samples/s (parallel efficiency {studies['parallel_efficiency']:.0%}); design study with rebuilt geometry "
          f"({studies['design_samples']} samples, 5 structures) {studies['design_samples_per_s']:.1f} samples/s")
    print_muscles(muscles)
    print(f"measured {machine['date']} on {machine['cpus']} CPUs, Python {machine['python']}")
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps({"quick": args.quick, "machine": machine, "startup": started, "simulate": cycle,
                                       "dynamics": motion, "study": studies, "muscles": muscles,
                                       "check": checks, "rows": rows}, indent=2))
    print(f"wrote {args.output}")
    return rows


def print_muscles(muscles):
    for kind, r in muscles.items():
        print(f"muscles ({kind}): build {r['build_s']:.3f} s, cold {r['cold_s'] * 1e3:.1f} ms, warm Newton "
              f"{r['warm_newton_s'] * 1e3:.2f} ms, sweep of {r['sweep_steps']} steps {r['sweep_s']:.2f} s"
              f"{'' if r['sweep_completed'] else ' (STOPPED)'}, check: collocation {r['collocation_s'] * 1e3:.1f} ms, "
              f"shooting {r['shooting_s'] * 1e3:.0f} ms, {'agree' if r['agree'] else 'DISAGREE'} "
              f"(tip {r['tip_difference_m']:.1e} m)")


def dynamics_rates(quick):
    """Per dynamic problem the BDF2 step rates (:func:`dynamics_rate`) and Till's cantilever's
    whole ``simulate`` call (:func:`till_cantilever`: 0.5 s simulated in a quick run, else 25 s,
    with and without ``solver.jit``)."""
    motion = {name: [dynamics_rate(name, dt, 5 if quick else 50, jit) for jit in ((False,) if quick else (False, True))
                     for dt in (0.002, 0.01)] for name in (["bending module"] if quick else list(DYNAMIC_PROBLEMS))}
    motion["till"] = [till_cantilever(0.5 if quick else 25.0, jit) for jit in ((False,) if quick else (False, True))]
    motion["till_stages"] = till_stages(0.5 if quick else 5.0)
    motion["warm_stages"] = warm_stages(20 if quick else 200)
    return motion


def print_dynamics(motion):
    from stages import print_stages
    for name, runs in motion.items():
        if name == "till":
            print_till(runs)
            continue
        if name == "till_stages":
            print_stages(f"where the time goes: Till's cantilever, {runs['steps']} steps of 2 ms in-process "
                         f"({runs['run_s']:.2f} s; scenario, NLP and static start before it {runs['setup_s']:.2f} s)",
                         runs["stages"], per=(runs["steps"], "step"))
            continue
        if name == "warm_stages":
            print_stages(f"where the time goes: bending module, warm Newton solve after +1 degC "
                         f"({runs['solve_s'] * 1e3:.2f} ms each, {runs['repeats']} solves)",
                         runs["stages"], per=(runs["repeats"], "solve"))
            continue
        print(f"dynamics (BDF2) {name}: " + ", ".join(
            f"dt {r['dt_s'] * 1e3:g} ms{' jit' if r['jit'] else ''}: {r['step_s'] * 1e3:.2f} ms per step "
            f"({r['newton_iterations']:g} Newton iterations), {r['real_time_factor']:.2f}x real time"
            if r["step_s"] else f"dt {r['dt_s'] * 1e3:g} ms: failed ({r['message']})" for r in runs))


def _dynamics_only(args):
    return _only(args, "dynamics", dynamics_rates(args.quick), print_dynamics)


def _muscles_only(args):
    return _only(args, "muscles", muscle_rates(args.repeats, 35), print_muscles)


def _contact_only(args):
    return _only(args, "contact", contact_rates(1 if args.quick else args.repeats), print_contact)


def _only(args, name, rates, printer):
    """Print one group's ``rates`` and write them, with the machine, to ``bench_NAME.json``."""
    printer(rates)
    machine = {"date": date.today().isoformat(), "cpus": _cpus(), "python": platform.python_version(),
               "platform": platform.platform()}
    print(f"measured {machine['date']} on {machine['cpus']} CPUs, Python {machine['python']}")
    output = args.output.with_name(f"bench_{name}.json")
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps({"machine": machine, name: rates}, indent=2))
    print(f"wrote {output}")
    return rates


def _cpus():
    import os
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


if __name__ == "__main__":
    main()

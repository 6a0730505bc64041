"""``tc.Study`` / ``tca-casadi study`` in one process: every row against an independent solve,
Monte Carlo moments, sensitivities against finite differences, designs with rebuilt structure,
resume, files and bad input."""
import json
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

import tca_casadi as tc
from tca_casadi.cli import main
from tca_casadi.errors import ScenarioError
from tca_casadi.studies.batch.study import PARTIAL, Study

TEMPERATURES = ["bending.tca1.temperature", "bending.tca2.temperature", "bending.tca3.temperature"]
TIP = ["tip_x [m]", "tip_y [m]", "tip_z [m]"]


@pytest.fixture
def bending(scenarios):
    return scenarios / "bending_module.yaml"


def test_rows_equal_independent_solves(bending):
    """A Sobol design over the three temperatures: random rows against ``solve --set`` of that
    row (cold, continuation and accuracy control) to 1e-9 m."""
    sim = tc.Simulation.from_file(bending)
    study = Study(sim, vary={p: [25, 125] for p in TEMPERATURES}, design="sobol", samples=24, seed=2)
    result = study.run()
    frame = result.frame
    assert len(frame) == 24 and frame["converged"].all()
    assert frame["sample"].tolist() == list(range(24))
    for _, row in frame.sample(4, random_state=0).iterrows():
        overrides = [f"{p}={float(row[f'{p} [degC]'])!r}" for p in TEMPERATURES]
        independent = tc.Simulation.from_file(bending, overrides).solve(warn=False)
        assert independent.converged
        assert_allclose(row[TIP].to_numpy(float), independent.tip_position, rtol=0, atol=1e-9)
        for key, actuator in independent.actuators.items():
            assert_allclose(row[f"{key}.tension [N]"], actuator.tension, rtol=1e-7, atol=1e-12)
    checked = frame["balance [-]"].dropna()          # each chunk's first and last sample in its solving order
    assert len(checked) >= 1 and (checked < 1e-9).all()


def test_rows_between_balance_checks_equal_rows_from_solutions(bending, monkeypatch):
    """Between its global balance checks (every ``BALANCE_EVERY``-th sample of a chunk and its
    last, issue 36) a study builds no Solution: the row comes from the solve's outputs. Every
    column equals the row built from a Solution at every sample, to roundoff; the balance is
    NaN exactly where it was not checked, and says so in the summary."""
    import tca_casadi.studies.batch.worker as worker
    vary = {p: [25, 125, 4] for p in TEMPERATURES}
    lean = Study(tc.Simulation.from_file(bending), vary=vary).run()
    monkeypatch.setattr(worker, "BALANCE_EVERY", 1)
    full = Study(tc.Simulation.from_file(bending), vary=vary).run()
    assert full.frame["converged"].all() and (full.frame["balance [-]"] < 1e-9).all()
    checked = lean.frame["balance [-]"].notna()
    assert 2 <= checked.sum() < len(lean.frame) // 4
    assert f"global balance checked at {checked.sum()} of {len(lean.frame)} converged samples" in lean.summary()
    columns = [c for c in lean.frame.columns if c not in ("balance [-]", "wall_time [s]", "solve_time [s]", "worker",
                                                           "message", "status")]
    assert_allclose(lean.frame[columns].to_numpy(float), full.frame[columns].to_numpy(float), rtol=0, atol=1e-12)
    assert (lean.frame["status"] == full.frame["status"]).all()


def test_monte_carlo_and_sensitivities(bending):
    """Monte Carlo of the modulus: the inputs carry the asked moments; the tip's spread matches
    the first-order propagation ``|dtip/dE| std(E)`` (exact local sensitivity) within 5 %; the
    local sensitivity equals a central difference of two solves."""
    sim = tc.Simulation.from_file(bending)
    path = "materials.ecoflex30.youngs_modulus"
    study = Study(sim, vary={path: {"normal": {"mean": "0.125 MPa", "std": "0.00125 MPa"}}},
                  design="sobol", samples=256, seed=0)
    result = study.run()
    values = result.frame[f"{path} [Pa]"].to_numpy(float)
    assert_allclose(values.mean(), 0.125e6, rtol=1e-3)
    assert_allclose(values.std(ddof=1), 1250.0, rtol=2e-2)
    local = result.sensitivity("local")
    derivative = local.loc[path].to_numpy(float)                         # [m/Pa]
    step = 100.0
    plus = tc.Simulation.from_file(bending, [f"{path}={0.125e6 + step}"]).solve(warn=False).tip_position
    minus = tc.Simulation.from_file(bending, [f"{path}={0.125e6 - step}"]).solve(warn=False).tip_position
    assert_allclose(derivative, (plus - minus) / (2 * step), rtol=1e-4, atol=1e-14)
    spread = result.tips().std(axis=0, ddof=1)
    predicted = np.abs(derivative) * values.std(ddof=1)
    big = predicted > 1e-3 * predicted.max()
    assert_allclose(spread[big], predicted[big], rtol=0.05)
    indices = result.sensitivity()                                       # one input: it explains all
    assert_allclose(indices.loc[f"{path} [Pa]", "tip_z [m]"], 1.0, rtol=0, atol=0.05)


def test_design_with_rebuilt_structure(bending):
    """A structural path (the module's length) groups the samples; each row equals a solve of
    that length, and the tip's distance from the base grows with the length."""
    sim = tc.Simulation.from_file(bending)
    study = Study(sim, vary={"bending.length": {"values": ["40 mm", "50 mm"]},
                             "bending.tca2.temperature": [25, 125, 3]})
    assert study.structural == ["bending.length"] and len(study.groups()) == 2
    result = study.run()
    frame = result.frame
    assert len(frame) == 6 and frame["converged"].all()
    row = frame.iloc[-1]
    independent = tc.Simulation.from_file(bending, [f"bending.length={float(row['bending.length [m]'])!r}",
                                                    f"bending.tca2.temperature={float(row['bending.tca2.temperature [degC]'])!r}"])
    assert_allclose(row[TIP].to_numpy(float), independent.solve(warn=False).tip_position, rtol=0, atol=1e-9)
    cold = frame[frame["bending.tca2.temperature [degC]"] == 25.0]
    lengths = np.linalg.norm(cold[TIP].to_numpy(float), axis=1)
    assert lengths[cold["bending.length [m]"].to_numpy() == 0.05][0] > lengths[cold["bending.length [m]"].to_numpy() == 0.04][0]


def test_rows_from_a_csv(bending, tmp_path):
    """Explicit samples from a CSV (units in brackets in the header, comment lines allowed):
    each row equals an independent solve."""
    table = tmp_path / "samples.csv"
    table.write_text("# two heated TCAs\nbending.tca2.temperature [degC],materials.ecoflex30.youngs_modulus [Pa]\n"
                     "40,120000\n90,130000\n65,125000\n")
    result = Study(tc.Simulation.from_file(bending), rows=table).run()
    frame = result.frame
    assert frame["bending.tca2.temperature [degC]"].tolist() == [40.0, 90.0, 65.0]
    for _, row in frame.iterrows():
        independent = tc.Simulation.from_file(bending, [
            f"bending.tca2.temperature={float(row['bending.tca2.temperature [degC]'])!r}",
            f"materials.ecoflex30.youngs_modulus={float(row['materials.ecoflex30.youngs_modulus [Pa]'])!r}"])
        assert_allclose(row[TIP].to_numpy(float), independent.solve(warn=False).tip_position, rtol=0, atol=1e-9)
    (tmp_path / "bad.csv").write_text("bending.tca2.temperature\n40\nhot\n")
    with pytest.raises(ScenarioError, match="bad.csv line 3, column 'bending.tca2.temperature': 'hot' is not a number"):
        Study(tc.Simulation.from_file(bending), rows=tmp_path / "bad.csv")


def test_failed_samples_are_rows(bending):
    """Samples the scenario cannot hold (a negative modulus drawn from a wide normal) are rows
    with converged False and the reason; none is dropped."""
    sim = tc.Simulation.from_file(bending)
    study = Study(sim, vary={"materials.ecoflex30.youngs_modulus": {"normal": {"mean": 1e5, "std": 1e5}}},
                  samples=20, seed=1)
    result = study.run()
    frame = result.frame
    assert len(frame) == 20
    bad = frame["materials.ecoflex30.youngs_modulus [Pa]"] <= 0
    assert bad.any() and (~frame.loc[bad, "converged"]).all()
    assert frame.loc[bad, "message"].str.contains("E = -").all()
    assert frame.loc[bad, "tip_x [m]"].isna().all()
    assert frame.loc[~bad, "converged"].all()


def test_a_serial_chunk_starts_from_the_chunk_before_it(bending, monkeypatch):
    """Serially, a chunk whose first sample follows the last one solved starts warm from its
    answer, where every chunk's first sample used to start cold (continuation from the
    reference state): the same rows as one chunk, to 1e-9 m, with fewer cold starts. A chunk
    after one that resume skipped starts cold."""
    import tca_casadi.studies.batch.executors as executors
    import tca_casadi.studies.batch.study as study_module
    from tca_casadi.solvers.strategy import SolveStrategy
    cold, starts = [], []
    original, solve_from = SolveStrategy.continue_from_rest, executors.solve_chunk_from
    monkeypatch.setattr(SolveStrategy, "continue_from_rest",
                        lambda self, *a, **k: cold.append(1) or original(self, *a, **k))
    monkeypatch.setattr(executors, "solve_chunk_from",
                        lambda chunk, progress=None, start=None: starts.append(start) or solve_from(chunk, progress, start))
    vary = {TEMPERATURES[1]: [25, 125, 7], TEMPERATURES[2]: [25, 125, 3]}
    whole = Study(tc.Simulation.from_file(bending), vary=vary).run()
    in_one_chunk, cold[:] = len(cold), []
    monkeypatch.setattr(study_module, "MAX_CHUNK", 6)
    study = Study(tc.Simulation.from_file(bending), vary=vary)
    starts.clear()
    chunked = study.run()
    assert len(starts) == 4 and starts[0] is None and all(s is not None and s.converged for s in starts[1:])
    assert len(cold) == in_one_chunk and chunked.frame["converged"].all()
    assert_allclose(chunked.frame[TIP].to_numpy(float), whole.frame[TIP].to_numpy(float), rtol=0, atol=1e-9)
    chunks = study.chunks()
    starts.clear()
    executors.run_serial([chunks[0], chunks[2], chunks[3]], lambda chunk, rows: None)    # chunk 1 done before
    assert starts[0] is None and starts[1] is None and starts[2] is not None


def test_resume_finishes_an_interrupted_study(bending, tmp_path):
    """A study stopped after 5 samples keeps them in study_rows.jsonl; --resume solves only the
    rest and gives the same rows as an uninterrupted run."""
    vary = {TEMPERATURES[1]: [25, 125, 4], TEMPERATURES[2]: [25, 125, 3]}
    sim = tc.Simulation.from_file(bending)
    calls = []

    def stop_after_five(fraction, text):
        calls.append(text)
        if len(calls) == 5:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        Study(sim, vary=vary).run(directory=tmp_path, progress=stop_after_five)
    lines = (tmp_path / PARTIAL).read_text().splitlines()
    assert len(lines) == 6                                   # the plan and five rows
    resumed = Study(sim, vary=vary).run(directory=tmp_path, resume=True)
    assert resumed.info["resumed_samples"] == 5 and len(resumed.frame) == 12
    whole = Study(sim, vary=vary).run()
    assert_allclose(resumed.frame[TIP].to_numpy(float), whole.frame[TIP].to_numpy(float), rtol=0, atol=1e-9)
    with pytest.raises(ScenarioError, match="another study"):
        Study(sim, vary={TEMPERATURES[1]: [25, 100, 4]}).run(directory=tmp_path, resume=True)


def test_cli_writes_every_file(bending, tmp_path, capsys):
    out = tmp_path / "study"
    code = main(["study", str(bending), "--vary", "bending.tca2.temperature=25:125:3",
                 "--monte-carlo", "bending.tca3.temperature=normal:75:5", "--samples", "12",
                 "--outputs", "bending.tca1.length", "max_residual", "-o", str(out), "--quiet"])
    assert code == 0
    text = capsys.readouterr().out
    assert "12 samples (random), 12 converged" in text
    frame = pd.read_parquet(out / "study.parquet")
    assert list(frame.columns[:3]) == ["sample", "bending.tca2.temperature [degC]", "bending.tca3.temperature [degC]"]
    assert {"bending.tca1.length [m]", "max_residual [-]", "bending.tca3.stroke [m]"} <= set(frame.columns)
    from_csv = pd.read_csv(out / "study.csv")
    assert_allclose(from_csv["tip_z [m]"].to_numpy(), frame["tip_z [m]"].to_numpy(), rtol=1e-11, atol=0)
    info = json.loads((out / "study.json").read_text())
    assert info["samples"] == 12 and info["failed"] == 0 and info["ran_on"] == "serial"
    assert info["workspace"]["points"] == 12
    for name in ("study_workspace.png", "study_monte_carlo.png"):
        assert (out / name).stat().st_size > 10000
    assert not (out / PARTIAL).exists()


@pytest.mark.parametrize("args, message", [
    (["--vary", "bending.tca9.temperature=25:125"], "neither a parameter nor a scenario value"),
    (["--vary", "bending.lenght=40mm:50mm:2"], "did you mean 'length'"),
    (["--rows", "missing.csv"], "missing.csv: no such file"),
    (["--vary", "bending.tca2.temperature=100:100"], "empty"),
    (["--vary", "bending.tca2.temperature=125:25"], "empty"),
    (["--vary", "bending.tca2.temperature=25:125:-2"], "points"),
    (["--vary", "bending.tca2.temperature=25:125:two"], "whole number"),
    (["--vary", "bending.tca2.temperature=25"], "LO:HI"),
    (["--vary", "bending.tca2.temperature=25:400"], "validated range"),
    (["--monte-carlo", "bending.tca2.temperature=normal:75:0"], "std"),
    (["--monte-carlo", "bending.tca2.temperature=normal:75:-1"], "std"),
    (["--monte-carlo", "bending.tca2.temperature=gauss:75:1"], "normal:MEAN:STD"),
    (["--vary", "bending.tca2.temperature=25:125", "--samples", "-3", "--design", "sobol"], "samples"),
    (["--vary", "bending.tca2.temperature=25:125", "--outputs", "bending.tip_w"], "unknown output"),
    (["--vary", "bending.tca2.temperature=25:125", "--workers", "0"], "workers"),
    ([], "nothing varies"),
])
def test_bad_input_is_one_line_exit_2(bending, tmp_path, capsys, args, message):
    code = main(["study", str(bending), "-o", str(tmp_path), "--quiet"] + args)
    err = capsys.readouterr().err
    assert code == 2
    assert message in err and err.count("\n") == 1, err


def test_unreachable_scheduler_is_exit_2(bending, tmp_path):
    """No scheduler at the address: one line, exit 2, within the connect timeout (5 s) plus start-up."""
    run = subprocess.run([sys.executable, "-m", "tca_casadi.cli", "study", str(bending), "--vary",
                          "bending.tca2.temperature=25:125:2", "--scheduler", "tcp://127.0.0.1:1",
                          "-o", str(tmp_path), "--quiet"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stderr
    assert "no Dask scheduler answers at 'tcp://127.0.0.1:1'" in run.stderr
    assert run.stderr.count("\n") == 1

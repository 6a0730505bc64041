"""scripts/bench.py runs (quick mode) and reports what the README's performance table shows."""
import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT / "scripts"))


def test_bench_quick_smoke(tmp_path, capsys):
    from bench import main
    rows = main(["--quick", "-o", str(tmp_path / "bench.json")])
    assert (tmp_path / "bench.json").exists()
    import json
    cycle = json.loads((tmp_path / "bench.json").read_text())["simulate"]
    assert cycle["simulate_completed"] and cycle["simulate_outputs"] == 61
    # Till's steel cantilever, 0.5 s of the whole simulate call: its first mode against Euler-Bernoulli
    # (BDF2 at 2 ms lags by (omega h)^2 / 3 ~ 2e-3; 0.5 s holds under 3 periods: 5.583 Hz measured)
    till = json.loads((tmp_path / "bench.json").read_text())["dynamics"]["till"][0]
    assert abs(till["first_mode_hz"] / till["euler_bernoulli_hz"] - 1) < 0.005, till
    # where the time goes: the stages (each its own time) and the rest add up to the run, and
    # every wrapped method is the original again afterwards
    motion = json.loads((tmp_path / "bench.json").read_text())["dynamics"]
    for profile, total in ((motion["till_stages"], motion["till_stages"]["run_s"]),
                           (motion["warm_stages"], motion["warm_stages"]["solve_s"] * motion["warm_stages"]["repeats"])):
        assert abs(sum(row["s"] for row in profile["stages"].values()) - total) < 1e-9 * max(total, 1.0)
        assert profile["stages"]["residual evaluations (CasADi)"]["calls"] >= 1
    assert motion["till_stages"]["stages"]["energy account"]["calls"] == motion["till_stages"]["steps"] + 1
    from tca_casadi.solvers.newton import SquareSystem
    assert SquareSystem.residual.__qualname__ == "SquareSystem.residual"
    by_name = {row["problem"]: row for row in rows}
    bending = by_name["bending_module"]
    assert bending["cold_converged"] and bending["sweep_completed"]
    assert bending["warm_newton_equals_ipopt_m"] < 1e-9          # the fast path is the same answer
    assert bending["tip_error_collocation_m"] < 1e-6              # the default mesh's accuracy
    assert bending["tip_error_shooting_m"] < 1e-6
    assert bending["inverse_reduced_reached"] == "3/3" and bending["inverse_ipopt_reached"] == "3/3"
    assert "speedup_cold" in bending and "problem | unknowns" in capsys.readouterr().out


def test_scaling_quick(tmp_path, capsys):
    """``bench.py --scaling --quick``: every point converges in its own process, and the
    printed table has its exponents."""
    from bench import main
    result = main(["--scaling", "--quick", "-o", str(tmp_path / "bench.json")])
    for kind in ("intervals", "modules"):
        rows = result[kind]["rows"]
        assert len(rows) == 3 and all(row.get("converged") for row in rows), rows
        assert all(row["unknowns"] > 0 and row["peak_rss_mb"] > 0 for row in rows)
        assert result[kind]["exponents"]["warm_s"] is not None
    out = capsys.readouterr().out
    assert "exponents (larger half)" in out and (tmp_path / "bench_scaling.json").exists()


def test_control_quick(tmp_path, capsys):
    """``bench.py --control --quick``: the 10-node plan reaches its target and the 5 s closed loop
    reports its solve times."""
    from bench import main
    result = main(["--control", "--quick", "-o", str(tmp_path / "bench.json")])
    assert result["plan bending module"]["converged"] and result["plan bending module"]["reached_at_s"] is not None
    assert result["mpc bending module"]["periods"] == 10 and result["mpc bending module"]["solve_time_median_s"] > 0
    assert "controller solve median" in capsys.readouterr().out and (tmp_path / "bench_control.json").exists()


def test_wall_pressing_quick():
    """Issue 33's contact benchmark runs: the bending module pressed on a wall and the same run
    without it both step (the wall adds the contact unknowns), with a ratio of their rates."""
    from bench import wall_pressing
    result = wall_pressing(steps=3)
    assert result["wall"]["unknowns"] > result["no_wall"]["unknowns"]
    assert result["ratio"] is not None and result["ratio"] > 0


def test_a_target_not_met_says_where_its_time_goes():
    """``bench.py --targets`` profiles each target it does not meet by stage, in a fresh process:
    the sweep's stages (its imports and NLP builds among them) add up to its run, and every
    point's record is one call."""
    from targets import PROFILES, where_the_time_goes
    profile = where_the_time_goes(PROFILES["sweep"])
    stages = profile["stages"]
    assert abs(sum(row["s"] for row in stages.values()) - profile["total_s"]) < 1e-9 * profile["total_s"]
    assert stages["imports (tca_casadi, CasADi, scipy)"]["s"] > 0 and stages["NLP builds"]["calls"] >= 1
    assert stages["a sweep point's record (sensitivities, singular value)"]["calls"] == 101
    assert all(row["s"] >= 0 for name, row in stages.items() if name != "other (Python between stages)")


def test_targets_quick(tmp_path, capsys):
    """``bench.py --targets --quick``: a row per cheap target, each with its measured value, its
    goal and whether it is met, and the JSON beside it."""
    import json
    from bench import main
    rows = main(["--targets", "--quick", "-o", str(tmp_path / "bench.json")])
    assert len(rows) == 6 and all(r["measured"] is not None and r["target"] > 0 for r in rows)
    assert rows[0]["what"].startswith("bending module: warm solve") and rows[0]["measured"] < 50   # ms
    assert json.loads((tmp_path / "bench_targets.json").read_text())["targets"][0]["unit"] == "ms"
    out = capsys.readouterr().out
    assert "target 0.5" in out and ("met" in out or "NOT MET" in out)

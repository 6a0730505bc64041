"""``solver.jit: true``: the collocation residual compiled to machine code, kept on disk, giving
the same answers as CasADi's virtual machine."""
import numpy as np
import pytest
from numpy.testing import assert_allclose

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.errors import TcaError

BENDING = SCENARIOS / "bending_module.yaml"
HEATED = ["bending.tca2.temperature=90"]


def test_the_compiled_residual_gives_the_same_solution_and_is_kept(tmp_path, monkeypatch):
    """Solved without the error estimate, whose degree d + 1 NLP would compile its own (the
    mesh is the scenario's either way: no refinement)."""
    monkeypatch.setenv("TCA_CASADI_CACHE", str(tmp_path))
    plain_sim = Simulation.from_file(BENDING, HEATED)
    plain = plain_sim.solve_at(plain_sim.params, estimate=False)
    sim = Simulation.from_file(BENDING, HEATED + ["solver.jit=true"])
    fast = sim.solve_at(sim.params, estimate=False)
    assert fast.converged
    libraries = sorted((tmp_path / "jit").glob("nlp_g_*.so"))
    assert len(libraries) == 1
    square = sim.solver("collocation").square
    w = fast.iterate.w
    interpreted = np.array(square._residual_function(w, sim.params)).ravel()
    assert_allclose(square.residual(w, sim.params), interpreted, rtol=0, atol=1e-14)
    assert_allclose(fast.tip_position, plain.tip_position, rtol=0, atol=1e-12)
    modified = [p.stat().st_mtime_ns for p in libraries]
    from tca_casadi.solvers.collocation import clear_built_solvers
    clear_built_solvers()
    again = Simulation.from_file(BENDING, HEATED + ["solver.jit=true"])
    again.solve_at(again.params, estimate=False)
    assert [p.stat().st_mtime_ns for p in sorted((tmp_path / "jit").glob("nlp_g_*.so"))] == modified   # reused


def test_without_a_compiler_it_says_so(tmp_path, monkeypatch):
    monkeypatch.setenv("TCA_CASADI_CACHE", str(tmp_path))
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    with pytest.raises(TcaError, match="needs a C compiler"):
        Simulation.from_file(BENDING, HEATED + ["solver.jit=true"]).solve(warn=False)


def test_auto_compiles_only_a_long_dynamic_run_and_only_with_a_compiler(tmp_path, monkeypatch):
    """``solver.jit: auto`` (the default): a static solve and a short dynamic run stay in CasADi's
    virtual machine; a dynamic run of ``AUTO_JIT_STEPS`` steps or more (lowered to 3 here) runs
    its step's residual compiled, with the same motion to 1e-12 m and ``compiled_residual`` in
    the report; without a C compiler it runs uncompiled, and says so."""
    from tca_casadi.solvers import dynamics
    from tca_casadi.time_simulation.timeline import TimeSimulation
    monkeypatch.setenv("TCA_CASADI_CACHE", str(tmp_path))
    cantilever = SCENARIOS / "analytic" / "steel_cantilever.yaml"

    def run(steps_to_compile):
        monkeypatch.setattr(dynamics, "AUTO_JIT_STEPS", steps_to_compile)
        timed = TimeSimulation(Simulation.from_file(cantilever, ["duration=0.01"]), dt=0.002)
        series = timed.run()
        assert series.completed, series.message
        return series, timed.report(series)["dynamics"]["compiled_residual"]

    plain, compiled_plain = run(10 ** 9)
    fast, compiled_fast = run(3)
    assert not compiled_plain and compiled_fast and list((tmp_path / "jit").glob("nlp_g_*.so"))
    assert_allclose(fast.tip_positions(), plain.tip_positions(), rtol=0, atol=1e-12)
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    _, compiled_without = run(3)
    assert not compiled_without


def test_compiled_chord_steps_give_the_same_motion(tmp_path, monkeypatch):
    """A compiled dynamic run (``solver.jit: auto`` on a run of ``AUTO_JIT_STEPS`` steps or
    more, lowered to 10 here; ``true`` compiles the Jacobians as well, 15 s more) runs the chord
    steps in C (:mod:`tca_casadi.solvers.native`), kept while they cut the residual threefold
    instead of tenfold: a different sequence of iterates to the same tolerance, so 100 steps of
    the steel cantilever's free vibration agree with the uncompiled run to 1e-10 m (the tip
    moves about 60 mm), with fewer fresh Jacobians."""
    from tca_casadi.time_simulation.timeline import TimeSimulation
    from tca_casadi.solvers import dynamics
    from tca_casadi.solvers.newton import SquareSystem
    monkeypatch.setenv("TCA_CASADI_CACHE", str(tmp_path))
    monkeypatch.setattr(dynamics, "AUTO_JIT_STEPS", 10)
    cantilever = SCENARIOS / "analytic" / "steel_cantilever.yaml"
    counted = SquareSystem._fresh_factors

    def run(jit):
        calls = []

        def fresh_factors(self, w, P):
            calls.append(1)
            return counted(self, w, P)
        monkeypatch.setattr(SquareSystem, "_fresh_factors", fresh_factors)
        series = TimeSimulation(Simulation.from_file(cantilever, ["duration=0.2", f"solver.jit={jit}"]), dt=0.002).run()
        assert series.completed, series.message
        return series.tip_positions(), len(calls)

    (plain, plain_factorisations), (fast, fast_factorisations) = run("false"), run("auto")
    assert np.ptp(plain[:, 0]) > 0.03
    assert_allclose(fast, plain, rtol=0, atol=1e-10)
    assert fast_factorisations < plain_factorisations


def test_a_large_study_compiles_under_auto(tmp_path, monkeypatch):
    """``solver.jit: auto`` compiles a study of ``AUTO_JIT_SAMPLES`` samples or more (lowered to
    8 here): it says so, and its rows equal the uncompiled study's to 1e-10 m; ``false`` never
    compiles."""
    from tca_casadi.studies.batch import study as study_module
    from tca_casadi.studies.batch.study import Study
    from tca_casadi.solvers.collocation import clear_built_solvers
    monkeypatch.setenv("TCA_CASADI_CACHE", str(tmp_path))
    monkeypatch.setattr(study_module, "AUTO_JIT_SAMPLES", 8)
    vary = {"bending.tca2.temperature": [25, 125, 3], "bending.tca3.temperature": [25, 125, 3]}

    def run(jit):
        clear_built_solvers()
        return Study(Simulation.from_file(BENDING, [f"solver.jit={jit}"]), vary=vary).run()

    fast, plain = run("auto"), run("false")
    assert fast.info["compiled"] and not plain.info["compiled"] and "compiled (solver.jit)" in fast.summary()
    assert list((tmp_path / "jit").glob("nlp_g_*.so"))
    assert int(fast.info["converged"]) == 9 == int(plain.info["converged"])
    assert_allclose(fast.tips(), plain.tips(), rtol=0, atol=1e-10)

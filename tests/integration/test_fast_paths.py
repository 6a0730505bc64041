"""The fast path for the forward problem (Newton on the square system) gives the same solutions
as IPOPT, on every shipped scenario, warm and cold."""
import numpy as np
from numpy.testing import assert_allclose
import pytest

from conftest import SCENARIOS
from tca_casadi import Simulation
from tca_casadi.status import Status

SHIPPED = sorted(SCENARIOS.rglob("*.yaml"))
# the physical pick-and-place (30 s here) is solved step by step in test_bodies.py; free_pinch
# stands for scenarios with contact objects (their warm solves are continuations)
FAST = [p for p in SHIPPED if p.stem != "arm_pick_and_place_contact"]


def nudge(sim):
    """A small change of every actuator parameter (+1 degC, +1 % tension or pull) and load (+1 %)."""
    for name in sim.robot.layout.names():
        if name.endswith(".temperature"):
            sim.set_parameter(name, sim.get_parameter(name) + 1.0)
        elif name.endswith((".tension", ".displacement", ".force", ".moment", ".mass")):
            sim.set_parameter(name, 1.01 * np.asarray(sim.get_parameter(name)))


def assert_same(a, b, position=1e-9, tension=1e-8):
    """Same tip and tensions (relative, floored at the largest tension: slack ones are ~1e-18 N)."""
    assert a.converged and b.converged
    assert np.max(np.abs(a.tip_position - b.tip_position)) < position
    largest = max([abs(x.tension) for x in a.actuators.values()] + [1e-12])
    for key, actuator in a.actuators.items():
        floor = max(abs(actuator.tension), 1e-6 * largest)
        # + 1e-11 N: both stop at scaled residual 1e-10, tensions scaled by EI/L^2 (8 mN on the
        # arm's fingers), so a 0.25 mN tension may differ by a few 1e-12 N
        assert abs(b.actuators[key].tension - actuator.tension) <= tension * floor + 1e-11


@pytest.mark.parametrize("path", FAST, ids=[p.stem for p in FAST])
def test_newton_matches_ipopt_cold_warm_and_on_a_step(path):
    """Cold, the default algorithm (newton) and ``solver.algorithm: ipopt`` agree; after a nudge,
    one Newton step equals IPOPT's from the same start; and so do the two warm solves."""
    by_ipopt = Simulation.from_file(path, ["solver.algorithm=ipopt"], allow_code=True)
    fast = Simulation.from_file(path, allow_code=True)                    # newton is the default
    assert fast.scenario.solver.algorithm == "newton"
    start = fast.solve()
    assert_same(by_ipopt.solve(), start)
    nudge(by_ipopt), nudge(fast)
    solver = fast.solver()
    step_ipopt = solver.solve_ipopt(fast.params, start)
    step_newton = solver.solve_newton(fast.params, start.iterate.w)
    assert step_newton.result.algorithm == "Newton" and step_newton.status == Status.CONVERGED
    assert_same(step_ipopt, step_newton)
    warm_ipopt, warm_fast = by_ipopt.solve(warm_start="last"), fast.solve(warm_start="last")
    assert warm_fast.result.algorithm == "Newton" and warm_ipopt.result.algorithm == "IPOPT"
    assert_same(warm_ipopt, warm_fast)


def tip_load(force, *options):
    return Simulation.from_file(SCENARIOS / "analytic" / "tip_load.yaml",
                                [f"tip_force.force=[{force}, 0, 0]", *options])


def test_direct_newton_solve_from_the_straight_rod():
    """No continuation: Newton alone from the straight rod converges at P L^2/EI = 10."""
    fast = tip_load(-5e-4, "solver.continuation=never").solve()
    assert fast.converged and fast.result.algorithm == "Newton"
    assert np.max(np.abs(fast.tip_position - tip_load(-5e-4).solve().tip_position)) < 1e-9


def test_newton_failure_falls_back_to_ipopt_and_is_reported():
    """At P L^2/EI = 40 without continuation Newton finds no descent; IPOPT takes over from the
    same start, and its answer is the one continuation finds (the default path)."""
    sim = tip_load(-2e-3, "solver.continuation=never", "solver.refine=off")
    newton = sim.solver().solve_newton(sim.params, sim.solver().initial_guess(sim.params))
    assert not newton.converged and newton.result.algorithm == "Newton"
    assert newton.status == Status.NO_DESCENT and newton.warnings[0].kind == "not_converged"
    solution = sim.solve()
    assert solution.result.algorithm == "IPOPT" and solution.converged   # IPOPT's answer
    assert solution.result.detail == "IPOPT: Solve_Succeeded"
    assert solution.max_residual <= sim.scenario.solver.tolerance
    continued = tip_load(-2e-3, "solver.refine=off").solve()   # continuation (the default), same mesh
    assert continued.converged
    assert_allclose(solution.tip_position, continued.tip_position, rtol=0, atol=1e-9)


def test_state_derivative_by_forward_mode_equals_the_full_parameter_jacobian_s():
    """``SquareSystem.state_derivative`` and a linearisation's along up to two directions
    (``dg/dP`` only along them, by CasADi's forward mode; what plans, sweeps and paths
    differentiate through) against the full sparse ``dg/dP`` (the structured Jacobian, which a
    linearisation uses for three directions), for the three TCA temperatures of the bending
    module at a bent equilibrium: the same ``dw/dT`` to 1e-10 of its size, and against central
    differences of Newton solves to 1e-6 of it."""
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    solution = sim.solve(warn=False)
    solver, w, params = sim.solver("collocation"), solution.iterate.w, sim.params.copy()
    selector = np.zeros((params.size, 3))
    for j, key in enumerate(("bending.tca1", "bending.tca2", "bending.tca3")):
        selector[sim.robot.layout[f"{key}.temperature"].start, j] = 1.0
    fast, lu = solver.square.state_derivative(w, params, selector)
    linear = solver.linearise(w, params)
    assert_allclose(linear.state_derivative(selector[:, 1]), fast[:, 1], rtol=0, atol=1e-10 * np.max(np.abs(fast)))
    assert_allclose(linear.state_derivative(selector[:, :2]), fast[:, :2], rtol=0, atol=1e-10 * np.max(np.abs(fast)))
    assert linear._J_P is None                                 # forward mode so far: no full dg/dP
    full = linear.state_derivative(selector)                   # three directions: the full dg/dP
    assert linear._J_P is not None
    size = np.max(np.abs(full))
    assert_allclose(fast, full, rtol=0, atol=1e-10 * size)
    step = 1e-3                                              # K
    ends = [solver.square.newton(w, params + sign * step * selector[:, 1], 1e-12)[0] for sign in (1, -1)]
    assert_allclose((ends[0] - ends[1]) / (2 * step), full[:, 1], rtol=0, atol=1e-6 * size)


def test_the_tangent_predictor_of_a_nearby_solve_is_second_order():
    """``SquareSystem.predicted`` (the start of a study's next sample): from the root at P0 along
    J_w^-1 J_P dP, its residual at P0 + dP falls like dP^2 (a quarter when dP halves), the plain
    start's like dP (a half), so that at 0.5 degC it is below a tenth of the plain start's
    (measured 0.07). A step of zero returns the root itself."""
    sim = Simulation.from_file(SCENARIOS / "bending_module.yaml")
    solution = sim.solve(warn=False)
    square, w, params = sim.solver("collocation").square, solution.iterate.w, sim.params.copy()
    lu = square.factorise(square.evaluate(w, params)[1])
    slot = sim.robot.layout["bending.tca2.temperature"].start
    sizes = []
    for step in (2.0, 1.0, 0.5):                          # K
        moved = params.copy()
        moved[slot] += step
        start = square.predicted(w, params, moved, lu)
        sizes.append((np.linalg.norm(square.residual(start, moved)), np.linalg.norm(square.residual(w, moved))))
    tangent, plain = np.array(sizes).T
    assert_allclose(tangent[:-1] / tangent[1:], 4.0, rtol=0.15, atol=0)
    assert_allclose(plain[:-1] / plain[1:], 2.0, rtol=0.05, atol=0)
    assert tangent[2] < 0.1 * plain[2]
    assert square.predicted(w, params, params, lu) is w

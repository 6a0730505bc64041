"""One result API (issue 35): every result type has ``success``, ``status``, ``message`` and
``result`` (a SolveStatus), a short ``repr`` (under 2000 characters: what, whether it succeeded,
the headline numbers), an HTML repr for notebooks and ``plot()``, the figure the command line
saves; and a failed result says so in its first line."""
import matplotlib
import numpy as np
import pytest

import tca_casadi as tc
from conftest import ROOT, SCENARIOS
from tca_casadi.status import SolveStatus, Status

BENDING = SCENARIOS / "bending_module.yaml"
HEATING = SCENARIOS / "bending_module_heating.yaml"


def _solution():
    return tc.Simulation.from_file(BENDING).solve(warn=False)


def _sweep():
    return tc.Sweep(tc.Simulation.from_file(BENDING), ["bending.tca2.temperature"], 25.0, 60.0, 5).run()


def _inverse():
    sim = tc.Simulation.from_file(BENDING)
    goal = tc.Simulation.from_file(BENDING, ["bending.tca2.temperature=60"]).solve(warn=False).tip_position
    return tc.InverseStatics(sim).solve(tc.Target.create(goal))


def _sequence():
    from tca_casadi.studies.sequence.steps import run_sequence
    return run_sequence(tc.Simulation.from_file(BENDING))


def _time_series():
    from tca_casadi.time_simulation.timeline import TimeSimulation
    return TimeSimulation(tc.Simulation.from_file(HEATING), dt=20.0).run()


def _study():
    return tc.Study(tc.Simulation.from_file(BENDING), vary={"bending.tca2.temperature": [25, 125]},
                    design="grid", samples=4).run()


def _fit():
    return tc.Fit(tc.Simulation.from_file(BENDING), ROOT / "data" / "bending_module_measurements.csv",
                  ["materials.ecoflex30.youngs_modulus"]).run()


def _check():
    from tca_casadi.studies import check
    return check(tc.Simulation.from_file(BENDING))[0]


def _plan():
    from tca_casadi.control import Plan
    goal = tc.Simulation.from_file(HEATING, ["bending.tca2.temperature=60"]).solve(warn=False).tip_position
    return Plan(tc.Simulation.from_file(HEATING), goal, horizon=24.0, nodes=4).solve()


def _closed_loop():
    from tca_casadi.control import ClosedLoop
    return ClosedLoop(SCENARIOS / "bending_module_mpc.yaml", ["duration=3"]).run()


MAKERS = [_solution, _sweep, _inverse, _sequence, _time_series, _study, _fit, _check, _plan, _closed_loop]


@pytest.mark.parametrize("make", MAKERS, ids=[m.__name__.strip("_") for m in MAKERS])
def test_every_result_has_the_api_a_short_repr_and_its_figure(make):
    result = make()
    assert isinstance(result.result, SolveStatus) and isinstance(result.success, bool)
    assert result.status == result.result.status or not result.success
    assert isinstance(result.message, str)
    text = repr(result)
    assert len(text) < 2000, len(text)
    first = text.splitlines()[0]
    assert first.startswith(f"<{type(result).__name__}: ") and ("success>" in first) == result.success, first
    assert type(result).__name__ in result._repr_html_()
    figure = result.plot()
    assert isinstance(figure, matplotlib.figure.Figure) and figure.axes
    assert figure.axes[0].has_data() or figure.axes[0].collections or figure.axes[0].lines
    matplotlib.pyplot.close(figure)


def test_a_result_that_failed_says_so_first():
    """A sweep stopped early and a solution that did not converge: 'no success' and why, in the
    repr's first line; ``success`` False and ``status`` not 0."""
    solution = _solution()
    failed = type(solution)(**{**{f: getattr(solution, f) for f in solution.__dataclass_fields__},
                               "result": SolveStatus(Status.MAX_ITERATIONS, "Newton", nit=25, residual=1e-3,
                                                     tolerance=1e-10)})
    assert not failed.success and failed.status == Status.MAX_ITERATIONS
    assert repr(failed).splitlines()[0] == "<Solution: no success: stopped at the iteration limit>"
    assert len(repr(solution)) < 2000 and np.isfinite(solution.max_residual)

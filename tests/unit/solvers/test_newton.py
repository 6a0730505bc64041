"""Newton on a square system: the semismooth mode's stop when its steps go round."""
from types import SimpleNamespace

import casadi as ca
import numpy as np

from tca_casadi.solvers.newton import CYCLE_ITERATIONS, SquareSystem
from tca_casadi.status import Status


def _cubic():
    """``g(w) = w^3 - 2 w + P``: at ``P = 2`` Newton's full steps cycle between 0 and 1, and
    ``|g|`` has a local minimum, not a root, at ``w = sqrt(2/3)``; the root is at -1.7693."""
    w, P = ca.SX.sym("w"), ca.SX.sym("P")
    g = w ** 3 - 2 * w + P
    return SquareSystem(SimpleNamespace(), ca.Function("g", [w, P], [g]),
                        ca.Function("J", [w, P], [g, ca.jacobian(g, w)]))


def test_semismooth_newton_stops_when_its_steps_go_round():
    """From 0 the non-monotone steps wander about the local minimum of ``|g|`` (left to it, they
    find the root after 53 iterations): they stop once :data:`CYCLE_ITERATIONS` in a row leave
    the residual above its best (a time step then tries a shorter step, which is cheaper than
    wandering: on the cantilever falling onto a table with Coulomb friction, 100 iterations
    each, many times over, went round and never converged); the monotone mode stops at once (no
    descent)."""
    system = _cubic()
    _, status = system.newton(np.array([0.0]), np.array([2.0]), 1e-10, 100, monotone=False)
    assert status.status == Status.CYCLING and status.nit <= CYCLE_ITERATIONS + 10
    _, status = system.newton(np.array([0.0]), np.array([2.0]), 1e-10, 100)
    assert status.status == Status.NO_DESCENT


def test_semismooth_newton_that_gets_out_converges():
    """From 0.5 a capped step leaves the basin of the local minimum: the residual keeps falling
    to the root, which the stop does not cut short."""
    w, status = _cubic().newton(np.array([0.5]), np.array([2.0]), 1e-10, 100, monotone=False)
    assert status.success
    np.testing.assert_allclose(w, [-1.7692923542386314], rtol=0, atol=1e-10)

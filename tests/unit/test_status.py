"""The one status type: success is decided by the residual, every status has a meaning."""
import json

import pytest

from tca_casadi.status import MESSAGES, SolveStatus, Status


def test_every_status_has_a_message_and_zero_is_success():
    assert set(MESSAGES) == set(Status)
    assert [s for s in Status if SolveStatus(s, "x").success] == [Status.CONVERGED]


@pytest.mark.parametrize("residual, failure, expected", [
    (1e-11, None, Status.CONVERGED),
    (1e-10, None, Status.CONVERGED),                       # the tolerance itself passes
    (2e-10, None, Status.ABOVE_TOLERANCE),
    (2e-10, Status.CONVERGED, Status.ABOVE_TOLERANCE),     # an algorithm's "success" is not enough
    (1e-12, Status.MAX_ITERATIONS, Status.MAX_ITERATIONS),  # nor is a small residual after a failure
    (float("nan"), None, Status.ABOVE_TOLERANCE),
])
def test_judged_by_the_residual_and_the_reported_failure(residual, failure, expected):
    status = SolveStatus.judged("Newton", residual, 1e-10, failure, nit=3)
    assert status.status == expected and status.success == (expected == Status.CONVERGED)


def test_message_and_json():
    status = SolveStatus.judged("IPOPT", 3e-5, 1e-10, Status.ALGORITHM_FAILED, nit=34,
                                detail="IPOPT: Infeasible_Problem_Detected").noted("3 steps")
    assert status.message == ("IPOPT: the algorithm reported failure (max scaled residual 3.00e-05, "
                              "tolerance 1e-10, 34 iterations); IPOPT: Infeasible_Problem_Detected; 3 steps")
    data = json.loads(json.dumps(status.as_dict()))
    assert data["status"] == 3 and data["success"] is False and data["nit"] == 34

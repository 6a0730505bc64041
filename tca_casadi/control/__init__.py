"""Control: optimal heating schedules from the model that ``simulate`` runs (``tca-casadi plan``)."""
from .mpc import ClosedLoop, ClosedLoopResult
from .plan import Plan, PlanResult

__all__ = ["ClosedLoop", "ClosedLoopResult", "Plan", "PlanResult"]

"""Control: optimal heating schedules from the model that ``simulate`` runs (``tca-casadi plan``)."""
from .plan import Plan, PlanResult

__all__ = ["Plan", "PlanResult"]

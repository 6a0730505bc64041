"""tca_casadi: shape and motion of soft robots (Cosserat rods) driven by twisted-and-coiled
actuators and tendons, by direct collocation in CasADi solved by Newton/IPOPT.

    import tca_casadi as tc
    sim = tc.Simulation.from_file("scenarios/bending_module.yaml")
    solution = sim.solve()
    print(solution.tip_position, solution.tensions)

The names below are imported on first use, so that ``tca-casadi --help`` and ``validate`` start
without loading CasADi, SciPy or matplotlib.
"""
from ._lazy import lazy_getattr
from .errors import ModelError, OutputError, PhysicsWarning, ScenarioError, SolverError, TcaError

__version__ = "0.1.0"

#: public name -> module that defines it
_LAZY = {"Simulation": ".simulation", "solve": ".simulation", "Solution": ".solution",
         "Sweep": ".studies", "SweepResult": ".studies", "InverseStatics": ".studies",
         "InverseResult": ".studies", "Target": ".studies", "Scenario": ".scenario",
         "load_scenario": ".scenario", "Robot": ".model", "TcaLaw": ".model",
         "TimeSimulation": ".time_simulation.timeline", "simulate": ".time_simulation.timeline",
         "Study": ".studies.batch.study", "StudyResult": ".studies.batch.result",
         "Fit": ".studies.fit.least_squares", "FitResult": ".studies.fit.result",
         "Plan": ".control", "PlanResult": ".control"}

__all__ = list(_LAZY) + ["ScenarioError", "SolverError", "ModelError", "OutputError", "TcaError",
                         "PhysicsWarning"]


__getattr__ = lazy_getattr(__name__, _LAZY)


def __dir__():
    return sorted(set(globals()) | set(__all__))

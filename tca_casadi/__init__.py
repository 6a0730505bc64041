"""tca_casadi: static shape of soft robots (Cosserat rods) driven by twisted-and-coiled actuators
and tendons, by direct collocation in CasADi solved with IPOPT.

    import tca_casadi as tc
    sim = tc.Simulation.from_file("scenarios/bending_module.yaml")
    solution = sim.solve()
    print(solution.tip_position, solution.tensions)
"""
from .errors import ModelError, PhysicsWarning, ScenarioError, SolverError, TcaError
from .model import Robot, TcaLaw
from .scenario import Scenario, load_scenario
from .simulation import Simulation, solve
from .solution import Solution
from .studies import InverseResult, InverseStatics, Sweep, SweepResult, Target

__version__ = "0.1.0"

__all__ = ["Simulation", "solve", "Solution", "Sweep", "SweepResult", "InverseStatics", "InverseResult", "Target", "Scenario", "load_scenario", "Robot", "TcaLaw",
           "ScenarioError", "SolverError", "ModelError", "TcaError", "PhysicsWarning"]

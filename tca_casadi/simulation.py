"""A thin orchestrator: scenario -> robot model -> solver (built once, cached) -> solution.
How each point is solved (continuation, fallbacks, refinement, localisation) is the
:class:`~tca_casadi.solvers.strategy.SolveStrategy`'s; the simulation holds the scenario, the
current parameters and the last solution.

    sim = Simulation.from_file("scenarios/bending_module.yaml")
    first = sim.solve()
    sim.set("bending.tca2.temperature", 110)      # a parameter: no rebuild
    second = sim.solve(warm_start=first)
"""
import logging
import warnings

from .errors import ScenarioError, flag
from .model import Robot
from .scenario import load_scenario
from .scenario.loader import validate
from .scenario.overrides import apply_overrides
from .solvers.outputs import StepOutputs
from .solvers.strategy import SolveStrategy

log = logging.getLogger(__name__)


class Simulation:
    """Holds a scenario, its robot model, the current parameter values and the built solver."""

    def __init__(self, scenario, method=None):
        self.scenario = scenario
        self.strategy = SolveStrategy(scenario, Robot.from_scenario(scenario), method or scenario.solver.method)
        self.params = self.robot.values.copy()
        self.last = None

    @property
    def robot(self):
        """The robot model (with the contact candidates localisation added, once it has)."""
        return self.strategy.robot

    @property
    def method(self):
        """The solver method solves use unless told otherwise (``collocation``, ``shooting``)."""
        return self.strategy.method

    @classmethod
    def from_file(cls, source, overrides=(), method=None, allow_code=False):
        """Load (YAML path, YAML text or dict), apply ``overrides``, build the model.
        ``allow_code``: run the Python code a ``custom`` muscle law names (refused otherwise,
        see :func:`~tca_casadi.scenario.load_scenario`)."""
        return cls(load_scenario(source, overrides, allow_code=allow_code), method=method)

    # ------------------------------------------------------------------ parameters
    def set(self, path, value):
        """Set a scenario value by dotted path (units allowed: ``"110 degC"``).

        A parameter (temperature, tension, load, gravity, base pose, a material's modulus or
        density, a TCA type's geometry or fit, a route's radius or angle: the names in
        ``robot.layout``) changes only the parameter vector; anything else (a length, a route's
        kind or span, the mesh) rebuilds the model and solver.
        """
        if self.scenario._raw is None:           # built in Python, not loaded: start from its data
            from .scenario.sources import SourceMap
            self.scenario._raw = self.scenario.model_dump(mode="json")
            self.scenario._sources = SourceMap("<scenario>")
        raw = apply_overrides(self.scenario._raw, {path: value}, self.scenario._sources)
        scenario = validate(raw, self.scenario._sources)
        scenario._allow_code = self.scenario._allow_code
        if self.robot.structure_key(scenario) == self.robot.structure_key(self.scenario):
            params = self.robot.parameter_vector(scenario)
            problems = self.robot.problems(params)
            if problems:
                Robot.from_scenario(scenario)        # names the scenario key where it can
                raise ScenarioError(f"{flag('--set')} {path}: " + "; ".join(problems))
            self.scenario, self.params = scenario, params
            return
        log.info("%s changes the structure: rebuilding", path)
        self.__init__(scenario, self.method)

    def set_parameter(self, name, value):
        """Fast path: set a parameter-vector entry (``robot.layout`` name) to an SI value."""
        if name not in self.robot.layout:
            raise ScenarioError(f"{name!r} is not a parameter; parameters: {', '.join(self.robot.layout.names())}")
        self.params[self.robot.layout[name]] = value

    def get_parameter(self, name):
        value = self.params[self.robot.layout[name]]
        return float(value[0]) if value.size == 1 else value.copy()

    def use_meshes(self, meshes, degree=None):
        """Solve by collocation on ``meshes`` (per module, e.g. another process's refined mesh)
        at ``degree`` (default the scenario's): the same NLP wherever it is built."""
        self.strategy.use_meshes(meshes, degree)

    # ------------------------------------------------------------------ solving
    def solver(self, method=None):
        """The solver for ``method`` (default the simulation's), built on first use."""
        return self.strategy.solver(method)

    def solve(self, warm_start=None, method=None, continuation=None, refine=True, warn=True, params=None):
        """Equilibrium at ``params`` (a parameter vector, which the simulation keeps as its
        current parameters; None: the current parameters).

        ``warm_start``: a previous Solution, or ``"last"``. ``continuation`` (default from the
        scenario): ``"auto"`` follows the loads up from the unloaded reference state on a cold start
        (SPEC section 6: a direct cold solve may land on a branch where TCAs push) and, after a warm
        start that fails or leaves a TCA in compression; ``"always"``; ``"never"`` (direct solve).

        A cold collocation solve carries an error estimate (``solution.accuracy``); with
        ``refine`` and ``solver.refine: auto`` the mesh is refined where the error is until the
        tip and tensions meet ``solver.tip_tolerance`` / ``tension_tolerance``, and the refined
        solver is kept for later solves (sweeps, inverse statics).

        The solution's :class:`~tca_casadi.errors.PhysicsWarning` s (non-convergence,
        compression, slack, accuracy, ...) are recorded in ``solution.warnings`` and, with
        ``warn``, also issued with :func:`warnings.warn` (studies pass ``warn=False``).
        """
        initial = self.last if warm_start == "last" else warm_start
        solution, self.params = self.strategy.solve(self.params if params is None else params, initial, method,
                                                    continuation, refine)
        self.last = solution
        if warn:
            for warning in solution.warnings:
                warnings.warn(warning, stacklevel=2)
        return solution

    def solve_near(self, previous=None, params=None, lean=False):
        """The equilibrium at ``params`` (a parameter vector; None: the current parameters),
        for one of many nearby points (a study); parameters that the robot cannot take (an
        actuator's temperature out of its law's range, an obstacle cutting the reference
        state) raise a :class:`~tca_casadi.errors.TcaError` naming each problem. The solve:
        Newton from ``previous`` (the Solution at a nearby point; the solver's own warm start
        without a square system), continuation from the reference state when there is none,
        or when Newton fails or leaves a TCA pushing. Newton's first steps are chord steps on
        the Jacobian factorised last (at or near ``previous``). No error estimate, no
        refinement, no warnings issued (they are in ``solution.warnings``). ``lean``: where
        Newton converges on a robot without contact or friction, the answer is the sample's
        :class:`~tca_casadi.solvers.outputs.StepOutputs` (tip, actuators, status; no global
        balance, no warnings), not a Solution: a study builds Solutions on a schedule."""
        solution, self.params = self.strategy.solve_near(self.params if params is None else params, previous, lean)
        if not isinstance(solution, StepOutputs):        # a sample's outputs are no warm start for solve()
            self.last = solution
        return solution

    def solve_at(self, params, method=None, estimate=True):
        """Solve at the parameter vector ``params`` from the reference state (cold, with
        continuation), leaving this simulation's own parameters and last solution unchanged;
        ``estimate`` False: without the error estimate (a start point)."""
        return self.strategy.solve(params, None, method, refine=False, estimate=estimate)[0]

    def continue_from_rest(self, solver=None, params=None):
        """Continuation from the unloaded reference state to ``params`` (default the current
        parameters) by ``solver`` (default the simulation's): :meth:`SolveStrategy.continue_from_rest
        <tca_casadi.solvers.strategy.SolveStrategy.continue_from_rest>`."""
        return self.strategy.continue_from_rest(solver or self.solver(), self.params if params is None else params)


def solve(source, overrides=(), allow_code=False, **options):
    """One call: load a scenario and solve it. Returns a :class:`Solution`."""
    return Simulation.from_file(source, overrides, allow_code=allow_code).solve(**options)


__all__ = ["Simulation", "solve"]

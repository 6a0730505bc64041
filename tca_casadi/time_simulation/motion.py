"""``simulate`` with the rods' inertia (``dynamics: {enabled: true}``, issue 16): one implicit
time step per output time (:class:`~tca_casadi.solvers.dynamics.RodDynamics`) from the static
equilibrium at t = 0, the TCAs' temperatures and every other parameter from the timeline as in
the quasi-static run, and the energy account of the motion.

Energies at each output time [J]: kinetic ``int (rho A |q|^2 + w . rho J w) / 2 ds`` plus the
rigid point masses' ``M |v|^2 / 2``, elastic ``int (xi - xi*) . K (xi - xi*) / 2 ds``,
gravitational ``-int rho A g . p ds - sum M g . x``; and from t = 0:
the work the actuators do on the body, ``-sum_i int F_i dl_i`` (a TCA that shortens while it
pulls does positive work), the work of the point loads ``int F . dp + M . dtheta`` (and the
energy a point mass takes with it when it changes: an object let go), and the
energy the rods' viscosity dissipated, ``int int xi_t . B xi_t ds dt`` (all in time by the
trapezoidal rule, ``xi_t`` as ``(xi_{n+1} - xi_n) / h``; on a step implicit Euler takes, the
actuators' and loads' work by the forces at its end, the rule that step is solved by), and
with obstacles the impact loss,
the work the contact forces take: per step ``sum_k f_k,n+1 (g_k,n - g_k,n+1) >= 0`` (the
implicit step's contact force acts at its end; ``docs/contact.md`` section 5a), and with
friction the energy friction took, ``-sum f_t . (x_{n+1} - x_n)`` over the contacts (their
points' slip over the step), and on the steps implicit Euler takes (BDF2's first, and the
steps of an impact) its own damping, ``|x_{n+1} - x_n|^2 / 2`` in every quadratic store
(:meth:`RodDynamics.euler_loss <tca_casadi.solvers.dynamics.RodDynamics.euler_loss>`). Their
balance

    (kinetic + elastic + gravitational)(t) - (...)(0) + dissipated + impact loss + friction work
        + integrator loss - actuator work - load work

is zero up to the time discretisation (BDF2's own damping on its other steps), reported per
output as ``energy_balance``.
"""
from collections.abc import Sequence

import numpy as np

from ..errors import ScenarioError, flag
from ..model.dynamics import KelvinVoigt
from ..solvers.dynamics import RodDynamics, StepState

#: the range of time steps [s] the dynamics is run on (1e-7 s: the smallest at which every step
#: converged on the cantilever; at 1e-8 s roundoff, amplified by c0 ~ 1/h, floors the residual)
STEP_RANGE = (1e-7, 0.1)
#: a step that does not converge is halved at most this many times
HALVINGS = 6
ENERGY_COLUMNS = ("kinetic_energy", "elastic_energy", "gravitational_energy", "actuator_work", "load_work",
                  "dissipated_energy", "impact_loss", "friction_work", "integrator_loss", "energy_balance")


def damping_of(config, scenario):
    """The :class:`KelvinVoigt` of a scenario's ``dynamics.damping`` (None without one); a
    damping ratio at a frequency uses the first module's material's Young's modulus."""
    if config is None:
        return None
    if config.viscosity is not None:
        return KelvinVoigt(config.viscosity, config.shear_viscosity)
    material = scenario.materials[scenario.modules[0].material]
    return KelvinVoigt.with_ratio(config.ratio, config.frequency, material.youngs_modulus)


def check_dynamics(sim, dt):
    """Bad input for a dynamic run, as a ScenarioError: a step outside :data:`STEP_RANGE` or a
    massless module."""
    low, high = STEP_RANGE
    if not low <= dt <= high:
        raise ScenarioError(f"dynamics: {flag('--dt')} {dt:g} s is outside the range the dynamics is run on "
                            f"({low:g} to {high:g} s)")
    for module in sim.robot.modules:
        if not module.weight_density > 0:
            raise ScenarioError(f"dynamics: module {module.name} has no mass (materials.{module.material}.density is 0)")


class EnergyAccount:
    """The running energy account of a dynamic run (module docstring)."""

    def __init__(self, dynamics):
        self.dynamics = dynamics
        self.rows = []
        self._work = {"actuator_work": 0.0, "load_work": 0.0, "dissipated_energy": 0.0, "impact_loss": 0.0,
                      "friction_work": 0.0, "integrator_loss": 0.0}
        self._start = None
        self._damped = any(np.any(d) for d in dynamics.damping)

    def stored(self, state, solution):
        """``(kinetic, elastic, gravitational)`` [J] at a state and its Solution (or its
        StepOutputs), and the rigid point masses' share of their sum."""
        params = solution.parameters
        kinetic, elastic = self.dynamics.energies(state, params)
        rigid_kinetic, rigid_potential = self.dynamics.rigid_energies(state, solution)
        body_kinetic, _ = self.dynamics.body_energies(state, params)
        return ((kinetic + rigid_kinetic + body_kinetic, elastic, self._gravitational(state, solution, params)),
                rigid_kinetic + rigid_potential)

    def add(self, previous, state, solution, previous_solution, during=None):
        """Account for the step from ``previous`` to ``state`` (StepStates, with their
        Solutions or StepOutputs). ``during``: the Solution the step was solved at (the midpoint rule's
        midpoint state), whose tensions and loads then do the work over the whole step (the
        rule's own discrete energy identity); on implicit Euler's steps those at the step's end
        (its identity, completed by ``euler_loss``); else the trapezoidal rule on the two ends."""
        # implicit Euler's step (BDF2's first, an impact's) is solved at its end: the forces there
        # do the work over the step, the rule whose energy identity ``euler_loss`` completes
        euler = previous is not None and during is None and state.implicit_euler
        during = solution if euler else during
        if previous is not None:
            robot = self.dynamics.robot
            if during is None:
                pulls = {k: 0.5 * (a.tension + previous_solution.actuators[k].tension) for k, a in solution.actuators.items()}
            else:
                pulls = {k: a.tension for k, a in during.actuators.items()}
            self._work["actuator_work"] -= sum(pulls[k] * (a.length - previous_solution.actuators[k].length)
                                               for k, a in solution.actuators.items())
            self._work["load_work"] += _load_work(robot, previous_solution, solution, during)
            self._work["dissipated_energy"] += self._dissipated(previous, state)
            if getattr(solution, "contact_forces", None) is not None:
                # the step's contact impulse acts at its end: sum f_{n+1} (g_n - g_{n+1}), = sum f_{n+1} g_n
                self._work["impact_loss"] += float(solution.contact_forces @ (previous_solution.contact_gaps
                                                                                - solution.contact_gaps))
            if getattr(solution, "grip_forces", None) is not None:
                self._work["impact_loss"] += float(solution.grip_forces @ (previous_solution.grip_gaps
                                                                             - solution.grip_gaps))
            self._work["impact_loss"] += _support_impact_loss(previous_solution, solution)
            self._work["friction_work"] += _friction_work(previous_solution, solution)
            self._work["friction_work"] += _body_friction_work(previous_solution, solution)
            if state.implicit_euler:
                self._work["integrator_loss"] += self.dynamics.euler_loss(previous, state)
        stored, rigid = self.stored(state, solution)
        if previous is not None:
            self._work["load_work"] += self._field_work(previous, state, previous_solution, solution, euler)
        if previous is not None and not np.array_equal(solution.parameters, previous_solution.parameters):
            # a point mass that changed (an object let go or taken) takes or brings its energy (at
            # this step's gravity: a change of gravity is the field's work above)
            masses = np.array(previous_solution.parameters, float)
            index = self.dynamics.robot.layout["gravity"]
            masses[index] = np.asarray(solution.parameters, float)[index]
            kept = self.dynamics.rigid_energies(state, solution, masses)
            self._work["load_work"] += rigid - sum(kept)
        if self._start is None:
            self._start = sum(stored)
        balance = (sum(stored) - self._start + self._work["dissipated_energy"] + self._work["impact_loss"]
                   + self._work["friction_work"] + self._work["integrator_loss"] - self._work["actuator_work"]
                   - self._work["load_work"])
        self.rows.append((*stored, *(self._work[name] for name in ENERGY_COLUMNS[3:-1]), balance))

    def _field_work(self, previous, state, before, after, euler=False):
        """The work [J] of a change of gravity over a step (a lift's acceleration is one, in its
        frame): ``-sum m (g_{n+1} - g_n) . (x_n + x_{n+1}) / 2`` over every mass, as the mean over
        the step's two ends of the gravitational energy's change with ``g`` alone; ``euler``: an
        implicit Euler step, whose gravity ``g_{n+1}`` acts over the whole step, ``-sum m (g_{n+1}
        - g_n) . x_n`` (``m g_{n+1} . (x_{n+1} - x_n)`` is the store's change less that)."""
        robot = self.dynamics.robot
        old = np.asarray(before.parameters, float)
        index = robot.layout["gravity"]
        if np.array_equal(old[index], np.asarray(after.parameters, float)[index]):
            return 0.0
        turned = old.copy()
        turned[index] = np.asarray(after.parameters, float)[index]
        ends = ((previous, before),) if euler else ((previous, before), (state, after))
        return sum(self._gravitational(x, view, turned) - self._gravitational(x, view, old)
                   for x, view in ends) / len(ends)

    def _gravitational(self, state, view, params):
        """The gravitational energy [J] of the rods, rigid point masses and free bodies at
        ``state`` (its StepOutputs ``view``) with the masses and gravity of ``params``."""
        gravity = np.asarray(params, float)[self.dynamics.robot.layout["gravity"]]
        potential = -sum(float(mass * (gravity @ result.p) @ result.weights)
                         for result, (mass, *_) in zip(view.modules, self.dynamics.sections(params)))
        return (potential + self.dynamics.rigid_energies(state, view, params)[1]
                + self.dynamics.body_energies(state, params)[1])

    def _dissipated(self, previous, state):
        """The energy [J] the rods' viscosity took over the step (none without damping)."""
        if not self._damped:
            return 0.0
        h = state.t - previous.t
        total = 0.0
        for m, ((before, _), (after, _)) in enumerate(zip(self.dynamics.nodes_of(previous), self.dynamics.nodes_of(state))):
            change = after - before
            weights = self.dynamics.solver.nlp.node_weights(m)[:-1]
            density = np.sum(self.dynamics.damping[m][:, None] * change * change, axis=0) / h
            total += float(density @ weights)
        return total


def _friction_work(before, after):
    """The energy [J] friction took from the rods over a step: ``-sum f_t . slip`` over the
    contacts against obstacles closed at both ends (``contacts`` of the two StepOutputs; only a
    contact closed at the step's start is anchored and carries friction; not the grips on free
    bodies, which a Solution's ``contacts`` also lists: :func:`_body_friction_work` takes
    those), the slip the rod's held material point's motion over the step (:func:`_slip`).
    With Coulomb's law ``f_t`` opposes the slip, so it is never negative; a sticking contact
    does not move."""
    if getattr(after, "contacts", None) is None or getattr(before, "contacts", None) is None:
        return 0.0
    was = {(c.module, c.s, c.obstacle) for c in before.contacts}
    bodies = {body.name for body in getattr(after, "bodies", None) or ()}     # their grips: _body_friction_work
    return float(sum(-c.tangential_force @ _slip(c) for c in after.contacts
                     if c.friction > 0 and c.obstacle not in bodies and (c.module, c.s, c.obstacle) in was))


def _slip(contact):
    """How far a contact's held material point moved over its body or obstacle during the step
    that ended at ``contact`` (3,) [m]: ``held_at - anchored_at``, the anchor taken where it was
    held at the step's start (:func:`~tca_casadi.model.history.carried_history`)."""
    if contact.anchored_at is None or contact.held_at is None:
        return np.zeros(3)
    return np.asarray(contact.held_at, float) - np.asarray(contact.anchored_at, float)


def _support_impact_loss(before, after):
    """The free bodies' supports' share of the impact loss over a step [J]: ``sum f_{n+1} (g_n -
    g_{n+1})`` over every body's corners."""
    was = {body.name: body.corners for body in before.bodies if body.corners is not None}
    return float(sum(body.corners.normal_forces @ (was[body.name].gaps - body.corners.gaps)
                     for body in after.bodies if body.corners is not None and body.name in was))


def _body_friction_work(before, after):
    """The energy [J] friction took at the free bodies over a step: at each grip closed at both
    ends ``-f_t . slip``, ``f_t`` the force on the rod and the slip its held material point's
    motion relative to the body's material point under it at the start (:func:`_slip`); at each
    corner pressed at both ends ``-F_t . (y_{n+1} - y_n)``, ``F_t`` the support's force on the
    body."""
    was, work = {body.name: body for body in before.bodies}, 0.0
    for body in after.bodies:
        start = was.get(body.name)
        if start is None:
            continue
        gripped = {(c.module, c.s) for c in start.grips}
        work -= float(sum(c.tangential_force @ _slip(c) for c in body.grips if (c.module, c.s) in gripped))
        if body.corners is not None and start.corners is not None:
            both = body.corners.pressed & start.corners.pressed
            moved = body.corners.positions - start.corners.positions
            work -= float(np.sum(body.corners.tangential_forces[both] * moved[both]))
    return work


def _load_work(robot, before, after, during=None):
    """Work of the point loads between two solutions: force times displacement plus moment
    times the rotation vector of the load point's frame change (small steps), the forces and
    moments those of ``during`` if given, else the mean of the two ends."""
    work = 0.0
    for k, load in enumerate(robot.point_loads):
        if load.kind != "point":
            continue
        a, b = before.loads[k], after.loads[k]
        force, moment = ((during.loads[k]["force"], during.loads[k]["moment"]) if during is not None else
                         (0.5 * (a["force"] + b["force"]), 0.5 * (a["moment"] + b["moment"])))
        work += float(force @ (b["position"] - a["position"]))
        if np.any(moment):
            work += float(moment @ _rotation_between(before, after, load))
    return work


def _rotation_between(before, after, load):
    """Rotation vector [rad] of the body frame at a point load from one solution to the next."""
    def frame(solution):
        module = solution.modules[load.module]
        return module.R[:, :, int(np.argmin(np.abs(module.s - load.s)))]
    change = frame(after) @ frame(before).T
    return 0.5 * np.array([change[2, 1] - change[1, 2], change[0, 2] - change[2, 0], change[1, 0] - change[0, 1]])


class StepSolutions(Sequence):
    """The Solutions of a dynamic run's output times, built when asked (issue 36): a run of
    12 500 steps keeps each step's :class:`~tca_casadi.solvers.dynamics.StepState` and builds
    the :class:`Solution` of only those whose global balance is checked (and any a reader asks
    for: a frame of the animation, a VTK file); :attr:`TimeSeries.views` carries the tables'
    and the energy account's values of every step."""

    def __init__(self, dynamics):
        self.dynamics = dynamics
        self._items = []              # a Solution (built) or a StepState (built on request)
        self._last = (None, None)     # the last one built on request: (index, Solution)

    def append(self, item):
        """Add an output: its Solution, or the StepState that reached it."""
        self._items.append(item)

    def __len__(self):
        return len(self._items)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        k = range(len(self))[k]
        item = self._items[k]
        if not isinstance(item, StepState):
            return item
        if self._last[0] != k:
            self._last = (k, self.dynamics.solution(item, balance=False))
        return self._last[1]

    def __delitem__(self, k):
        del self._items[k]
        self._last = (None, None)

    def checked(self):
        """The Solutions built during the run (the start and those whose balance was checked)."""
        return [item for item in self._items if not isinstance(item, StepState)]


def follow_dynamics(sim, series, path, progress=None, initial=None, start=None):
    """Fill ``series`` (a TimeSeries) with the motion at the parameter vectors ``path`` (one per
    output time, each step's parameters running from one to the next): the static equilibrium
    at ``initial`` (default ``path[0]``; the parameters before an event at the first output
    time; or ``start``, a Solution given, as a sequence's step), then one implicit step per output time
    (halved up to :data:`HALVINGS` times when Newton fails: the run stops, with the solutions
    up to there, when even that fails). The global balance is checked at the first step, every
    ``dynamics.balance_every`` steps and the last: those steps' Solutions are built as the run
    goes, the others' only when asked (:class:`StepSolutions`; ``series.views`` holds every
    output's :class:`~tca_casadi.solvers.outputs.StepOutputs`). Adds ``series.tip_velocities``
    (n, 3) [m/s] and ``series.energies`` (n, 10) [J] (:data:`ENERGY_COLUMNS`)."""
    config = sim.scenario.dynamics
    first = start if start is not None else _static_start(sim, path[0] if initial is None else initial)
    if not first.converged:
        series.message = f"no equilibrium at t = {series.t[0]:g} s: {first.message}"
        return series
    dynamics = RodDynamics(sim.robot, sim.solver("collocation"), config.integrator,
                           damping_of(config.damping, sim.scenario), steps=len(path) - 1)
    series.compiled = dynamics.solver.compiles
    state = dynamics.start(first, series.t[0])
    state.params = np.array(path[0], float)         # the steps start from the values after any event at t0
    account = EnergyAccount(dynamics)
    series.solutions = StepSolutions(dynamics)
    series.solutions.append(first)
    view = dynamics.outputs(state)  # at the parameters after any event at t0 (the first step's loads)
    series.views = [view]
    series.tip_velocities = [np.zeros(3)]
    account.add(None, state, view, None)
    for k in range(1, len(path)):
        previous, previous_view = state, view
        state = _advance(dynamics, path[k - 1], path[k], series.t[k] - series.t[k - 1])
        if state is None:
            series.message = (f"stopped at t = {series.t[k]:g} s: the step from t = {series.t[k - 1]:g} s did not "
                              f"converge even halved {HALVINGS} times ({dynamics.last_status.message})")
            break
        checked = k == 1 or k % config.balance_every == 0 or k == len(path) - 1
        series.solutions.append(dynamics.solution(state) if checked else state)
        view = dynamics.outputs(state)
        series.views.append(view)
        series.tip_velocities.append(dynamics.output_tip_velocity(state))
        account.add(previous, state, view, previous_view,
                    dynamics.solved_outputs(state) if dynamics.integrator.at_midpoint else None)
        if progress is not None:
            progress((k + 1) / len(path), f"t = {series.t[k]:.4g} s")
    series.tip_velocities = np.array(series.tip_velocities)
    series.energies = np.array(account.rows)
    if series.completed:
        series.message = f"stepped {len(series.t) - 1} times (dynamics, {config.integrator})"
    return series


def _static_start(sim, params):
    """The static equilibrium at ``params`` (a dynamic run's start at rest)."""
    base = sim.params.copy()
    try:
        return sim.solve(warn=False, params=params)
    finally:
        sim.params = base


def _advance(dynamics, start, end, h):
    """From the current state (at parameters ``start``) over ``h`` to parameters ``end``: one
    step, or 2, 4, ... equal substeps (parameters linear in between) when Newton fails. The
    StepState reached, or None if the last attempt failed (``dynamics.last_status`` says why)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    saved = dynamics.checkpoint()
    for halving in range(HALVINGS + 1):
        count = 2 ** halving
        dynamics.restore(saved)
        for j in range(1, count + 1):
            state = dynamics.advance(start + (end - start) * j / count, h / count)
            if state is None:
                break
        else:
            return state
    dynamics.restore(saved)
    return None

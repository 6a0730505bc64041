"""Implicit time stepping of the rod dynamics (issue 16): every step is one warm Newton solve of
the boundary-value problem in s on one built NLP (:mod:`tca_casadi.discretisation.dynamics`).

The NLP's time derivatives are ``x_t = c0 x + x_hist`` for the strain deviations and the
velocities ``x = [xi - xi*, q, w]`` at every node; the integrators (BDF2, implicit Euler, the
implicit midpoint rule) are choices of ``c0`` and of the history from the previous steps' node
values (:mod:`.integrators`).

The positions and orientations are not time-stepped: they follow, along s, from the base and
the strains at each instant, as in the statics; the velocity compatibility makes ``p_t = R q``.
"""
import functools
from dataclasses import dataclass, field, replace

import numpy as np

from ..discretisation.dynamics import DynamicCollocationNLP
from ..errors import ModelError
from ..model.bodies import (CONTACT_UNKNOWNS, body_motion, body_pose, body_rotation, body_shape, box_moments,
                             inertial_wrench, kinetic_energy)
from ..model.contact import CLOSED, gaps, outline_of, outline_size
from ..model.history import carried_history
from ..model.dynamics import (elastic_energy_density, inertia_per_length, inertial_loads, kinetic_energy_density,
                              point_inertia, point_mass_of)
from ..model.rotations import rotation_numpy, rotations_of
from .collocation import CollocationSolver
from .compiled import has_compiler
from .integrators import ImplicitEuler, integrator_named

#: ``solver.jit: auto`` compiles the residual of a dynamic run of at least this many steps (when
#: a C compiler is found): a compile of 1-2 s (kept on disk) against about 0.4 ms saved per step
AUTO_JIT_STEPS = 5000


class DynamicSolver(CollocationSolver):
    """The collocation solver of one implicit time step (:class:`DynamicCollocationNLP`); its
    parameter vector is ``[robot parameters; c0; history]``. Solutions' global balance includes
    the sections' inertial loads."""
    method = "collocation-dynamics"
    nlp_class = DynamicCollocationNLP
    estimates_error = False

    def node_values(self, w):
        """Per module ``(deviation strains (6, nodes), velocities (6, nodes))`` [SI] at every
        node (interval starts and collocation points, interval by interval) of scaled ``w``."""
        physical = np.asarray(w, float) * self.nlp.scale
        out = []
        for m in range(len(self.robot.modules)):
            states = physical[self.nlp.state_index[m].transpose(1, 0, 2).reshape(13, -1)]
            velocities = physical[self.nlp.velocity_index[m].transpose(1, 0, 2).reshape(6, -1)]
            out.append((states[7:13], velocities))
        return out

    def parameters(self, params, c0, damping, histories):
        """``[params; c0; B per module; history]`` from per-module damping diagonals (6,) and
        histories ((12, nodes) each, then with free bodies (12, bodies): theirs, zero when
        left out)."""
        histories = list(histories)
        if self.robot.bodies and len(histories) == len(self.robot.modules):
            histories.append(np.zeros((12, len(self.robot.bodies))))
        return np.concatenate([np.asarray(params, float), [c0]] + [np.asarray(b, float) for b in damping]
                              + [h.T.ravel() for h in histories])

    def body_values(self, w, params):
        """The free bodies' ``[pose (6); velocity (3) [m/s]; body-frame angular velocity (3)
        [rad/s]]`` (12, bodies) at scaled ``w`` and the step's parameter vector ``params``
        (:meth:`~tca_casadi.discretisation.dynamics.DynamicCollocationNLP._body_inertia`'s
        rule), or None without bodies."""
        if not self.robot.bodies:
            return None
        nlp, physical = self.nlp, np.asarray(w, float) * self.nlp.scale
        out = []
        for body in self.robot.bodies:
            pose = physical[nlp.pose_index[body.index]]
            velocity, omega, _, _ = body_motion(params[nlp.c0_index], pose, params[nlp.body_history_index[body.index]])
            out.append(np.r_[pose, velocity, omega])
        return np.array(out).T

    def _body_inertias(self, w, params):
        """Per free body its d'Alembert force and moment (global) at scaled ``w`` and ``params``
        (for its :class:`~tca_casadi.solution.BodyResult`'s residual)."""
        if not self.robot.bodies:
            return None
        nlp, physical = self.nlp, np.asarray(w, float) * self.nlp.scale
        param = self.robot.param_function(params[:self.robot.layout.size])
        out = []
        for body in self.robot.bodies:
            pose = physical[nlp.pose_index[body.index]]
            _, omega, acceleration, omega_rate = body_motion(params[nlp.c0_index], pose,
                                                             params[nlp.body_history_index[body.index]])
            mass = float(param(f"{body.name}.mass")[0])
            out.append(inertial_wrench(mass, box_moments(body.size, mass), body_rotation(body, pose[3:6]), acceleration,
                                       omega, omega_rate))
        return out

    def outputs(self, w, params):
        """The :class:`~tca_casadi.solvers.outputs.StepOutputs` at scaled ``w`` and the step's
        parameter vector ``params`` (:meth:`CollocationSolver.outputs`), with the contacts' and
        grips' forces and gaps."""
        out = super().outputs(w, params)
        robot, nlp = self.robot, self.nlp
        if robot.obstacles or robot.grips:
            w_phys = np.asarray(w, float) * nlp.scale
        if robot.obstacles:
            out.contact_forces = np.asarray(w_phys[nlp.contact_index], float).ravel()
            out.obstacles = [c.obstacle for c in robot.contacts]
            out.contact_gaps, out.clearance = self._gaps(robot.at(out.parameters).obstacles, out.modules)
        if robot.grips:
            out.grip_forces = np.array([w_phys[index[0]] for index in nlp.grip_index], float)
            out.grip_gaps = self._grip_gaps(w_phys, out.modules)
        return out

    def _grip_gaps(self, w_phys, modules):
        """The gaps [m] (grips,) of the grip candidates (``robot.grips``) to their bodies at the
        poses in ``w_phys``, at the centrelines' nearest nodes."""
        robot, nlp = self.robot, self.nlp
        out = []
        for c in robot.grips:
            line = modules[c.module]
            k = int(np.argmin(np.abs(line.s - c.s)))
            function = self._grip_gap_function(c.body, c.module)
            out.append(float(function(line.p[:, k], line.h[:, k], w_phys[nlp.pose_index[c.body]])))
        return np.array(out)

    def _grip_gap_function(self, b, m):
        """CasADi Function ``(p (3,), h (4,), pose (6,)) -> gap [m]`` of module m's outline at a
        centreline point against body b at its pose unknowns (built once: a body moves at every
        step, and a gap function per pose would be built anew each time)."""
        cache = self.__dict__.setdefault("_grip_gap_functions", {})
        if (b, m) not in cache:
            import casadi as ca
            from ..model.contact import gap
            from ..model.rotations import rotation_matrix
            p, h, pose = ca.SX.sym("p", 3), ca.SX.sym("h", 4), ca.SX.sym("pose", 6)
            body = self.robot.bodies[b]
            g, _ = gap(body_shape(body, *body_pose(body, pose)), outline_of(self.robot.modules[m]), p,
                       rotation_matrix(h))
            cache[b, m] = ca.Function("grip_gap", [p, h, pose], [g])
        return cache[b, m]

    def _gaps(self, shapes, modules):
        """``(gaps (contacts,) [m] at the contact candidates, {obstacle: nearest approach [m]
        over every node})`` of the centrelines ``modules`` to the placed obstacles ``shapes``."""
        robot = self.robot
        per_node = {(k, m): gaps(shape, outline_of(robot.modules[m]), line.p, line.h)
                    for k, shape in enumerate(shapes) for m, line in enumerate(modules)}
        at_candidates = np.array([per_node[c.obstacle, c.module][int(np.argmin(np.abs(modules[c.module].s - c.s)))]
                                  for c in robot.contacts])
        nearest = {shape.name: float(min(per_node[k, m].min() for m in range(len(modules))))
                   for k, shape in enumerate(shapes)}
        return at_candidates, nearest

    def _extra_loads(self, w, params, module_data):
        """The sections' inertial forces and moments at the nodes (global frame, times the
        quadrature weights), for the global balance."""
        nlp, robot_params = self.nlp, params[:self.robot.layout.size]
        c0 = params[nlp.c0_index]
        param = self.robot.param_function(robot_params)
        points, forces, moments = [], [], []
        for m, (deviation, velocity) in enumerate(self.node_values(w)):
            s, states, _, weights = module_data[m]
            history = params[nlp.history_index[m]].T                     # (12, nodes)
            rates = c0 * velocity + history[6:12]
            mass, rotary = inertia_per_length(self.robot.modules[m], param)
            force, moment = inertial_loads(velocity[0:3], velocity[3:6], rates[0:3], rates[3:6], mass, rotary)
            R = rotations_of(states[3:7, :-1])                                # nodes without the tip
            weight = weights[:-1]
            points.append(states[0:3, :-1])
            forces.append(np.einsum("ijk,jk->ik", R, force) * weight)
            moments.append(np.einsum("ijk,jk->ik", R, moment) * weight)
        for point, force, moment in self._rigid_inertias(w, params, module_data):
            points.append(point[:, None])
            forces.append(force[:, None])
            moments.append(moment[:, None])
        return np.hstack(points), np.hstack(forces), np.hstack(moments)

    def rigid_points(self, w, params, frame):
        """The rigid point masses at the variables ``w``: point masses, held objects' shares and
        connector masses, as ``(mass [kg], offset (3,) or None, (q, w, q_t, w_t) (3,) each,
        position (3,), R (3, 3))`` in the frame of the section they ride on; ``frame(m,
        column)`` gives ``(p, R)`` of module m at a node column (-1: its tip)."""
        nlp, robot, d = self.nlp, self.robot, self.degree
        c0 = params[nlp.c0_index]
        param = robot.param_function(params[:robot.layout.size])
        nodes = self.node_values(w)

        def motion(m, s):
            velocity = nodes[m][1]
            rates = c0 * velocity + params[nlp.history_index[m]].T[6:12]
            if s >= robot.modules[m].length * (1 - 1e-12):          # the tip: the last interval's end
                return tuple(np.split(np.r_[velocity[:, -(d + 1):] @ nlp.scheme.D,
                                            rates[:, -(d + 1):] @ nlp.scheme.D], 4)), -1
            k = next(k for k, (s0, _) in enumerate(nlp.meshes[m].intervals)
                     if abs(s0 - s) <= 1e-12 * robot.modules[m].length)
            column = k * (d + 1)
            return tuple(np.split(np.r_[velocity[:, column], rates[:, column]], 4)), column

        out = []
        for load in robot.point_loads:
            mass = float(point_mass_of(load, param))
            if load.kind != "point" and mass > 0:
                kinematics, column = motion(load.module, load.s)
                out.append((mass, None, kinematics, *frame(load.module, column)))
        for module in robot.modules:
            if module.connector is not None and module.connector.mass > 0:
                kinematics, _ = motion(module.parent, robot.modules[module.parent].length)
                out.append((module.connector.mass, module.connector.center_of_mass, kinematics,
                            *frame(module.parent, -1)))
        return out

    def _rigid_inertias(self, w, params, module_data):
        """``(point, force, moment)`` (3,) each, global: the inertial loads of :meth:`rigid_points`
        (:func:`~tca_casadi.model.dynamics.point_inertia`, rotated to the global frame)."""
        def frame(m, column):
            states = module_data[m][1]
            return states[0:3, column], rotation_numpy(states[3:7, column])

        out = []
        for mass, offset, kinematics, position, R in self.rigid_points(w, params, frame):
            wrench = point_inertia(mass, *kinematics, offset=offset)
            point = position if offset is None else position + R @ offset
            out.append((point, R @ wrench[3:6], np.zeros(3)))
        return out


#: an impact's step starts with the obstacles this far (times the section's size) from the rods
CLEARANCE = 0.5
#: Newton's iterations (chord steps included) on a step where a contact closes or opens
CONTACT_ITERATIONS = 100
#: a step in which a contact closes (an impact) is taken by the integrator's first-step rule
#: (BDF2: implicit Euler), and so are this many after it: a two-step rule whose history straddles
#: the impact extrapolates it into a rebound (a body landing at 0.25 m/s left at 0.1 m/s). The
#: impact's step lands it still moving in, the next stops it, the one after steps from a
#: velocity history past the stop; then BDF2 resumes (``docs/contact.md`` section 5a)
RESTART_STEPS = 2


def _check_contact(robot, integrator):
    """ModelError for contact that rod dynamics does not model: obstacles (and so free
    bodies, which rest on one) with the midpoint rule (its end state, ``2 z - x_n``, is
    extrapolated past the contact solved at the midpoint)."""
    if robot.obstacles and integrator.at_midpoint:
        raise ModelError("dynamics.integrator: midpoint with obstacles: its end state is extrapolated past the "
                            "contact solved at the step's middle; use bdf2")


@dataclass
class StepState:
    """Node values at one instant: per module (deviation strains (6, n), velocities (6, n))
    and the scaled NLP variables ``w``."""
    t: float
    nodes: list
    w: np.ndarray
    params: np.ndarray
    #: the tip module's end rotation (3, 3) where the step's outputs gave it (None: from ``w``)
    tip_rotation: np.ndarray = None
    #: the step that reached it: the parameter vector it was solved at (robot parameters, c0,
    #: damping, history), its SolveStatus, the solved variables (the midpoint rule's midpoint;
    #: else ``w``) and the state it started from (None: the start)
    full: np.ndarray = None
    status: object = None
    solved: np.ndarray = None
    previous: "StepState" = field(default=None, repr=False)
    #: its Solution where one was built for friction's history (without balance or search)
    solution: object = field(default=None, repr=False)
    #: the free bodies' pose, velocity and angular velocity (12, bodies) (DynamicSolver.body_values)
    bodies: np.ndarray = None
    #: how many more steps from it restart the integrator (its first step's rule: an impact)
    restart: int = 0
    #: whether the step that reached it was implicit Euler's (its own dissipation accounted)
    implicit_euler: bool = False


class RodDynamics:
    """Time stepping of a robot from its static equilibrium at rest.

    Parameters
    ----------
    robot : Robot
        The robot model.
    static : CollocationSolver
        Its static solver: the options and mesh (after any refinement) the steps are solved on.
    integrator : str
        The name of one of :data:`~tca_casadi.solvers.integrators.INTEGRATORS`.
    damping : KelvinVoigt, optional
        The rods' viscosity (default none).
    steps : int, optional
        How many steps the run will take: with ``solver.jit: auto``, at least
        :data:`AUTO_JIT_STEPS` compile the step's residual (where a C compiler is found).
    """

    def __init__(self, robot, static, integrator="bdf2", damping=None, steps=None):
        integrator = integrator_named(integrator)
        _check_contact(robot, integrator)
        self.robot, self.integrator = robot, integrator
        self.solver = DynamicSolver(robot, static.options, meshes=static.nlp.meshes, degree=static.degree)
        self.solver.compile_when_auto = steps is not None and steps >= AUTO_JIT_STEPS and has_compiler()
        self.damping = [np.zeros(6) if damping is None else damping.matrix(module)
                        for module in robot.modules]
        self.states = []                     # StepState s, the last two kept
        self._midpoints = []                 # the midpoint rule's solved states, the last two
        self._history_w = []
        self._lu = None

    def start(self, solution, t=0.0):
        """Begin at rest in the static ``solution`` (its collocation variables) at time ``t``."""
        static_w = solution.iterate.w
        w = np.concatenate([static_w, np.zeros(self.solver.nlp.scale.size - static_w.size)])
        at_rest = self.solver.parameters(solution.parameters, 0.0, self.damping,
                                         [np.zeros((12, x[0].shape[1])) for x in self.solver.node_values(w)])
        self.states = [StepState(t, self.solver.node_values(w), w, np.array(solution.parameters, float),
                                 solution=solution, bodies=self.solver.body_values(w, at_rest))]
        self._equilibrium = np.array(solution.parameters, float)      # where the start was solved
        self._midpoints = []
        self._history_w = [(t, w)]               # (t, w) of the last three states, for the predictor
        return self.states[-1]

    def _coefficients(self, h, first=False):
        """``(c0, history per module)`` for the next step of size ``h``: the integrator's, or
        its first step's rule (``first``: no step before it, or a restart after an impact,
        :data:`RESTART_STEPS`)."""
        now = self.states[-1]
        if first:
            return self.integrator.first().coefficients(h, self._history_values(now))
        before = self.states[-2]
        return self.integrator.coefficients(h, self._history_values(now), self._history_values(before),
                                            now.t - before.t)

    def _history_values(self, state):
        """What the integrator's history is made of at ``state``: per module its node values
        (12, nodes), then with free bodies theirs (12, bodies)."""
        values = [np.vstack(x) for x in self.nodes_of(state)]
        return values if state.bodies is None else values + [state.bodies]

    def nodes_of(self, state):
        """A state's node values (recomputed from its ``w`` if it dropped them)."""
        if state.nodes is None:
            state.nodes = self.solver.node_values(state.w)
        return state.nodes

    def advance(self, params, h):
        """Advance by ``h`` [s] to the robot parameters ``params`` (at the end of the step; the
        midpoint rule solves at the mean of the previous step's and these). Returns the
        :class:`StepState` at the end of the step (its Solution is built only on request:
        :meth:`solution`), or None if Newton did not converge (``last_status`` says why)."""
        now = self.states[-1]
        params = np.asarray(params, float)
        if self.robot.path_dependent:        # friction anchored where the contacts touch now
            params = carried_history(self.robot, params, self.contact_solution(now))
        scheme = self.integrator
        solved_at = scheme.parameters_at(params, now.params)
        restarting = len(self.states) < 2 or now.restart > 0
        c0, histories = self._coefficients(h, restarting)
        full = self.solver.parameters(solved_at, c0, self.damping, histories)
        w, status = self._solve(now, solved_at, full, c0, histories, self._predicted(now.t + scheme.fraction * h))
        rule = scheme.first() if restarting else scheme
        if status.success and not restarting and self._closes(now.w, w):
            # an impact: its step by the first-step rule too (RESTART_STEPS)
            c0, histories = self._coefficients(h, True)
            first = self.solver.parameters(solved_at, c0, self.damping, histories)
            again, again_status = self._solve(now, solved_at, first, c0, histories, w)
            if again_status.success:
                w, status, full, rule = again, again_status, first, scheme.first()
        self._lu = self.solver.square.last_lu           # chord steps of the next step start on it
        self.last_status = status
        if not status.success:
            self._failed = (w, full)                    # for the Solution of the failed step
            return None
        solved = w
        if scheme.at_midpoint:
            middle = StepState(now.t + scheme.fraction * h, self.solver.node_values(w), w, solved_at)
            self._midpoints = (self._midpoints + [middle])[-2:]
            w = scheme.end(w, now.w)
        state = StepState(now.t + h, self.solver.node_values(w), w, params, full=full, status=status, solved=solved,
                          previous=now, bodies=self.solver.body_values(w, full))
        state.restart = RESTART_STEPS if self._closes(now.w, w) else max(now.restart - 1, 0)
        state.implicit_euler = isinstance(rule, ImplicitEuler)
        if len(self.states) == 2:          # it leaves the window: its nodes follow from w when asked
            self.states[0].nodes = self.states[0].solution = None
        self.states = (self.states + [state])[-2:]
        self._history_w = (self._history_w + [(state.t, w)])[-3:]
        return state

    def _solve(self, now, solved_at, full, c0, histories, guess):
        """The step's variables from ``now`` at the parameter vector ``full`` (robot parameters
        ``solved_at``, ``c0``, ``histories``) from ``guess``: Newton, then the fallbacks of
        :meth:`advance`. ``(w, status)``."""
        w, status = self._newton(guess, full, self._lu)
        if not status.success:
            w, status = self._continued(guess, self._solved_parameters(now), solved_at, c0, histories, status,
                                        contact=bool(self.robot.obstacles))
        if not status.success and self.robot.obstacles:
            # a contact closing or opening: the complementarity's kink defeats the line search
            w, status = self._newton(guess, full, contact=True)
            clear = None if status.success else self._clear_of_obstacles(guess, solved_at)
            if clear is not None:           # an impact: from the obstacles moved clear back to their places
                w, status = self._continued(guess, clear, solved_at, c0, histories, status, solve_start=True,
                                            contact=True)
        return w, status

    def _closes(self, before, after):
        """Whether a contact (a rod's against an obstacle, a grip, a body's corner) open at the
        scaled variables ``before`` is closed at ``after``: an impact."""
        index = self._normal_force_index
        if index.size == 0:
            return False
        return bool(np.any((np.asarray(after)[index] > CLOSED) & (np.asarray(before)[index] <= CLOSED)))

    @functools.cached_property
    def _normal_force_index(self):
        """Indices in ``w`` of every contact's normal force (scaled by its force scale)."""
        nlp = self.solver.nlp
        parts = [np.asarray(nlp.contact_index, int)] + [np.asarray(i[0:1], int) for i in nlp.grip_index]
        parts += [np.asarray(i[0::CONTACT_UNKNOWNS], int) for i in nlp.support_index.values()]
        return np.concatenate(parts)

    def _newton(self, guess, full, lu=None, contact=False):
        """Newton on the step's equations at the parameter vector ``full``: ``(w, status)``;
        ``contact``: semismooth (the step taken where the line search finds no descent, capped
        on the rods' states: :meth:`SquareSystem.newton <tca_casadi.solvers.newton.SquareSystem.newton>`)
        with :data:`CONTACT_ITERATIONS` iterations, for a step where a contact closes or opens."""
        self.solver.solve_count += 1
        return self.solver.square.newton(guess, full, self.solver.options.tolerance,
                                         CONTACT_ITERATIONS if contact else 25, lu=lu, monotone=not contact)

    def _solved_parameters(self, state):
        """The robot parameters ``state`` was solved at (the start: its static equilibrium's)."""
        return self._equilibrium if state.full is None else state.full[:self.robot.layout.size]

    def _continued(self, guess, start, end, c0, histories, status, shortest=1 / 64, solve_start=False,
                   contact=False):
        """The step's equations at the robot parameters ``end`` by Newton along the way from
        ``start`` (those the state it starts from was solved at): a step whose parameters jump
        (an event at its start: a TCA stepped by 35 K) that Newton cannot take at once. Each
        stage has the step's own ``c0`` and ``histories`` and starts from the last one's
        solution; a stage that fails is halved down to ``shortest`` of the way. Only the last
        stage's solution is the step's. ``(w, status)``; ``status`` (the first attempt's) when
        the parameters did not change."""
        if np.array_equal(start, end):
            return guess, status
        done, stride, w = 0.0, 0.25, guess
        if solve_start:
            w, status = self._newton(guess, self.solver.parameters(start, c0, self.damping, histories),
                                     contact=contact)
            if not status.success:
                return w, status
        while done < 1.0:
            trial = min(1.0, done + stride)
            full = self.solver.parameters(start + trial * (end - start), c0, self.damping, histories)
            reached, status = self._newton(w, full, contact=contact)
            if status.success:
                done, w, stride = trial, reached, min(2.0 * stride, 0.5)
            elif stride / 2 < shortest:
                return reached, status
            else:
                stride /= 2
        return w, status

    def _clear_of_obstacles(self, w, params):
        """``params`` with every obstacle that the rods at scaled ``w`` (a predictor) cut into,
        or come within :data:`CLEARANCE` of their section's size of, moved back along its
        outward normal at the deepest node until they clear it by that much; None if none is
        that near. Where an impact's step fails, the step is solved with the obstacles there
        and continued to their places (:meth:`_continued`)."""
        robot, nlp = self.robot, self.solver.nlp
        physical = np.asarray(w, float) * nlp.scale
        moved, changed = np.array(params, float), False
        for shape in robot.at(params).obstacles:
            deepest, normal = np.inf, None
            for m, (index, _, _) in enumerate(self.solver._node_layout()):
                module = robot.modules[m]
                pose = physical[index[0:7]] + nlp.state_offset[m][0:7, None]
                g = gaps(shape, outline_of(module), pose[0:3], pose[3:7]) - CLEARANCE * outline_size(module)
                j = int(np.argmin(g))
                if g[j] < deepest:
                    deepest, normal = float(g[j]), np.asarray(shape.signed_distance(pose[0:3, j])[1], float).ravel()
            if deepest < 0:
                moved[robot.layout[f"obstacles.{shape.name}.position"]] += deepest * normal
                changed = True
        return moved if changed else None

    def step(self, params, h, balance=True):
        """:meth:`advance`, with the Solution of the solved point (the end, or the midpoint for
        ``midpoint``): ``(state, solution)``, or ``(None, solution)`` where Newton did not
        converge; ``balance`` False: the solution without its global balance."""
        state = self.advance(params, h)
        if state is None:
            return None, self.solver.evaluate(*self._failed, self.last_status, balance=balance)
        return state, self.solver.evaluate(state.solved, state.full, state.status, balance=balance)

    def solution(self, state, balance=True, search=True):
        """The :class:`Solution` of the end of the step that reached ``state`` (for the
        midpoint rule: :meth:`end_solution`, the balance that of the solved midpoint);
        ``search`` False: no search for contacts between nodes."""
        solved = self.solver.evaluate(state.solved, state.full, state.status, search, balance)
        if not self.integrator.at_midpoint:
            return solved
        return self.end_solution(state, state.previous, solved)

    def contact_solution(self, state):
        """The Solution of ``state`` without its balance or the search between nodes (its closed
        contacts, for friction's history and work), built once."""
        if state.solution is None:
            state.solution = self.solution(state, balance=False, search=False)
        return state.solution

    def outputs(self, state):
        """The :class:`~tca_casadi.solvers.outputs.StepOutputs` of the end of the step that
        reached ``state`` (the start: the state at rest, at its parameters; with friction, its
        closed contacts too)."""
        out = self._outputs(state)
        if self.robot.path_dependent:
            found = self.contact_solution(state)
            out.contacts, out.bodies, out.body_motion = found.contacts, found.bodies, state.bodies
        return out

    def _outputs(self, state):
        if state.full is None:
            return self.solver.outputs(state.w, self.solver.parameters(
                state.params, 0.0, self.damping, [np.zeros((12, x[0].shape[1])) for x in self.nodes_of(state)]))
        if self.integrator.at_midpoint:
            return self.solver.outputs(state.w, self._end_parameters(state, state.previous))
        out = self.solver.outputs(state.w, state.full)
        state.tip_rotation = out.tip_rotation
        return out

    def solved_outputs(self, state):
        """The :class:`~tca_casadi.solvers.outputs.StepOutputs` of the point the step was solved
        at (the midpoint rule's midpoint; else the end)."""
        return self.solver.outputs(state.solved, state.full)

    def tip_velocity(self, state):
        """The tip's global velocity [m/s] (3,) at ``state``: ``R q`` at the tip module's end."""
        nlp, tip = self.solver.nlp, self.robot.tip_index
        rotation = state.tip_rotation
        if rotation is None:
            _, ends, _ = self.solver._outputs_at(state.w, np.zeros(nlp.parameter_size))
            rotation = rotation_numpy(ends[3:7, tip])
        last = self.nodes_of(state)[tip][1][:, -(self.solver.degree + 1):]            # the last interval's nodes
        q_end = last @ nlp.scheme.D
        return rotation @ q_end[0:3]

    def checkpoint(self):
        """The stepper's history (states, predictor and midpoint memories), for :meth:`restore`."""
        return list(self.states), list(self._history_w), list(self._midpoints)

    def restore(self, checkpoint):
        """Back to a :meth:`checkpoint` (after a step that is to be redone in substeps)."""
        self.states, self._history_w, self._midpoints = (list(part) for part in checkpoint)

    def _predicted(self, t):
        """Newton's start at time ``t``: the quadratic (Lagrange) extrapolation of the last
        three states' variables (linear with two, the last with one)."""
        known = self._history_w[-3:]
        guess = np.zeros_like(known[-1][1])
        for j, (t_j, w_j) in enumerate(known):
            weight = 1.0
            for k, (t_k, _) in enumerate(known):
                if k != j:
                    weight *= (t - t_k) / (t_j - t_k)
            guess += weight * w_j
        return guess

    def output_tip_velocity(self, state):
        """The tip velocity [m/s] (3,) to report at ``state``: :meth:`tip_velocity`; for the
        midpoint rule, extrapolated linearly to the state's time from the last two solved
        midpoint states (from rest and the first one after the first step), whose velocities
        are free of the period-2 oscillation that the extrapolated end states carry."""
        if not self.integrator.at_midpoint or not self._midpoints:
            return self.tip_velocity(state)
        last = self._midpoints[-1]
        if len(self._midpoints) == 1:
            before = self.states[-2] if len(self.states) > 1 else self.states[0]     # the start, at rest
            before_velocity, before_time = self.tip_velocity(before), before.t
        else:
            before_velocity, before_time = self.tip_velocity(self._midpoints[0]), self._midpoints[0].t
        velocity = self.tip_velocity(last)
        return velocity + (velocity - before_velocity) * (state.t - last.t) / (last.t - before_time)

    def end_solution(self, state, previous, solved):
        """The :class:`Solution` of the end state of a midpoint step (extrapolated, not itself a
        solution of the step's equations), with the step's status and the global balance of the
        solved midpoint state ``solved`` (an extrapolated state has no consistent acceleration
        to balance)."""
        end = self.solver.evaluate(state.w, self._end_parameters(state, previous), solved.result, balance=False)
        warnings = [w for w in end.warnings if w.kind != "global_balance"] + \
                   [w for w in solved.warnings if w.kind == "global_balance"]
        return replace(end, balance=solved.balance, warnings=warnings)

    def _end_parameters(self, state, previous):
        """The parameter vector of the end ``state`` of a midpoint step from ``previous``: the
        end's rates as implicit Euler's over the step, ``(x_{n+1} - x_n) / h``."""
        nodes = previous.nodes if previous.nodes is not None else self.solver.node_values(previous.w)
        c0, histories = ImplicitEuler().coefficients(state.t - previous.t, [np.vstack(x) for x in nodes])
        return self.solver.parameters(state.params, c0, self.damping, histories)

    def tip_position(self, state):
        """The tip [m] (3,) at ``state`` (the end of the tip module, from the node values)."""
        nlp = self.solver.nlp
        _, ends, _ = self.solver._outputs_at(state.w, np.zeros(nlp.parameter_size))
        return ends[0:3, self.robot.tip_index]

    def rigid_energies(self, state, solution, params=None):
        """``(kinetic, gravitational)`` [J] of the rigid point masses at ``state`` (its
        :class:`Solution` gives their frames): ``M |R (q + w x c)|^2 / 2`` and ``-M g . x``;
        the masses (and gravity) from ``params`` (default the solution's)."""
        def frame(m, column):
            module = solution.modules[m]
            return module.p[:, column], module.R[:, :, column]
        if not self._rigid_masses:
            return 0.0, 0.0
        params = solution.parameters if params is None else np.asarray(params, float)
        full = self.solver.parameters(params, 0.0, self.damping,
                                      [np.zeros((12, nodes[0].shape[1])) for nodes in self.nodes_of(state)])
        gravity = params[self.robot.layout["gravity"]]
        kinetic = potential = 0.0
        for mass, offset, (q, w, _, _), position, R in self.solver.rigid_points(state.w, full, frame):
            c = np.zeros(3) if offset is None else np.asarray(offset, float)
            kinetic += 0.5 * mass * float(np.sum((R @ (q + np.cross(w, c))) ** 2))
            potential -= mass * float(gravity @ (position + R @ c))
        return kinetic, potential

    @property
    def _rigid_masses(self):
        """Whether the robot carries rigid point masses (point masses, held objects, connector
        masses; their values may still be 0 at some parameters)."""
        robot = self.robot
        return any(load.kind != "point" for load in robot.point_loads) or any(
            module.connector is not None and module.connector.mass > 0 for module in robot.modules)

    def sections(self, params):
        """Per module ``(rho A [kg/m], rho J (3,) [kg m], stiffness (6,), node weights (nodes,)
        [m])`` at the robot parameters ``params`` (the last few kept: a run's parameters change
        only at its events)."""
        params = np.asarray(params, float)
        key = params.tobytes()
        cache = self.__dict__.setdefault("_sections", {})
        if key not in cache:
            if len(cache) >= 8:
                cache.pop(next(iter(cache)))
            param, evaluated = self.robot.param_function(params), self.robot.at(params)
            cache[key] = [(*inertia_per_length(module, param), evaluated.modules[m].stiffness,
                           self.solver.nlp.node_weights(m)[:-1]) for m, module in enumerate(self.robot.modules)]
        return cache[key]

    def body_energies(self, state, params):
        """``(kinetic, gravitational)`` [J] of the free bodies at ``state``: ``m |v|^2 / 2 +
        omega . J omega / 2`` and ``-m g . r`` (masses and gravity from ``params``)."""
        if state.bodies is None:
            return 0.0, 0.0
        robot = self.robot
        param = robot.param_function(params)
        gravity = np.asarray(param("gravity"), float).ravel()
        kinetic = potential = 0.0
        for body, value in zip(robot.bodies, state.bodies.T):
            mass = float(param(f"{body.name}.mass")[0])
            kinetic += kinetic_energy(mass, box_moments(body.size, mass), value[6:9], value[9:12])
            potential -= mass * float(gravity @ (body.position + value[0:3]))
        return kinetic, potential

    def euler_loss(self, previous, state):
        """The energy [J] implicit Euler's own damping took over the step from ``previous`` to
        ``state``: ``1/2 int (rho A |dq|^2 + dw . rho J dw + dxi . K dxi) ds`` over the rods,
        ``1/2 (m |dv|^2 + d omega . J d omega)`` over the free bodies and ``1/2 M |d(q + w x c)|^2``
        over the rigid point masses (``d`` the step's change). With ``x_t = (x_{n+1} - x_n) / h``
        a force that does ``F . x_t`` of work per time puts ``d(x . x) / 2h + |dx|^2 / 2h`` into a
        quadratic store: the second term is this loss (``docs/dynamics.md``)."""
        total = 0.0
        pairs = zip(self.nodes_of(previous), self.nodes_of(state), self.sections(state.params))
        for (dev_a, vel_a), (dev_b, vel_b), (mass, rotary, stiffness, weights) in pairs:
            change, strain = vel_b - vel_a, dev_b - dev_a
            density = (kinetic_energy_density(change[0:3], change[3:6], mass, rotary)
                       + elastic_energy_density(stiffness, strain))
            total += float(density @ weights)
        if state.bodies is not None:
            param = self.robot.param_function(state.params)
            for body, a, b in zip(self.robot.bodies, previous.bodies.T, state.bodies.T):
                mass = float(param(f"{body.name}.mass")[0])
                total += kinetic_energy(mass, box_moments(body.size, mass), b[6:9] - a[6:9], b[9:12] - a[9:12])
        if self._rigid_masses:
            speeds = [self._rigid_speeds(x) for x in (previous, state)]
            total += sum(0.5 * mass * float(np.sum((b - a) ** 2)) for (mass, a), (_, b) in zip(*speeds))
        return total

    def _rigid_speeds(self, state):
        """``[(mass, q + w x c (3,) in its section's frame)]`` of the rigid point masses at ``state``."""
        full = self.solver.parameters(state.params, 0.0, self.damping,
                                      [np.zeros((12, x[0].shape[1])) for x in self.nodes_of(state)])
        frame = lambda m, column: (np.zeros(3), np.eye(3))          # noqa: E731 (velocities need no frame)
        return [(mass, q + np.cross(w, np.zeros(3) if offset is None else np.asarray(offset, float)))
                for mass, offset, (q, w, _, _), _, _ in self.solver.rigid_points(state.w, full, frame)]

    def energies(self, state, params):
        """``(kinetic, elastic)`` [J] of the rods at ``state`` (Gauss quadrature on the nodes)."""
        kinetic = elastic = 0.0
        for (deviation, velocity), (mass, rotary, stiffness, weights) in zip(self.nodes_of(state), self.sections(params)):
            kinetic += float(kinetic_energy_density(velocity[0:3], velocity[3:6], mass, rotary) @ weights)
            elastic += float(elastic_energy_density(stiffness, deviation) @ weights)
        return kinetic, elastic

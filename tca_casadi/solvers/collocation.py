"""The collocation solver: the NLP of :mod:`tca_casadi.discretisation` solved with IPOPT.
Built once per scenario structure; each :meth:`solve` takes new parameters and a warm start."""
import logging
import time
from collections import OrderedDict

import casadi as ca
import numpy as np

from ..discretisation import CollocationNLP
from ..discretisation.structure import StructuredJacobian
from ..errors import PhysicsWarning
from ..status import SolveStatus, Status
from . import accuracy
from ..model.balance import load_markers
from ..model.contact import gaps, outline_of
from ..solution import Iterate
from .assemble import build_solution
from .guess import reference_guess
from ..buffers import BufferedFunction
from .newton import MEMORY_ADVICE, SquareSystem
from .outputs import ActuatorState, Centreline, StepOutputs

log = logging.getLogger(__name__)

#: what to change when a robot's NLP does not fit in memory
#: samples per interval where contact gaps are checked between the nodes
FINE_SAMPLES = 16
#: built solvers kept for reuse, by (scenario name, structure key, meshes, degree); the oldest go
BUILT_SOLVERS = 6
#: semismooth Newton's iterations where the monotone one found no descent (with contact)
SEMISMOOTH_ITERATIONS = 40
_built = OrderedDict()


def clear_built_solvers():
    """Forget every kept solver (e.g. after patching a model function in a test)."""
    _built.clear()


def forget(solver):
    """Stop keeping ``solver`` (it lives on while something else holds it)."""
    for key in [k for k, v in _built.items() if v is solver]:
        del _built[key]


class CollocationSolver:
    """Direct collocation + IPOPT. ``solve(params, initial=None)`` -> :class:`Solution`."""
    method = "collocation"
    #: capabilities that :class:`Simulation` and the studies rely on (declared, not probed):
    #: a square system with Newton and linearisations (continuation, sweeps, inverse statics),
    #: and an error estimate against degree d + 1 (accuracy control)
    has_square_system = True
    estimates_error = True
    #: the NLP it builds (a dynamic time step's: :class:`~tca_casadi.solvers.dynamics.DynamicSolver`)
    nlp_class = CollocationNLP

    def __init__(self, robot, options, meshes=None, degree=None, structure=None):
        from ..resources import memory_guard
        start = time.perf_counter()
        self.robot, self.options, self.structure = robot, options, structure
        self.degree = degree or options.degree
        what = f"building the collocation NLP of {robot.name!r}"
        with memory_guard(what + (f" on {sum(len(m.intervals) for m in meshes)} intervals" if meshes else ""),
                          MEMORY_ADVICE):
            self.nlp = self.nlp_class(robot, options.intervals, self.degree, options.scheme, meshes)
            self._constraints = ca.Function("nlp_g", [self.nlp.w, self.nlp.P], [self.nlp.problem["g"]]).expand()
            # the Jacobian through the rod equations at one point, mapped (linear in the mesh)
            self._jacobian = StructuredJacobian(self.nlp)
        self._ipopt_instance = None      # IPOPT is built on first use (Newton needs only g and J)
        self._square = None
        self._higher = None
        self.build_time_s = time.perf_counter() - start
        self.solve_count = 0
        log.info("built collocation NLP: %d variables in %.3f s", self.nlp.w.numel(), self.build_time_s)

    @classmethod
    def shared(cls, robot, options, structure, meshes=None, degree=None):
        """The solver of this structure, mesh and degree, built once per process and kept (the
        last :data:`BUILT_SOLVERS`). ``structure``: ``Robot.structure_key`` of the scenario (it
        holds every non-parameter value, the solver options included); everything a solver
        bakes in is in it, so two scenarios with the same key and name have the same NLP and
        differ only in the parameter vector each solve is given."""
        if structure is None:
            return cls(robot, options, meshes, degree)
        key = (robot.name, structure, None if meshes is None else tuple(meshes), degree or options.degree)
        if key in _built:
            _built.move_to_end(key)
            return _built[key]
        solver = _built[key] = cls(robot, options, meshes, degree, structure)
        while len(_built) > BUILT_SOLVERS:
            _built.popitem(last=False)
        return solver

    def release_higher(self):
        """Forget the degree d + 1 solver of the error estimate (kept and shared otherwise): a
        mesh that refinement left behind needs no more estimates, and on a fine mesh that
        solver is most of the memory."""
        if self._higher is not None:
            forget(self._higher)
            self._higher = None

    def release(self):
        """Stop keeping this solver for later :meth:`shared` calls (a mesh refinement left behind)."""
        forget(self)

    def finer(self, meshes):
        """The solver of the same structure and degree on ``meshes`` (kept like :meth:`shared`)."""
        return CollocationSolver.shared(self.robot, self.options, self.structure, meshes, self.degree)

    def initial_guess(self, params, initial=None):
        """Scaled start point: a previous solution's variables if compatible, else the reference shape."""
        if initial is not None and initial.iterate.fits(self.method, self.nlp.scale.size):
            return initial.iterate.w
        return reference_guess(self.nlp, params)

    def solve(self, params, initial=None):
        """Solve at parameter vector ``params``, warm-started from ``initial`` (a Solution).

        ``solver.algorithm: newton`` tries Newton's method on the square system first (from the
        warm start, or the reference shape) and falls back to IPOPT if it fails; ``ipopt`` (the
        default) goes to IPOPT directly."""
        if self.options.algorithm == "newton":
            # from a warm start, the first steps are chord steps on the Jacobian factorised last
            # (kept only while they contract the residual tenfold)
            lu = self.square.last_lu if initial is not None and self._square is not None else None
            newton = self.solve_newton(params, self.initial_guess(params, initial), lu=lu)
            if newton.converged:
                return newton
        return self.solve_ipopt(params, initial)

    @property
    def _ipopt(self):
        """IPOPT on the square feasibility problem (f = 0), built on first use: success is
        governed by constr_viol_tol on our own order-one scaled constraints; equalities are not
        relaxed (bound_relax_factor = 0); pivtol = 0 lets MUMPS skip threshold pivoting (IPOPT
        raises it when a solve is inaccurate); the Lagrangian Hessian is zero at the multipliers
        of a square problem: no need to build it."""
        if self._ipopt_instance is None:
            options = self.options
            ipopt = {"print_level": 0, "sb": "yes", "tol": max(options.tolerance, 1e-8),
                     "constr_viol_tol": options.tolerance, "max_iter": options.max_iterations,
                     "warm_start_init_point": "yes", "hessian_approximation": "limited-memory",
                     "mumps_pivtol": 0.0, "nlp_scaling_method": "none", "bound_relax_factor": 0.0}
            self._ipopt_instance = ca.nlpsol("collocation", "ipopt", self.nlp.problem,
                                             {"ipopt": ipopt, "print_time": False, "error_on_fail": False,
                                              "expand": True})
        return self._ipopt_instance

    def solve_ipopt(self, params, initial=None):
        """IPOPT on the square NLP at ``params``, warm-started from ``initial`` (a Solution).
        Converged when IPOPT reports success *and* the max scaled residual meets
        ``solver.tolerance`` (IPOPT's own ``tol`` on its overall error is floored at 1e-8, which
        never loosens that test; its "acceptable level" exits do not pass it)."""
        params = np.asarray(params, dtype=float)
        w0 = self.initial_guess(params, initial)
        start = time.perf_counter()
        result = self._ipopt(x0=w0, p=params, lbg=0.0, ubg=0.0, lam_g0=0.0, lam_x0=0.0)
        elapsed = time.perf_counter() - start
        self.solve_count += 1
        stats = self._ipopt.stats()
        w = np.array(result["x"]).ravel()
        failure = None if stats["success"] else (
            Status.MAX_ITERATIONS if stats["return_status"] == "Maximum_Iterations_Exceeded" else Status.ALGORITHM_FAILED)
        status = SolveStatus.judged("IPOPT", self.max_residual(w, params), self.options.tolerance, failure,
                                    nit=int(stats.get("iter_count", 0)), solve_time_s=elapsed,
                                    build_time_s=self.build_time_s, detail=f"IPOPT: {stats['return_status']}")
        return self._assemble(w, params, status)

    @property
    def higher(self):
        """The same NLP at degree d + 1 on the same meshes (built on first use): the reference of
        the error estimate (:mod:`tca_casadi.solvers.accuracy`)."""
        if self._higher is None:
            self._higher = CollocationSolver.shared(self.robot, self.options, self.structure,
                                                    self.nlp.meshes, self.degree + 1)
        return self._higher

    #: ``solver.jit: auto`` compiles this solver's residual (set by a long dynamic run)
    compile_when_auto = False

    @property
    def compiles(self):
        """Whether numeric residuals run compiled (``solver.jit: true``, or ``auto`` where the
        solver asked for it)."""
        jit = getattr(self.options, "jit", False)
        return jit is True or (jit == "auto" and self.compile_when_auto)

    @property
    def square(self):
        """The :class:`SquareSystem` (residual, sparse Jacobian, Newton) of this NLP."""
        if self._square is None:
            native = None
            if self.compiles:                    # the residual and the chord steps compiled (one library)
                from .native import NativeChord
                native = NativeChord(self._constraints)
            # the Jacobians too only when asked (solver.jit: true): their compile pays over many runs
            self._square = SquareSystem(self.nlp, self._constraints, self._jacobian, native=native,
                                        compile_jacobians=getattr(self.options, "jit", False) is True)
        return self._square

    def linearise(self, w, params):
        """:class:`Linearisation` of the square system at scaled variables ``w`` and ``params``."""
        return self.square.linearise(w, params)

    def solve_newton(self, params, w0, lu=None, search=True, balance=True, semismooth=False):
        """Newton's method on the square system from scaled variables ``w0`` (a predictor):
        the same equations and tolerance as :meth:`solve`, without IPOPT's machinery (``lu``: a
        factorised Jacobian from a nearby point for the first chord steps; ``search`` and
        ``balance``: as in :meth:`evaluate`). ``semismooth``: where the line search finds no
        descent on a robot with contact, semismooth Newton from ``w0`` is tried next
        (:data:`SEMISMOOTH_ITERATIONS`; where the alternative is IPOPT, not a shorter step)."""
        params = np.asarray(params, dtype=float)
        w, status = self.square.newton(w0, params, self.options.tolerance, lu=lu)
        if semismooth and status.status == Status.NO_DESCENT and self._complementarity:
            # a contact closing or opening: the complementarity's kink defeats the line search,
            # where semismooth Newton (the capped step taken without descent) goes through it
            again, again_status = self.square.newton(w0, params, self.options.tolerance, SEMISMOOTH_ITERATIONS,
                                                     monotone=False)
            if again_status.success:
                w, status = again, again_status.noted("semismooth: the line search found no descent at a kink")
        self.solve_count += 1
        return self.evaluate(w, params, status, search, balance)

    @property
    def _complementarity(self):
        """Whether the equations hold complementarity conditions (obstacles, objects' grips and
        supports), whose kinks a line search cannot pass."""
        return bool(self.robot.obstacles) or bool(self.robot.bodies)

    def evaluate(self, w, params, status, search=True, balance=True):
        """A :class:`Solution` from scaled variables ``w`` found by some algorithm (Newton, the
        pseudo-arclength corrector); ``status`` its :class:`SolveStatus` (a residual that is not
        a number is evaluated at ``(w, params)``); ``search`` False skips the search for contacts
        between candidates (:meth:`clearance`; continuation's intermediate steps: the nodes'
        gaps stand in); ``balance`` False skips the global balance (the Solution's ``balance`` is
        None)."""
        w, params = np.asarray(w, float), np.asarray(params, float)
        if not np.isfinite(status.residual):
            status = SolveStatus.judged(status.algorithm, self.max_residual(w, params), status.tolerance,
                                        status.status, nit=status.nit, solve_time_s=status.solve_time_s,
                                        detail=status.detail)
        return self._assemble(w, params, status.replace(build_time_s=self.build_time_s), search, balance)

    def max_residual(self, w, params):
        """Largest scaled constraint violation at ``(w, params)``."""
        return float(np.max(np.abs(np.array(self._constraints(w, params))))) if np.size(w) else 0.0

    def _outputs_at(self, w, params):
        """``(lengths, ends, base_wrenches)`` of the NLP's ``outputs`` as numpy arrays (dense
        outputs into preallocated buffers)."""
        if getattr(self, "_buffered_outputs", None) is None:
            outputs = self.nlp.outputs
            shapes = [outputs.size_out(k) for k in range(outputs.n_out())]
            dense = all(outputs.nnz_out(k) == outputs.numel_out(k) for k in range(outputs.n_out()))
            if dense and self.compiles:          # a long dynamic run reads them at every step
                from .compiled import compiled
                outputs = compiled(outputs.expand())
            self._buffered_outputs = (BufferedFunction(outputs) if dense else None, shapes)
        buffered, shapes = self._buffered_outputs
        if buffered is None:
            return tuple(np.array(v) for v in self.nlp.outputs(w, params))
        return tuple(v.reshape(shape, order="F").copy() for v, shape in zip(buffered(w, params), shapes))

    def _node_layout(self):
        """Per module: the state indices (13, nodes) into ``w``, the nodes' arc lengths with the
        tip appended (nodes + 1,) [m] and their quadrature weights; computed once."""
        if getattr(self, "_nodes", None) is None:
            nlp = self.nlp
            self._nodes = [(nlp.state_index[m].transpose(1, 0, 2).reshape(13, -1),        # (n_int, 13, d+1)
                            np.append(nlp.node_s(m).ravel(), module.length), nlp.node_weights(m))
                           for m, module in enumerate(self.robot.modules)]
        return self._nodes

    def _assemble(self, w, params, status, search=True, balance=True):
        nlp = self.nlp
        lengths, ends, base = self._outputs_at(w, params)
        w_phys = w * nlp.scale
        module_data = []
        for m, (index, s, weights) in enumerate(self._node_layout()):
            states = np.hstack([w_phys[index], ends[:, m:m + 1]]) + nlp.state_offset[m][:, None]
            module_data.append((s, states, base[:, m], weights))
        tensions = self._tensions(w_phys, params)
        robot_params = params[:self.robot.layout.size]
        contact = {}
        if self.robot.obstacles:       # (a contact object's support is one)
            contact = {"contact_forces": w_phys[nlp.contact_index],
                       "clearance": self.clearance(w, params) if search else None,
                       "frictions": {c: (w_phys[i[0:3]], float(w_phys[i[3]])) for c, i in nlp.friction_index.items()}}
        if self.robot.bodies:
            contact["bodies"] = {"grips": [w_phys[i] for i in nlp.grip_index],
                                 "poses": [w_phys[i] for i in nlp.pose_index],
                                 "supports": {b: w_phys[i] for b, i in nlp.support_index.items()},
                                 "inertia": self._body_inertias(w, params)}
        notices = []
        if status.tolerance > self.options.tolerance:
            notices.append(PhysicsWarning("tolerance_floor", f"the max scaled residual {status.residual:.1e} met a "
                                          f"tolerance of {status.tolerance:.1e}, above solver.tolerance "
                                          f"{self.options.tolerance:.0e}: roundoff in the equations' terms on this "
                                          "mesh allows no less"))
        return build_solution(self.robot, robot_params, module_data, tensions, lengths.ravel(), status,
                              self.method, Iterate(self.method, w=np.asarray(w, float), contact=w_phys[nlp.contact_block_index]), notices=notices,
                              check_balance=balance,
                              extra_loads=self._extra_loads(w, params, module_data) if balance else None,
                              **contact)

    def _body_inertias(self, w, params):
        """Per free body its d'Alembert force and moment (none in statics)."""
        return None

    def outputs(self, w, params):
        """The :class:`~tca_casadi.solvers.outputs.StepOutputs` at scaled ``w`` and the
        parameter vector ``params``: the centrelines (nodes and tip), the actuators' tensions,
        lengths and strokes and the point loads' markers, without a Solution (no global balance,
        no warnings, no search between nodes): what a dynamic run keeps of a step and a study of
        a sample between their balance checks."""
        nlp, robot = self.nlp, self.robot
        lengths, ends, _ = self._outputs_at(w, params)
        w_phys = np.asarray(w, float) * nlp.scale
        modules = []
        for m, (index, s, weights) in enumerate(self._node_layout()):
            pose = np.hstack([w_phys[index[0:7]], ends[0:7, m:m + 1]]) + nlp.state_offset[m][0:7, None]
            modules.append(Centreline(s, pose[0:3], pose[3:7], weights))
        robot_params = params[:robot.layout.size]
        tensions, lengths = self._tensions(w_phys, params), lengths.ravel()
        references = self._reference_lengths(robot_params)
        actuators = {a.key: ActuatorState(float(tensions[k]), float(lengths[k]), float(lengths[k]) - references[k])
                     for k, a in enumerate(robot.actuators)}
        return StepOutputs(np.array(robot_params, float), modules, actuators,
                           load_markers(robot, modules, robot_params) if robot.point_loads else [], robot.tip_index,
                           parameter_names=dict(robot.layout.slices))

    def _reference_lengths(self, robot_params):
        """The actuators' reference lengths [m] at ``robot_params`` (the last set kept)."""
        key = np.asarray(robot_params, float).tobytes()
        if getattr(self, "_references", (None,))[0] != key:
            self._references = (key, [a.reference_length for a in self.robot.at(robot_params).actuators])
        return self._references[1]

    def _tensions(self, w_phys, params):
        """Every actuator's tension [N] (``robot.actuators`` order): an unknown's from the
        physical variables ``w_phys``, a prescribed one's from ``params``."""
        nlp, robot = self.nlp, self.robot
        return [w_phys[nlp.tension_index[robot.unknowns.index(a)]] if a.unknown_tension
                else params[robot.layout[a.parameter]][0] for a in robot.actuators]

    def clearance(self, w, params):
        """Per obstacle (placed at ``params``), the body's nearest approach ``{name: {gap [m],
        module, s [m]}}``: every module's gap sampled at :data:`FINE_SAMPLES` points per
        interval of its collocation polynomials, then, about each of the lowest sampled dips,
        sampled again ever more finely (a window of two sample spacings, shrunk 32 times per
        round, three rounds: to 3e-5 of a spacing), so that a dip between samples (beside a
        closed candidate) is found wherever it is."""
        out, fine = {}, self.fine_states(w)
        for shape in self.robot.at(params[:self.robot.layout.size]).obstacles + self.placed_bodies(w):
            best = {"gap": np.inf}
            for m, (s, states) in fine.items():
                module = self.robot.modules[m]
                outline = outline_of(module)
                g = gaps(shape, outline, states[0:3], states[3:7])
                dips = [j for j in range(g.size) if g[j] <= g[max(j - 1, 0)] and g[j] <= g[min(j + 1, g.size - 1)]]
                for j in sorted(dips, key=lambda j: g[j])[:4]:
                    centre, half = float(s[j]), float(np.max(np.diff(s)))
                    value = float(g[j])
                    for _ in range(3):
                        around = np.clip(np.linspace(centre - half, centre + half, 65), 0.0, module.length)
                        p, h = self._poses_at(w, m, around)
                        found = gaps(shape, outline, p, h)
                        k = int(np.argmin(found))
                        if found[k] < value:
                            value, centre = float(found[k]), float(around[k])
                        half /= 32
                    if value < best["gap"]:
                        best = {"gap": value, "module": module.name, "s": centre}
            out[shape.name] = best
        return out

    def placed_bodies(self, w):
        """The free bodies as boxes at their solved poses (:mod:`tca_casadi.model.bodies`)."""
        from ..model.bodies import body_pose, body_shape
        physical = np.asarray(w, float) * self.nlp.scale
        return [body_shape(body, *body_pose(body, physical[self.nlp.pose_index[body.index]]))
                for body in self.robot.bodies]

    def _poses_at(self, w, m, s):
        """``(p (3, n), h (4, n))`` of module m at arc lengths ``s`` (n,) (:meth:`states_at`)."""
        states = self.states_at(w, m, s)
        return states[0:3], states[3:7]

    def states_at(self, w, m, s):
        """States (13, n) of module m at arc lengths ``s`` (n,) from its collocation polynomials,
        as the nodes hold them (a point on a breakpoint from the interval after it)."""
        nlp = self.nlp
        s = np.atleast_1d(np.asarray(s, float))
        intervals = np.array(nlp.meshes[m].intervals)
        i = np.minimum(np.searchsorted(intervals[:, 1], s, side="right"), len(intervals) - 1)
        nodes = (np.asarray(w, float) * nlp.scale)[nlp.state_index[m][i]]            # (n, 13, d + 1)
        local = (s - intervals[i, 0]) / (intervals[i, 1] - intervals[i, 0])
        return np.einsum("nir,nr->in", nodes, accuracy.lagrange_basis(nlp.scheme.tau, local))

    def fine_states(self, w, per_interval=FINE_SAMPLES):
        """``{m: (s (n,), states (13, n))}``: every module's collocation polynomials sampled at
        ``per_interval`` + 1 evenly spaced points of each interval (both ends included; where
        contact is checked between nodes)."""
        tau = np.linspace(0.0, 1.0, per_interval + 1)
        out = {}
        for m in range(len(self.robot.modules)):
            steps = np.array(self.nlp.meshes[m].intervals)
            s = (steps[:, :1] + tau[None, :] * (steps[:, 1:] - steps[:, :1])).ravel()
            out[m] = (s, self.states_at(w, m, s))
        return out

    def _extra_loads(self, w, params, module_data):
        """Loads beyond the robot's own for the global balance (a dynamic step's inertia)."""
        return None

"""The square forward system ``g(w, P) = 0`` of the collocation NLP, for Newton's method.

The residual and its exact sparse Jacobian come from the Function IPOPT already uses
(``nlp_jac_g``), evaluated into preallocated numpy buffers (CasADi's buffer API), so nothing is
rebuilt and no CasADi matrix is converted at solve time. The Jacobian is factorised by SuperLU
(row pivoting keeps it stable) in one column order per structure (:class:`OrderedLU`): the
NLP's block-banded order (interval by interval, the unknowns that couple intervals last:
fill and time linear in the mesh) unless COLAMD's fill is less than half of it (a tree of
modules, whose branches the banded order puts one after the other).
"""
import time

import casadi as ca
import numpy as np

from ..buffers import BufferedFunction, CscPattern  # noqa: F401  (re-exported: the solvers' evaluation)
from ..status import SolveStatus, Status
from .linearisation import Linearisation, OrderedLU, column_order  # noqa: F401

#: what to do when the Jacobian's factorisation runs out of memory
MEMORY_ADVICE = ("lower solver.max_intervals or solver.intervals (or loosen solver.tip_tolerance and "
                 "tension_tolerance, which drive the refinement), or use a machine with more memory")


#: a chord step (the factorised Jacobian of an earlier point) is kept if it cuts |g|_2 this much
CHORD_CONTRACTION = 0.1
#: a residual entry can be computed no smaller than about a roundoff of the size of its terms
#: (``eps (|J| |w|)_i``); on fine meshes the collocation's derivative terms (~d^2/h) make that
#: floor pass 1e-10 (384 intervals: 1.5e-10), where Newton then stagnates
ROUNDOFF_FACTOR = 2
#: the same in compiled code (:mod:`.native`), where a chord step costs about 1/50 of a fresh
#: Jacobian and its factorisation: a weaker contraction pays (the steel cantilever's steps: a
#: fresh Jacobian every 12 steps instead of every 6, 30 % less time); 14 steps at most from
#: 1e-3 to 1e-10, well inside the iteration budget
NATIVE_CHORD_CONTRACTION = 0.3
#: a semismooth Newton step taken without descent moves the rods' scaled states (positions in
#: module lengths, strains) by at most this much (the forces and multipliers as far as it says)
SEMISMOOTH_STEP = 0.5
#: the predictor's central differences step this fraction of the parameter step
#: (:meth:`SquareSystem._predictor_rates`)
PREDICTOR_DIFFERENCE = 1e-4
#: semismooth Newton stops when this many iterations in a row have not brought the residual
#: below its best so far: its steps go round (contacts sticking and sliding, closing and opening
#: in turn; the caller tries a shorter step), where it used to spend all its iterations
CYCLE_ITERATIONS = 16


def roundoff_floor(J, w):
    """The smallest max |g| computable at ``w`` for a system with Jacobian ``J`` (CSC):
    :data:`ROUNDOFF_FACTOR` roundoffs of the largest row's terms, ``eps max_i (|J| |w|)_i``."""
    if J.shape[0] == 0:
        return 0.0
    return floor_of_terms(abs(J) @ np.abs(w))


def floor_of_terms(terms):
    """:func:`roundoff_floor` from each row's ``(|J| |w|)_i`` (n,)."""
    return float(ROUNDOFF_FACTOR * np.finfo(float).eps * np.max(terms)) if terms.size else 0.0
class SquareSystem:
    """``g`` and ``J_w = dg/dw`` at ``(w, P)`` for the NLP ``nlp``, from the Functions
    ``residual (w, P) -> g`` and ``jacobian (w, P) -> (g, J_w)``; ``native``: the residual and
    the chord steps as compiled code (:class:`~tca_casadi.solvers.native.NativeChord`), used for
    numeric evaluation instead; ``compile_jacobians``: the Jacobians and sensitivities compiled
    as well (:func:`~tca_casadi.solvers.compiled.compiled`, large ones unoptimised)."""

    def __init__(self, nlp, residual, jacobian, native=None, compile_jacobians=False):
        self.nlp = nlp
        self.native = native
        self._compile_jacobians = compile_jacobians
        self._residual_function = residual
        self._residual = BufferedFunction(native.residual if native is not None else residual)
        #: the rods' states (positions, rotations, strains) in ``w``: a semismooth step is capped
        #: on these only (forces and multipliers may need long steps)
        self._shape_variables = (np.concatenate([index.ravel() for index in nlp.state_index])
                                 if getattr(nlp, "state_index", None) else None)
        if compile_jacobians:
            if isinstance(jacobian, ca.Function):
                jacobian = self._fast(jacobian)
            else:
                jacobian.compile(self._fast)
        if isinstance(jacobian, ca.Function):
            self._with_jacobian = BufferedFunction(jacobian)
            self._jacobian_pattern = CscPattern(jacobian.sparsity_out(1))
        else:                                    # a StructuredJacobian: (w, P) -> (g, nonzeros)
            self._with_jacobian = jacobian
            self._jacobian_pattern = CscPattern.of(jacobian.indptr, jacobian.indices, jacobian.shape)
        self.shape = self._jacobian_pattern.shape
        self._sensitivity = None
        #: ``(P_from, P_to, tangent)`` of the last :meth:`predicted` (its error carried to the next)
        self._last_tangent = None
        self._order = None
        self.last_lu = None
        #: the roundoff floor of the residual at the last Jacobian (:func:`roundoff_floor`)
        self.floor = 0.0

    def evaluate(self, w, P):
        """``(g, J_w)``: copies of the residual (n,) and the Jacobian (CSC)."""
        g, J = self._with_jacobian(w, P)
        return g.copy(), self._jacobian_pattern.matrix(J)

    def factorise(self, J):
        """:class:`OrderedLU` of a Jacobian ``J`` (CSC) of this system, in the column order chosen
        (:func:`column_order`) at the first one."""
        from ..resources import memory_guard
        with memory_guard(f"factorising the Jacobian of {J.shape[0]} unknowns ({J.nnz} nonzeros)", MEMORY_ADVICE):
            if self._order is None:
                banded = self.nlp.banded_columns() if hasattr(self.nlp, "banded_columns") else None
                self._order = (column_order(J, banded),)
            return OrderedLU(J, self._order[0])

    def _fresh_factors(self, w, P):
        """``(OrderedLU, roundoff floor)`` of the Jacobian at ``(w, P)`` for Newton: once the
        column order is chosen, the Jacobian's nonzeros go straight into a matrix kept in that
        order (scipy's column slicing, matrix checks and ``abs`` cost 0.15 ms a Jacobian on the
        bending module, a quarter of its factorisation), and the floor is summed from them."""
        if self._order is None:
            _, J = self.evaluate(w, P)
            return self.factorise(J), roundoff_floor(J, w)
        _, values = self._with_jacobian(w, P)
        ordered, take, columns = self._ordered_jacobian()
        ordered.data[:] = values[take]
        floor = floor_of_terms(np.bincount(self._jacobian_pattern.indices, np.abs(values) * np.abs(w)[columns],
                                           minlength=self.shape[0]))
        from ..resources import memory_guard
        with memory_guard(f"factorising the Jacobian of {self.shape[0]} unknowns ({take.size} nonzeros)", MEMORY_ADVICE):
            return OrderedLU.of_ordered(ordered, self._order[0]), floor

    def _ordered_jacobian(self):
        """``(matrix, take, columns)``: a CSC matrix with the Jacobian's pattern in the chosen column
        order (its values overwritten by each fresh Jacobian: the LU keeps none of it), where
        its nonzeros come from in the Jacobian's (``values[take]``), and each of those
        nonzeros' column; built once."""
        if getattr(self, "_ordered", None) is None:
            pattern, order = self._jacobian_pattern, self._order[0]
            n = self.shape[1]
            columns = np.repeat(np.arange(n), np.diff(pattern.indptr))
            if order is None:
                take = np.arange(pattern.indices.size)
                indptr, indices = pattern.indptr, pattern.indices
            else:
                counts = np.diff(pattern.indptr)[order]
                take = np.concatenate([np.arange(pattern.indptr[j], pattern.indptr[j + 1]) for j in order]) \
                    if n else np.zeros(0, int)
                indptr, indices = np.concatenate([[0], np.cumsum(counts)]), pattern.indices[take]
            import scipy.sparse as sp
            matrix = sp.csc_matrix((np.zeros(take.size), indices, indptr), shape=self.shape)
            self._ordered = (matrix, take, columns)
        return self._ordered

    def residual(self, w, P):
        """A copy of ``g(w, P)`` (n,)."""
        return self._residual(w, P)[0].copy()

    def newton(self, w0, P, tolerance, max_iterations=25, lu=None, monotone=True):
        """Newton from ``w0`` until ``max |g| <= tolerance``. The factorised Jacobian is kept while
        steps contract the residual tenfold (a chord step costs one residual evaluation and two
        triangular solves; a weaker contraction means a long linear tail, so the Jacobian is
        refreshed instead) and the full Newton step is backtracked on ``|g|_2``. ``lu``: a
        factorised Jacobian from a nearby point to start the chord steps with (e.g. the
        linearisation of the previous point of a path). With :attr:`native` (``solver.jit``) the
        chord steps run in compiled code (:mod:`.native`), with no Python between them, kept
        while they cut the residual by :data:`NATIVE_CHORD_CONTRACTION`. ``monotone`` False: where
        no backtracked step cuts ``|g|_2``, the step is taken all the same, capped at
        :data:`SEMISMOOTH_STEP` in the rods' scaled states (semismooth Newton on complementarity: a
        contact that closes, where the residual's kink defeats the line search; the cap keeps it
        from roots far away), stopping once :data:`CYCLE_ITERATIONS` in a row leave the residual
        above its best. Returns ``(w, SolveStatus)``."""
        started = time.perf_counter()
        w, fresh = np.array(w0, float), False
        g = self.residual(w, P)
        floor = max(tolerance, self.floor)      # what roundoff allows (:func:`roundoff_floor`)

        def ended(iteration, failure=None, floored=False):
            self.last_lu = lu                      # the factors last used (a time stepper's next chord start)
            residual = float(np.max(np.abs(g))) if g.size else 0.0
            status = SolveStatus.judged("Newton", residual, floor if floored else tolerance, failure, nit=iteration,
                                        solve_time_s=time.perf_counter() - started)
            if floored:
                status = status.noted(f"tolerance floored at {floor:.1e} by roundoff (Newton stagnated there; the "
                                      f"residual's terms are {floor / (ROUNDOFF_FACTOR * np.finfo(float).eps):.1e})")
            return w, status

        before = np.inf                          # the residual before the last fresh Newton step
        iteration, best = 0, (np.inf, 0)         # the smallest residual so far and its iteration
        while True:
            residual = float(np.max(np.abs(g))) if g.size else 0.0
            if not np.isfinite(residual):
                return ended(iteration, Status.NOT_FINITE)
            if residual <= tolerance:
                return ended(iteration)
            if residual <= floor and residual > 0.5 * before:       # stagnated at the roundoff floor
                return ended(iteration, floored=True)
            if iteration >= max_iterations:
                break
            if residual < best[0]:
                best = (residual, iteration)
            elif not monotone and iteration - best[1] >= CYCLE_ITERATIONS:
                return ended(iteration, Status.CYCLING)
            if lu is not None and not fresh:
                taken = self._chord_steps(w, g, P, lu, tolerance, max_iterations - iteration)
                if taken:
                    iteration += taken
                    continue
                if residual <= floor and self.floor > tolerance:    # at the roundoff floor: no step helps
                    return ended(iteration, floored=True)
            try:
                lu, self.floor = self._fresh_factors(w, P)
                floor, fresh = max(tolerance, self.floor), True
            except RuntimeError:
                return ended(iteration, Status.SINGULAR)
            before = residual
            w, g, accepted = self._line_search(w, g, lu.solve(g), P, monotone=monotone)
            fresh = False
            iteration += 1
            if not accepted:
                floored = residual <= floor
                return ended(iteration, None if floored else Status.NO_DESCENT, floored=floored)
        return ended(max_iterations, Status.MAX_ITERATIONS)

    def _chord_steps(self, w, g, P, lu, tolerance, max_steps):
        """Chord steps with ``lu`` from ``w`` (residual ``g``; both updated in place) while each
        cuts ``|g|_2`` by :data:`CHORD_CONTRACTION`, at most ``max_steps``, stopping at
        ``tolerance``: in compiled code with :attr:`native` (cutting it by
        :data:`NATIVE_CHORD_CONTRACTION`), else one step here. Returns how
        many were taken (0: the first was rejected)."""
        if self.native is not None:
            return self.native.steps(w, g, P, lu, tolerance, NATIVE_CHORD_CONTRACTION, max_steps)[1]
        trial = w - lu.solve(g)
        g_trial = self.residual(trial, P)
        if float(g_trial @ g_trial) <= CHORD_CONTRACTION ** 2 * float(g @ g):     # not finite: rejected
            w[:], g[:] = trial, g_trial
            return 1
        return 0

    def _line_search(self, w, g, step, P, shortest=1 / 64, monotone=True):
        norm, alpha = np.linalg.norm(g), 1.0
        while alpha >= shortest:
            trial = w - alpha * step
            g_trial = self.residual(trial, P)
            if np.all(np.isfinite(g_trial)) and np.linalg.norm(g_trial) < (1 - 1e-4 * alpha) * norm:
                return trial, g_trial, True
            alpha /= 2
        if not monotone:                         # the step, capped, if its residual is a number
            shape = step[self._shape_variables] if self._shape_variables is not None else step
            longest = float(np.max(np.abs(shape))) if shape.size else 0.0
            trial = w - step * min(1.0, SEMISMOOTH_STEP / longest) if longest > 0 else w
            g_trial = self.residual(trial, P)
            if np.all(np.isfinite(g_trial)):
                return trial, g_trial, True
        return w, g, False

    # ------------------------------------------------------------------ sensitivities
    def _tip_function(self):
        """``(w, P) -> (dtip/dw, dtip/dP)`` and their patterns, built once."""
        if self._sensitivity is None:
            nlp = self.nlp
            w, P = ca.SX.sym("w", nlp.w.numel()), ca.SX.sym("P", nlp.P.numel())
            tip = nlp.outputs.expand()(w, P)[1][0:3, -1]
            function = ca.Function("tip_sensitivity", [w, P], [ca.jacobian(tip, w), ca.jacobian(tip, P)])
            self._sensitivity = (BufferedFunction(self._fast(function)),
                                 [CscPattern(function.sparsity_out(k)) for k in range(2)])
        return self._sensitivity

    def _parameter_jacobian_function(self):
        """``(function (w, P) -> (g, nonzeros of dg/dP), CscPattern)``, built once, where the
        full ``dg/dP`` is asked for."""
        if getattr(self, "_by_parameters", None) is None:
            self._by_parameters = _parameter_jacobian(self.nlp, self._residual_function, self._fast)
        return self._by_parameters

    def _fast(self, function):
        """``function`` compiled (:mod:`.compiled`; code larger than
        :data:`~tca_casadi.solvers.compiled.OPTIMISED_BYTES` unoptimised, which compiles in
        seconds instead of minutes) when the Jacobians are compiled, else itself."""
        if not self._compile_jacobians:
            return function
        from .compiled import OPTIMISED_BYTES, compiled
        return compiled(function, optimised_bytes=OPTIMISED_BYTES)

    def _tip_derivatives(self, w, P):
        """``(dtip/dw, dtip/dP)`` as scipy sparse matrices (CSC)."""
        tip, patterns = self._tip_function()
        return [pattern.matrix(v) for pattern, v in zip(patterns, tip(w, P))]

    def state_derivative(self, w, P, directions):
        """``(dw/dlam (n, k), lu)`` for ``P = P0 + lam directions`` at ``(w, P)`` (directions
        (nP, k)): ``-J_w^-1 (J_P directions)``, with ``J_P directions`` by CasADi's forward mode
        (k directional derivatives of the residual, about k residuals' cost: no full ``dg/dP``)
        and ``lu`` the factorised ``J_w`` (for the chord steps of a next solve nearby)."""
        directions = np.asarray(directions, float).reshape(len(P), -1)
        rates = self.parameter_rates(w, P, directions)
        _, J = self.evaluate(w, P)
        lu = self.factorise(J)
        return -lu.solve(rates), lu

    def parameter_rates(self, w, P, directions):
        """``J_P directions`` (n, k) at ``(w, P)`` (directions (nP, k)), by CasADi's forward
        mode: k directional derivatives of the residual, about k residuals' cost."""
        k = directions.shape[1]
        if getattr(self, "_directional", None) is None:
            self._directional = {}
        if k not in self._directional:                 # one Function per number of directions
            nlp = self.nlp
            w_sym, P_sym = ca.SX.sym("w", nlp.w.numel()), ca.SX.sym("P", nlp.P.numel())
            V = ca.SX.sym("V", nlp.P.numel(), k)
            g = self._residual_function(w_sym, P_sym)
            self._directional[k] = BufferedFunction(self._fast(ca.Function("residual_by_P", [w_sym, P_sym, V],
                                                                           [ca.jtimes(g, P_sym, V)])))
        rates = self._directional[k](w, P, np.asarray(directions, float).ravel(order="F"))[0]
        return np.ascontiguousarray(rates.reshape(-1, k, order="F"))

    def predicted(self, w, P_from, P_to, lu):
        """A start for Newton at ``P_to`` from the root ``w`` at ``P_from``: the tangent
        predictor ``w - J_w^-1 J_P (P_to - P_from)`` with ``lu`` (factors at or near ``w``; the
        error falls from O(dP) to O(dP^2)), or ``w`` itself where that has the smaller residual
        (factors too far off, a kink of a contact on the way). Where the step repeats the last
        one (the same ``dP`` from where it ended: a study's grid along one axis), the last
        tangent's error ``w - tangent`` (its ``dP^2 w'' / 2``, and the stale factors' part) is
        added as well, leaving O(dP^3), if that has the smallest residual."""
        P_from, P_to = np.asarray(P_from, float), np.asarray(P_to, float)
        step = (P_to - P_from).reshape(-1, 1)
        if lu is None or not np.any(step):
            return w
        tangent = w - lu.solve(self._predictor_rates(w, P_from, step))[:, 0]
        carried, self._last_tangent = self._tangent_error(w, P_from, step), (P_from, P_to, tangent)
        best, size = w, float(np.max(np.abs(self._residual(w, P_to)[0])))
        for start in (tangent,) if carried is None else (tangent, tangent + carried):
            g = self._residual(start, P_to)[0]
            if np.all(np.isfinite(g)) and float(np.max(np.abs(g))) < size:
                best, size = start, float(np.max(np.abs(g)))
        return best

    def _predictor_rates(self, w, P, step):
        """``J_P step`` (n, 1) for :meth:`predicted`: CasADi's forward mode, or where the residual
        is compiled and the derivatives are not (``solver.jit: auto``), central differences of
        the compiled residual over :data:`PREDICTOR_DIFFERENCE` of the step (two compiled
        residuals instead of a derivative in CasADi's virtual machine, a tenth of its time; a
        start for Newton needs no more than its 1e-8 relative accuracy)."""
        if self.native is None or self._compile_jacobians:
            return self.parameter_rates(w, P, step)
        h = PREDICTOR_DIFFERENCE * step[:, 0]
        up = self._residual(w, P + h)[0].copy()
        return ((up - self._residual(w, P - h)[0]) / (2 * PREDICTOR_DIFFERENCE)).reshape(-1, 1)

    def _tangent_error(self, w, P_from, step):
        """``w - tangent`` of the last :meth:`predicted` where it predicted ``w``'s point
        (``P_from``) by the same step, else None."""
        last = self._last_tangent
        if last is None or last[2].shape != w.shape or not np.array_equal(last[1], P_from):
            return None
        before = (last[1] - last[0]).reshape(-1, 1)
        if not np.allclose(before, step, rtol=1e-9, atol=0):
            return None
        return w - last[2]

    def parameter_jacobian(self, w, P):
        """``dg/dP`` (sparse, (n, nP)) at ``(w, P)``, in full."""
        function, pattern = self._parameter_jacobian_function()
        return pattern.matrix(function(w, P)[1])

    def linearise(self, w, P):
        """:class:`Linearisation` at ``(w, P)``: adds the tip's derivatives, and ``dg/dP`` when
        asked for: along up to :data:`~tca_casadi.solvers.linearisation.FORWARD_DIRECTIONS`
        directions by CasADi's forward mode (:meth:`parameter_rates`: a residual's cost a
        direction, where the full structured ``dg/dP`` costs as much as ``J_w``; a path's tangent
        and a sweep's sensitivities), in full for more (an inverse query's temperatures),
        evaluated once."""
        g, J_w = self.evaluate(w, P)
        T_w, T_P = self._tip_derivatives(w, P)
        w, P = np.array(w, float), np.array(P, float)
        return Linearisation(g, J_w, lambda: self.parameter_jacobian(w, P), T_w, T_P.toarray(), factorise=self.factorise,
                             rates=lambda directions: self.parameter_rates(w, P, directions))


def _parameter_jacobian(nlp, residual, fast):
    """``(function (w, P) -> (g, nonzeros of dg/dP), CscPattern)``: through the rod equations
    at one point where the NLP records them (:mod:`tca_casadi.discretisation.structure`), else
    the expanded residual's symbolic Jacobian; ``fast`` compiles a Function (or returns it)."""
    if getattr(nlp, "rod_calls", None) is not None:
        from ..discretisation.structure import StructuredJacobian
        structured = StructuredJacobian(nlp, wrt="P")
        structured.compile(fast)
        return structured, CscPattern.of(structured.indptr, structured.indices, structured.shape)
    w, P = ca.SX.sym("w", nlp.w.numel()), ca.SX.sym("P", nlp.P.numel())
    g = residual(w, P)
    function = ca.Function("parameter_jacobian", [w, P], [g, ca.jacobian(g, P)])
    return BufferedFunction(fast(function)), CscPattern(function.sparsity_out(1))

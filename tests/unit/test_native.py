"""Chord steps in compiled code (:mod:`tca_casadi.solvers.native`) against the same steps in
numpy: the same iterates, the same stopping codes, and each library calling its own residual."""
import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp
from numpy.testing import assert_allclose

from tca_casadi.solvers import native
from tca_casadi.solvers.compiled import compiler
from tca_casadi.solvers.linearisation import OrderedLU
from tca_casadi.errors import TcaError

try:
    compiler()
except TcaError:                                 # pragma: no cover - the CI machine has gcc
    pytest.skip("no C compiler", allow_module_level=True)


def system(n, name="nlp_g", shift=0.0):
    """A sparse nonlinear system ``g(w, P)``: a discrete Bratu-like chain with a cubic term,
    ``P`` its forcing (n,) and one shift."""
    w, P = ca.SX.sym("w", n), ca.SX.sym("P", n)
    g = []
    for i in range(n):
        left = w[i - 1] if i > 0 else 0
        right = w[i + 1] if i < n - 1 else 0
        g.append(2.5 * w[i] - left - right + 0.3 * w[i] ** 3 + 0.1 * ca.sin(w[(i + 7) % n]) - P[i] - shift)
    return ca.Function(name, [w, P], [ca.vertcat(*g)])


def jacobian(function, w, P):
    ws, Ps = ca.SX.sym("w", w.size), ca.SX.sym("P", P.size)
    return sp.csc_matrix(np.array(ca.Function("J", [ws, Ps], [ca.jacobian(function(ws, Ps), ws)])(w, P)))


def numpy_chord(function, w, P, lu, tolerance, contraction, max_steps):
    """The same loop as chord.c, in numpy: ``(code, steps, w, g)``."""
    w = w.copy()
    g = np.array(function(w, P)).ravel()
    steps = 0
    while True:
        r = np.max(np.abs(g))
        if not np.isfinite(r):
            return native.NOT_FINITE, steps, w, g
        if r <= tolerance:
            return native.CONVERGED, steps, w, g
        if steps >= max_steps:
            return native.STEPS_USED, steps, w, g
        trial = w - lu.solve(g)
        g_trial = np.array(function(trial, P)).ravel()
        if not g_trial @ g_trial <= contraction ** 2 * (g @ g):
            return native.REJECTED, steps, w, g
        w, g = trial, g_trial
        steps += 1


@pytest.mark.parametrize("ordered", [False, True])
@pytest.mark.parametrize("contraction, max_steps", [(0.3, 50), (0.1, 50), (0.5, 3)])
def test_the_compiled_steps_are_numpys_steps(tmp_path, ordered, contraction, max_steps):
    n = 40
    rng = np.random.default_rng(1)
    function = system(n)
    chord = native.NativeChord(function, directory=tmp_path)
    P = rng.uniform(-1, 1, n)
    start = rng.uniform(-0.2, 0.2, n)
    order = rng.permutation(n) if ordered else None
    lu = OrderedLU(jacobian(function, start + 0.05, P), order)        # factorised at a nearby point
    expected_code, expected_steps, expected_w, expected_g = numpy_chord(function, start, P, lu, 1e-12,
                                                                        contraction, max_steps)
    w, g = start.copy(), np.array(function(start, P)).ravel()
    code, steps = chord.steps(w, g, P, lu, 1e-12, contraction, max_steps)
    assert (code, steps) == (expected_code, expected_steps) and steps > 0
    assert_allclose(w, expected_w, rtol=0, atol=1e-13)
    assert_allclose(g, expected_g, rtol=0, atol=1e-13)
    assert_allclose(chord.residual(w, P).full().ravel(), g, rtol=0, atol=1e-15)


def test_a_rejected_or_not_finite_step_leaves_the_point(tmp_path):
    n = 20
    function = system(n)
    chord = native.NativeChord(function, directory=tmp_path)
    P = np.linspace(-1, 1, n)
    far = OrderedLU(jacobian(function, np.full(n, 5.0), P))          # the Jacobian of a far point
    w = np.zeros(n)
    g = np.array(function(w, P)).ravel()
    code, steps = chord.steps(w, g, P, far, 1e-12, 0.01, 10)
    assert (code, steps) == (native.REJECTED, 0)
    assert_allclose(w, 0.0, rtol=0, atol=0) and np.all(np.isfinite(g))
    g[3] = np.nan
    assert chord.steps(w, g, P, far, 1e-12, 0.3, 10) == (native.NOT_FINITE, 0)


def test_each_library_calls_its_own_residual(tmp_path):
    """Two systems whose residuals share a C name (every NLP's is ``nlp_g``), loaded in one
    process: each library's chord steps converge on its own system's root."""
    n = 12
    P = np.zeros(n)
    roots = []
    for shift in (0.0, 0.5):
        function = system(n, shift=shift)
        chord = native.NativeChord(function, directory=tmp_path / f"shift{shift}")
        w = np.zeros(n)
        g = np.array(function(w, P)).ravel()
        lu = OrderedLU(jacobian(function, w, P))
        for _ in range(5):                       # refresh the Jacobian until the chord converges
            code, _ = chord.steps(w, g, P, lu, 1e-13, 0.3, 50)
            if code == native.CONVERGED:
                break
            lu = OrderedLU(jacobian(function, w, P))
        assert code == native.CONVERGED
        assert np.max(np.abs(np.array(function(w, P)).ravel())) <= 1e-13
        roots.append(w)
    assert np.max(np.abs(roots[0] - roots[1])) > 0.05

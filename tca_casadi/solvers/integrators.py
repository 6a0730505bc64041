"""The implicit integrators of the rod dynamics (:class:`~tca_casadi.solvers.dynamics.RodDynamics`).

The dynamic NLP's time derivatives are ``x_t = c0 x + x_hist`` for the strain deviations and the
velocities ``x = [xi - xi*, q, w]`` (12, nodes) of every module at every node: an integrator is a
choice of ``c0`` and of the history from the previous steps' node values, of where in the step its
unknown sits and of how the step's end follows from it (step ``h``):

* :class:`ImplicitEuler` (``bdf1``, order 1): ``c0 = 1/h``, ``x_hist = -x_n / h``;
* :class:`BDF2` (order 2, L-stable: damps what the step cannot resolve), with variable steps
  (ratio ``r = h / h_prev``): ``x_t = [(1 + 2r)/(1 + r) x_{n+1} - (1 + r) x_n + r^2/(1 + r)
  x_{n-1}] / h``; its first step is implicit Euler's;
* :class:`ImplicitMidpoint` (``midpoint``, order 2, symplectic: no numerical damping; for
  checking): the unknown is the midpoint state ``z = x_{n+1/2}``, solved at the mean of the two
  ends' parameters with ``c0 = 2/h``, ``x_hist = -2 x_n / h`` (so ``x_t = (x_{n+1} - x_n)/h``),
  and ``x_{n+1} = 2 z - x_n``.
"""
import numpy as np

from ..errors import ScenarioError


class Integrator:
    """One implicit integrator (module docstring)."""
    #: its name in ``dynamics.integrator``
    name = ""
    #: where in the step its unknown sits, as a fraction of the step (1: the end)
    fraction = 1.0

    @property
    def at_midpoint(self):
        """Whether the unknown is the state in the middle of the step (not its end)."""
        return self.fraction != 1.0

    def first(self):
        """The integrator of a run's first step (one with no step before it)."""
        return self

    def weights(self, h, h_before=None):
        """``(c0, a, b)`` [1/s] of a step ``h`` [s] (after one ``h_before`` long, for a two-step
        rule): ``x_t = c0 x + a x_now + b x_before``, so the history is ``a x_now + b x_before``."""
        raise NotImplementedError

    def coefficients(self, h, now, before=None, h_before=None):
        """``(c0, histories)`` of a step ``h`` [s] from the node values ``now`` (per module,
        (12, nodes)) and, for a two-step rule, ``before`` (the step before, ``h_before`` long)."""
        c0, a, b = self.weights(h, h_before)
        if b == 0.0:
            return c0, [a * x for x in now]
        return c0, [a * x + b * y for x, y in zip(now, before)]

    def parameters_at(self, params, previous):
        """The parameter vector the step is solved at, from the step's end ``params`` and its
        start ``previous``."""
        return params

    def end(self, w, w_now):
        """The step's end state from the solved variables ``w`` and the start's ``w_now``."""
        return w


class ImplicitEuler(Integrator):
    name = "bdf1"

    def weights(self, h, h_before=None):
        return 1.0 / h, -1.0 / h, 0.0


class BDF2(Integrator):
    name = "bdf2"

    def first(self):
        return ImplicitEuler()

    def weights(self, h, h_before=None):
        r = h / h_before
        return (1.0 + 2.0 * r) / ((1.0 + r) * h), -(1.0 + r) / h, r ** 2 / ((1.0 + r) * h)


class ImplicitMidpoint(Integrator):
    name = "midpoint"
    fraction = 0.5

    def weights(self, h, h_before=None):
        return 2.0 / h, -2.0 / h, 0.0

    def parameters_at(self, params, previous):
        return 0.5 * (np.asarray(params, float) + np.asarray(previous, float))

    def end(self, w, w_now):
        return 2.0 * w - w_now


#: every integrator by name
INTEGRATORS = {kind.name: kind for kind in (BDF2, ImplicitMidpoint, ImplicitEuler)}


def integrator_named(name):
    """The :class:`Integrator` called ``name`` (``bdf2``, ``midpoint``, ``bdf1``)."""
    if name not in INTEGRATORS:
        raise ScenarioError(f"dynamics.integrator: {name!r} is not one of {', '.join(INTEGRATORS)}")
    return INTEGRATORS[name]()

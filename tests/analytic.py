"""Analytic and independent reference solutions used by the tests (one shared module)."""
import math

from scipy.integrate import quad
from scipy.optimize import brentq

#: Mattiasson (1981), Int. J. Numer. Meth. Eng. 17: inextensible cantilever, transverse tip load,
#: ``alpha = P L^2 / EI`` -> (vertical tip deflection / L, horizontal shortening / L)
ELASTICA_TABLE = {1.0: (0.30172, 0.05643), 2.0: (0.49346, 0.16064),
                  5.0: (0.71379, 0.38763), 10.0: (0.81061, 0.55500)}


def elastica_tip(alpha):
    """Tip of an inextensible cantilever (length 1) under a transverse tip load ``alpha = PL^2/EI``.

    With theta the tangent angle, ``theta'^2 = 2 alpha (sin theta0 - sin theta)``; the tip angle
    theta0 solves ``sqrt(2 alpha) = int_0^theta0 dtheta / sqrt(sin theta0 - sin theta)``.
    Returns ``(deflection, shortening, theta0)``, each per unit length.
    """
    def length_integral(theta0):
        # substitute sin(theta) = sin(theta0) (1 - t^2): removes the endpoint singularity
        s0 = math.sin(theta0)

        def integrand(t):
            sin_t = s0 * (1.0 - t * t)
            return 2.0 * math.sqrt(s0) / math.sqrt(1.0 - sin_t**2)
        return quad(integrand, 0.0, 1.0, epsabs=1e-13, epsrel=1e-12, limit=200)[0]

    theta0 = brentq(lambda th: length_integral(th) - math.sqrt(2.0 * alpha), 1e-6, 1.55,
                    xtol=1e-15)
    s0 = math.sin(theta0)

    def deflection_integrand(t):
        sin_t = s0 * (1.0 - t * t)
        return sin_t * 2.0 * math.sqrt(s0) / math.sqrt(1.0 - sin_t**2)
    deflection = quad(deflection_integrand, 0.0, 1.0, epsabs=1e-13, epsrel=1e-12, limit=200)[0]
    deflection /= math.sqrt(2.0 * alpha)
    horizontal = math.sqrt(2.0 * s0 / alpha)
    return deflection, 1.0 - horizontal, theta0


def cantilever_deflection(force, length, ei, ga):
    """Small-deflection tip deflection with shear: ``P L^3 / (3 EI) + P L / (G A)`` [m]."""
    return force * length**3 / (3.0 * ei) + force * length / ga


def tendon_arc(tension, offset, ei, ea):
    """Straight tendon at constant ``offset`` with ``tension`` over the whole rod (no gravity):
    exact equilibrium ``u = F r / EI``, ``v3 = 1 - F / EA``, ``n = -F e3``. Returns (u, v3)."""
    return tension * offset / ei, 1.0 - tension / ea


def beam_scenario(length=0.1, diameter=0.005, youngs=1e6, intervals=12, degree=4, loads=(),
                  actuators=(), scheme="legendre", gravity=(0, 0, 0), tolerance=1e-12, **module):
    """A one-module straight rod along +z from the origin, as a scenario dict."""
    return {"name": "beam", "gravity": list(gravity),
            "materials": {"m": {"youngs_modulus": youngs, "poisson_ratio": 0.5, "density": 1000.0}},
            "modules": [dict({"name": "rod", "length": length, "material": "m",
                              "cross_section": {"shape": "circle", "diameter": diameter},
                              "actuators": list(actuators)}, **module)],
            "loads": list(loads),
            "solver": {"intervals": intervals, "degree": degree, "scheme": scheme, "tolerance": tolerance}}


if __name__ == "__main__":
    for a, (dv, dh) in ELASTICA_TABLE.items():
        print(a, elastica_tip(a), dv, dh)

"""A shape-memory-alloy (NiTi) wire: Liang and Rogers' one-dimensional cosine model.

The wire's martensite fraction ``xi`` follows the temperature ``T`` and the stress
``sigma = F / A`` (``A = pi d^2 / 4``) along one branch of the transformation (Liang and Rogers,
J. Intell. Mater. Syst. Struct. 1 (1990) 207-234, with full transformations, ``xi_M = 1`` at the
start of heating and ``xi_A = 0`` at the start of cooling)::

    heating (M -> A):  xi = (1 + cos(pi clip((T - A_s - sigma / C_A) / (A_f - A_s), 0, 1))) / 2
    cooling (A -> M):  xi = (1 + cos(pi clip((T - M_f - sigma / C_M) / (M_s - M_f), 0, 1))) / 2

(the clamp at 0 and 1 is C1: the cosine is flat there). The wire's constitutive law, with its
strain ``eps`` measured from the austenite (parent) length ``L_A`` and a recoverable
(transformation) strain ``eps_L xi`` (Brinson's form of the Liang-Rogers law)::

    sigma = E(xi) (eps - eps_L xi),    E(xi) = E_A + xi (E_M - E_A).

The wire lies along its path; in the reference shape at ``reference_temperature`` it is stress
free, so it was installed detwinned by ``eps_0 = eps_L xi(T_ref, 0)``: ``L_A = l* / (1 + eps_0)``
and ``eps = (l* + delta) / L_A - 1``. The residual, in newtons, ``r = A E(xi) (eps - eps_L xi) - F``,
is zero on the law and positive when the path is longer than the free wire.

Hysteresis: a static solve cannot know the history, so the type names its ``branch`` (heating,
the default: the wire was cold and is being heated; or cooling: it was fully austenitic and is
cooling). Inside a transformation the two branches differ by the hysteresis (about
``A_s - M_s``); a time run keeps the type's branch throughout (a heat-then-cool cycle is two runs).

Defaults: a Flexinol-type 70 degC NiTi wire, 0.15 mm across (Dynalloy, "Technical
Characteristics of Flexinol Actuator Wires": E_A 83 GPa, E_M 28 GPa, A_s 68, A_f 78, M_s 52,
M_f 42 degC, density 6450 kg/m^3, specific heat 837 J/(kg K), resistivity 80 micro-ohm cm,
recommended recoverable strain up to 4 %, safe stress 172 MPa); the stress-influence
coefficients C_M = 8 MPa/K and C_A = 13.8 MPa/K are Liang and Rogers' (1990).
"""
from dataclasses import dataclass
import math

from ..arith import clip, cos
from ..thermal import ThermalLaw, conductance, heat_capacity
from ...catalogue.sma import Sma
from .base import HeatedLaw, compression_warnings


@dataclass(frozen=True)
class SmaLaw(Sma, HeatedLaw):
    """One NiTi wire (SI, degC). Its type lives in ``muscle_types`` with ``kind: sma``."""
    reference_length: float
    wire_diameter: float = 0.15e-3
    E_A: float = 83e9
    E_M: float = 28e9
    A_s: float = 68.0
    A_f: float = 78.0
    M_s: float = 52.0
    M_f: float = 42.0
    C_A: float = 13.8e6
    C_M: float = 8.0e6
    max_recoverable_strain: float = 0.04
    reference_temperature: float = 25.0
    branch: str = "heating"
    min_temperature: float = 0.0
    max_temperature: float = 150.0
    max_stress: float = 172e6
    resistivity: float = 80e-8
    resistance: object = None

    def structural_problems(self, key):
        out = super().structural_problems(key)
        for low, high in (("M_f", "M_s"), ("A_s", "A_f"), ("M_f", "A_s"), ("M_s", "A_f")):
            if not float(getattr(self, low)) < float(getattr(self, high)):
                out.append(f"{key}: transformation temperatures out of order ({low} must be below {high})")
        return out

    # ------------------------------------------------------------------ the law
    @property
    def area(self):
        """Wire cross-section ``pi d^2 / 4`` [m^2]."""
        return math.pi * self.wire_diameter ** 2 / 4.0

    def martensite_fraction(self, temperature, stress):
        """``xi(T, sigma)`` on the type's branch (module docstring); numbers or symbols."""
        if self.branch == "heating":
            start, finish, influence = self.A_s, self.A_f, self.C_A
        else:
            start, finish, influence = self.M_f, self.M_s, self.C_M
        phase = clip((temperature - start - stress / influence) / (finish - start), 0.0, 1.0)
        return 0.5 * (1.0 + cos(math.pi * phase))

    def modulus(self, fraction):
        """``E(xi) = E_A + xi (E_M - E_A)`` [Pa]."""
        return self.E_A + fraction * (self.E_M - self.E_A)

    @property
    def installed_strain(self):
        """``eps_0 = eps_L xi(T_ref, 0)``: the wire's strain in the reference shape."""
        return self.max_recoverable_strain * self.martensite_fraction(self.reference_temperature, 0.0)

    def strain(self, stroke):
        """``eps = (l* + delta) / L_A - 1`` with ``L_A = l* / (1 + eps_0)``."""
        return (1.0 + self.installed_strain) * (1.0 + stroke / self.reference_length) - 1.0

    def residual(self, stroke, force, temperature):
        """``A E(xi) (eps - eps_L xi) - F`` [N], ``xi = xi(T, F / A)``."""
        fraction = self.martensite_fraction(temperature, force / self.area)
        return (self.area * self.modulus(fraction) * (self.strain(stroke) - self.max_recoverable_strain * fraction)
                - force)

    @property
    def residual_scale(self):
        """``A E_M eps_L`` [N]: the force of stretching a martensitic wire by its recoverable strain."""
        return self.area * self.E_M * self.max_recoverable_strain

    def free_stroke(self, temperature):
        """Stroke [m] of the unloaded wire: ``L_A (1 + eps_L xi(T, 0)) - l*``."""
        fraction = self.martensite_fraction(temperature, 0.0)
        austenite_length = self.reference_length / (1.0 + self.installed_strain)
        return float(austenite_length * (1.0 + self.max_recoverable_strain * fraction) - self.reference_length)

    # ------------------------------------------------------------------ range and warnings

    def warnings(self, key, stroke, force, value, tension_only):
        out = compression_warnings(key, force, tension_only, "a wire cannot push; set tension_only: true")
        stress = force / self.area
        if stress > self.max_stress:
            out.append(("stress", f"{key} stress {stress / 1e6:.4g} MPa is above the wire's max_stress "
                        f"({self.max_stress / 1e6:.4g} MPa)"))
        return out



def thermal_law(config, law):
    """The lumped :class:`~tca_casadi.model.thermal.ThermalLaw` of a wire of type ``config``
    along its path (length ``l*``): ``C = rho c A l*``, ``G = h area_factor pi d l*``,
    ``R = rho_e l* / A`` (the phase's few-percent change of resistivity and the latent heat of
    the transformation are neglected)."""
    thermal, length, radius = config.thermal, law.reference_length, law.wire_diameter / 2
    C = thermal.heat_capacity or heat_capacity(radius, length, thermal.density, thermal.specific_heat)
    G = thermal.conductance or conductance(radius, length, thermal.convection_coefficient, thermal.area_factor)
    resistance = config.resistance or config.resistivity * length / law.area
    return ThermalLaw(C, G, resistance, 0.0, law.reference_temperature)


LAW = SmaLaw

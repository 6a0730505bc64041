"""Shape-memory-alloy wires (Liang and Rogers), declared: their types live in ``muscle_types`` with
``kind: sma``; the law is :mod:`tca_casadi.model.laws.sma`."""
from typing import Literal

from .base import Heated, LawParameter


class Sma(Heated):
    """One NiTi wire (SI, degC). Its type lives in ``muscle_types`` with ``kind: sma``."""
    KIND = "sma"
    REST_INPUT = "reference_temperature"
    PARAMETERS = (
        LawParameter("wire_diameter", "length", 0.15e-3, "wire diameter d [m]"),
        LawParameter("E_A", "pressure", 83e9, "austenite Young's modulus [Pa]"),
        LawParameter("E_M", "pressure", 28e9, "martensite Young's modulus [Pa]"),
        LawParameter("A_s", "temperature", 68.0, "austenite start temperature [degC]", positive=False),
        LawParameter("A_f", "temperature", 78.0, "austenite finish temperature [degC]", positive=False),
        LawParameter("M_s", "temperature", 52.0, "martensite start temperature [degC]", positive=False),
        LawParameter("M_f", "temperature", 42.0, "martensite finish temperature [degC]", positive=False),
        LawParameter("C_A", "pressure_per_kelvin", 13.8e6, "stress influence on A_s, A_f [Pa/K]"),
        LawParameter("C_M", "pressure_per_kelvin", 8.0e6, "stress influence on M_s, M_f [Pa/K]"),
        LawParameter("max_recoverable_strain", "dimensionless", 0.04, "eps_L, the transformation strain"),
        LawParameter("reference_temperature", "temperature", 25.0,
                     "where the wire is stress free in the reference shape [degC]", positive=False),
    )
    OPTIONS = {"branch": (Literal["heating", "cooling"], "heating"),
               "min_temperature": ("temperature", 0.0), "max_temperature": ("temperature", 150.0),
               "max_stress": ("pressure", 172e6),
               "resistivity": ("resistivity", 80e-8), "resistance": ("resistance", None)}
    #: the thermal model's keys (``simulate`` only): ``thermal`` (NiTi defaults), and the
    #: electrical ``resistivity`` [ohm m] or the wire's ``resistance`` [ohm]
    THERMAL_KEYS = ("thermal", "resistivity", "resistance")
    THERMAL_DEFAULTS = {"density": 6450.0, "specific_heat": 837.0, "convection_coefficient": 25.0}

    # ------------------------------------------------------------------ checks
    @classmethod
    def validate_type(cls, config):
        for low, high in (("M_f", "M_s"), ("A_s", "A_f"), ("M_f", "A_s"), ("M_s", "A_f")):
            if not getattr(config, low) < getattr(config, high):
                raise ValueError(f"transformation temperatures out of order: need {low} < {high} "
                                 f"(got {getattr(config, low):g} and {getattr(config, high):g} degC)")
        if not config.max_recoverable_strain < 1:
            raise ValueError(f"max_recoverable_strain {config.max_recoverable_strain:g} must be below 1")
        if not config.min_temperature <= config.reference_temperature < config.max_temperature:
            raise ValueError("need min_temperature <= reference_temperature < max_temperature")


DECLARATION = Sma

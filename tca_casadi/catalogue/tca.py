"""The twisted-and-coiled actuator (SPEC section 3), declared: its types live in ``tca_types``
(their keys, units and checks are the schema's ``TcaType``); the law is
:mod:`tca_casadi.model.laws.tca`."""
from .base import Heated

#: a TCA type's NLP parameters: key -> unit kind (``fiber_length`` only when the scenario gives it)
TCA_KEYS = {"fiber_radius": "length", "coil_radius": "length", "pitch_angle": "angle",
            "fiber_length": "length", "reference_temperature": "temperature",
            "untwist.c2": "untwist_c2", "untwist.c1": "untwist_c1", "untwist.c0": "untwist_c0",
            "shear_modulus.a2": "pressure_per_force2", "shear_modulus.a1": "pressure_per_force",
            "shear_modulus.a0": "pressure"}


class Tca(Heated):
    """A TCA: tension unknown, fixed by its law at its temperature."""
    KIND = "tca"
    NAME = "TCA"
    TYPES_KEY = "tca_types"
    REST_INPUT = "reference_temperature"
    #: the keys only the thermal model (``simulate``) reads
    THERMAL_KEYS = ("thermal", "resistance", "resistance_temperature_coefficient")

    @classmethod
    def parameter_entries(cls, config):
        out = []
        for key, kind in TCA_KEYS.items():
            value = config
            for part in key.split("."):
                value = getattr(value, part)
            out.append((key, kind, value))
        return out

    @classmethod
    def input_problem_of(cls, config, value, type_path):
        for bound, beyond, word in (("max_temperature", value > config.max_temperature, "above"),
                                    ("min_temperature", value < config.min_temperature, "below")):
            if beyond:
                return (f"{value:g} degC is {word} the TCA type's {bound} ({getattr(config, bound):g} degC), the "
                        f"range its law is validated for; to go there, set {type_path}.{bound}")
        return None


DECLARATION = Tca

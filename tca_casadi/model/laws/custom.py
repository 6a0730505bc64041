"""A user's own actuator law, given by a Python entry point (never by scenario text).

``muscle_types.NAME: {kind: custom, entry_point: "package.module:function", parameters: {...}}``
names a function that builds the residual from named CasADi symbols::

    def my_law(stroke, force, input, reference_length, **parameters):
        return ...   # a scalar CasADi expression r(delta, F, u)

``stroke`` [m], ``force`` [N], ``input`` (the actuator's ``input:``, SI), ``reference_length``
``l*`` [m] and one symbol per key of ``parameters`` (each an NLP parameter,
``muscle_types.NAME.parameters.KEY``, so sweeps, studies and fits reach them). The expression
must be zero on the law and positive when the path is longer than the free actuator at that
tension; ``scale`` (default 1) is its natural size. The function is called once per robot
build; the module is imported from the Python path or, failing that, from ``folder`` (default,
and relative to, the scenario file's folder; the loader writes it down absolute, so the law is
found wherever the scenario travels as a mapping).
"""
from dataclasses import dataclass, field
import math

from ...catalogue.custom import Custom, residual_function
from .base import ActuatorLaw


@dataclass(frozen=True)
class CustomLaw(Custom, ActuatorLaw):
    """A law from an entry point; ``function`` is the CasADi Function
    ``(stroke, force, input, l*, p_1..p_k) -> r`` built from it."""
    reference_length: float
    entry_point: str = ""
    parameters: dict = field(default_factory=dict)
    scale: float = 1.0
    min_input: float = -math.inf
    max_input: float = math.inf
    function: object = None
    folder: object = None

    @classmethod
    def from_type(cls, config, reference_length, **context):
        function = residual_function(config.entry_point, tuple(config.parameters), config.folder)
        return cls(reference_length, config.entry_point, dict(config.parameters), config.scale,
                   config.min_input, config.max_input, function, config.folder)

    def with_parameters(self, param, prefix, reference_length):
        values = {key: param(f"{prefix}parameters.{key}")[0] for key in self.parameters}
        return CustomLaw(reference_length, self.entry_point, values, self.scale, self.min_input,
                         self.max_input, self.function, self.folder)

    def structural_problems(self, key):
        return []

    def residual(self, stroke, force, value):
        out = self.function(stroke, force, value, self.reference_length, *self.parameters.values())
        return float(out) if all(isinstance(v, (int, float)) for v in
                                 (stroke, force, value, *self.parameters.values())) else out

    @property
    def residual_scale(self):
        return self.scale

    def free_stroke(self, value):
        """The stroke where ``r(delta, 0, u) = 0``, found by Newton from ``delta = 0`` (None if
        it does not converge)."""
        import casadi as ca
        delta = ca.SX.sym("delta")
        r = self.function(delta, 0.0, value, self.reference_length, *self.parameters.values())
        if not ca.depends_on(r, delta):
            return None
        try:
            solver = ca.rootfinder("free", "newton", ca.Function("r", [delta], [r]),
                                   {"error_on_fail": False, "abstol": 1e-14 * self.scale})
            stroke = float(solver(0.0))
        except RuntimeError:          # singular where it starts: no free stroke found
            return None
        return stroke if abs(float(self.residual(stroke, 0.0, value))) < 1e-9 * self.scale else None

    @property
    def input_range(self):
        return (self.min_input, self.max_input)


LAW = CustomLaw

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
import functools
import importlib
import math
import sys

from ...catalogue.custom import Custom
from .base import ActuatorLaw


class EntryPointError(ValueError):
    """The entry point cannot be imported or does not build a scalar CasADi expression."""


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



@functools.lru_cache(maxsize=32)
def residual_function(entry_point, parameter_names, folder=None):
    """The CasADi Function ``(stroke, force, input, l*, *parameters) -> r`` of an entry point
    (``EntryPointError`` with a one-line reason when it cannot be made)."""
    import casadi as ca
    function = load_entry_point(entry_point, folder)
    symbols = [ca.SX.sym(name) for name in ("stroke", "force", "input", "reference_length")]
    values = {name: ca.SX.sym(name) for name in parameter_names}
    try:
        out = function(*symbols, **values)
    except Exception as error:           # the user's code: any failure is a bad entry point
        raise EntryPointError(f"{entry_point} failed when called with CasADi symbols: "
                              f"{type(error).__name__}: {error}") from None
    if isinstance(out, (int, float)):
        out = ca.SX(out)
    if not isinstance(out, (ca.SX, ca.MX, ca.DM)):
        raise EntryPointError(f"{entry_point} returned {type(out).__name__}, not a CasADi expression "
                              "(build it with casadi operations on the arguments)")
    if out.shape != (1, 1):
        raise EntryPointError(f"{entry_point} returned shape {out.shape}, expected a scalar (1, 1)")
    try:
        return ca.Function("custom_law", symbols + list(values.values()), [ca.SX(out)])
    except Exception as error:
        raise EntryPointError(f"{entry_point}: {error}".splitlines()[0]) from None


def load_entry_point(entry_point, folder=None):
    """The function ``module:function`` names, imported from the Python path or ``folder``."""
    module_name, _, name = entry_point.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if folder is None or error.name != module_name.split(".")[0]:
            raise EntryPointError(f"cannot import {module_name!r}: {error}") from None
        sys.path.insert(0, str(folder))
        try:
            module = importlib.import_module(module_name)
        except ImportError as inner:
            raise EntryPointError(f"cannot import {module_name!r} (looked on the Python path and in "
                                  f"{folder}): {inner}") from None
        finally:
            sys.path.remove(str(folder))
    except Exception as error:
        raise EntryPointError(f"cannot import {module_name!r}: {type(error).__name__}: {error}") from None
    function = getattr(module, name, None)
    if not callable(function):
        raise EntryPointError(f"module {module_name!r} has no function {name!r}")
    return function


LAW = CustomLaw

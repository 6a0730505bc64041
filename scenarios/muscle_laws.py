"""User-defined actuator laws for ``muscle_types`` entries of ``kind: custom`` (see the README,
"Other muscles"). Each function gets CasADi symbols and returns the residual ``r(delta, F, u)``:
zero on the law, positive when the path is longer than the free actuator at that tension."""


def linear_muscle(stroke, force, input, reference_length, stiffness, gain):
    """A linear muscle whose rest length shrinks with its input: ``F = k (l - l* (1 - g u))``,
    i.e. ``r = k (delta + g u l*) - F`` [N] (``k`` [N/m], ``g`` per unit of input)."""
    return stiffness * (stroke + gain * input * reference_length) - force

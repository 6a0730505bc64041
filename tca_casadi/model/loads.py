"""Distributed loads on a module and where actuators run, written once for both solvers (the
collocation NLP evaluates them per interval, the shooting solver per integration segment).

``param(name)`` gives a parameter's value, as numbers or CasADi symbols alike."""


def is_active(actuator, s_mid):
    """True if the actuator runs through the interval or segment whose midpoint is ``s_mid``."""
    return actuator.route.span[0] < s_mid < actuator.route.span[1]


def distributed_fields(robot, m, s_mid, param):
    """``[f_glob, l_glob, f_body, l_body]`` (3 each, per unit reference length) on module m over
    the interval or segment whose midpoint is ``s_mid``: the self-weight ``rho A g`` in the global
    force, plus every distributed load whose span contains it, in its frame."""
    module, gravity = robot.modules[m], param("gravity")
    zero = 0.0 * gravity
    fields = [module.weight_density_of(param) * gravity, zero, zero, zero]
    for load in robot.distributed_loads:
        if load.module == m and load.span[0] < s_mid < load.span[1]:
            first = 0 if load.frame == "global" else 2
            fields[first] = fields[first] + param(f"{load.name}.force")
            fields[first + 1] = fields[first + 1] + param(f"{load.name}.moment")
    return fields

"""The rod equations of one module as CasADi Functions (SPEC sections 2 and 3), shared by the
collocation and shooting solvers.

State ``x = [p (3), h (4), u - u* (3), v - v* (3)]``: global position, non-unit quaternion and the
body strains as deviations from the reference strains ``xi* = [u*, v*]`` (the internal wrench is
``K (xi - xi*)``: computing it from the deviation keeps stiff axial/shear terms free of roundoff).
Actuator route data per actuator: ``[r, r', r'']`` (9 values, body frame, per metre of s).
"""
import casadi as ca

from .rotations import omega, rotation_matrix

STATE_SIZE = 13


def path_tangent(u, v, du, dv, r, dr, ddr):
    """``a = R^T p_a'``, ``|a|`` and ``q = R^T t_a'`` of a path at body offset r (SPEC section 3)."""
    a = v + ca.cross(u, r) + dr
    speed = ca.norm_2(a)
    t = a / speed
    a_dot = ca.cross(u, a) + dv + ca.cross(du, r) + ca.cross(u, dr) + ddr
    q = (a_dot - t * ca.dot(t, a_dot)) / speed
    return t, speed, q


def rod_equations(xi_star, n_actuators, viscous=False):
    """Function ``(x, dxi, routes, F, K, f_glob, l_glob, f_body, l_body) -> (kin, eq, speed)``
    (``viscous``: two more inputs, ``W_v`` and ``dW_v``, below).

    ``x`` is the deviation state (module docstring). ``kin`` (7): ``[p', h']``; ``eq`` (6): the residual of equilibrium in the body frame,
    ``[m' + u x m + v x n + l ; n' + u x n + f]`` [N, N/m], which is linear in ``dxi``;
    ``speed`` (n_actuators): ``|a|`` of each route. ``F`` are the tensions [N] (zero for actuators
    not present at this s); ``K`` the diagonal of the stiffness (6,) [N m^2, N] (a parameter:
    it follows the material's moduli); ``f_glob``/``l_glob`` are distributed loads per unit length
    in the global frame (self-weight included), ``f_body``/``l_body`` in the body frame.
    ``xi_star`` are the reference strains (6,), constant along the module (structure).
    ``viscous``: the internal wrench is ``K (xi - xi*) + W_v`` with a viscous part ``W_v`` (6,)
    (Kelvin-Voigt: ``B xi_t``) whose derivative along s is the input ``dW_v`` (6,).
    """
    x = ca.SX.sym("x", STATE_SIZE)
    dxi = ca.SX.sym("dxi", 6)
    routes = ca.SX.sym("routes", 9, n_actuators)
    tension = ca.SX.sym("F", n_actuators)
    k = ca.SX.sym("K", 6)
    loads = [ca.SX.sym(name, 3) for name in ("f_glob", "l_glob", "f_body", "l_body")]
    h = x[3:7]
    u, v = x[7:10] + ca.DM(xi_star[0:3]), x[10:13] + ca.DM(xi_star[3:6])
    du, dv = dxi[0:3], dxi[3:6]
    R = rotation_matrix(h)
    extra = [ca.SX.sym("W_v", 6), ca.SX.sym("dW_v", 6)] if viscous else [ca.SX.zeros(6), ca.SX.zeros(6)]
    m = k[0:3] * x[7:10] + extra[0][0:3]
    n = k[3:6] * x[10:13] + extra[0][3:6]
    f = R.T @ loads[0] + loads[2]
    l = R.T @ loads[1] + loads[3]
    speeds = []
    for i in range(n_actuators):
        r, dr, ddr = routes[0:3, i], routes[3:6, i], routes[6:9, i]
        _, speed, q = path_tangent(u, v, du, dv, r, dr, ddr)
        f += tension[i] * q
        l += ca.cross(r, tension[i] * q)
        speeds.append(speed)
    eq_m = k[0:3] * du + extra[1][0:3] + ca.cross(u, m) + ca.cross(v, n) + l
    eq_n = k[3:6] * dv + extra[1][3:6] + ca.cross(u, n) + f
    kin = ca.vertcat(R @ v, 0.5 * omega(u) @ h)
    speed = ca.vertcat(*speeds) if speeds else ca.SX(0, 1)
    names = ["x", "dxi", "routes", "F", "K", "f_glob", "l_glob", "f_body", "l_body"] + (["W_v", "dW_v"] if viscous else [])
    return ca.Function("rod_equations", [x, dxi, routes, tension, k] + loads + (extra if viscous else []),
                       [kin, ca.vertcat(eq_m, eq_n), speed], names, ["kin", "eq", "speed"])


def explicit_strain_rate(equations):
    """Function ``(x, routes, F, loads...) -> dxi`` solving the (linear in dxi) equilibrium
    ``eq(dxi) = 0`` for ``dxi``: paper eq. (25), ``(K + A) xi' = ...``, from the same residual."""
    inputs = [ca.SX.sym(name, equations.size1_in(i), equations.size2_in(i))
              for i, name in enumerate(equations.name_in())]
    dxi = inputs[1]
    eq = equations(*inputs)[1]
    matrix = ca.jacobian(eq, dxi)
    rest = ca.substitute(eq, dxi, ca.DM.zeros(6))
    rate = ca.solve(matrix, -rest)
    others = [inputs[0]] + inputs[2:]
    return ca.Function("strain_rate", others, [rate],
                       [equations.name_in(0)] + equations.name_in()[2:], ["dxi"])


def _anchor():
    u, v, r, dr = (ca.SX.sym(n, 3) for n in ("u", "v", "r", "dr"))
    tension = ca.SX.sym("F")
    a = v + ca.cross(u, r) + dr
    force = tension * a / ca.norm_2(a)
    return ca.Function("anchor_wrench", [u, v, r, dr, tension], [ca.vertcat(ca.cross(r, force), force)],
                       ["u", "v", "r", "dr", "F"], ["wrench"])


def _point():
    h = ca.SX.sym("h", 4)
    f_glob, m_glob, f_body, m_body = (ca.SX.sym(n, 3) for n in ("f_glob", "m_glob", "f_body", "m_body"))
    R = rotation_matrix(h)
    wrench = ca.vertcat(R.T @ m_glob + m_body, R.T @ f_glob + f_body)
    return ca.Function("point_wrench", [h, f_glob, m_glob, f_body, m_body], [wrench],
                       ["h", "f_glob", "m_glob", "f_body", "m_body"], ["wrench"])


#: body-frame wrench ``[r x F t; F t]`` an actuator's anchor at offset r puts on the body,
#: ``t`` its unit tangent there (pulling towards the distal end for F > 0)
ANCHOR_WRENCH = _anchor()
#: body-frame wrench of a point force/moment given in global and body frames (at the centerline)
POINT_WRENCH = _point()

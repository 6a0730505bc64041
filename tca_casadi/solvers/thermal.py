"""Time integration of the TCAs' lumped thermal model (:mod:`tca_casadi.model.thermal`).

The state is every TCA's temperature plus two energy integrals per TCA, ``E_in = int P dt`` and
``E_out = int G (T - T_amb) dt`` [J], so that the heat balance
``E_in = C (T_end - T_0) + E_out`` can be checked on every run. The drives are piecewise
linear in time; the integrator (scipy's ``solve_ivp``, DOP853 with tight tolerances) never steps
across one of their breakpoints: each piece is integrated on its own, so a step in a drive lands
exactly where it is scheduled.
"""
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Schedule:
    """A value [SI] that is piecewise linear in time: ``values[k]`` at ``times[k]`` [s], held
    before the first and after the last time. A step is two points at the same time (the value
    after the step is the later one)."""
    times: tuple
    values: tuple

    @classmethod
    def constant(cls, value):
        return cls((0.0,), (float(value),))

    def __call__(self, t, left=False):
        """The value at ``t`` [s]; at a step, the value after it (``left``: before it). Values
        may be vectors (each ``values[k]`` an array): the result is then an array."""
        times, values = np.asarray(self.times, float), np.asarray(self.values, float)
        after = np.searchsorted(times, t, side="left" if left else "right")
        if after == 0:
            value = values[0]
        elif after == len(times):
            value = values[-1]
        else:
            t0, t1 = times[after - 1], times[after]
            value = values[after - 1] + (values[after] - values[after - 1]) * (t - t0) / (t1 - t0)
        return float(value) if np.ndim(value) == 0 else np.array(value)

    @property
    def breakpoints(self):
        return tuple(sorted(set(float(t) for t in self.times)))


@dataclass(frozen=True)
class Drive:
    """How one TCA is heated: ``kind`` ``power`` [W], ``voltage`` [V], ``current`` [A] or
    ``setpoint`` [degC], and its :class:`Schedule`. A ``setpoint`` drive is a PI temperature
    controller with a power limit, as on a lab bench: ``P = clip(kp e + ki I, 0, max_power)``,
    ``e = T_set - T``, ``dI/dt = e`` except while the output is saturated and ``e`` would push
    it further (conditional integration: no wind-up)."""
    kind: str
    schedule: Schedule
    proportional: float = 0.0           # kp [W/K]
    integral: float = 0.0               # ki [W/(K s)]
    max_power: float = float("inf")     # [W]

    def controller_power(self, error, state):
        """``(P, dI/dt)`` of the PI controller for ``error`` [K] and integral ``state`` [K s]."""
        raw = self.proportional * error + self.integral * state
        power = min(max(raw, 0.0), self.max_power)
        winding = (raw >= self.max_power and error > 0) or (raw <= 0.0 and error < 0)
        return power, 0.0 if winding else error

    def initial_state(self, law, ambient):
        """``(T, I)`` before any event: a setpoint drive at its steady state (the setpoint if
        ``max_power`` can hold it, else the temperature ``max_power`` holds); others at the
        closed-form steady state of their drive, ``I = 0``."""
        value = self.schedule(0.0, left=True)
        if self.kind != "setpoint":
            return law.steady_temperature(self.kind, value, ambient), 0.0
        needed = law.conductance * (value - ambient)
        if needed <= 0:
            return ambient, 0.0
        power = min(needed, self.max_power)
        temperature = ambient + power / law.conductance
        return temperature, (power - self.proportional * (value - temperature)) / self.integral


@dataclass
class ThermalHistory:
    """Temperatures and powers at the output times (n,); arrays are (n, number of TCAs)."""
    t: np.ndarray
    temperature: np.ndarray     # [degC]
    power: np.ndarray           # [W]
    energy_in: np.ndarray       # int P dt from t[0], per TCA [J]
    energy_lost: np.ndarray     # int G (T - T_amb) dt from t[0], per TCA [J]
    heat_capacity: np.ndarray   # (number of TCAs,) [J/K]
    energy_exchanged: np.ndarray = None   # int sum_j G_ij (T_i - T_j) dt, to the neighbours [J]

    def heat_balance_residual(self):
        """``E_in - C (T - T_0) - E_lost - E_exchanged`` per TCA at every output time [J],
        (n, number of TCAs) (zero up to the integrator's error)."""
        stored = (self.temperature - self.temperature[0]) * self.heat_capacity
        exchanged = 0.0 if self.energy_exchanged is None else self.energy_exchanged
        return self.energy_in - stored - self.energy_lost - exchanged


def exchange_matrix(coupling, count):
    """The (count, count) matrix ``L`` with ``(L T)_i = sum_j G_ij (T_i - T_j)`` [W/K] (a graph
    Laplacian) from the symmetric conductances ``coupling`` (None: no coupling)."""
    if coupling is None:
        return np.zeros((count, count))
    G = np.asarray(coupling, float)
    return np.diag(G.sum(axis=1)) - G


def steady_state(laws, drives, ambient, coupling=None):
    """Every TCA's ``(T, I)`` before any event (``I``: a setpoint drive's integral state).
    Uncoupled, each from :meth:`Drive.initial_state` (closed forms). Coupled, the root of
    ``P_i(T_i) = G_i (T_i - T_amb) + (L T)_i`` with setpoint drives holding their setpoint
    while their power stays within ``[0, max_power]`` (else held at the limit): an active-set
    loop of scipy roots started from the uncoupled state."""
    from scipy.optimize import root
    states = np.array([d.initial_state(law, ambient) for law, d in zip(laws, drives)], float).reshape(len(laws), 2)
    L = exchange_matrix(coupling, len(laws))
    if not np.any(L):
        return states
    G = np.array([law.conductance for law in laws])
    setpoint = np.array([d.kind == "setpoint" for d in drives])
    values = np.array([d.schedule(0.0, left=True) for d in drives])
    clamped = {}                                         # setpoint drive index -> the power it is held at
    for _ in range(len(laws) + 1):
        holds = setpoint & ~np.isin(np.arange(len(laws)), list(clamped))

        def temperatures(free):
            T = np.where(holds, values, 0.0)
            T[~holds] = free
            return T

        def residual(free):
            T = temperatures(free)
            power = np.array([clamped.get(j, 0.0) if d.kind == "setpoint" else float(law.power(d.kind, values[j], T[j]))
                              for j, (law, d) in enumerate(zip(laws, drives))])
            return (power - G * (T - ambient) - L @ T)[~holds]

        free = states[~holds, 0]
        if free.size:
            found = root(residual, free)
            free = found.x
            if np.max(np.abs(residual(free))) > 1e-12 * max(1.0, float(np.max(np.abs(G[~holds] * free)))):
                raise RuntimeError(f"no coupled thermal steady state: {found.message}")
        T = temperatures(free)
        needed = G * (T - ambient) + L @ T
        beyond = [j for j in np.flatnonzero(holds) if needed[j] > drives[j].max_power or needed[j] < 0]
        if not beyond:
            break
        for j in beyond:
            clamped[j] = min(max(needed[j], 0.0), drives[j].max_power)
    for j, d in enumerate(drives):
        states[j, 0] = T[j]
        if d.kind == "setpoint":
            power = clamped.get(j, needed[j])
            states[j, 1] = (power - d.proportional * (values[j] - T[j])) / d.integral
        else:
            states[j, 1] = 0.0
    return states


def integrate(laws, drives, ambient, initial, outputs, coupling=None, rtol=1e-11, atol=1e-11, step=None):
    """Integrate ``C_i dT_i/dt = P_i(t, T_i) - G_i (T_i - T_amb) - sum_j G_ij (T_i - T_j)`` for
    each TCA (``laws``: :class:`ThermalLaw` s, ``drives``: :class:`Drive` s, ``coupling``:
    the symmetric (count, count) conductances ``G_ij`` [W/K] between TCAs, None for none;
    ``initial`` temperatures [degC], or ``(T, I)`` pairs with the controllers' integral states,
    e.g. from :func:`steady_state`) and report at the increasing ``outputs`` [s] (the first is
    the start). Adaptive DOP853 (order 8) to ``rtol``/``atol``; ``step`` [s]: fixed steps of
    that size instead (no error control; for convergence studies), each piece between two
    breakpoints split into equal steps no longer than ``step``. Returns a
    :class:`ThermalHistory`."""
    outputs = np.asarray(outputs, float)
    count = len(laws)
    capacity = np.array([law.heat_capacity for law in laws])
    conductance = np.array([law.conductance for law in laws])
    L = exchange_matrix(coupling, count)

    def powers_and_rates(t, temperature, integral, left=False):
        """Electrical powers (count,) and the controllers' ``dI/dt`` (count,)."""
        power, rate = np.zeros(count), np.zeros(count)
        for j, (law, drive) in enumerate(zip(laws, drives)):
            value = drive.schedule(t, left)
            if drive.kind == "setpoint":
                power[j], rate[j] = drive.controller_power(value - temperature[j], integral[j])
            else:
                power[j] = float(law.power(drive.kind, value, temperature[j]))
        return power, rate

    def rhs_from(start):
        """The right-hand side on a piece starting at ``start``: drives take their values from
        inside the piece (the limit from the left at its end), never the next piece's."""
        def rhs(t, y):
            temperature, integral = y[:count], y[3 * count:4 * count]
            power, rate = powers_and_rates(t, temperature, integral, left=t > start)
            lost = conductance * (temperature - ambient)
            exchanged = L @ temperature
            return np.concatenate([(power - lost - exchanged) / capacity, power, lost, rate, exchanged])
        return rhs

    from scipy.integrate import solve_ivp          # here: a run without heating never imports it (0.1 s)
    cuts = sorted({b for d in drives for b in d.schedule.breakpoints if outputs[0] < b < outputs[-1]})
    edges = [outputs[0], *cuts, outputs[-1]]
    initial = np.asarray(initial, float).reshape(count, -1)          # (count,) T or (count, 2) T and I
    integral0 = initial[:, 1] if initial.shape[1] > 1 else np.zeros(count)
    y = np.concatenate([initial[:, 0], np.zeros(2 * count), integral0, np.zeros(count)])
    states = np.empty((outputs.size, 5 * count))
    states[0] = y
    for start, end in zip(edges[:-1], edges[1:]):
        inside = (outputs > start) & (outputs <= end)
        times = np.union1d(outputs[inside], [end])
        if step is None:
            options = {"rtol": rtol, "atol": atol}
        else:                      # equal steps: never rejected (huge tolerances), never longer than max_step
            size = (end - start) / max(1, int(np.ceil((end - start) / step - 1e-9)))
            options = {"rtol": 1e6, "atol": 1e6, "first_step": size, "max_step": size}
        solution = solve_ivp(rhs_from(start), (start, end), y, method="DOP853", t_eval=times, **options)
        if not solution.success:
            raise RuntimeError(f"thermal integration failed between {start:g} s and {end:g} s: {solution.message}")
        states[inside] = solution.y.T[np.isin(times, outputs[inside])]
        y = solution.y[:, -1]
    temperature = states[:, :count]
    power = np.array([powers_and_rates(t, y[:count], y[3 * count:4 * count])[0]
                      for t, y in zip(outputs, states)]).reshape(outputs.size, count)
    return ThermalHistory(outputs, temperature, power, states[:, count:2 * count], states[:, 2 * count:3 * count],
                          capacity, states[:, 4 * count:])


def zero_order_hold(laws, ambient, step, coupling=None):
    """The exact discretisation of the lumped model under powers held constant over a step:
    ``T(t + h) = Phi T(t) + Gamma P + offset`` for ``C dT/dt = P - G (T - T_amb) - L T``
    (``laws``: :class:`ThermalLaw` s, ``L`` the :func:`exchange_matrix` of ``coupling``).
    With ``A = -C^-1 (diag G + L)``: ``Phi = exp(A h)``, ``Gamma = int_0^h exp(A s) ds C^-1``
    and ``offset = Gamma G T_amb``, from one matrix exponential of the augmented system
    (Van Loan). Returns ``(Phi, Gamma, offset)``: (n, n), (n, n), (n,)."""
    from scipy.linalg import expm
    count = len(laws)
    capacity = np.array([law.heat_capacity for law in laws])
    conductance = np.array([law.conductance for law in laws])
    A = -(np.diag(conductance) + exchange_matrix(coupling, count)) / capacity[:, None]
    augmented = np.zeros((2 * count, 2 * count))
    augmented[:count, :count] = A * step
    augmented[:count, count:] = np.diag(1.0 / capacity) * step
    exponential = expm(augmented)
    Phi, Gamma = exponential[:count, :count], exponential[:count, count:]
    return Phi, Gamma, Gamma @ (conductance * ambient)

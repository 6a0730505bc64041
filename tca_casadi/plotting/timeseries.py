"""``timeseries.png`` of ``simulate``: temperatures, electrical powers (where a TCA is heated
electrically), tensions, the tip's displacement and, for a dynamic run, its energies against
time; named events marked. One colour and line style per actuator in every panel."""
import numpy as np

from .robot3d import _pyplot, finish
from .sweep_plots import line_style, mark_events

#: an event's label is clipped to this many characters
EVENT_LABEL = 40


def actuator_styles(series):
    """``{actuator key: plot keywords}``: one colour and line style per actuator of the run (its
    index among the solution's actuators, then any other heated key), the same in every panel."""
    n = len(series.solutions)
    keys = list(series.outputs[0].actuators) if n else []
    keys += [key for key in series.keys if key not in keys]
    return {key: dict(line_style(k, n), color=f"C{k % 10}") for k, key in enumerate(keys)}


def event_labels(timeline):
    """``[(t [s], label)]`` of a scenario's timeline events: what each sets (the first path and
    value, and how many more)."""
    out = []
    for event in timeline:
        items = list(event.set.items())
        text = f"{items[0][0]} = {items[0][1]}" if items else "event"
        if len(items) > 1:
            text += f" (+{len(items) - 1})"
        out.append((float(event.at), text if len(text) <= EVENT_LABEL else text[:EVENT_LABEL - 3] + "..."))
    return out


def save_timeseries_png(series, path, events=()):
    """The panels against time [s] (the solved output times); ``events``: times [s] or ``(t,
    label)`` pairs, drawn as dotted lines and named at the top panel. Saves a PNG at ``path``
    (None: returns the figure)."""
    plt = _pyplot()
    n = len(series.solutions)
    t = series.t[:n]
    styles = actuator_styles(series)
    heated = [k for k, key in enumerate(series.keys) if not np.all(np.isnan(series.powers[:n, k]))]
    dynamic = getattr(series, "energies", None) is not None and len(series.energies)
    electrical = getattr(series, "electrical", None) or {}
    kinds = [kind for kind in ("voltage", "current") if any(k == kind for k, _ in electrical.values())]
    has_tcas = len(series.keys) > 0
    has_actuators = bool(n and series.outputs[0].actuators)
    bodies = [body.name for body in series.outputs[0].bodies] if n and getattr(series.outputs[0], "bodies", None) else []
    panels = ((["temperature"] if has_tcas else []) + (["power"] if heated else []) + kinds
              + (["tension"] if has_actuators else []) + ["tip"] + (["objects", "grip"] if bodies else [])
              + (["energy"] if dynamic else []))
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.2 * len(panels) + 0.6), sharex=True, squeeze=False)
    axes = axes[:, 0]
    ax = dict(zip(panels, axes))
    for k, key in enumerate(series.keys):
        ax["temperature"].plot(t, series.temperatures[:n, k], label=key, **styles[key])
        if k in heated:
            ax["power"].plot(t, series.powers[:n, k] * 1e3, label=key, drawstyle="steps-post", **styles[key])
    for key, (kind, values) in electrical.items():
        ax[kind].plot(t, values[:n] * (1e3 if kind == "current" else 1.0), label=key, drawstyle="steps-post",
                      **styles[key])
    for key in (series.outputs[0].actuators if n else []):
        ax["tension"].plot(t, [s.actuators[key].tension * 1e3 for s in series.outputs], label=key, **styles[key])
    if n:
        move = (series.tip_positions() - series.tip_positions()[0]) * 1e3
        for axis, name in enumerate("xyz"):
            ax["tip"].plot(t, move[:, axis], label=f"tip {name}", **line_style(axis, n))
        ax["tip"].plot(t, np.linalg.norm(move, axis=1), color="black", label="|tip displacement|", **line_style(3, n))
    if bodies:
        _bodies(ax["objects"], ax["grip"], t, series.outputs, bodies, n)
    if dynamic:
        _energies(ax["energy"], t, series.energies[:n], n)
    labels = {"temperature": "temperature [degC]", "power": "electrical power [mW]", "voltage": "voltage [V]",
              "current": "current [mA]", "tension": "tension [mN]",
              "tip": "tip displacement [mm]", "energy": "energy [mJ]", "objects": "object displacement [mm]",
              "grip": "grip force [mN]"}
    for name, axis in ax.items():
        axis.set_ylabel(labels[name])
        axis.grid(True, alpha=0.3)
        if axis.get_legend_handles_labels()[0]:
            axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    mark_events(axes, [(e, None) if np.isscalar(e) else e for e in events])
    axes[-1].set_xlabel("time [s]")
    state = "" if series.completed else f"  (stopped: {series.message[:60]})"
    axes[0].set_title(f"simulate{state}", fontsize=10)
    return finish(plt, fig, path, dpi=110)


def _bodies(moved, gripped, t, outputs, names, n):
    """The free bodies' centres' displacement from the start [mm] (x, y, z) and the sum of their
    grips' normal forces [mN] at the outputs."""
    for j, name in enumerate(names):
        found = [next(b for b in out.bodies if b.name == name) for out in outputs]
        centres = np.array([b.position for b in found]) * 1e3
        for axis, label in enumerate("xyz"):
            moved.plot(t, centres[:, axis] - centres[0, axis], label=f"{name} {label}",
                       **line_style(3 * j + axis, n))
        gripped.plot(t, [b.grip_force * 1e3 for b in found], label=name, **line_style(j, n))


def _energies(axis, t, energies, n):
    """A dynamic run's energy account [mJ]: kinetic, elastic, gravitational (from its start),
    the actuators' and loads' work, what damping dissipated, the impact loss, friction's work
    and implicit Euler's loss (where any is above 1e-9 of the largest value shown) and the
    balance (zero up to the time discretisation)."""
    from ..time_simulation.motion import ENERGY_COLUMNS
    shown = energies * 1e3
    shown[:, ENERGY_COLUMNS.index("gravitational_energy")] -= shown[0, ENERGY_COLUMNS.index("gravitational_energy")]
    largest = np.max(np.abs(shown)) if shown.size else 0.0
    for k, name in enumerate(ENERGY_COLUMNS):
        if name in ("impact_loss", "friction_work", "integrator_loss") and not (
                np.max(np.abs(shown[:, k])) > 1e-9 * largest):        # no contact, no friction, no impact
            continue
        style = dict(line_style(k, n), color="black") if name == "energy_balance" else line_style(k, n)
        axis.plot(t, shown[:, k], label=name.replace("_", " ") + (" (from t0)" if name.startswith("grav") else ""),
                  **style)

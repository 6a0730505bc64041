"""Plots of a sweep: tip displacement and actuator tensions against the first swept parameter
(events marked), and the robot drawn at a few points of the branch."""
import numpy as np

from .robot3d import _equal_axes, _pyplot, _smooth, axes_box, bounded, draw_obstacle, finish, style_axes


#: marker, dash pattern and size per curve, so that curves lying on each other stay visible
#: (a larger hollow marker under a smaller one, different dashes)
_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]
_DASHES = ["-", "--", "-.", ":"]


def line_style(k, points=None):
    """Keyword arguments of ``plot`` for the k-th curve of a panel; with ``points`` (the curve's
    length), markers on about 12 of them only (staggered per curve), so that long curves stay
    lines."""
    style = {"marker": _MARKERS[k % len(_MARKERS)], "linestyle": _DASHES[k % len(_DASHES)],
             "markersize": max(9 - 1.5 * (k % 4), 3), "markerfacecolor": "none", "linewidth": 1.3}
    if points is not None and points > 24:
        every = points // 12
        style["markevery"] = (k * every // 7 % every, every)
    return style


def mark_events(axes, events):
    """Dotted red lines at ``events`` (``[(x, label or None)]``) on every axis of ``axes``, the
    labels written along the lines at the top of the first (events at the same x share a line)."""
    at = {}
    for x, label in events:
        at.setdefault(float(x), [])
        if label and label not in at[float(x)]:
            at[float(x)].append(label)
    for x, labels in at.items():
        for axis in axes:
            axis.axvline(x, color="tab:red", linestyle=":", linewidth=1)
        if labels:
            axes[0].annotate("\n".join(labels), (x, 1.0), xycoords=("data", "axes fraction"), xytext=(2, -2),
                             textcoords="offset points", rotation=90, va="top", ha="left", fontsize=6,
                             color="tab:red", annotation_clip=True)


def sweep_event_labels(result):
    """``[(x, label)]`` of a sweep's events on its first parameter's shown axis: what happens
    (``"body.t2 goes slack"``, ``"body touches wall"``)."""
    parameter = result.parameters[0]
    return [(parameter.shown(event["values"][parameter.path]), event["message"].split(" near ")[0])
            for event in result.events]


def contact_forces(result):
    """``{"module / obstacle": (n,) total normal force [N]}`` along a sweep (0 where open);
    empty without contacts."""
    pairs = {}
    for k, point in enumerate(result.points):
        for contact in point.solution.contacts:
            pairs.setdefault(f"{contact.module} / {contact.obstacle}", np.zeros(len(result.points)))
            pairs[f"{contact.module} / {contact.obstacle}"][k] += contact.normal_force
    return pairs


def plot_sweep(result, path):
    """Panels against the first parameter (in the unit it was given in): tip displacement from the
    first point [mm], TCA/tendon tensions [mN] (N beyond 10 N) and, where the robot touches
    something, the contact forces [mN]; events as named dotted lines. Saves a PNG at ``path``
    (None: returns the figure)."""
    plt = _pyplot()
    parameter = result.parameters[0]
    x = parameter.shown(result.values[:, 0])
    contacts = contact_forces(result)
    fig, axes = plt.subplots(3 if contacts else 2, 1, figsize=(8, 9.5 if contacts else 7), sharex=True,
                             layout="constrained")
    top, bottom = axes[0], axes[1]
    move = (result.tip_positions - result.tip_positions[0]) * 1e3
    for axis, name in enumerate("xyz"):
        top.plot(x, move[:, axis], label=f"tip {name}", **line_style(axis))
    top.plot(x, np.linalg.norm(move, axis=1), color="black", label="|tip displacement|", **line_style(3))
    top.set_ylabel("tip displacement [mm]")
    keys = list(result.points[0].solution.actuators)
    largest = max([float(np.max(np.abs(result.tensions(key)))) for key in keys], default=0.0)
    factor, unit = (1.0, "N") if largest >= 10.0 else (1e3, "mN")      # McKibben muscles pull newtons
    for k, key in enumerate(keys):
        bottom.plot(x, result.tensions(key) * factor, label=key, **line_style(k))
    bottom.axhline(0.0, color="grey", linewidth=0.8)
    bottom.set_ylabel(f"tension [{unit}]")
    for k, (pair, force) in enumerate(contacts.items()):
        axes[2].plot(x, force * 1e3, label=pair, **line_style(k))
    if contacts:
        axes[2].set_ylabel("contact normal force [mN]")
    axes[-1].set_xlabel(parameter.label + ("" if len(result.parameters) == 1 else " (and the others with it)"))
    if parameter.display is None:
        axes[-1].ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))   # SI moduli: 1e5, not 100000
    mark_events(axes, sweep_event_labels(result))
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    state = "" if result.completed else "  (stopped early)"
    top.set_title(f"sweep of {', '.join(p.path for p in result.parameters)}{state}", fontsize=10)
    return finish(plt, fig, path, dpi=120)


def plot_sweep_robots(result, path, count=5):
    """The robot's centerline and actuators at ``count`` points spread along the branch, one
    colour per point (labelled with the first parameter's value). Saves a PNG at ``path``."""
    plt = _pyplot()
    fig = plt.figure(figsize=(8.4, 6.4), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    chosen = np.unique(np.linspace(0, len(result.points) - 1, min(count, len(result.points))).round().astype(int))
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(chosen)))
    everything, parameter = [], result.parameters[0]
    for colour, index in zip(colours, chosen):
        solution = result.points[index].solution
        label = parameter.describe(result.points[index].values[0], digits=4)
        for m, module in enumerate(solution.modules):
            ax.plot(*(module.p * 1e3), color=colour, linewidth=2.5, label=label if m == 0 else None)
            everything.append(module.p * 1e3)
        for actuator in solution.actuators.values():
            style = "-" if actuator.kind == "tendon" or actuator.heated else "--"
            ax.plot(*(_smooth(actuator.path) * 1e3), style, color=colour, linewidth=0.8, alpha=0.8)
    extent = np.hstack(everything)
    obstacles = result.points[chosen[-1]].solution.obstacles      # fixed: drawn once
    for shape in filter(bounded, obstacles):
        everything += draw_obstacle(ax, shape, extent)
    _equal_axes(ax, np.hstack(everything))
    for shape in (s for s in obstacles if not bounded(s)):       # unbounded: cut to the box
        draw_obstacle(ax, shape, extent, clip=axes_box(ax))
    ax.set_box_aspect(ax.get_box_aspect(), zoom=0.88)            # room for the tick and axis labels
    style_axes(ax)
    ax.set_title("robot along the sweep (thick: centerline; thin: heated TCAs and tendons, "
                 "dashed: passive)", fontsize=8)
    fig.legend(loc="outside right upper", fontsize=7)          # beside the drawing, never over it
    return finish(plt, fig, path, dpi=120)

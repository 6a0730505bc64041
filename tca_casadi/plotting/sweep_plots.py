"""Plots of a sweep: tip displacement and actuator tensions against the first swept parameter
(events marked), and the robot drawn at a few points of the branch."""
import numpy as np

from .robot3d import _equal_axes, _pyplot, _smooth, draw_obstacle, finish, style_axes


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


def plot_sweep(result, path):
    """Two panels against the first parameter: tip displacement from the first point [mm] and
    TCA/tendon tensions [mN] (N beyond 10 N); dashed lines at events. Saves a PNG at ``path``."""
    plt = _pyplot()
    parameter = result.parameters[0]
    x = result.values[:, 0]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
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
    bottom.set_xlabel(parameter.label + ("" if len(result.parameters) == 1 else " (and the others with it)"))
    bottom.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))   # moduli in Pa: 1e5, not 100000
    for event in result.events:
        for ax in (top, bottom):
            ax.axvline(event["values"][parameter.path], color="tab:red", linestyle=":", linewidth=1)
    for ax in (top, bottom):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    state = "" if result.completed else "  (stopped early)"
    top.set_title(f"sweep of {', '.join(p.path for p in result.parameters)}{state}", fontsize=10)
    return finish(plt, fig, path, dpi=120)


def plot_sweep_robots(result, path, count=5):
    """The robot's centerline and actuators at ``count`` points spread along the branch, one
    colour per point (labelled with the first parameter's value). Saves a PNG at ``path``."""
    plt = _pyplot()
    fig = plt.figure(figsize=(6.4, 6.4))
    ax = fig.add_subplot(projection="3d")
    chosen = np.unique(np.linspace(0, len(result.points) - 1, min(count, len(result.points))).round().astype(int))
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(chosen)))
    everything, parameter = [], result.parameters[0]
    for colour, index in zip(colours, chosen):
        solution = result.points[index].solution
        label = f"{parameter.path} = {result.points[index].values[0]:.4g} {parameter.unit}"
        for m, module in enumerate(solution.modules):
            ax.plot(*(module.p * 1e3), color=colour, linewidth=2.5, label=label if m == 0 else None)
            everything.append(module.p * 1e3)
        for actuator in solution.actuators.values():
            style = "-" if actuator.kind == "tendon" or actuator.heated else "--"
            ax.plot(*(_smooth(actuator.path) * 1e3), style, color=colour, linewidth=0.8, alpha=0.8)
    extent = np.hstack(everything)
    for shape in result.points[chosen[-1]].solution.obstacles:      # fixed: drawn once
        everything += draw_obstacle(ax, shape, extent)
    _equal_axes(ax, np.hstack(everything))
    style_axes(ax)
    ax.set_title("robot along the sweep (thick: centerline; thin: heated TCAs and tendons, "
                 "dashed: passive)", fontsize=8)
    ax.legend(loc="upper left", fontsize=7)
    return finish(plt, fig, path, dpi=120, bbox_inches="tight", pad_inches=0.15)

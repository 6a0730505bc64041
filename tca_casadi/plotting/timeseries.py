"""``timeseries.png`` of ``simulate``: temperatures, electrical powers, tensions and the tip's
displacement against time, events marked."""
import numpy as np

from .robot3d import _pyplot, finish
from .sweep_plots import line_style


def save_timeseries_png(series, path, events=()):
    """Four panels against time [s] (the solved output times); dotted red lines at ``events``
    [s]. Saves a PNG at ``path`` and returns it."""
    plt = _pyplot()
    n = len(series.solutions)
    t = series.t[:n]
    fig, axes = plt.subplots(4, 1, figsize=(9, 9), sharex=True)
    for k, key in enumerate(series.keys):
        axes[0].plot(t, series.temperatures[:n, k], label=key, **line_style(k, n))
        if not np.all(np.isnan(series.powers[:n, k])):
            axes[1].plot(t, series.powers[:n, k] * 1e3, label=key, drawstyle="steps-post", **line_style(k, n))
    for k, key in enumerate(series.solutions[0].actuators if n else []):
        axes[2].plot(t, [s.actuators[key].tension * 1e3 for s in series.solutions], label=key, **line_style(k, n))
    if n:
        move = (series.tip_positions() - series.tip_positions()[0]) * 1e3
        for axis, name in enumerate("xyz"):
            axes[3].plot(t, move[:, axis], label=f"tip {name}", **line_style(axis, n))
        axes[3].plot(t, np.linalg.norm(move, axis=1), color="black", label="|tip displacement|", **line_style(3, n))
    if not axes[1].get_lines():
        axes[1].text(0.5, 0.5, "no electrically heated TCA (temperatures set)", ha="center", va="center",
                     transform=axes[1].transAxes, fontsize=9, color="0.4")
    labels = ["temperature [degC]", "electrical power [mW]", "tension [mN]", "tip displacement [mm]"]
    for ax, label in zip(axes, labels):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        for at in events:
            ax.axvline(at, color="tab:red", linestyle=":", linewidth=1)
    axes[-1].set_xlabel("time [s]")
    state = "" if series.completed else f"  (stopped: {series.message[:60]})"
    axes[0].set_title(f"simulate{state}", fontsize=10)
    return finish(plt, fig, path, dpi=110)

"""``plan.png`` of ``plan``: the planned inputs, the temperatures against their limits and the
tip's distance from the target against time."""
import numpy as np

from .robot3d import _pyplot, finish
from .sweep_plots import line_style


def save_plan_png(plan, path):
    """Three panels against time [s] of a :class:`PlanResult` or a closed loop's
    :class:`ClosedLoopResult`: each input [mW] (held over its step), each heated TCA's
    temperature [degC] with its type's maximum dashed, the tip's distance from the target [mm]
    with the tolerance dashed and the time it is reached marked. Saves a PNG; returns ``path``."""
    plt = _pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    t, n = plan.t, len(plan.t)
    held = plan.inputs if len(plan.inputs) == n else np.vstack([plan.inputs, plan.inputs[-1:]])   # per node
    for j, path_name in enumerate(plan.paths):
        axes[0].plot(t, held[:, j] * 1e3, drawstyle="steps-post", label=path_name, **line_style(j, n))
    for j, key in enumerate(plan.keys):
        line = axes[1].plot(t, plan.temperatures[:, j], label=key, **line_style(j, n))[0]
        axes[1].axhline(plan.max_temperatures[j], color=line.get_color(), linestyle="--", linewidth=0.8)
    along = plan.objective == "track" or getattr(plan, "path", None) is not None       # a path, not a target
    axes[2].plot(t, plan.errors * 1e3, color="black", label="|tip - path|" if along else "|tip - target|",
                 **line_style(0, n))
    axes[2].axhline(plan.tolerance * 1e3, color="tab:green", linestyle="--", linewidth=1, label="tolerance")
    if plan.reached:
        for ax in axes:
            ax.axvline(plan.reached_at_s, color="tab:green", linestyle=":", linewidth=1)
        axes[2].annotate(f"reached at {plan.reached_at_s:.3g} s", (plan.reached_at_s, plan.tolerance * 1e3),
                         textcoords="offset points", xytext=(6, 8), fontsize=8, color="tab:green")
    if np.all(plan.errors > 0):
        axes[2].set_yscale("log")
    labels = ["input power [mW]", "temperature [degC]\n(dashed: max)",
              "distance to the path [mm]" if along else "distance to target [mm]"]
    for ax, label in zip(axes, labels):
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[-1].set_xlabel("time [s]")
    state = "reached" if plan.reached else "not reached"
    name = plan.objective if plan.objective.startswith("mpc") else f"plan ({plan.objective})"
    axes[0].set_title(f"{name}: {state}, energy {plan.energy_J:.3g} J", fontsize=10)
    return finish(plt, fig, path, dpi=110)

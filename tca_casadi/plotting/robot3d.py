"""3D drawing of a solved robot, as the paper draws it: centerline thick black, heated TCAs red,
passive TCAs green, tendons orange, cross-sections blue."""
import numpy as np

COLORS = {"heated": "#d62728", "passive": "#2ca02c", "tendon": "#ff7f0e",
          "section": "#1f77b4", "centerline": "black"}


def _pyplot():
    import matplotlib
    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg") and not _has_display():
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _has_display():
    import os
    return bool(os.environ.get("DISPLAY"))


def draw_robot(solution, ax=None, sections_per_module=6, title=None, extra_points=()):
    """Draw ``solution`` on a 3D axes (created when ``ax`` is None). Lengths in mm.

    ``extra_points``: iterable of ``(position (3,) [m], label, color)`` to mark (e.g. a target).
    """
    plt = _pyplot()
    if ax is None:
        fig = plt.figure(figsize=(6.4, 6.4))
        ax = fig.add_subplot(projection="3d")
    everything = []
    for module in solution.modules:
        p = module.p * 1e3
        ax.plot(*p, color=COLORS["centerline"], linewidth=3.0, zorder=3)
        everything.append(p)
        for k in np.linspace(0, p.shape[1] - 1, sections_per_module).round().astype(int):
            ring = p[:, k:k + 1] + module.R[:, :, k] @ module.outline * 1e3
            ax.plot(*ring, color=COLORS["section"], linewidth=0.8)
            everything.append(ring)
    for key, actuator in solution.actuators.items():
        kind = "tendon" if actuator.kind == "tendon" else ("heated" if actuator.heated else "passive")
        ax.plot(*(_smooth(actuator.path) * 1e3), color=COLORS[kind], linewidth=1.6,
                label=f"{key} ({kind}, {actuator.tension * 1e3:.2f} mN)")
    for position, label, color in extra_points:
        point = np.asarray(position) * 1e3
        ax.scatter(*point, color=color, s=40, label=label, depthshade=False)
        everything.append(point.reshape(3, 1))
    _equal_axes(ax, np.hstack(everything))
    ax.set_xlabel("x [mm]"), ax.set_ylabel("y [mm]"), ax.set_zlabel("z [mm]")
    state = "" if solution.converged else "  (NOT CONVERGED)"
    ax.set_title(title or f"{solution.scenario_name}{state}")
    if solution.actuators or extra_points:
        ax.legend(loc="upper left", fontsize=7)
    return ax


def _smooth(path, per_segment=6):
    """A cubic spline through the path's nodes (parameterised by chord length) for drawing only."""
    from scipy.interpolate import CubicSpline
    steps = np.linalg.norm(np.diff(path, axis=1), axis=0)
    keep = np.r_[True, steps > 1e-12]
    path = path[:, keep]
    if path.shape[1] < 4:
        return path
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=1), axis=0))]
    fine = np.linspace(0.0, chord[-1], per_segment * path.shape[1])
    return CubicSpline(chord, path, axis=1)(fine)


def _equal_axes(ax, points):
    low, high = points.min(axis=1), points.max(axis=1)
    center, half = (low + high) / 2, max((high - low).max() / 2, 1e-3) * 1.1
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), center):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))


def save_robot_png(solution, path, **options):
    """Draw ``solution`` and save it as a PNG at ``path``."""
    plt = _pyplot()
    ax = draw_robot(solution, **options)
    ax.figure.tight_layout()
    ax.figure.savefig(path, dpi=120)
    plt.close(ax.figure)
    return path

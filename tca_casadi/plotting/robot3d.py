"""3D drawing of a solved robot, as the paper draws it: centerline thick black, heated TCAs red,
passive TCAs green, tendons orange, cross-sections blue; objects as grey boxes."""
import numpy as np

COLORS = {"heated": "#d62728", "passive": "#2ca02c", "tendon": "#ff7f0e",
          "section": "#1f77b4", "centerline": "black", "object": "#7f7f7f", "held": "#9467bd"}


def _pyplot():
    import matplotlib
    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg") and not _has_display():
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _has_display():
    import os
    return bool(os.environ.get("DISPLAY"))


def draw_robot(solution, ax=None, sections_per_module=6, title=None, extra_points=(), objects=()):
    """Draw ``solution`` on a 3D axes (created when ``ax`` is None). Lengths in mm.

    ``extra_points``: iterable of ``(position (3,) [m], label, color)`` to mark (e.g. a target);
    ``objects``: :class:`~tca_casadi.studies.objects.ObjectPose` boxes to draw.
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
        force = "slack" if actuator.slack else f"{actuator.tension * 1e3:.2f} mN"
        ax.plot(*(_smooth(actuator.path) * 1e3), color=COLORS[kind], linewidth=1.6,
                linestyle=":" if actuator.slack else "-", label=f"{key} ({kind}, {force})")
    for position, label, color in extra_points:
        point = np.asarray(position) * 1e3
        ax.scatter(*point, color=color, s=40, label=label, depthshade=False)
        everything.append(point.reshape(3, 1))
    for pose in objects:
        corners = pose.corners() * 1e3
        color = COLORS["held" if pose.held else "object"]
        for k, (a, b) in enumerate(pose.edges()):
            ax.plot(*corners[:, [a, b]], color=color, linewidth=1.4,
                    label=f"{pose.name} ({'held' if pose.held else 'resting'})" if k == 0 else None)
        everything.append(corners)
    _equal_axes(ax, np.hstack(everything))
    ax.set_xlabel("x [mm]"), ax.set_ylabel("y [mm]"), ax.set_zlabel("z [mm]")
    state = "" if solution.converged else "  (NOT CONVERGED)"
    ax.set_title(title or f"{solution.scenario_name}{state}")
    if solution.actuators or extra_points or objects:
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
    set_equal_limits(ax, low, high)


def set_equal_limits(ax, low, high, margin=0.08, thinnest=0.25):
    """Axis limits around [low, high] (3,) with one scale on every axis: the box takes the
    data's proportions (no axis thinner than ``thinnest`` of the longest)."""
    span = np.maximum(high - low, 1e-3)
    span = np.maximum(span, thinnest * span.max()) * (1 + 2 * margin)
    center = (low + high) / 2
    for setter, c, half in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), center, span / 2):
        setter(c - half, c + half)
    ax.set_box_aspect(tuple(span / span.max()))


def save_robot_png(solution, path, **options):
    """Draw ``solution`` and save it as a PNG at ``path``."""
    plt = _pyplot()
    ax = draw_robot(solution, **options)
    ax.figure.tight_layout()
    ax.figure.savefig(path, dpi=120)
    plt.close(ax.figure)
    return path

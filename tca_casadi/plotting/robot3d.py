"""3D drawing of a solved robot, as the paper draws it: centerline thick black, cross-sections
blue, TCAs coloured by their temperature (a colour bar), other muscles red when active and green
when not, tendons orange; objects as grey boxes."""
import functools

import numpy as np
from ..errors import flag

COLORS = {"heated": "#d62728", "passive": "#2ca02c", "tendon": "#ff7f0e",
          "section": "#1f77b4", "centerline": "black", "object": "#7f7f7f", "held": "#9467bd",
          "obstacle": "#8c8c8c", "contact": "#e377c2"}


def finish(plt, fig, path, dpi=110, **options):
    """Lay out ``fig``, save it atomically at ``path``, close it; return ``path``. ``path``
    None: return the open figure instead (what a result's ``plot()`` hands over)."""
    from ..output import save_figure
    if fig.get_layout_engine() is None:            # (a constrained figure lays itself out)
        fig.tight_layout()
    if path is None:
        return fig
    save_figure(fig, path, dpi=dpi, **options)
    plt.close(fig)
    return path


def _pyplot():
    import matplotlib
    if matplotlib.get_backend().lower() not in ("agg", "pdf", "svg") and not _has_display():
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _has_display():
    import os
    return bool(os.environ.get("DISPLAY"))


#: TCA temperatures are coloured on this map from TEMPERATURE_RANGE[0] to at least [1] [degC]
TEMPERATURE_MAP, TEMPERATURE_RANGE = "plasma", (20.0, 100.0)
#: ``--projection``: (elevation, azimuth) of an orthographic view along the third axis, and that axis
PROJECTIONS = {"xy": (90.0, -90.0, "z"), "xz": (0.0, -90.0, "y"), "yz": (0.0, 0.0, "x")}


def view_of(view=None, projection=None):
    """``{"view": (azimuth, elevation) or None, "projection": name or None}`` checked: a
    projection is one of :data:`PROJECTIONS`; a view two finite angles [deg]."""
    from ..errors import ScenarioError
    if projection is not None and projection not in PROJECTIONS:
        raise ScenarioError(f"{flag('--projection')} {projection!r}: one of {', '.join(PROJECTIONS)}")
    if view is not None:
        try:
            azimuth, elevation = (float(v) for v in (view.split(",") if isinstance(view, str) else view))
        except (TypeError, ValueError):
            raise ScenarioError(f"{flag('--view')} {view!r}: give AZIMUTH,ELEVATION in degrees, e.g. {flag('--view')} -60,20") from None
        if not (np.isfinite(azimuth) and np.isfinite(elevation)):
            raise ScenarioError(f"{flag('--view')} {view!r}: the angles must be finite")
        view = (azimuth, elevation)
    return {"view": view, "projection": projection}


def apply_view(ax, view=None, projection=None):
    """Point the camera of a 3-D axes: an orthographic projection onto a coordinate plane (the
    axis along the view hidden), or a perspective from ``(azimuth, elevation)`` [deg]."""
    if projection is not None:
        elevation, azimuth, hidden = PROJECTIONS[projection]
        ax.set_proj_type("ortho")
        ax.view_init(elev=elevation, azim=azimuth)
        getattr(ax, f"set_{hidden}ticks")([])
        getattr(ax, f"set_{hidden}label")("")
    elif view is not None:
        ax.view_init(elev=view[1], azim=view[0])


@functools.lru_cache(maxsize=1)
def temperature_colours():
    """The TCAs' temperature colour map: :data:`TEMPERATURE_MAP` without its palest 15 % (dark
    blue-violet when cool to orange when hot, all visible on white)."""
    import matplotlib
    from matplotlib.colors import ListedColormap
    return ListedColormap(matplotlib.colormaps[TEMPERATURE_MAP](np.linspace(0.0, 0.85, 256)), name="tca_temperature")


def temperature_norm(solution):
    """The colour scale of the TCAs' temperatures: from :data:`TEMPERATURE_RANGE`'s low end to
    its high end or the hottest TCA, whichever is higher."""
    from matplotlib.colors import Normalize
    hottest = max((a.temperature for a in solution.actuators.values() if a.kind == "tca" and a.temperature is not None),
                  default=TEMPERATURE_RANGE[1])
    return Normalize(TEMPERATURE_RANGE[0], max(TEMPERATURE_RANGE[1], hottest))


def draw_robot(solution, ax=None, sections_per_module=6, title=None, extra_points=(), objects=(), view=None,
               projection=None, norm=None, limits=None):
    """Draw ``solution`` on a 3D axes (created when ``ax`` is None, with a colour bar of the TCAs'
    temperatures and the legend beside the drawing). Lengths in mm.

    Centerline thick black, the joints between modules as white rings; cross-sections as
    translucent blue outlines (rectangles as rectangles); a thin grey line along each body's
    material x axis, so that twist shows; TCAs coloured by their temperature (:data:`TEMPERATURE_MAP`,
    ``norm`` or :func:`temperature_norm`), other actuators by kind (dotted when slack); point
    masses as black dots and point forces as arrows; ``extra_points``: iterable of ``(position
    (3,) [m], label, color)`` to mark (e.g. a target), drawn on top; ``objects``:
    :class:`~tca_casadi.studies.sequence.objects.ObjectPose` boxes; ``view``, ``projection``:
    :func:`apply_view`; ``limits``: ``(low, high)`` (3,) [mm] of the box (an animation's, the
    same in every frame; default the drawing's own extent). Unbounded obstacles (planes,
    cylinders) are cut to the box.
    """
    import matplotlib
    plt = _pyplot()
    own = ax is None
    if own:
        fig = plt.figure(figsize=(8.4, 6.4), layout="constrained")
        ax = fig.add_subplot(projection="3d")
    if limits is not None:
        ax.set_autoscale_on(False)           # (the box is given: no rescaling after every line)
    norm = norm or temperature_norm(solution)
    colour_map = temperature_colours()
    everything = [_draw_module(ax, module, sections_per_module) for module in solution.modules]
    everything = [points for group in everything for points in group]
    joints = np.column_stack([m.p[:, 0] for m in solution.modules[1:]]) * 1e3 if len(solution.modules) > 1 else None
    if joints is not None:
        ax.scatter(*joints, s=36, facecolors="white", edgecolors="black", linewidths=1.2, depthshade=False, zorder=8,
                   label="joints between modules")
    largest = max([abs(a.tension) for a in solution.actuators.values() if np.isfinite(a.tension)], default=0.0)
    scale, unit = (1.0, "N") if largest >= 1 else (1e3, "mN")          # one unit for every actuator
    for key, actuator in solution.actuators.items():
        kind = "tendon" if actuator.kind == "tendon" else ("heated" if actuator.heated else "passive")
        force = "slack" if actuator.slack else f"{actuator.tension * scale:.3g} {unit}"
        word = {"heated": "pressurised" if actuator.pressure is not None else (
            "active" if actuator.input is not None else "heated")}.get(kind, kind)
        by_temperature = actuator.kind == "tca" and actuator.temperature is not None
        colour = colour_map(norm(actuator.temperature)) if by_temperature else COLORS[kind]
        state = f"{actuator.temperature:.0f} degC" if by_temperature else word
        ax.plot(*(_smooth(actuator.path) * 1e3), color=colour, linewidth=1.8,
                linestyle=":" if actuator.slack else "-", label=f"{key} ({state}, {force})")
    everything += _draw_loads(ax, solution.loads, np.hstack(everything))
    everything += _draw_contacts(ax, solution.contacts, np.hstack(everything))
    extent = np.hstack(everything)
    for shape in solution.obstacles:
        if bounded(shape):                     # spheres and boxes count in the extent; planes do not
            everything += draw_obstacle(ax, shape, extent)
    for pose in objects:
        corners = pose.corners() * 1e3
        color = COLORS["held" if pose.held else "object"]
        for k, (a, b) in enumerate(pose.edges()):
            ax.plot(*corners[:, [a, b]], color=color, linewidth=1.4,
                    label=f"{pose.name} ({'held' if pose.held else 'resting'})" if k == 0 else None)
        everything.append(corners)
    for k, (position, label, color) in enumerate(extra_points):
        point = np.asarray(position) * 1e3       # the first as a large ring, the rest as stars on top
        style = ({"s": 220, "facecolors": "none", "edgecolors": color, "linewidths": 2.0} if k == 0 else
                 {"s": 70, "marker": "*", "color": color, "edgecolors": "black", "linewidths": 0.5})
        ax.scatter(*point, label=label, depthshade=False, zorder=10 + k, **style)
        everything.append(point.reshape(3, 1))
    if limits is None:
        _equal_axes(ax, np.hstack(everything))
    else:
        set_equal_limits(ax, *limits)
    for shape in solution.obstacles:           # unbounded: cut to the axes' box
        if not bounded(shape):
            draw_obstacle(ax, shape, extent, clip=axes_box(ax))
    style_axes(ax)
    apply_view(ax, view, projection)
    state = "" if solution.converged else "  (NOT CONVERGED)"
    ax.set_title(f"{title or solution.scenario_name}{state}", fontsize=10)
    if own and any(a.kind == "tca" and a.temperature is not None for a in solution.actuators.values()):
        bar = ax.figure.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=colour_map), ax=ax, shrink=0.55,
                                 pad=0.02, location="left")
        bar.set_label("TCA temperature [degC]", fontsize=8)
        bar.ax.tick_params(labelsize=7)
    if ax.get_legend_handles_labels()[0]:
        if own:                              # beside the drawing, never over it, inside the figure
            ax.figure.legend(*ax.get_legend_handles_labels(), loc="outside right upper", fontsize=7)
        else:
            ax.legend(loc="upper left", fontsize=6)
    return ax


def _draw_module(ax, module, sections):
    """Centerline, cross-sections and the material-x marker line of one module; returns the
    point sets drawn (mm)."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    p = module.p * 1e3
    ax.plot(*p, color=COLORS["centerline"], linewidth=3.0, zorder=3)
    drawn = [p]
    for k in np.linspace(0, p.shape[1] - 1, sections).round().astype(int):
        ring = p[:, k:k + 1] + module.R[:, :, k] @ module.outline * 1e3
        ax.add_collection3d(Poly3DCollection([ring.T], facecolors=COLORS["section"], alpha=0.12,
                                             edgecolors=COLORS["section"], linewidths=0.8))
        drawn.append(ring)
    reach = np.max(np.abs(module.outline[0])) * 1e3
    stripe = p + np.einsum("ijk,j->ik", module.R, np.array([reach, 0.0, 0.0]))
    ax.plot(*stripe, color="0.45", linewidth=0.7, linestyle="--")
    return drawn


def _draw_loads(ax, loads, points):
    """Point masses as black dots, point forces as arrows scaled to a fifth of the drawing."""
    size = float(np.max(np.ptp(points, axis=1))) if points.size else 1.0
    forces = [np.linalg.norm(load["force"]) for load in loads if load["kind"] == "point"]
    scale = 0.2 * size / max(forces) if forces and max(forces) > 0 else 0.0
    drawn = []
    for load in loads:
        at = np.asarray(load["position"]) * 1e3
        if load["kind"] in ("mass", "object"):
            grams = np.linalg.norm(load["force"]) / 9.81 * 1e3
            if grams > 0:
                ax.scatter(*at, color="black", s=30, depthshade=False, zorder=9,
                           label=f"{load['name']} ({grams:.3g} g)" if load["kind"] == "mass" else None)
        elif scale > 0 and np.linalg.norm(load["force"]) > 0:
            arrow = np.asarray(load["force"]) * scale
            ax.quiver(*at, *arrow, color="#8c564b", linewidth=1.5, arrow_length_ratio=0.25,
                      label=f"{load['name']} ({np.linalg.norm(load['force']) * 1e3:.3g} mN)")
            drawn.append(np.column_stack([at, at + arrow]))
    return drawn


def _draw_contacts(ax, contacts, points):
    """Contact forces on the rods as arrows (a fifth of the drawing for the largest)."""
    size = float(np.max(np.ptp(points, axis=1))) if points.size else 1.0
    largest = max((float(np.linalg.norm(c.force)) for c in contacts), default=0.0)   # friction included
    drawn = []
    for k, contact in enumerate(contacts):
        at = np.asarray(contact.position) * 1e3
        arrow = contact.force * 0.2 * size / largest
        ax.quiver(*(at - arrow), *arrow, color=COLORS["contact"], linewidth=2.6, arrow_length_ratio=0.3, zorder=9,
                  label=f"contact forces on the rods (largest {largest * 1e3:.3g} mN)" if k == 0 else None)
        drawn.append(np.column_stack([at - arrow, at]))
    return drawn


def bounded(shape):
    """Whether an obstacle has a finite extent (a sphere or box; not a plane or cylinder)."""
    return type(shape).__name__ in ("Sphere", "Box")


def axes_box(ax):
    """``(low, high)`` (3,) of a 3D axes' limits."""
    limits = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
    return limits[:, 0], limits[:, 1]


def draw_obstacle(ax, shape, points, resolution=24, clip=None):
    """A fixed obstacle as a light wireframe around the drawing's extent ``points`` (3, n) [mm]
    (planes and cylinders are unbounded); with ``clip`` ``(low, high)`` [mm], every line is cut
    to that box (nothing drawn over the tick labels). Returns the points drawn (mm) of a sphere
    or box (those that count in the drawing's extent)."""
    low, high = (points.min(axis=1), points.max(axis=1)) if clip is None else clip
    center, half = (low + high) / 2, max(float(np.max(high - low)) / 2, 1.0) * (1.1 if clip is None else 1.8)
    kind = type(shape).__name__
    style = {"color": COLORS["obstacle"], "linewidth": 0.6, "alpha": 0.7}
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, resolution), np.linspace(-1, 1, resolution // 2))
    if kind == "Sphere":
        r, c = shape.radius * 1e3, shape.position * 1e3
        x, y, z = (c[0] + r * np.cos(u) * np.sqrt(1 - v ** 2), c[1] + r * np.sin(u) * np.sqrt(1 - v ** 2), c[2] + r * v)
    elif kind == "Cylinder":
        r, c = shape.radius * 1e3, shape.position * 1e3
        along = (center - c) @ shape.rotation[:, 2]
        local = np.stack([r * np.cos(u), r * np.sin(u), along + half * v])
        x, y, z = np.einsum("ij,jkl->ikl", shape.rotation, local) + c[:, None, None]
    elif kind == "Plane":
        n = shape.normal / np.linalg.norm(shape.normal)
        a = np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0])
        a /= np.linalg.norm(a)
        b = np.cross(n, a)
        foot = center - ((center - shape.position * 1e3) @ n) * n
        corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                            for z in (low[2], high[2])]) - foot            # the box, in the plane's axes
        (a_low, b_low), (a_high, b_high) = (corners @ np.column_stack([a, b])).min(0), (corners @ np.column_stack([a, b])).max(0)
        along_a, along_b = np.linspace(a_low, a_high, 9), np.linspace(b_low, b_high, 9)
        fine_a, fine_b = np.linspace(a_low, a_high, 121), np.linspace(b_low, b_high, 121)
        lines = [foot[:, None] + a[:, None] * g + b[:, None] * fine_b[None, :] for g in along_a]
        lines += [foot[:, None] + b[:, None] * g + a[:, None] * fine_a[None, :] for g in along_b]
        for k, line in enumerate(lines):
            ax.plot(*_clipped(line, clip), label=shape.name if k == 0 else None, **style)
        return []
    else:                                                              # Box
        half_edges = shape.size * 1e3 / 2
        signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
        corners = shape.position[:, None] * 1e3 + shape.rotation @ (signs * half_edges).T
        for i in range(8):
            for j in range(i + 1, 8):
                if np.sum(signs[i] != signs[j]) == 1:
                    ax.plot(*corners[:, [i, j]], **style, label=shape.name if (i, j) == (0, 1) else None)
        return [corners]
    if clip is None:
        ax.plot_wireframe(x, y, z, rstride=1, cstride=1, label=shape.name, **style)
    else:
        rows = [np.vstack([x[i], y[i], z[i]]) for i in range(x.shape[0])]
        columns = [np.vstack([x[:, j], y[:, j], z[:, j]]) for j in range(x.shape[1])]
        for k, line in enumerate(rows + columns):
            ax.plot(*_clipped(line, clip), label=shape.name if k == 0 else None, **style)
    return [np.vstack([x.ravel(), y.ravel(), z.ravel()])] if kind == "Sphere" else []


def _clipped(line, clip):
    """``line`` (3, n) with the points outside the box ``clip`` = (low, high) set to NaN (so the
    drawn line stops at the box)."""
    if clip is None:
        return line
    low, high = clip
    inside = np.all((line >= np.asarray(low)[:, None] - 1e-9) & (line <= np.asarray(high)[:, None] + 1e-9), axis=0)
    return np.where(inside[None, :], line, np.nan)


def style_axes(ax, ticks=4):
    """Few ticks, labels in mm set off from the tick labels (no collisions on small boxes)."""
    from matplotlib.ticker import MaxNLocator
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(ticks))
    ax.tick_params(labelsize=7, pad=1)
    ax.set_xlabel("x [mm]", labelpad=4, fontsize=8)
    ax.set_ylabel("y [mm]", labelpad=4, fontsize=8)
    ax.set_zlabel("z [mm]", labelpad=6, fontsize=8)


def _smooth(path, per_segment=6):
    """A smooth curve through the path's nodes (3, n), for drawing only: cubic Hermite pieces
    parameterised by chord length, with the tangents of central differences (Catmull-Rom; a
    spline solve would need scipy.interpolate, 0.25 s to import in each process that draws)."""
    steps = np.linalg.norm(np.diff(path, axis=1), axis=0)
    keep = np.r_[True, steps > 1e-12]
    path = path[:, keep]
    if path.shape[1] < 4:
        return path
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(path, axis=1), axis=0))]
    tangents = np.gradient(path, chord, axis=1)
    fine = np.linspace(0.0, chord[-1], per_segment * path.shape[1])
    k = np.clip(np.searchsorted(chord, fine, side="right") - 1, 0, chord.size - 2)
    h = chord[k + 1] - chord[k]
    t = (fine - chord[k]) / h
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * path[:, k] + (t3 - 2 * t2 + t) * h * tangents[:, k]
            + (-2 * t3 + 3 * t2) * path[:, k + 1] + (t3 - t2) * h * tangents[:, k + 1])


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
    """Draw ``solution`` and save it as a PNG at ``path`` (None: return the figure)."""
    plt = _pyplot()
    ax = draw_robot(solution, **options)
    return finish(plt, ax.figure, path, dpi=120, bbox_inches="tight", pad_inches=0.15)

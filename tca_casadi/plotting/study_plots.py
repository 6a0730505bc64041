"""Plots of a study (:class:`~tca_casadi.studies.batch.result.StudyResult`).

* ``study_workspace.png``: the converged tips as a 3D point cloud and in the three coordinate
  planes, coloured by a column (default the first input), each projection with its convex hull,
  and the reachability density (samples per bin) of the same three projections.
* ``study_monte_carlo.png`` (a study with a distribution axis): histograms of the tip's
  coordinates about their mean, and the tip scatter in two planes with the 1- and 2-sigma
  ellipses of its covariance.
* ``study_response.png`` (one or two inputs): the tip and the bending angle against the input,
  or the bending angle as a surface over the two inputs.
"""
import numpy as np

from .robot3d import _pyplot, finish, set_equal_limits, style_axes
from ..errors import flag

PLANES = (("x", "y", 0, 1), ("x", "z", 0, 2), ("y", "z", 1, 2))


def save_study_plots(result, directory, color=None):
    """Every figure that applies to ``result``; the paths written."""
    written = []
    if len(result.converged) >= 3:
        written.append(plot_workspace(result, directory / "study_workspace.png", color))
        if result.study is not None and any(a.distribution for a in result.study.axes):
            written.append(plot_monte_carlo(result, directory / "study_monte_carlo.png"))
        if len(result.inputs) in (1, 2):
            written.append(plot_response(result, directory / "study_response.png"))
    return written


#: a tip coordinate whose samples spread less than this [mm] is constant (1 nm: roundoff of a
#: symmetric robot), drawn as a value, not as a histogram of roundoff
CONSTANT_MM = 1e-6


def shown_input(result, label):
    """``(values, axis label)`` of an input column in the unit it was given in (SI columns in the
    files); the column as stored where the study is not at hand."""
    values = result.converged[label].to_numpy(float)
    study = result.study
    if study is None or label not in result.inputs:
        return values, label
    path = study.design.paths[result.inputs.index(label)]
    factor, unit = study.shown(path)
    return values * factor, f"{path} [{unit}]"


def _colour_column(result, color):
    data = result.converged
    column = color or result.inputs[0]
    if column not in data.columns:
        from ..errors import ScenarioError
        raise ScenarioError(f"study {flag('--color')}: no column {column!r}; columns: {', '.join(data.columns[:40])}")
    values, label = shown_input(result, column)
    return label, values


def _on_a_curve(result):
    """One varied input: the tips lie on a curve (no area to hull, no density to map)."""
    return len(result.inputs) == 1


def plot_workspace(result, path, color=None):
    """The workspace figure (module docstring); one varied input: the curve of tips in 3D and
    the three planes, without hulls or densities (a curve has neither)."""
    from scipy.spatial import ConvexHull, QhullError
    plt = _pyplot()
    tips = result.tips() * 1e3
    column, values = _colour_column(result, color)
    curve = _on_a_curve(result)
    fig = plt.figure(figsize=(16, 4.8) if curve else (14, 8.5), layout="constrained")
    rows, columns = (1, 4) if curve else (2, 3)
    grid = fig.add_gridspec(rows, columns, width_ratios=[1.3, 1, 1, 1] if curve else None)
    ax3 = fig.add_subplot(grid[0, 0], projection="3d")
    ax3.scatter(*tips.T, c=values, s=6, cmap="viridis", depthshade=False)
    set_equal_limits(ax3, tips.min(axis=0), tips.max(axis=0))
    style_axes(ax3)
    ax3.set_box_aspect(None, zoom=0.8)            # room for the axis labels
    ax3.set_title(f"{len(tips)} tips" + (" (one input: a curve)" if curve else ""), fontsize=9)
    for k, (a, b, i, j) in enumerate(PLANES):
        ax = fig.add_subplot(grid[0, 1 + k] if (curve or k < 2) else grid[1, 0])
        flat = ax.scatter(tips[:, i], tips[:, j], c=values, s=5, cmap="viridis")
        if k == (2 if curve else 0):
            fig.colorbar(flat, ax=ax, label=column)
        if not curve:
            try:
                hull = ConvexHull(tips[:, [i, j]])
                ring = np.append(hull.vertices, hull.vertices[0])
                ax.plot(tips[ring, i], tips[ring, j], color="black", linewidth=1.0, label="convex hull")
                ax.legend(fontsize=7, loc="best")
            except QhullError:                 # the projection is a line: no hull to draw
                pass
        _plane_axes(ax, a, b)
    for k, (a, b, i, j) in enumerate(PLANES[:0 if curve else 2]):
        ax = fig.add_subplot(grid[1, 1 + k])
        counts = ax.hexbin(tips[:, i], tips[:, j], gridsize=30, cmap="Greys", mincnt=1, vmin=0)
        fig.colorbar(counts, ax=ax, label="samples per bin")
        _plane_axes(ax, a, b)
        ax.set_title(f"reachability density, {a}{b}", fontsize=9)
    fig.suptitle(f"{result.info['scenario']}: workspace ({result.info['design']}, "
                 f"{result.info['converged']} of {result.info['samples']} samples converged)")
    return finish(plt, fig, path)


def _plane_axes(ax, a, b):
    ax.set_xlabel(f"tip {a} [mm]")
    ax.set_ylabel(f"tip {b} [mm]")
    ax.ticklabel_format(useOffset=False)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(ax.get_title() or f"{a}{b} projection", fontsize=9)


def _spread_unit(spread_mm):
    """``(factor from mm, unit)`` for deviations of this size: µm below 1 mm, else mm."""
    return (1e3, "µm") if np.max(np.abs(spread_mm), initial=0.0) < 1.0 else (1.0, "mm")


def plot_monte_carlo(result, path):
    """Histograms and covariance ellipses of the tip (module docstring). A coordinate that does
    not vary (its spread below :data:`CONSTANT_MM`) is written as its value, not drawn as a
    histogram of roundoff; with one varied input the tip moves on a curve, drawn coloured by the
    input without ellipses (its covariance is degenerate)."""
    from .fit_plots import histogram_bins
    plt = _pyplot()
    tips = result.tips() * 1e3
    mean = tips.mean(axis=0)
    spread = tips - mean
    constant = np.ptp(tips, axis=0) < CONSTANT_MM
    factor, unit = _spread_unit(spread[:, ~constant]) if np.any(~constant) else (1e3, "µm")
    curve = _on_a_curve(result)
    colour_label, colour = _colour_column(result, None)
    fig, axes = plt.subplots(2, 3, figsize=(12.5, 7.5), layout="constrained")
    for k, axis in enumerate("xyz"):
        ax = axes[0, k]
        if constant[k]:
            ax.text(0.5, 0.5, f"tip {axis} = {round(mean[k], 4) + 0.0:.4f} mm in every sample\n(spread below 1 nm)",
                    ha="center", va="center", transform=ax.transAxes, fontsize=9)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.set_title(f"tip {axis}: constant", fontsize=9)
            continue
        ax.hist(spread[:, k] * factor, bins=histogram_bins(len(tips)), color="tab:blue", alpha=0.8)
        std = spread[:, k].std(ddof=1) * factor if len(tips) > 1 else 0.0
        ax.ticklabel_format(useOffset=False)
        ax.set_xlabel(f"tip {axis} about its mean ({round(mean[k], 3) + 0.0:.3f} mm) [{unit}]")
        ax.set_ylabel("samples")
        ax.set_title(f"tip {axis}: std {std:.3g} {unit}", fontsize=9)
    for k, (a, b, i, j) in enumerate(PLANES):
        ax = axes[1, k]
        points = ax.scatter(spread[:, i] * factor, spread[:, j] * factor, s=5, alpha=0.8,
                            **({"c": colour, "cmap": "viridis"} if curve else {}))
        if curve and k == 2:
            fig.colorbar(points, ax=ax, label=colour_label)
        covariance = np.cov(spread[:, [i, j]].T) * factor ** 2 if len(tips) > 2 else None
        if not curve and covariance is not None and not constant[i] and not constant[j] and \
                np.linalg.eigvalsh(covariance)[0] > 1e-8 * np.linalg.eigvalsh(covariance)[1]:
            for sigma, style in ((1, "-"), (2, "--")):
                ring = _ellipse(covariance, sigma)
                ax.plot(ring[0], ring[1], "k" + style, linewidth=1.0, label=f"{sigma} sigma")
            ax.legend(fontsize=7)
        ax.ticklabel_format(useOffset=False)
        ax.set_xlabel(f"tip {a} - mean [{unit}]")
        ax.set_ylabel(f"tip {b} - mean [{unit}]")
        ax.set_aspect("equal", adjustable="datalim")
    import textwrap
    varied = ", ".join(a.path for a in result.study.axes if a.distribution)
    title = f"{result.info['scenario']}: Monte Carlo of {varied} ({len(tips)} samples)"
    if curve:
        title += "; one varied input: the tip moves on a curve (no covariance ellipses)"
    fig.suptitle("\n".join(textwrap.wrap(title, 110)), fontsize=10)
    return finish(plt, fig, path)


def _ellipse(covariance, sigma, points=100):
    """``sigma``-ellipse (2, points) of a 2x2 covariance."""
    values, vectors = np.linalg.eigh(covariance)
    angle = np.linspace(0, 2 * np.pi, points)
    circle = np.vstack([np.cos(angle), np.sin(angle)])
    return vectors @ (sigma * np.sqrt(np.maximum(values, 0))[:, None] * circle)


def plot_response(result, path):
    """The response to one or two inputs (module docstring)."""
    plt = _pyplot()
    data = result.converged
    if len(result.inputs) == 1:
        x, label = shown_input(result, result.inputs[0])
        order = np.argsort(x)
        x = x[order]
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True, layout="constrained")
        for axis in "xyz":
            tip = data[f"tip_{axis} [m]"].to_numpy(float)[order] * 1e3
            top.plot(x, tip - tip[0], marker=".", label=f"tip {axis}")
        top.set_ylabel("tip moved from the first sample [mm]")
        top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        bottom.plot(x, data["bending_angle [deg]"].to_numpy(float)[order], marker=".", color="black")
        bottom.set_ylabel("bending angle [deg]")
        bottom.set_xlabel(label)
        bottom.ticklabel_format(axis="x", useOffset=False)
    else:
        (x, first), (y, second) = (shown_input(result, label) for label in result.inputs)
        z = data["bending_angle [deg]"].to_numpy(float)
        fig, ax = plt.subplots(figsize=(7, 6), layout="constrained")
        if len(np.unique(x)) >= 2 and len(np.unique(y)) >= 2 and len(x) >= 4:
            surface = ax.tricontourf(x, y, z, levels=14, cmap="viridis")
            fig.colorbar(surface, ax=ax, label="bending angle [deg]")
        ax.scatter(x, y, s=6, color="white", edgecolors="black", linewidths=0.3)
        ax.set_xlabel(first)
        ax.set_ylabel(second)
    fig.suptitle(f"{result.info['scenario']}: response ({len(data)} samples)", fontsize=10)
    return finish(plt, fig, path)

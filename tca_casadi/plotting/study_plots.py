"""Plots of a study (:class:`~tca_casadi.studies.study_result.StudyResult`).

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


def _colour_column(result, color):
    data = result.converged
    column = color or result.inputs[0]
    if column not in data.columns:
        from ..errors import ScenarioError
        raise ScenarioError(f"study --color: no column {column!r}; columns: {', '.join(data.columns[:40])}")
    return column, data[column].to_numpy(float)


def plot_workspace(result, path, color=None):
    """The workspace figure (module docstring)."""
    from scipy.spatial import ConvexHull, QhullError
    plt = _pyplot()
    tips = result.tips() * 1e3
    column, values = _colour_column(result, color)
    fig = plt.figure(figsize=(14, 8.5))
    ax3 = fig.add_subplot(2, 3, 1, projection="3d")
    ax3.scatter(*tips.T, c=values, s=6, cmap="viridis", depthshade=False)
    set_equal_limits(ax3, tips.min(axis=0), tips.max(axis=0))
    style_axes(ax3)
    ax3.set_box_aspect(None, zoom=0.85)           # room for the axis labels
    ax3.set_title(f"{len(tips)} tips", fontsize=9)
    for k, (a, b, i, j) in enumerate(PLANES):
        ax = fig.add_subplot(2, 3, 2 + k) if k < 2 else fig.add_subplot(2, 3, 4)
        flat = ax.scatter(tips[:, i], tips[:, j], c=values, s=5, cmap="viridis")
        if k == 0:
            fig.colorbar(flat, ax=ax, label=column)
        try:
            hull = ConvexHull(tips[:, [i, j]])
            ring = np.append(hull.vertices, hull.vertices[0])
            ax.plot(tips[ring, i], tips[ring, j], color="black", linewidth=1.0, label="convex hull")
            ax.legend(fontsize=7, loc="best")
        except QhullError:                 # the projection is a line: no hull to draw
            pass
        ax.set_xlabel(f"tip {a} [mm]")
        ax.set_ylabel(f"tip {b} [mm]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"{a}{b} projection", fontsize=9)
    for k, (a, b, i, j) in enumerate(PLANES):
        ax = fig.add_subplot(2, 3, 5 + k) if k < 2 else None
        if ax is None:
            break
        counts = ax.hexbin(tips[:, i], tips[:, j], gridsize=30, cmap="Greys", mincnt=1, vmin=0)
        fig.colorbar(counts, ax=ax, label="samples per bin")
        ax.set_xlabel(f"tip {a} [mm]")
        ax.set_ylabel(f"tip {b} [mm]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"reachability density, {a}{b}", fontsize=9)
    fig.suptitle(f"{result.info['scenario']}: workspace ({result.info['design']}, "
                 f"{result.info['converged']} of {result.info['samples']} samples converged)")
    return finish(plt, fig, path)


def plot_monte_carlo(result, path):
    """Histograms and covariance ellipses of the tip (module docstring)."""
    plt = _pyplot()
    tips = result.tips() * 1e3
    mean = tips.mean(axis=0)
    spread = tips - mean
    fig, axes = plt.subplots(2, 3, figsize=(12, 7))
    for k, axis in enumerate("xyz"):
        ax = axes[0, k]
        ax.hist(spread[:, k] * 1e3, bins=min(40, max(8, len(tips) // 10)), color="tab:blue", alpha=0.8)
        std = spread[:, k].std(ddof=1) * 1e3 if len(tips) > 1 else 0.0
        ax.set_xlabel(f"tip {axis} about its mean ({mean[k]:.3f} mm) [um]")
        ax.set_ylabel("samples")
        ax.set_title(f"tip {axis}: std {std:.2f} um", fontsize=9)
    for k, (a, b, i, j) in enumerate(PLANES):
        ax = axes[1, k]
        ax.scatter(spread[:, i] * 1e3, spread[:, j] * 1e3, s=5, alpha=0.6)
        if len(tips) > 2:
            covariance = np.cov(spread[:, [i, j]].T) * 1e6
            for sigma, style in ((1, "-"), (2, "--")):
                ring = _ellipse(covariance, sigma)
                ax.plot(ring[0], ring[1], "k" + style, linewidth=1.0, label=f"{sigma} sigma")
            ax.legend(fontsize=7)
        ax.set_xlabel(f"tip {a} - mean [um]")
        ax.set_ylabel(f"tip {b} - mean [um]")
        ax.set_aspect("equal", adjustable="datalim")
    import textwrap
    varied = ", ".join(a.path for a in result.study.axes if a.distribution)
    title = f"{result.info['scenario']}: Monte Carlo of {varied} ({len(tips)} samples)"
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
        label = result.inputs[0]
        order = np.argsort(data[label].to_numpy(float))
        x = data[label].to_numpy(float)[order]
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
        for axis in "xyz":
            top.plot(x, data[f"tip_{axis} [m]"].to_numpy(float)[order] * 1e3, marker=".", label=f"tip {axis}")
        top.set_ylabel("tip [mm]")
        top.legend(fontsize=8)
        bottom.plot(x, data["bending_angle [deg]"].to_numpy(float)[order], marker=".", color="black")
        bottom.set_ylabel("bending angle [deg]")
        bottom.set_xlabel(label)
    else:
        first, second = result.inputs
        x, y = data[first].to_numpy(float), data[second].to_numpy(float)
        z = data["bending_angle [deg]"].to_numpy(float)
        fig, ax = plt.subplots(figsize=(7, 6))
        if len(np.unique(x)) >= 2 and len(np.unique(y)) >= 2 and len(x) >= 4:
            surface = ax.tricontourf(x, y, z, levels=14, cmap="viridis")
            fig.colorbar(surface, ax=ax, label="bending angle [deg]")
        ax.scatter(x, y, s=6, color="white", edgecolors="black", linewidths=0.3)
        ax.set_xlabel(first)
        ax.set_ylabel(second)
    fig.suptitle(f"{result.info['scenario']}: response ({len(data)} samples)", fontsize=10)
    return finish(plt, fig, path)

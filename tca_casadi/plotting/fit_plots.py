"""Plots of a calibration (:class:`~tca_casadi.studies.fit.result.FitResult`).

* ``fit.png``: for each measured quantity, the prediction against the measurement for every
  experiment, before (at the nominal values) and after the fit, with the line of equality
  (held-out experiments marked), and below it the residual per experiment; and the histogram of the fitted residuals in units of their
  sigma, with the standard normal density for comparison.
* ``fit_parameters.png``: each parameter's fitted value and 95 % interval relative to its
  nominal value (an unidentifiable one marked, without an interval).
"""
import numpy as np

from .robot3d import _pyplot, finish


def _scale(name):
    return (1e3, "mN") if name.endswith(".tension") else (1e3, "mm")


def plot_fit(result, path):
    if result.fit.time_series:
        return plot_heating_fit(result, path)
    plt = _pyplot()
    names = result.names[:6]
    columns = len(names) + 1
    fig, grid = plt.subplots(2, columns, figsize=(3.6 * columns, 7.2))
    axes, below = grid[0], grid[1]
    measured = result.fit.data.values
    for ax, name in zip(below, names):
        j = result.names.index(name)
        factor, unit = _scale(name)
        micro = factor * 1e3
        experiment = np.arange(1, len(measured) + 1)
        ax.plot(experiment[result.train], (result.predicted_before[result.train, j] - measured[result.train, j]) * micro,
                "o", markerfacecolor="none", color="tab:gray", markersize=4, label="before")
        ax.plot(experiment[result.train], (result.predicted[result.train, j] - measured[result.train, j]) * micro,
                ".", color="tab:blue", label="after")
        ax.axhline(0, color="black", linewidth=0.8)
        ax.set_xlabel("experiment")
        ax.set_ylabel(f"predicted - measured {name} [{'µN' if unit == 'mN' else 'µm'}]")
        ax.legend(fontsize=7)
    below[-1].axis("off")
    for ax, name in zip(axes, names):
        j = result.names.index(name)
        factor, unit = _scale(name)
        y = measured[:, j] * factor
        ax.scatter(y[result.train], result.predicted_before[result.train, j] * factor, s=14, facecolors="none",
                   edgecolors="tab:gray", label="before (nominal)")
        ax.scatter(y[result.train], result.predicted[result.train, j] * factor, s=10, color="tab:blue", label="after")
        if result.test.size:
            ax.scatter(y[result.test], result.predicted[result.test, j] * factor, s=24, marker="x", color="tab:red",
                       label="held out")
        low, high = np.nanmin(y), np.nanmax(y)
        pad = 0.05 * (high - low or 1.0)
        ax.plot([low - pad, high + pad], [low - pad, high + pad], "k-", linewidth=0.8)
        ax.set_xlabel(f"measured {name} [{unit}]")
        ax.set_ylabel(f"predicted [{unit}]")
        ax.legend(fontsize=7)
    _residual_histogram(axes[-1], result)
    fig.suptitle(f"fit to {len(result.train)} experiments: RMS {result.rms['before'].get('length_mm', float('nan')):.3g}"
                 f" -> {result.rms['after'].get('length_mm', float('nan')):.3g} mm", fontsize=10)
    return finish(plt, fig, path)


def histogram_bins(count):
    """Sturges' number of bins for ``count`` samples (1 + ceil(log2 n): 6 for 20, 8 for 100), 3 to 30:
    each bin holds enough samples to compare with a density."""
    return int(np.clip(np.ceil(np.log2(max(count, 1))) + 1, 3, 30))


def _residual_histogram(ax, result):
    """The fitted residuals in units of their sigma, against the standard normal density."""
    weighted = (result.residuals / result.fit.data.sigmas[result.train]).ravel()
    ax.hist(weighted, bins=histogram_bins(weighted.size), density=True, color="tab:blue", alpha=0.7,
            label=f"{weighted.size} residuals")
    grid = np.linspace(min(-4, weighted.min()), max(4, weighted.max()), 200)
    ax.plot(grid, np.exp(-grid ** 2 / 2) / np.sqrt(2 * np.pi), "k-", linewidth=1, label="N(0, 1)")
    ax.set_xlabel("residual / sigma")
    ax.set_ylabel("density")
    ax.legend(fontsize=7)


def plot_heating_fit(result, path):
    """A heating-curve fit: the measured temperatures against time with the model before and
    after, the residuals against time, and their histogram in units of sigma."""
    plt = _pyplot()
    data = result.fit.data
    fig, (top, middle, right) = plt.subplots(1, 3, figsize=(15, 4.2))
    for j, name in enumerate(result.names):
        top.plot(data.times, data.values[:, j], ".", markersize=4, label=f"measured {name}")
        top.plot(data.times, result.predicted_before[:, j], "--", color="tab:gray", label="before (nominal)")
        top.plot(data.times, result.predicted[:, j], "-", color="tab:blue", label="after")
        middle.plot(data.times[result.train], result.predicted[result.train, j] - data.values[result.train, j], ".",
                    label=name)
    top.set_xlabel("t [s]")
    top.set_ylabel("temperature [degC]")
    top.legend(fontsize=7)
    middle.axhline(0, color="black", linewidth=0.8)
    middle.set_xlabel("t [s]")
    middle.set_ylabel("predicted - measured [K]")
    _residual_histogram(right, result)
    fig.suptitle(f"heating-curve fit: RMS {result.rms['before']['temperature_K']:.3g} -> "
                 f"{result.rms['after']['temperature_K']:.3g} K", fontsize=10)
    return finish(plt, fig, path)


def plot_fit_parameters(result, path):
    plt = _pyplot()
    count = len(result.parameters)
    fig, ax = plt.subplots(figsize=(7, 1.2 + 0.6 * count))
    for k, q in enumerate(result.parameters):
        scale = q.nominal if q.nominal != 0 else 1.0
        if q.identifiable:
            ax.errorbar(q.value / scale, k, xerr=[[(q.value - q.low) / abs(scale)], [(q.high - q.value) / abs(scale)]],
                        fmt="o", color="tab:blue", capsize=4)
        else:
            ax.plot(q.value / scale, k, "x", color="tab:red", markersize=9)
            ax.annotate("not identifiable", (q.value / scale, k), textcoords="offset points", xytext=(8, 6),
                        fontsize=8, color="tab:red")
    ax.axvline(1.0, color="gray", linestyle="--", linewidth=1, label="nominal")
    ax.set_yticks(range(count), [f"{q.path}\n(nominal {q.shown(q.nominal):.4g} {q.shown_unit})"
                                 for q in result.parameters], fontsize=8)
    ax.set_xlabel("fitted value / nominal value (95 % interval)")
    ax.legend(fontsize=8)
    return finish(plt, fig, path)

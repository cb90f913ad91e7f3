"""Figures: each function takes data or fitted objects and an optional matplotlib ``ax``
and returns the figure.

The command line and the notebooks use these same functions: trajectory overlays in the style
of the paper's Figures 2-5, time series, coefficient bars beside a reference, sparsity paths and
their Pareto view, before/after bars, and (from :mod:`sindyship.diagnose_plots`) the
comparison of a model with a measurement, force residuals over time and binned over the state,
the ranking of missing effects and the error after each diagnosed effect.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np

from .diagnose_plots import (  # noqa: F401  (the diagnosis figures, one namespace for all)
    plot_before_after,
    plot_comparison,
    plot_ranking,
    plot_residual_bins,
    plot_residual_time_series,
    plot_rounds,
    plot_time_series,
    plot_track,
)
from .trajectory import Trajectory


def trajectory_overlay(reference: Trajectory, flown: Mapping[str, Trajectory], *, L: float,
                       title: str = "", ax=None, reference_label: str = "MMG (reference)"):
    """Tracks in ship lengths, y east against x north, like the paper's Figures 2-5.

    Parameters
    ----------
    reference : Trajectory
        The measured or MMG record.
    flown : mapping of label to Trajectory
        Identified models flown the same way.
    L : float
        Ship length [m] for the axes.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if ax is None:
        fig, ax = plt.subplots(figsize=(6.0, 5.5), layout="constrained")
    else:
        fig = ax.figure
    ax.plot(reference["y"] / L, reference["x"] / L, color="black", lw=2.2,
            label=reference_label)
    styles = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1))]
    for k, (label, traj) in enumerate(flown.items()):
        line = ax.plot(traj["y"] / L, traj["x"] / L, ls=styles[k % len(styles)], lw=1.6,
                       label=label)[0]
        diverged = traj.meta.get("diverged_at")
        if diverged is not None:
            ok = np.flatnonzero(np.isfinite(traj["x"]))
            if ok.size:
                ax.plot(traj["y"][ok[-1]] / L, traj["x"][ok[-1]] / L, "x", ms=9,
                        color=line.get_color())
    ax.set_xlabel("y / L (east)")
    ax.set_ylabel("x / L (north)")
    span_x = np.nanmax(reference["x"]) - np.nanmin(reference["x"])
    span_y = np.nanmax(reference["y"]) - np.nanmin(reference["y"])
    if max(span_x, span_y) < 5 * min(span_x, span_y) + 1e-9:
        ax.set_aspect("equal", adjustable="datalim")  # a turn: true shape
    # an elongated track (a zig-zag) keeps independent axis scales so the weave is visible
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    if title:
        ax.set_title(title)
    return fig


def _figure(ax, size=(7.0, 4.0)):
    if ax is None:
        fig, ax = plt.subplots(figsize=size, layout="constrained")
        return fig, ax
    return ax.figure, ax


STATE_PANELS = (
    ("u", "u [m/s]", 1.0),
    ("v", "v [m/s]", 1.0),
    ("r", "r [deg/s]", 180.0 / np.pi),
    ("psi", "psi [deg]", 180.0 / np.pi),
    ("delta", "delta [deg]", 180.0 / np.pi),
)


def time_series(reference: Trajectory, flown: Mapping[str, Trajectory] | None = None, *,
                reference_label: str = "measured", axes=None):
    """u, v, r, psi and delta against time, the reference beside flown models.

    Returns
    -------
    matplotlib.figure.Figure
    """
    flown = flown or {}
    if axes is None:
        fig, axes = plt.subplots(len(STATE_PANELS), 1, figsize=(8.0, 9.0), sharex=True,
                                 layout="constrained")
    else:
        fig = axes[0].figure
    for ax, (column, label, scale) in zip(axes, STATE_PANELS, strict=True):
        ax.plot(reference.t, reference[column] * scale if column != "delta"
                else reference.rudder * scale, color="black", lw=1.8, label=reference_label)
        for name, traj in flown.items():
            values = traj[column] if column != "delta" else traj.rudder
            ax.plot(traj.t, values * scale, lw=1.2, ls="--", label=name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t [s]")
    axes[0].legend(fontsize=8, loc="best", ncols=min(4, 1 + len(flown)))
    return fig


def coefficient_bars(models: Mapping[str, object], dof: str, *,
                     reference: Mapping[str, float] | None = None,
                     reference_label: str = "paper", ax=None):
    """Coefficients of one equation (x 1e-5) as grouped bars, one group per term.

    Parameters
    ----------
    models : mapping of label to AbkowitzModel
    dof : {"X", "Y", "N"}
    reference : mapping of term to value (Prime I), optional
        Shown beside the models (e.g. the paper's Tables 7-9 or the Taylor reference).
    """
    first = next(iter(models.values()))
    terms = [t.text for t in first.library.terms[dof]]
    names = [t.identifier(dof) for t in first.library.terms[dof]]
    series = {label: [m.coefficients[dof].get(t, 0.0) * 1e5 for t in terms]
              for label, m in models.items()}
    if reference is not None:
        series = {reference_label: [reference.get(t, np.nan) * 1e5 for t in terms], **series}
    fig, ax = _figure(ax, (max(7.0, 0.45 * len(terms) * len(series) / 2), 4.2))
    width = 0.8 / len(series)
    x = np.arange(len(terms))
    for k, (label, values) in enumerate(series.items()):
        ax.bar(x + (k - (len(series) - 1) / 2) * width, values, width, label=label)
    ax.set_xticks(x, names, rotation=60, ha="right", fontsize=8)
    ax.set_yscale("symlog", linthresh=10.0)
    ax.set_ylabel(f"{dof}' coefficient [x 1e-5, Prime I]")
    ax.axhline(0.0, color="black", lw=0.6)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8)
    return fig


def sparsity_path(estimator, terms, *, target: int = 0, title: str = "", axes=None):
    """Coefficient paths and the cross-validation curve of a LASSO or STLSQ fit.

    For :class:`~sindyship.optimizers.LassoCV` the x axis is the penalty alpha, for
    :class:`~sindyship.optimizers.STLSQ` the threshold; the chosen value is marked.  The
    coefficients are shown standardised (times the column's standard deviation is not
    available here, so relative to their largest magnitude per term) on a symmetric log scale.

    Parameters
    ----------
    estimator : fitted LassoCV or STLSQ (with ``threshold="cv"``)
    terms : sequence of str
        Term names in column order (legend labels).
    """
    if hasattr(estimator, "alphas_"):
        grid = estimator.alphas_[target]
        mse = estimator.mse_path_[target].mean(axis=1)
        chosen = float(estimator.alpha_[target])
        xlabel = "LASSO penalty alpha"
    elif hasattr(estimator, "cv_results_"):
        grid = estimator.cv_results_["threshold"][target]
        mse = estimator.cv_results_["mean_mse"][target]
        chosen = float(estimator.threshold_[target])
        xlabel = "STLSQ threshold (standardised)"
    else:
        raise TypeError("sparsity_path needs a LassoCV or STLSQ fitted with cross-validation")
    path = estimator.coef_path_[target]
    if axes is None:
        fig, axes = plt.subplots(2, 1, figsize=(7.5, 7.0), sharex=True, layout="constrained",
                                 height_ratios=(2.2, 1.0))
    else:
        fig = axes[0].figure
    ax, ax_cv = axes
    scale = np.max(np.abs(path), axis=1, keepdims=True)
    scale[scale == 0] = 1.0
    for k, name in enumerate(terms):
        ax.plot(grid, path[k] / scale[k], lw=1.0, label=name)
    ax.axvline(chosen, color="black", ls="--", lw=1.0)
    ax.set_xscale("log")
    ax.set_ylabel("coefficient / its largest value")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, ncols=3, loc="upper right")
    if title:
        ax.set_title(title)
    ax_cv.plot(grid, mse, color="black", marker=".", ms=3)
    ax_cv.axvline(chosen, color="black", ls="--", lw=1.0, label="chosen")
    ax_cv.set_xscale("log")
    ax_cv.set_yscale("log")
    ax_cv.set_xlabel(xlabel)
    ax_cv.set_ylabel("CV mean squared error\n(Prime I force$^2$)")
    ax_cv.grid(alpha=0.3)
    ax_cv.legend(fontsize=8)
    return fig


def pareto(estimator, *, target: int = 0, ax=None, label: str = ""):
    """Number of active terms against cross-validation error (a Pareto view)."""
    if hasattr(estimator, "alphas_"):
        path = estimator.coef_path_[target]
        n_active = np.count_nonzero(path, axis=0)
        mse = estimator.mse_path_[target].mean(axis=1)
        chosen = int(np.count_nonzero(estimator.coef_[target]))
    else:
        n_active = estimator.cv_results_["n_nonzero"][target]
        mse = estimator.cv_results_["mean_mse"][target]
        chosen = int(np.count_nonzero(estimator.coef_[target]))
    fig, ax = _figure(ax, (5.5, 4.0))
    best = {}
    for n, e in zip(n_active, mse, strict=True):
        best[int(n)] = min(best.get(int(n), np.inf), float(e))
    ns = sorted(best)
    line = ax.plot(ns, [best[n] for n in ns], marker="o", label=label or None)[0]
    ax.axvline(chosen, color=line.get_color(), ls="--", lw=1.0)  # the chosen model
    ax.set_yscale("log")
    ax.set_xlabel("number of active terms")
    ax.set_ylabel("CV mean squared error (Prime I force$^2$)")
    ax.grid(alpha=0.3)
    if label:
        ax.legend(fontsize=8)
    return fig


def before_after(errors_before: Mapping[str, float], errors_after: Mapping[str, float], *,
                 labels: tuple[str, str] = ("before", "after"), ax=None,
                 ylabel: str = "mean distance [ship lengths]"):
    """Grouped bars of an error per manoeuvre before and after a change (e.g. an effect)."""
    names = list(errors_before)
    fig, ax = _figure(ax, (max(6.0, 0.9 * len(names)), 4.0))
    x = np.arange(len(names))
    ax.bar(x - 0.2, [errors_before[n] for n in names], 0.4, label=labels[0])
    ax.bar(x + 0.2, [errors_after.get(n, np.nan) for n in names], 0.4, label=labels[1])
    ax.set_xticks(x, names, rotation=30, ha="right")
    ax.set_ylabel(ylabel)
    ax.set_yscale("log")
    ax.grid(alpha=0.3, axis="y")
    ax.legend()
    return fig

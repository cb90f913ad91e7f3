"""Figures of coefficients: bars beside a reference, sparsity paths, the Pareto view, drift."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from ..errors import SindyshipInputError
from ._axes import figure_axes, single_axes


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
    fig, ax = single_axes(ax, (max(7.0, 0.45 * len(terms) * len(series) / 2), 4.2))
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
    available here, so relative to their largest magnitude per term), on a linear scale
    against a logarithmic penalty or threshold.

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
    fig, axes = figure_axes(axes, (2, 1), (7.5, 7.0), sharex=True, height_ratios=(2.2, 1.0))
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
    fig, ax = single_axes(ax, (5.5, 4.0))
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


def plot_coefficient_drift(result, dof: str, *, ax=None, order: str = "cluster") -> Figure:
    """Heat map of the correlations between one equation's ensemble coefficients.

    Strongly correlated (red) or anti-correlated (blue) pairs drift together: the data
    determine a combination of them better than each one.  Coefficients that never vary
    (always zero) are grey.

    Parameters
    ----------
    result : sindyship.uncertainty.EnsembleResult
    dof : {"X", "Y", "N"}
        The equation.
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure otherwise.
    order : {"cluster", "library"}
        Term order: hierarchical clustering on ``1 - |correlation|`` (groups that drift
        together are adjacent), or the library's order.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if order not in ("cluster", "library"):
        raise SindyshipInputError(f"order must be 'cluster' or 'library', not {order!r}.")
    corr = result.correlation(dof)
    terms = list(result.terms[dof])
    index = np.arange(len(terms))
    if order == "cluster" and len(terms) > 2:
        from scipy.cluster.hierarchy import leaves_list, linkage
        from scipy.spatial.distance import squareform

        distance = 1.0 - np.abs(np.nan_to_num(corr, nan=0.0))
        np.fill_diagonal(distance, 0.0)
        distance = np.clip(0.5 * (distance + distance.T), 0.0, None)
        index = leaves_list(linkage(squareform(distance, checks=False), "average"))
    shown = corr[np.ix_(index, index)]
    size = max(4.0, 0.32 * len(terms) + 1.5)
    fig, ax = single_axes(ax, (size + 1.0, size))
    cmap = colormaps["RdBu_r"].with_extremes(bad="0.85")
    image = ax.imshow(np.ma.masked_invalid(shown), cmap=cmap, vmin=-1.0, vmax=1.0,
                      interpolation="nearest")
    labels = [terms[i] for i in index]
    ax.set_xticks(range(len(labels)), labels, rotation=90, fontsize=7)
    ax.set_yticks(range(len(labels)), labels, fontsize=7)
    ax.set_title(f"{dof}: correlation of coefficients over {result.n_models} "
                 f"{result.scheme} models ({result.optimizer})", fontsize=9)
    ax.figure.colorbar(image, ax=ax, fraction=0.046, pad=0.04, label="correlation")
    return fig

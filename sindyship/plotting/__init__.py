"""Figures shared by the command line and the notebooks.

Every plot takes results or records and an optional ``ax`` and returns the
:class:`matplotlib.figure.Figure` it drew on, made without pyplot state
(:func:`figure_axes`): tracks and time series (:mod:`.trajectories`), the diagnosis
(:mod:`.diagnosis`), coefficients, sparsity paths and their drift (:mod:`.coefficients`).
"""

from __future__ import annotations

from ._axes import figure_axes, single_axes
from .coefficients import coefficient_bars, pareto, plot_coefficient_drift, sparsity_path
from .diagnosis import (
    diagnosis_figures,
    plot_before_after,
    plot_ranking,
    plot_residual_bins,
    plot_residual_time_series,
    plot_rounds,
    save_diagnosis_figures,
)
from .manoeuvres import plot_turning_circle, plot_zigzag
from .trajectories import (
    CHANNEL_LABELS,
    STATE_PANELS,
    plot_comparison,
    plot_time_series,
    plot_track,
    time_series,
    trajectory_overlay,
)

__all__ = [
    "CHANNEL_LABELS",
    "STATE_PANELS",
    "coefficient_bars",
    "diagnosis_figures",
    "figure_axes",
    "pareto",
    "plot_before_after",
    "plot_coefficient_drift",
    "plot_comparison",
    "plot_ranking",
    "plot_residual_bins",
    "plot_residual_time_series",
    "plot_rounds",
    "plot_time_series",
    "plot_turning_circle",
    "plot_track",
    "plot_zigzag",
    "save_diagnosis_figures",
    "single_axes",
    "sparsity_path",
    "time_series",
    "trajectory_overlay",
]

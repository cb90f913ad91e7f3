"""Figures (kept for existing imports): everything lives in :mod:`sindyship.plotting`."""

from __future__ import annotations

from .plotting import (  # noqa: F401
    CHANNEL_LABELS,
    STATE_PANELS,
    coefficient_bars,
    diagnosis_figures,
    figure_axes,
    pareto,
    plot_before_after,
    plot_coefficient_drift,
    plot_comparison,
    plot_ranking,
    plot_residual_bins,
    plot_residual_time_series,
    plot_rounds,
    plot_time_series,
    plot_track,
    save_diagnosis_figures,
    single_axes,
    sparsity_path,
    time_series,
    trajectory_overlay,
)

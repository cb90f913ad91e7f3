"""Figures of the diagnosis (kept for existing imports): see :mod:`sindyship.plotting`."""

from __future__ import annotations

from .plotting.diagnosis import (  # noqa: F401
    diagnosis_figures,
    plot_before_after,
    plot_ranking,
    plot_residual_bins,
    plot_residual_time_series,
    plot_rounds,
    save_diagnosis_figures,
)
from .plotting.trajectories import (  # noqa: F401
    CHANNEL_LABELS,
    plot_comparison,
    plot_time_series,
    plot_track,
)

"""Figures: each function takes data or fitted objects and an optional matplotlib ``ax``.

The command line and the notebooks use these same functions.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np

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

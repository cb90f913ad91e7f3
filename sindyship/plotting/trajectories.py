"""Figures of records and flights: tracks, time series, a model beside a measurement."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from ..trajectory import Trajectory
from ._axes import figure_axes, single_axes

#: Time-series channels of a comparison: (label with unit, factor from SI).
CHANNEL_LABELS: dict[str, tuple[str, float]] = {
    "u": ("surge speed u [m/s]", 1.0),
    "v": ("sway speed v [m/s]", 1.0),
    "r": ("yaw rate r [deg/s]", 180.0 / math.pi),
    "psi": ("heading psi [deg]", 180.0 / math.pi),
    "delta": ("rudder angle delta [deg]", 180.0 / math.pi),
}
_STYLES = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1))]


def _rudder(record) -> np.ndarray:
    return record["delta"] if record.has("delta") else record["delta_c"]


def _channel(record, channel: str) -> np.ndarray:
    return _rudder(record) if channel == "delta" else record[channel]


def plot_track(record, flights: Mapping[str, object], *, L: float, ax=None) -> Figure:
    """Measured track and model tracks in ship lengths (y east across, x north up).

    Parameters
    ----------
    record : Trajectory
        The measurement.
    flights : mapping of str to Trajectory
        Models flown the same way, by label.  A flight that diverged ends in a cross.
    L : float
        Ship length [m].
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, (ax,) = figure_axes(ax, (1, 1), (5.5, 5.0))
    ax.plot(record["y"] / L, record["x"] / L, color="black", lw=2.0, label="measured")
    for k, (label, flown) in enumerate(flights.items()):
        line = ax.plot(
            flown["y"] / L, flown["x"] / L, ls=_STYLES[k % len(_STYLES)], lw=1.5, label=label
        )[0]
        if flown.meta.get("diverged_at") is not None:
            ok = np.flatnonzero(np.isfinite(flown["x"]))
            if ok.size:
                ax.plot(
                    flown["y"][ok[-1]] / L,
                    flown["x"][ok[-1]] / L,
                    "x",
                    ms=9,
                    color=line.get_color(),
                    label=f"{label} diverged",
                )
    ax.set_xlabel("y / L (east) [-]")
    ax.set_ylabel("x / L (north) [-]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return fig


def plot_time_series(record, flights: Mapping[str, object], channel: str, *, ax=None) -> Figure:
    """One channel (u, v, r, psi or delta) over time: measured and flown.

    Parameters
    ----------
    record : Trajectory
    flights : mapping of str to Trajectory
    channel : {"u", "v", "r", "psi", "delta"}
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    label, factor = CHANNEL_LABELS[channel]
    fig, (ax,) = figure_axes(ax, (1, 1), (6.0, 3.0))
    ax.plot(record.t, factor * _channel(record, channel), color="black", lw=1.6, label="measured")
    for k, (name, flown) in enumerate(flights.items()):
        ax.plot(
            flown.t,
            factor * _channel(flown, channel),
            ls=_STYLES[k % len(_STYLES)],
            lw=1.2,
            label=name,
        )
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return fig


def plot_comparison(
    record,
    flights: Mapping[str, object],
    *,
    L: float,
    errors: Mapping[str, float] | None = None,
    ax=None,
) -> Figure:
    """The model flown like the measurement: track, and u, v, r, psi and delta over time.

    Parameters
    ----------
    record : Trajectory
    flights : mapping of str to Trajectory
    L : float
        Ship length [m].
    errors : mapping, optional
        An error summary (:func:`sindyship.evaluation.error_summary`) shown in the title.
    ax : sequence of 6 matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = figure_axes(ax, (2, 3), (13.0, 7.0))
    plot_track(record, flights, L=L, ax=axes[0])
    for axis, channel in zip(axes[1:], ("u", "v", "r", "psi", "delta"), strict=True):
        plot_time_series(record, flights, channel, ax=axis)
        axis.legend().set_visible(channel == "u")
    title = f"{record.name}: identified model flown like the measurement"
    if errors:
        title += (
            f"\nmean distance {errors['mean_distance_L']:.3f} L, max "
            f"{errors['max_distance_L']:.3f} L, heading RMS "
            f"{errors.get('rms_heading_deg', math.nan):.2f} deg, speed RMS "
            f"{errors.get('rms_speed_m_s', math.nan):.3f} m/s"
        )
        if errors.get("diverged_at_s") is not None:
            title += f", diverged at {errors['diverged_at_s']:.0f} s"
    fig.suptitle(title, fontsize=10)
    return fig


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
    fig, ax = single_axes(ax, (6.0, 5.5))
    ax.plot(reference["y"] / L, reference["x"] / L, color="black", lw=2.2,
            label=reference_label)
    for k, (label, traj) in enumerate(flown.items()):
        line = ax.plot(traj["y"] / L, traj["x"] / L, ls=_STYLES[k % len(_STYLES)], lw=1.6,
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
    fig, axes = figure_axes(axes, (len(STATE_PANELS), 1), (8.0, 9.0), sharex=True)
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

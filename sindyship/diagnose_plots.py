"""Figures of the diagnosis: where an identified model fails and what adding an effect changes.

Every function takes data or result objects of :mod:`sindyship.diagnose` and an optional
matplotlib ``ax`` (one Axes, or for the multi-panel figures a sequence of Axes), and returns
the :class:`~matplotlib.figure.Figure` it drew on.  Figures are made with
:class:`matplotlib.figure.Figure` directly (no pyplot state), so a caller never has to close
them.  Axes carry units; angles are shown in degrees, positions in ship lengths.

Examples
--------
>>> import numpy as np
>>> import pandas as pd
>>> from sindyship.trajectory import Trajectory
>>> t = np.arange(50.0)
>>> frame = pd.DataFrame({"t": t, "u": 10.0, "v": 0.0, "r": 0.01, "x": 10 * t, "y": t**2 / 10,
...                       "psi": 0.01 * t, "delta": 0.1})
>>> record = Trajectory(frame, "demo")
>>> fig = plot_comparison(record, {"model": record}, L=100.0)
>>> len(fig.axes)
6
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

__all__ = [
    "CHANNEL_LABELS",
    "plot_before_after",
    "plot_comparison",
    "plot_ranking",
    "plot_residual_bins",
    "plot_residual_time_series",
    "plot_rounds",
    "plot_time_series",
    "plot_track",
]

#: Time-series channels of a comparison: (label with unit, factor from SI).
CHANNEL_LABELS: dict[str, tuple[str, float]] = {
    "u": ("surge speed u [m/s]", 1.0),
    "v": ("sway speed v [m/s]", 1.0),
    "r": ("yaw rate r [deg/s]", 180.0 / math.pi),
    "psi": ("heading psi [deg]", 180.0 / math.pi),
    "delta": ("rudder angle delta [deg]", 180.0 / math.pi),
}
_DOF_LABELS = {
    "X": "surge force residual X' [-]",
    "Y": "sway force residual Y' [-]",
    "N": "yaw moment residual N' [-]",
}
_STYLES = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1))]


def _axes(ax, shape: tuple[int, int], figsize: tuple[float, float]) -> tuple[Figure, list]:
    """The figure and a flat list of axes: new ones of ``shape``, or those given in ``ax``."""
    n = shape[0] * shape[1]
    if ax is None:
        fig = Figure(figsize=figsize, layout="constrained")
        axes = fig.subplots(*shape, squeeze=False).ravel().tolist()
        return fig, axes
    axes = list(np.ravel(np.asarray(ax, dtype=object))) if not hasattr(ax, "plot") else [ax]
    if len(axes) != n:
        raise ValueError(f"this figure needs {n} axes, not {len(axes)}")
    return axes[0].figure, axes


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
    fig, (ax,) = _axes(ax, (1, 1), (5.5, 5.0))
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
    fig, (ax,) = _axes(ax, (1, 1), (6.0, 3.0))
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
    fig, axes = _axes(ax, (2, 3), (13.0, 7.0))
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


def _shade_phases(axis, phases: Sequence) -> None:
    """Steady turns as shaded spans, rudder changes as dashed lines (labelled once)."""
    labelled: set[str] = set()
    for phase in phases:
        label = phase.kind if phase.kind not in labelled else None
        labelled.add(phase.kind)
        if phase.end > phase.start:
            colour = "tab:green" if phase.kind == "steady turn" else "tab:gray"
            axis.axvspan(phase.start, phase.end, color=colour, alpha=0.12, label=label)
        else:
            colour = "tab:red" if phase.kind == "rudder reversal" else "tab:orange"
            axis.axvline(phase.start, color=colour, ls="--", lw=0.8, label=label)


def plot_residual_time_series(residuals, name: str, *, ax=None) -> Figure:
    """Force residuals (measured minus model) of one record over time, with its phases.

    Parameters
    ----------
    residuals : sindyship.diagnose.Residuals
    name : str
        The record.
    ax : sequence of 3 matplotlib Axes, optional
        For X, Y and N.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = _axes(ax, (3, 1), (10.0, 7.0))
    frame = residuals.record(name)
    phases = residuals.phases[residuals.names.index(name)]
    for axis, dof in zip(axes, ("X", "Y", "N"), strict=True):
        axis.plot(
            frame["t"], frame[f"residual_{dof}"], lw=0.9, color="tab:blue", label="measured - model"
        )
        axis.axhline(0.0, color="black", lw=0.6)
        _shade_phases(axis, phases)
        axis.set_ylabel(_DOF_LABELS[dof], fontsize=8)
        axis.grid(alpha=0.3)
    axes[-1].set_xlabel("time t [s]")
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{name}: force residuals (Prime I) with the manoeuvre phases", fontsize=10)
    return fig


def plot_residual_bins(residuals, *, variables: Sequence[str] | None = None, ax=None) -> Figure:
    """Force residuals binned over the state: mean with its standard deviation, per equation.

    One column per state variable (drift angle, yaw rate, rudder angle, heading), one row
    per equation; all training records together.  A mean far from zero in some bins is
    the regime where the model is wrong: even in yaw rate (same sign to port and
    starboard) points to asymmetry, a sine over heading to an earth-fixed load.

    Parameters
    ----------
    residuals : sindyship.diagnose.Residuals
    variables : sequence of str, optional
        Keys of :data:`sindyship.diagnose.STATE_BINS`; default all four.
    ax : sequence of 3 x len(variables) matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from .diagnose import STATE_BINS

    names = list(variables or STATE_BINS)
    fig, axes = _axes(ax, (3, len(names)), (3.4 * len(names), 7.5))
    for j, variable in enumerate(names):
        table = residuals.binned(variable)
        label = STATE_BINS[variable].label
        for i, dof in enumerate(("X", "Y", "N")):
            axis = axes[i * len(names) + j]
            rows = table[table["dof"] == dof]
            x = np.arange(len(rows))
            axis.bar(
                x,
                rows["mean"],
                yerr=rows["std"],
                color="tab:blue",
                alpha=0.7,
                ecolor="gray",
                capsize=2,
                label="mean +- std",
            )
            axis.axhline(0.0, color="black", lw=0.6)
            axis.set_xticks(x, rows["bin"], rotation=60, fontsize=6)
            axis.grid(alpha=0.3, axis="y")
            if j == 0:
                axis.set_ylabel(_DOF_LABELS[dof], fontsize=8)
            if i == 2:
                axis.set_xlabel(label, fontsize=8)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle("Force residuals (measured - model) binned over the state", fontsize=10)
    return fig


def plot_ranking(diagnosis, *, ax=None) -> Figure:
    """The candidate effects ranked by the share of the force error they explain.

    Bars are split by equation (X, Y, N each contribute a third of the mean); the dashed
    line is the threshold of a meaningful share.

    Parameters
    ----------
    diagnosis : sindyship.diagnose.Diagnosis
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    ranking = list(diagnosis.ranking)
    fig, (ax,) = _axes(ax, (1, 1), (7.0, 0.5 * max(len(ranking), 2) + 1.5))
    y = np.arange(len(ranking))[::-1]
    left = np.zeros(len(ranking))
    for dof, colour in zip(("X", "Y", "N"), ("tab:blue", "tab:orange", "tab:green"), strict=True):
        widths = np.array([100.0 * s.explained_by_dof[dof] / 3.0 for s in ranking])
        ax.barh(y, widths, left=left, color=colour, label=f"{dof} / 3")
        left += widths
    ax.axvline(
        100.0 * diagnosis.threshold,
        color="black",
        ls="--",
        lw=1.0,
        label=f"meaningful ({100 * diagnosis.threshold:.0f} %)",
    )
    ax.set_yticks(y, [s.effect.name for s in ranking])
    ax.set_xlabel("share of the leave-one-manoeuvre-out force error explained [%]")
    ax.set_xlim(0.0, 100.0)
    ax.grid(alpha=0.3, axis="x")
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(f"Missing effects of library {diagnosis.library.name}", fontsize=10)
    return fig


def plot_before_after(change, *, ax=None) -> Figure:
    """Mean distance per manoeuvre before and after adding effects, training and held-out.

    Parameters
    ----------
    change : sindyship.diagnose.BeforeAfter
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    table = change.table
    fig, (ax,) = _axes(ax, (1, 1), (max(6.0, 0.8 * len(table) + 2.0), 4.5))
    x = np.arange(len(table))
    width = 0.4
    for offset, column, label, colour in (
        (-width / 2, "before", change.before, "tab:gray"),
        (width / 2, "after", change.after, "tab:blue"),
    ):
        values = table[f"{column}_mean_L"].to_numpy(dtype=float)
        ax.bar(x + offset, values, width, label=label, color=colour)
        diverged = table[f"{column}_diverged_at_s"].notna().to_numpy()
        for k in np.flatnonzero(diverged):
            ax.annotate(
                "div.",
                (x[k] + offset, values[k]),
                ha="center",
                va="bottom",
                fontsize=7,
                color="tab:red",
            )
    labels = [f"{m}\n({s})" for m, s in zip(table["manoeuvre"], table["set"], strict=True)]
    ax.set_xticks(x, labels, fontsize=7, rotation=30)
    ax.set_yscale("log")
    ax.set_ylabel("mean distance [ship lengths]")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=7, loc="best")
    ax.set_title(f"Adding {', '.join(change.added)}: error on every manoeuvre", fontsize=10)
    return fig


def plot_rounds(iterative, *, ax=None) -> Figure:
    """Mean distance of every manoeuvre after each round of the iterative diagnosis.

    Parameters
    ----------
    iterative : sindyship.diagnose.IterativeDiagnosis
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    table = iterative.table
    fig, (ax,) = _axes(ax, (1, 1), (8.5, 4.5))
    libraries = list(dict.fromkeys(table["library"]))
    colours = {"training": plt.get_cmap("Greys"), "held-out": plt.get_cmap("tab10")}
    groups = list(table.groupby(["manoeuvre", "set"], sort=False))
    n_training = sum(kind == "training" for (_, kind), _ in groups)
    k_train = k_test = 0
    for (name, kind), rows in groups:
        order = [libraries.index(lib) for lib in rows["library"]]
        if kind == "held-out":  # held-out: bold colours; training: shades of grey
            colour, width = colours[kind](k_test % 10), 2.2
            k_test += 1
        else:
            colour, width = colours[kind](0.35 + 0.6 * k_train / max(n_training, 1)), 1.0
            k_train += 1
        ax.plot(order, rows["mean_distance_L"], marker="o", ms=4 if kind == "training" else 6,
                lw=width, ls="-" if kind == "held-out" else ":", label=f"{name} ({kind})",
                color=colour)
    ax.set_xticks(
        range(len(libraries)),
        [lib.split("+", 1)[1] if "+" in lib else lib for lib in libraries],
        rotation=20,
        fontsize=7,
    )
    ax.set_yscale("log")
    ax.set_xlabel("library (effects added round by round)")
    ax.set_ylabel("mean distance [ship lengths]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title("Iterative diagnosis: error after each added effect", fontsize=10)
    return fig

"""Figures of the diagnosis: where an identified model fails and what adding an effect changes.

Every function takes a result of :mod:`sindyship.diagnose` and an optional ``ax`` and returns
the :class:`~matplotlib.figure.Figure` it drew on.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from ._axes import figure_axes
from .trajectories import plot_comparison

_DOF_LABELS = {
    "X": "surge force residual X' [-]",
    "Y": "sway force residual Y' [-]",
    "N": "yaw moment residual N' [-]",
}


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
    fig, axes = figure_axes(ax, (3, 1), (10.0, 7.0))
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
        Keys of ``residuals.bins`` (:data:`sindyship.diagnose.STATE_BINS`); default all four.
    ax : sequence of 3 x len(variables) matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = list(variables or residuals.bins)
    fig, axes = figure_axes(ax, (3, len(names)), (3.4 * len(names), 7.5))
    for j, variable in enumerate(names):
        table = residuals.binned(variable)
        label = residuals.bins[variable].label
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
    fig, (ax,) = figure_axes(ax, (1, 1), (7.0, 0.5 * max(len(ranking), 2) + 1.5))
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
    fig, (ax,) = figure_axes(ax, (1, 1), (max(6.0, 0.8 * len(table) + 2.0), 4.5))
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
    fig, (ax,) = figure_axes(ax, (1, 1), (8.5, 4.5))
    libraries = list(dict.fromkeys(table["library"]))
    colours = {"training": colormaps.get_cmap("Greys"), "held-out": colormaps.get_cmap("tab10")}
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


def _safe(name: str) -> str:
    """A file-name fragment made of a record's name."""
    return re.sub(r"[^A-Za-z0-9_.+-]+", "_", name) or "record"


def figure_name(kind: str, name: str) -> str:
    """The file name of a record's figure of a kind, as ``diagnose`` and ``evaluate`` write it.

    Examples
    --------
    >>> figure_name("compare", "trials/tc 35")
    'compare-trials_tc_35.png'
    """
    return f"{kind}-{_safe(name)}.png"


def diagnosis_figures(diagnosis) -> list[tuple[str, Callable[[], Figure]]]:
    """The figures of a diagnosis by file name, each drawn only when called.

    ``compare-<record>.png`` (track and time series), ``residuals-<record>.png`` (force
    residuals over time with the phases), ``residuals-binned.png``, ``ranking.png`` and, per
    confirmed candidate, ``before-after-<effect>.png``.

    Parameters
    ----------
    diagnosis : sindyship.diagnose.Diagnosis

    Returns
    -------
    list of (str, callable)
        File name and a function that draws the figure.
    """
    tasks = []
    for c in diagnosis.comparisons:
        tasks.append(
            (
                figure_name("compare", c.name),
                lambda c=c: plot_comparison(
                    c.record, {diagnosis.library.name: c.flown}, L=diagnosis.ship.L,
                    errors=c.errors,
                ),
            )
        )
    for name in diagnosis.residuals.names:
        tasks.append(
            (
                figure_name("residuals", name),
                lambda name=name: plot_residual_time_series(diagnosis.residuals, name),
            )
        )
    tasks.append(("residuals-binned.png", lambda: plot_residual_bins(diagnosis.residuals)))
    if diagnosis.ranking:
        tasks.append(("ranking.png", lambda: plot_ranking(diagnosis)))
    for score in diagnosis.ranking:
        if score.confirmation is not None:
            tasks.append(
                (
                    f"before-after-{_safe(score.effect.name)}.png",
                    lambda change=score.confirmation: plot_before_after(change),
                )
            )
    return tasks


def save_diagnosis_figures(diagnosis, out_dir: str | Path, *, progress: bool = False
                           ) -> list[Path]:
    """Write the figures (PNG) and the before/after tables (CSV) of a diagnosis to a folder.

    The figures are those of :func:`diagnosis_figures`; per confirmed candidate also
    ``before-after-<effect>.csv``.

    Returns
    -------
    list of Path
        The files written.
    """
    from tqdm.auto import tqdm

    from .._io import save_figure, write_text_atomic

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    for score in diagnosis.ranking:
        if score.confirmation is not None:
            path = out / f"before-after-{_safe(score.effect.name)}.csv"
            write_text_atomic(path, score.confirmation.table.to_csv(index=False))
            written.append(path)
    for filename, draw in tqdm(
        diagnosis_figures(diagnosis), desc="figures", file=sys.stderr, disable=not progress,
        leave=False,
    ):
        written.append(save_figure(draw(), out / filename))
    return written

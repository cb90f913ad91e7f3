"""The standard manoeuvre figures: a zig-zag's heading and rudder against time, a turning
circle's track with advance and tactical diameter, each beside the IMO criteria.

The numbers drawn come from :func:`sindyship.manoeuvres.zigzag_events`,
:func:`~sindyship.manoeuvres.zigzag_figures` and :func:`~sindyship.manoeuvres.turning_figures`,
the criteria from :func:`~sindyship.manoeuvres.imo_criteria` (IMO Resolution MSC.137(76)).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

from ..manoeuvres import (
    _execute_index,
    imo_criteria,
    turning_figures,
    zigzag_events,
    zigzag_figures,
)
from ..trajectory import Trajectory
from ._axes import single_axes

__all__ = ["plot_turning_circle", "plot_zigzag"]

_STYLES = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1))]


def _criteria_text(values: Mapping[str, float], limits: Mapping[str, float],
                   labels: Mapping[str, str], unit: Mapping[str, str]) -> str:
    lines = []
    for key, label in labels.items():
        value = values[key]
        line = f"{label}: {value:.2f}{unit[key]}"
        if key in limits:
            verdict = "meets" if value <= limits[key] else "exceeds"
            line += f" (IMO <= {limits[key]:.3g}{unit[key]}: {verdict})"
        lines.append(line)
    return "\n".join(lines)


def plot_zigzag(record: Trajectory, *, flights: Mapping[str, Trajectory] | None = None,
                L: float | None = None, U: float | None = None, ax=None) -> Figure:
    """Heading and rudder angle against time, with the overshoots and the period marked.

    Parameters
    ----------
    record : Trajectory
        The zig-zag (measured or simulated).
    flights : mapping of label to Trajectory, optional
        Models flown the same way, drawn beside it (heading only).
    L, U : float, optional
        Ship length [m] and approach speed [m/s]: with both, the IMO criteria (which depend
        on L/V) are shown beside the overshoots.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axis = single_axes(ax, (9.0, 4.8))
    events = zigzag_events(record)
    figures = zigzag_figures(record)
    t, heading = record.t, events["heading_deg"]
    rudder = np.degrees(record["delta_c"] if record.has("delta_c") else record.rudder)
    axis.plot(t, heading, color="black", lw=1.8, label="heading change psi - psi0 (record)")
    axis.plot(t, np.degrees(record.rudder), color="tab:red", lw=1.2,
              label="rudder angle delta (record)")
    for k, (label, flown) in enumerate((flights or {}).items()):
        axis.plot(flown.t, np.degrees(flown["psi"] - flown["psi"][0]),
                  ls=_STYLES[k % len(_STYLES)], lw=1.2, label=f"heading, {label}")
    check = float(np.median(np.abs(heading[events["reversals"]]))) if len(
        events["reversals"]) else 0.0
    for level in (check, -check):
        axis.axhline(level, color="0.5", lw=0.7, ls=":")
    for n, (peak, over) in enumerate(zip(events["peaks"][:2], events["overshoots_deg"][:2],
                                         strict=False), start=1):
        axis.plot(t[peak], heading[peak], "v" if heading[peak] > 0 else "^", color="black",
                  ms=7)
        axis.annotate(f"overshoot {n}: {over:.1f} deg", (t[peak], heading[peak]),
                      xytext=(6, 10 if heading[peak] > 0 else -16), textcoords="offset points",
                      fontsize=8)
    reversals = events["reversals"]
    low = min(heading.min(), rudder.min())
    if len(reversals) >= 3:
        bar = low - 0.12 * (heading.max() - low)
        axis.annotate("", xy=(t[reversals[2]], bar), xytext=(t[reversals[0]], bar),
                      arrowprops={"arrowstyle": "<->", "color": "0.3"})
        axis.text(0.5 * (t[reversals[0]] + t[reversals[2]]), bar,
                  f"period {figures['period_s']:.0f} s", ha="center", va="bottom", fontsize=8)
        axis.set_ylim(bar - 0.08 * (heading.max() - low), None)
    if len(reversals) >= 6:  # the first cycles carry the standard figures
        axis.set_xlim(t[0], t[reversals[5]] + 0.1 * (t[reversals[5]] - t[0]))
    axis.set_xlabel("time t [s]")
    axis.set_ylabel("heading change and rudder angle [deg]")
    amplitude = float(np.median(np.abs(rudder[np.abs(rudder) > 0.5]))) if np.any(
        np.abs(rudder) > 0.5) else 0.0
    title = f"Zig-zag {amplitude:.0f}/{check:.0f}" + (f": {record.name}" if record.name else "")
    axis.set_title(title)
    if L and U:
        limits = imo_criteria("zigzag", L / U, rudder=round(amplitude), check=round(check))
        text = _criteria_text(figures, limits,
                              {"first_overshoot_deg": "first overshoot",
                               "second_overshoot_deg": "second overshoot"},
                              {"first_overshoot_deg": " deg", "second_overshoot_deg": " deg"})
        axis.text(0.99, 0.02, text, transform=axis.transAxes, ha="right", va="bottom",
                  fontsize=8, bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
    axis.grid(alpha=0.3)
    axis.legend(fontsize=8, loc="upper right", framealpha=0.7)
    return fig


def plot_turning_circle(record: Trajectory, *, L: float,
                        flights: Mapping[str, Trajectory] | None = None, ax=None) -> Figure:
    """Track in ship lengths (x north up, y east right) with the start, the first lap
    emphasised, the advance and tactical diameter marked, and the IMO criteria.

    Parameters
    ----------
    record : Trajectory
        The turning circle.
    L : float
        Ship length [m].
    flights : mapping of label to Trajectory, optional
        Models flown the same way, drawn beside it.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axis = single_axes(ax, (6.4, 6.4))
    k0 = _execute_index(record)
    x, y, psi = record["x"] / L, record["y"] / L, record["psi"]
    turned = np.abs(psi - psi[k0])
    lap = turned <= 2 * math.pi
    axis.plot(y[~lap], x[~lap], color="0.75", lw=0.8, label="record, later laps")
    axis.plot(y[lap], x[lap], color="black", lw=2.0, label="record, first 360 deg")
    for k, (label, flown) in enumerate((flights or {}).items()):
        first = np.abs(flown["psi"] - flown["psi"][k0]) <= 2 * math.pi
        axis.plot(flown["y"][first] / L, flown["x"][first] / L, ls=_STYLES[k % len(_STYLES)],
                  lw=1.4, label=f"{label}, first 360 deg")
    axis.plot(y[k0], x[k0], "o", color="tab:green", ms=9, zorder=5, label="start (rudder execute)")
    figures = turning_figures(record, L, execute=k0)
    c, s = math.cos(psi[k0]), math.sin(psi[k0])
    side = 1.0 if psi[-1] >= psi[k0] else -1.0
    advance, diameter = figures["advance_L"], figures["tactical_diameter_L"]
    # advance: along the approach course from the execute point
    axis.annotate("", xy=(y[k0] + advance * s, x[k0] + advance * c), xytext=(y[k0], x[k0]),
                  arrowprops={"arrowstyle": "<->", "color": "tab:blue"})
    axis.text(y[k0] + 0.5 * advance * s, x[k0] + 0.5 * advance * c,
              f" advance {advance:.2f} L", color="tab:blue", fontsize=8, rotation=0)
    # tactical diameter: across the approach course, from the approach line
    base_y, base_x = y[k0] + 0.3 * advance * s, x[k0] + 0.3 * advance * c
    across = (side * c, -side * s)  # (east, north) of the turn side, perpendicular to course
    end = (base_y + diameter * across[0], base_x + diameter * across[1])
    axis.annotate("", xy=end, xytext=(base_y, base_x),
                  arrowprops={"arrowstyle": "<->", "color": "tab:purple"})
    axis.text(0.5 * (base_y + end[0]), 0.5 * (base_x + end[1]),
              f"tactical diameter {diameter:.2f} L", color="tab:purple", fontsize=8,
              ha="center", va="bottom")
    limits = imo_criteria("turning-circle", 0.0, rudder=round(float(np.degrees(
        np.median(record.rudder[k0:])))))
    text = _criteria_text(figures, limits,
                          {"advance_L": "advance", "tactical_diameter_L": "tactical diameter"},
                          {"advance_L": " L", "tactical_diameter_L": " L"})
    axis.text(0.98, 0.02, text, transform=axis.transAxes, fontsize=8, va="bottom", ha="right",
              bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
    axis.set_xlabel("y / L (east)")
    axis.set_ylabel("x / L (north)")
    axis.set_aspect("equal", adjustable="datalim")
    axis.set_title(f"Turning circle{': ' + record.name if record.name else ''}")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=8, loc="upper right")
    return fig

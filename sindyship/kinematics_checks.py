"""The kinematic checks of a record's plausibility (:mod:`sindyship.plausibility`, whose
docstring gives their thresholds and reasons): ``heading``, whether psi agrees with the
integral of r, and ``frame``, whether (u, v) rotated by psi integrate to the track x, y.
Each refuses through the plausibility check's context (its ``refuse``, ``header`` and
``unit``), and names the reading of the channels that fits where one does.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

__all__ = ["FRAME_SEGMENTS", "FRAME_TOLERANCE", "HEADING_GAIN_TOLERANCE", "HEADING_MAX_DRIFT",
           "HEADING_MIN_SPAN", "UNIT_MATCH", "WRAP_TOLERANCE", "check_frame", "check_heading",
           "frame_misfit", "heading_gain", "unwrap_heading"]

WRAP_TOLERANCE = 0.5  # rad
HEADING_MIN_SPAN = 0.1  # rad
HEADING_GAIN_TOLERANCE = 0.25
HEADING_MAX_DRIFT = 0.35  # rad
FRAME_SEGMENTS = 32
FRAME_TOLERANCE = 0.1
UNIT_MATCH = 0.2

_KNOT = 1852.0 / 3600.0


def _running_integral(y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The trapezoidal integral of ``y`` over ``t`` from the first sample, as
    ``scipy.integrate.cumulative_trapezoid(y, t, initial=0.0)`` computes it (written out:
    importing scipy.integrate costs every command that reads a record a quarter second).

    Examples
    --------
    >>> _running_integral(np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 3.0])).tolist()
    [0.0, 0.5, 3.5]
    """
    y, t = np.asarray(y), np.asarray(t, dtype=float)  # y may be complex: x + i y
    return np.concatenate(([0.0], np.cumsum(np.diff(t) * (y[1:] + y[:-1]) / 2.0)))


def _yaw_integral(data) -> np.ndarray:
    return _running_integral(data["r"], data["t"])


def unwrap_heading(data, context) -> tuple[np.ndarray, str | None]:
    psi = data["psi"]
    unexplained = np.diff(psi) - np.diff(_yaw_integral(data))
    jumps = np.flatnonzero(np.abs(np.diff(psi)) > math.pi)
    if jumps.size == 0:
        return psi, None
    turns = np.round(unexplained[jumps] / (2 * math.pi))
    residual = np.abs(unexplained[jumps] - 2 * math.pi * turns)
    odd = np.flatnonzero(residual > WRAP_TOLERANCE)
    if odd.size:
        i = int(jumps[odd[0]]) + 1
        jump = float(psi[i] - psi[i - 1])
        degrees = context.unit("psi") is None and abs(abs(jump) - 360.0) < 20.0
        context.refuse(
            "heading",
            f"column '{context.header('psi')}' jumps by {jump:.4g} rad into {context.row(i)} "
            f"while r turns the ship by {psi[i] - psi[i - 1] - unexplained[i - 1]:.3g} rad",
            "the values look like degrees wrapped at +-180, so write the header as 'psi [deg]'"
            if degrees else "check the heading there",
        )
    steps = np.zeros_like(psi)
    steps[jumps + 1] = 2 * math.pi * turns
    note = (
        f"{context.source}: column '{context.header('psi')}' is kept within one turn and jumps "
        f"by a full turn {'once' if jumps.size == 1 else f'{jumps.size} times'}, first into "
        f"{context.row(int(jumps[0]) + 1)}; unwrapped it (psi must be continuous)."
    )
    return psi - np.cumsum(steps), note


def heading_gain(t: np.ndarray, r: np.ndarray, psi: np.ndarray) -> tuple[float, float]:
    """The least-squares gain of psi - psi[0] on the integral of r, and that integral's span.

    Examples
    --------
    >>> t = np.arange(100.0)
    >>> gain, span = heading_gain(t, np.full(100, 0.01), np.degrees(0.01 * t))
    >>> round(gain, 2), round(span, 2)
    (57.3, 0.99)
    """
    turned = _running_integral(r, t)
    change = psi - psi[0]
    span = float(np.max(np.abs(turned)))
    if span == 0.0:
        return math.nan, span
    return float(np.dot(change, turned) / np.dot(turned, turned)), span


def check_heading(data, context) -> None:
    psi_header, r_header = context.header("psi"), context.header("r")
    gain, span = heading_gain(data["t"], data["r"], data["psi"])
    if span < HEADING_MIN_SPAN:
        drift = float(np.max(np.abs(data["psi"] - data["psi"][0] - _yaw_integral(data))))
        if drift > HEADING_MAX_DRIFT:
            context.refuse(
                "heading",
                f"column '{psi_header}' strays {drift:.3g} rad from the integral of "
                f"'{r_header}', which turns the ship by at most {span:.3g} rad",
                f"the track agrees with psi, so check the unit of '{r_header}' (rad/s under a "
                "deg/s header reads 57 times too small)"
                if context.unit("r") is not None and _track_takes_psi(data, 1.0) else
                "check that psi is in rad (else write 'psi [deg]') and belongs with r",
            )
        return
    if abs(gain - 1.0) <= HEADING_GAIN_TOLERANCE:
        return
    problem = (
        f"column '{psi_header}' changes {gain:.4g} times as much as the integral of "
        f"'{r_header}' from psi[0] (expected 1 +- {HEADING_GAIN_TOLERANCE})"
    )
    context.refuse("heading", problem, _heading_fix(gain, data, context))


def _heading_fix(gain: float, data, context) -> str:
    """What to do about psi turning ``gain`` times the integral of r: the unit or sign that
    explains the gain, the track deciding between psi and r where either could."""
    psi_header, r_header = context.header("psi"), context.header("r")
    degree = math.pi / 180.0
    either = f"check the units of '{psi_header}' and '{r_header}'"
    if _near(gain, 1.0 / degree):  # psi in degrees read as rad, or r in rad/s read as deg/s
        if context.unit("r") is not None and _track_takes_psi(data, 1.0):
            return (f"the track agrees with psi, so '{r_header}' looks like rad/s: write the "
                    "header as 'r [rad/s]' or a bare 'r'")
        if context.unit("psi") is None:
            return "the heading looks like degrees, so write the header as 'psi [deg]'"
        if _track_takes_psi(data, degree):
            return (f"the track agrees with psi read as degrees, so '{psi_header}' looks "
                    "like deg: write the header as 'psi [deg]'")
        return either
    if _near(gain, degree):  # r in deg/s read as rad/s, or psi in rad read as degrees
        if context.unit("psi") is not None and _track_takes_psi(data, 1.0 / degree):
            return (f"the track agrees with psi read as radians, so '{psi_header}' looks "
                    "like rad: write the header as 'psi [rad]' or a bare 'psi'")
        if context.unit("r") is None:
            return "the yaw rate looks like deg/s, so write the header as 'r [deg/s]'"
        return either
    if _near(gain, 1e-3) and context.unit("t") in (None, "s"):
        return "the times look like milliseconds, so write the header as 't [ms]'"
    if _near(gain, -1.0):
        return ("psi and r turn opposite ways: psi is clockwise from north and r positive to "
                "starboard, so negate the one with the wrong sign")
    return "check the units and signs of psi and r"


def _track_takes_psi(data, factor: float) -> bool:
    """Whether (u, v) rotated by psi times ``factor`` integrate to the track (the ``frame``
    check's misfit within its tolerance): which of psi and r is in the wrong unit."""
    return frame_misfit({**data, "psi": data["psi"] * factor}) <= FRAME_TOLERANCE


def _near(value: float, target: float) -> bool:
    return value * target > 0 and abs(math.log(value / target)) < math.log1p(UNIT_MATCH)


# ---------------------------------------------------------------------------------------------
# frame


def _segments(n: int) -> np.ndarray:
    step = max(1, (n - 1) // FRAME_SEGMENTS)
    edges = np.arange(0, n, step)
    if edges[-1] != n - 1:
        edges = np.append(edges, n - 1)
    return edges


def _displacements(t: np.ndarray, velocity: np.ndarray, edges: np.ndarray) -> np.ndarray:
    travelled = _running_integral(velocity, t)
    return travelled[edges[1:]] - travelled[edges[:-1]]


def frame_misfit(data: Mapping[str, np.ndarray]) -> float:
    """The ``frame`` check's misfit: (u, v) rotated by psi against the track d(x, y)/dt.

    Sum over segments of |recorded displacement - integrated velocity| over the sum of
    |recorded displacement| (0 for a consistent record; NaN when x and y never change).

    Examples
    --------
    >>> t = np.arange(10.0)
    >>> record = {"t": t, "u": np.full(10, 2.0), "v": np.zeros(10), "psi": np.full(10, 0.5),
    ...           "x": 2 * t * math.cos(0.5), "y": 2 * t * math.sin(0.5)}
    >>> round(frame_misfit(record), 12)
    0.0
    """
    edges = _segments(len(data["t"]))
    track = np.asarray(data["x"]) + 1j * np.asarray(data["y"])
    recorded = track[edges[1:]] - track[edges[:-1]]
    scale = float(np.sum(np.abs(recorded)))
    velocity = np.exp(1j * np.asarray(data["psi"])) * (np.asarray(data["u"]) + 1j * data["v"])
    predicted = _displacements(np.asarray(data["t"]), velocity, edges)
    if scale == 0.0:
        return math.nan
    return float(np.sum(np.abs(recorded - predicted)) / scale)


def check_frame(data, context) -> None:
    t, psi = data["t"], data["psi"]
    body = data["u"] + 1j * data["v"]
    edges = _segments(len(t))
    track = data["x"] + 1j * data["y"]
    recorded = track[edges[1:]] - track[edges[:-1]]
    scale = float(np.sum(np.abs(recorded)))
    predicted = _displacements(t, np.exp(1j * psi) * body, edges)
    if scale == 0.0:
        context.refuse(
            "frame",
            f"x and y never change while (u, v) carry the ship "
            f"{np.sum(np.abs(predicted)):.4g} m",
            "give the track in x (north) and y (east) [m]",
        )
    misfit = float(np.sum(np.abs(recorded - predicted)) / scale)
    if misfit <= FRAME_TOLERANCE:
        return
    readings = _frame_readings(t, psi, data["r"], body, recorded, predicted, edges, context)
    fits = [(m, text, fix) for m, text, fix in readings if m <= FRAME_TOLERANCE]
    if fits:
        best, text, fix = min(fits, key=lambda item: item[0])
        context.refuse(
            "frame",
            f"{text}: misfit {best:.3f} against {misfit:.3f} when (u, v) are rotated by psi "
            f"into the track d(x, y)/dt (tolerance {FRAME_TOLERANCE})",
            fix,
        )
    context.refuse(
        "frame",
        f"(u, v) rotated by psi miss the track d(x, y)/dt by a misfit of {misfit:.3f} "
        f"(tolerance {FRAME_TOLERANCE})",
        "check that u, v are body-fixed (v to starboard), x points north, y east, psi is "
        "clockwise from north, and the units of t, u, v, x and y",
    )


def _frame_readings(t, psi, r, body, recorded, predicted, edges, context):
    """(misfit, what it looks like, fix) for each other reading of the channels."""
    scale = float(np.sum(np.abs(recorded)))

    def misfit(other_recorded, other_predicted) -> float:
        return float(np.sum(np.abs(other_recorded - other_predicted)) / scale)

    readings = [
        (misfit(recorded, _displacements(t, body, edges)),
         "(u, v) look earth-fixed: they match d(x, y)/dt without rotating by psi",
         "give body-fixed surge and sway, u = u_N cos psi + u_E sin psi and "
         "v = -u_N sin psi + u_E cos psi"),
        (misfit(recorded, _displacements(t, np.exp(1j * psi) * np.conj(body), edges)),
         "v looks positive to port", "negate v (sway is positive to starboard)"),
        (misfit(1j * np.conj(recorded), predicted),
         "x and y look swapped", "x points north and y east: swap the two columns"),
        (misfit(recorded, _displacements(t, np.exp(-1j * psi) * body, edges)),
         "psi looks anticlockwise", "psi is clockwise from north: negate psi (and r)"),
    ]
    if context.unit("psi") is None:
        readings.append(
            (misfit(recorded, _displacements(t, np.exp(1j * np.radians(psi)) * body, edges)),
             "psi looks like degrees", "write the header as 'psi [deg]'"))
    gain = complex(np.sum(np.conj(predicted) * recorded) / np.sum(np.abs(predicted) ** 2))
    ratio = abs(gain)
    if ratio > 0 and not _near(ratio, 1.0):
        readings.append((misfit(recorded, ratio * predicted),
                         f"the track is {ratio:.4g} times the distance (u, v) integrate to",
                         _scale_fix(ratio, context, _time_confirmed(t, psi, r))))
    return readings


def _time_confirmed(t: np.ndarray, psi: np.ndarray, r: np.ndarray) -> bool:
    """Whether psi turns by as much as the integral of r over t (the ``heading`` check's gain
    within its tolerance, over a span it judges)."""
    gain, span = heading_gain(t, r, psi)
    return span >= HEADING_MIN_SPAN and abs(gain - 1.0) <= HEADING_GAIN_TOLERANCE


def _scale_fix(ratio: float, context, time_confirmed: bool) -> str:
    """The fix of a track ``ratio`` times the integrated (u, v); ``time_confirmed`` when the
    yaw rate's integral over t turns psi by as much as psi turns (so t is in seconds)."""
    speed_bare = context.unit("u") in (None, "m/s")
    if _near(ratio, _KNOT) and speed_bare:
        return "u and v look like knots, so write the headers as 'u [kn]' and 'v [kn]'"
    if _near(ratio, 1 / 3.6) and speed_bare:
        return "u and v look like km/h, so write the headers as 'u [km/h]' and 'v [km/h]'"
    if _near(ratio, 1e-3):
        position_bare = all(context.unit(name) in (None, "m") for name in ("x", "y"))
        if position_bare and time_confirmed:
            return ("t agrees with psi and r, so x and y look like km: write the headers as "
                    "'x [km]' and 'y [km]'")
        if context.unit("t") in (None, "s"):
            return "the times look like milliseconds, so write the header as 't [ms]'"
    return "check the units of t, u, v, x and y"

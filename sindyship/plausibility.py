"""Plausibility of a measurement record on load: do its channels tell one consistent story?

:func:`check_record` runs on the SI values of every record that
:func:`sindyship.measurements.read_csv` and :func:`~sindyship.measurements.trajectory_from_frame`
load (docs/measurement-csv.md).  Each check compares channels
that must agree by kinematics alone, so a record in the wrong unit, axis or sign is refused
with one sentence that names the source, the check, the numbers and the fix, instead of being
fitted silently.  A check a user knows to be wrong for their data is switched off by name
(``skip_checks=["heading"]``, or ``"all"``); every refusal lists the names.

The checks, in the order they run, with their thresholds (module constants) and why:

``motion``
    Refuses a record in which u, v and r are zero and x, y never change (no more than
    ``MOTION_TOLERANCE`` = 1e-9 in SI): an export of an empty logger channel, nothing to fit.
``sampling`` (only with a ship)
    Compares the median time step dt and the duration with the ship's time scale L/U0.  Refuses
    dt > ``MAX_STEP`` = 1 L/U0 (a record that coarse cannot resolve the yaw response, which takes
    a fraction of L/U0; logged trials sample at 0.003 to 0.05 L/U0), dt < ``MIN_STEP`` = 1e-5 L/U0
    (faster than any logger: 100 kHz for a 7 m model) and a duration above ``MAX_DURATION`` =
    1e5 L/U0 (more than 20 days of a KCS at full speed).  Time in milliseconds under a bare
    ``t`` header trips the first or the last (1 s sampling: dt = 54 L/U0 for the KCS).
``heading``
    Integrates r from psi[0] (cumulative trapezoid) and compares it with psi.  First, jumps of
    psi by more than pi in one step (no ship turns that fast) are wrap-arounds when, less the
    turn the yaw rate explains, they are within ``WRAP_TOLERANCE`` = 0.5 rad of a multiple of
    2 pi: psi is unwrapped and a
    one-line note is returned (and warned by the reader); other jumps are refused (a jump of
    about 360 under a bare header is a heading in degrees wrapped at +-180).  When the
    integral of r spans at least ``HEADING_MIN_SPAN`` = 0.1 rad (6 deg), the least-squares gain
    of psi - psi[0] on that integral must lie within ``HEADING_GAIN_TOLERANCE`` = 0.25 of 1:
    a heading in degrees under a bare header gives 57.3, a flipped sign -1, a yaw rate in
    deg/s under a bare header 0.017, time in milliseconds 0.001; good records give 1 to
    within 0.015 (noise) and 0.05 (the MARIN records).  A record that barely turns must keep
    psi within ``HEADING_MAX_DRIFT`` = 0.35 rad (20 deg) of the integral of r.
``frame``
    Integrates (u, v) rotated by psi, d(x, y)/dt = R(psi) (u, v) with x north, y east, psi
    clockwise from north and v to starboard, over ``FRAME_SEGMENTS`` = 32 consecutive
    segments of the record, and compares each segment's displacement with the recorded one.
    The misfit (sum of the vector differences over the sum of the recorded displacements) must
    not exceed ``FRAME_TOLERANCE`` = 0.1.  Integrating over segments of tens of samples makes
    the check deaf to noise: five times 0.5 m on x, y and 1 % on u, v give at most 0.011 on
    the KCS protocol; the real MARIN records give at most 0.025 (positions rounded to 10 m).
    Spoilt records: earth-fixed (u, v) give 0.27 or more once the heading changes, knots 0.94,
    milliseconds 999; v positive to port gives 0.085 to 0.23, so it is caught in most turning
    records but not all.  A ship heading due north without turning cannot show any of these.
    A current does not matter: recorded u, v and x, y are both over ground.  When the misfit
    is too large the message names the reading that fits: (u, v) earth-fixed (no rotation),
    v positive to port, x and y swapped, psi anticlockwise, psi in degrees, or a scale factor
    matching a unit (within ``UNIT_MATCH`` = 20 %): knots for m/s, km/h, milliseconds.
``speed`` (only with a ship)
    Refuses a largest u (averaged over 5 samples against noise) above ``MAX_SPEED_RATIO`` =
    1.6 U0: no ship on trials runs 60 % above its design speed (good records reach 1.0 to
    1.1 U0, with noise or a current); knots under a m/s header read 1.94 U0.
``revolutions`` (only with a ship that has a propeller, and records with ``n``)
    Refuses a median n above ``MAX_REVOLUTION_RATIO`` = 5 times the ship's propeller
    revolutions: rpm under a bare header read 60 times too high (91.5 rpm of the full-scale
    KVLCC2 pass the reader's absolute limit of 100 rps).
``forward-speed``
    Refuses u <= 0 at every sample: the models describe a ship going ahead.
``rudder-sign``
    A positive rudder turns the ship to starboard: each rudder column (``delta``, ``delta_c``)
    the motion contradicts is refused by name (:mod:`sindyship.rudder_sign`: held over while
    the ship turned half a circle the other way, or a yaw acceleration that follows it with
    the opposite sign, ``RUDDER_SIGN_T`` = 5 standard errors below zero).

Decimal-comma files are recognised by the reader itself (:mod:`sindyship.measurements`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping

import numpy as np

from sindyship.errors import SindyshipInputError
from sindyship.rudder_sign import (
    against_rudder,
)

__all__ = [
    "CHECKS",
    "FRAME_SEGMENTS",
    "GAP_STEPS",
    "FRAME_TOLERANCE",
    "HEADING_GAIN_TOLERANCE",
    "HEADING_MAX_DRIFT",
    "HEADING_MIN_SPAN",
    "MAX_DURATION",
    "MAX_REVOLUTION_RATIO",
    "excess_revolutions",
    "MAX_SPEED_RATIO",
    "MAX_STEP",
    "MIN_STEP",
    "MOTION_TOLERANCE",
    "UNIT_MATCH",
    "WRAP_TOLERANCE",
    "check_record",
    "frame_misfit",
    "heading_gain",
    "resampling_gap_note",
    "resolve_skip",
]

#: Names of the checks, in the order they run.
CHECKS = ("motion", "sampling", "heading", "frame", "speed", "revolutions", "forward-speed",
          "rudder-sign")

MOTION_TOLERANCE = 1e-9
MAX_STEP = 1.0  # L/U0
MIN_STEP = 1e-5  # L/U0
MAX_DURATION = 1e5  # L/U0
WRAP_TOLERANCE = 0.5  # rad
HEADING_MIN_SPAN = 0.1  # rad
HEADING_GAIN_TOLERANCE = 0.25
HEADING_MAX_DRIFT = 0.35  # rad
FRAME_SEGMENTS = 32
FRAME_TOLERANCE = 0.1
UNIT_MATCH = 0.2
MAX_SPEED_RATIO = 1.6  # of U0
#: Most a record's median propeller revolutions may exceed the ship's own (a ratio): rpm read
#: as rps are 60 times too high.
MAX_REVOLUTION_RATIO = 5.0


_KNOT = 1852.0 / 3600.0

Rows = Callable[[int], str]


def resolve_skip(skip: str | Iterable[str] | None) -> frozenset[str]:
    """The set of check names to skip: ``"all"``, one name, or an iterable of names.

    Examples
    --------
    >>> sorted(resolve_skip(["frame", "heading"]))
    ['frame', 'heading']
    >>> len(resolve_skip("all")) == len(CHECKS)
    True
    """
    if skip is None:
        return frozenset()
    names = [skip] if isinstance(skip, str) else list(skip)
    if "all" in names:
        return frozenset(CHECKS)
    unknown = [name for name in names if name not in CHECKS]
    if unknown:
        raise SindyshipInputError(
            f"unknown plausibility check {unknown[0]!r}; choose from {', '.join(CHECKS)} "
            "or 'all'."
        )
    return frozenset(names)


def check_record(
    si: Mapping[str, np.ndarray],
    headers: Mapping[str, tuple[str, str | None]],
    *,
    source: str = "<data>",
    ship=None,
    skip: Iterable[str] = (),
    row: Rows | None = None,
) -> tuple[dict[str, np.ndarray], list[str]]:
    """Run the plausibility checks (module docstring) on a record in SI units.

    Parameters
    ----------
    si : mapping of str to ndarray
        The channels by bare name, SI units, time already checked to increase.
    headers : mapping of str to (str, str or None)
        For each channel, its header as written and the unit it gave (None for a bare header).
    source : str
        What to call the record in messages.
    ship : Ship, optional
        Enables the checks scaled by L and U0 (``sampling``, ``speed``).
    skip : iterable of str
        Names of checks not to run (see :data:`CHECKS`).
    row : callable, optional
        Names sample ``i`` for a message (``"row 7 (counting the header as row 1)"``).

    Returns
    -------
    (dict, list of str)
        The channels (``psi`` unwrapped where it wrapped) and the notes made on the way.

    Raises
    ------
    SindyshipInputError
        One sentence naming the source, the check, the numbers and the fix.
    """
    data = {name: np.asarray(values, dtype=float) for name, values in si.items()}
    context = _Context(source, headers, row or (lambda i: f"sample {i}"))
    notes: list[str] = []
    if "motion" not in skip:
        _check_motion(data, context)
    if ship is not None and "sampling" not in skip:
        _check_sampling(data["t"], ship, context)
    if "heading" not in skip:
        data["psi"], note = _unwrap_heading(data, context)
        if note:
            notes.append(note)
        _check_heading(data, context)
    if "frame" not in skip:
        _check_frame(data, context)
    if ship is not None and "speed" not in skip:
        _check_speed(data["u"], ship, context)
    if ship is not None and "revolutions" not in skip and "n" in data:
        _check_revolutions(data["n"], ship, context)
    if "forward-speed" not in skip:
        _check_forward_speed(data["u"], context)
    if "rudder-sign" not in skip:
        _check_rudder_sign(data, context)
    return data, notes


class _Context:
    def __init__(self, source: str, headers, row: Rows):
        self.source = source
        self.headers = headers
        self.row = row

    def header(self, name: str) -> str:
        return self.headers.get(name, (name, None))[0]

    def unit(self, name: str) -> str | None:
        return self.headers.get(name, (name, None))[1]

    def refuse(self, check: str, problem: str, fix: str) -> None:
        raise SindyshipInputError(
            f"{self.source}: the {check} check refuses the record: {problem}; {fix} (or, if "
            f"the values are right, skip the check: --skip-check {check} on the command line, "
            f"skip_checks=['{check}'] in Python; the checks are {', '.join(CHECKS)})."
        )


# ---------------------------------------------------------------------------------------------
# motion, sampling, speed


def _check_motion(data, context: _Context) -> None:
    speed = max(float(np.max(np.abs(data[name]))) for name in ("u", "v", "r"))
    travel = max(float(np.ptp(data[name])) for name in ("x", "y"))
    if speed <= MOTION_TOLERANCE and travel <= MOTION_TOLERANCE:
        context.refuse(
            "motion",
            "u, v and r are zero and x, y never change, so the record holds no motion",
            "give a record of the ship under way",
        )


def _check_sampling(t: np.ndarray, ship, context: _Context) -> None:
    tau = ship.time_scale
    step = float(np.median(np.diff(t)))
    duration = float(t[-1] - t[0])
    header = context.header("t")
    scale = f"the ship's time scale L/U0 = {tau:.3g} s"
    if step > MAX_STEP * tau or duration > MAX_DURATION * tau:
        in_ms = context.unit("t") in (None, "s") and MIN_STEP <= step / 1000 / tau <= MAX_STEP
        context.refuse(
            "sampling",
            f"column '{header}' steps by {step:.4g} s over {duration:.4g} s, {step / tau:.3g} "
            f"and {duration / tau:.3g} times {scale}",
            "the times look like milliseconds, so write the header as 't [ms]'"
            if in_ms else "check the unit of t and that the ship is the one measured",
        )
    if step < MIN_STEP * tau:
        context.refuse(
            "sampling",
            f"column '{header}' steps by {step:.3g} s, {step / tau:.2g} times {scale}, faster "
            "than any logger samples",
            "check the values of t and give their unit in the header, e.g. 't [ms]'",
        )


def _check_speed(u: np.ndarray, ship, context: _Context) -> None:
    window = min(5, len(u))
    high = float(np.max(np.convolve(u, np.full(window, 1.0 / window), mode="valid")))
    ratio = high / ship.U0
    if ratio <= MAX_SPEED_RATIO:
        return
    knots = context.unit("u") in (None, "m/s") and ratio * _KNOT <= MAX_SPEED_RATIO
    context.refuse(
        "speed",
        f"column '{context.header('u')}' reaches {high:.4g} m/s (averaged over 5 samples), "
        f"{ratio:.3g} times the ship's design speed U0 = {ship.U0:.4g} m/s",
        "the values look like knots, so write the headers as 'u [kn]' and 'v [kn]'"
        if knots else "check the unit of u and that the ship (full or model scale) is right",
    )


def excess_revolutions(typical: float, ship) -> tuple[float, bool] | None:
    """``(ratio, rpm)`` where revolutions of size ``typical`` [rps] are more than
    :data:`MAX_REVOLUTION_RATIO` times the ship's propeller revolutions: the ratio, and whether
    they would fit as rpm (60 times smaller); None where they do not exceed it, or the ship
    file gives no revolutions to compare with (one for identification only).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> excess_revolutions(2.0, kcs) is None
    True
    >>> ratio, rpm = excess_revolutions(116.0, kcs)
    >>> round(ratio), rpm
    (60, True)
    """
    if not ship.has_mmg:
        return None
    ratio = abs(typical) / ship.propeller.n_P
    if ratio <= MAX_REVOLUTION_RATIO:
        return None
    return ratio, ratio / 60.0 <= MAX_REVOLUTION_RATIO


def _check_revolutions(n: np.ndarray, ship, context: _Context) -> None:
    """Propeller revolutions far above the ship's own: rpm under a bare ``n`` header (which
    the reader's absolute limit cannot tell from rps at full scale)."""
    typical = float(np.median(np.abs(n)))
    excess = excess_revolutions(typical, ship)
    if excess is None:
        return
    (ratio, looks_rpm), own = excess, ship.propeller.n_P
    rpm = context.unit("n") is None and looks_rpm
    context.refuse(
        "revolutions",
        f"column '{context.header('n')}' has a median of {typical:.4g}, {ratio:.3g} times the "
        f"ship's propeller revolutions n = {own:.4g} rps",
        "the values look like rpm, so write the header as 'n [rpm]'" if rpm else
        "check the unit of n and that the ship (full or model scale) is right",
    )


def _check_forward_speed(u: np.ndarray, context: _Context) -> None:
    if np.max(u) <= 0.0:
        context.refuse(
            "forward-speed",
            f"column '{context.header('u')}' is never positive (at most {np.max(u):.4g} m/s)",
            "u is the surge speed, positive ahead: check its sign and that the ship is under way",
        )


def _check_rudder_sign(data, context: _Context) -> None:
    """A positive rudder angle turns the ship to starboard: a rudder column (each one recorded)
    held over while the ship turned half a circle the other way, or whose yaw acceleration
    follows it with the opposite sign, has its sign flipped."""
    for name in [n for n in ("delta", "delta_c") if n in data]:
        problem = against_rudder(data[name], data["r"], data["t"], context.header(name))
        if problem is not None:
            context.refuse("rudder-sign", problem, f"sindyship takes a positive rudder angle to "
                           f"turn the ship to starboard (r > 0): check the sign convention of "
                           f"'{context.header(name)}' and negate it if it is flipped")


# ---------------------------------------------------------------------------------------------
# heading


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


def _unwrap_heading(data, context: _Context) -> tuple[np.ndarray, str | None]:
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
        f"{context.source}: column '{context.header('psi')}' wraps around {jumps.size} "
        f"time{'s' if jumps.size > 1 else ''}, first into {context.row(int(jumps[0]) + 1)}; "
        "unwrapped it (psi must be continuous)."
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


def _check_heading(data, context: _Context) -> None:
    psi_header, r_header = context.header("psi"), context.header("r")
    gain, span = heading_gain(data["t"], data["r"], data["psi"])
    if span < HEADING_MIN_SPAN:
        drift = float(np.max(np.abs(data["psi"] - data["psi"][0] - _yaw_integral(data))))
        if drift > HEADING_MAX_DRIFT:
            context.refuse(
                "heading",
                f"column '{psi_header}' strays {drift:.3g} rad from the integral of "
                f"'{r_header}', which turns the ship by at most {span:.3g} rad",
                "check that psi is in rad (else write 'psi [deg]') and belongs with r",
            )
        return
    if abs(gain - 1.0) <= HEADING_GAIN_TOLERANCE:
        return
    problem = (
        f"column '{psi_header}' changes {gain:.4g} times as much as the integral of "
        f"'{r_header}' from psi[0] (expected 1 +- {HEADING_GAIN_TOLERANCE})"
    )
    if _near(gain, 180.0 / math.pi) and context.unit("psi") is None:
        fix = "the heading looks like degrees, so write the header as 'psi [deg]'"
    elif _near(gain, math.pi / 180.0) and context.unit("r") is None:
        fix = "the yaw rate looks like deg/s, so write the header as 'r [deg/s]'"
    elif _near(gain, 1e-3) and context.unit("t") in (None, "s"):
        fix = "the times look like milliseconds, so write the header as 't [ms]'"
    elif _near(gain, -1.0):
        fix = ("psi and r turn opposite ways: psi is clockwise from north and r positive to "
               "starboard, so negate the one with the wrong sign")
    else:
        fix = "check the units and signs of psi and r"
    context.refuse("heading", problem, fix)


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


def _check_frame(data, context: _Context) -> None:
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
    readings = _frame_readings(t, psi, body, recorded, predicted, edges, context)
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


def _frame_readings(t, psi, body, recorded, predicted, edges, context: _Context):
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
                         _scale_fix(ratio, context)))
    return readings


def _scale_fix(ratio: float, context: _Context) -> str:
    speed_bare = context.unit("u") in (None, "m/s")
    if _near(ratio, _KNOT) and speed_bare:
        return "u and v look like knots, so write the headers as 'u [kn]' and 'v [kn]'"
    if _near(ratio, 1 / 3.6) and speed_bare:
        return "u and v look like km/h, so write the headers as 'u [km/h]' and 'v [km/h]'"
    if _near(ratio, 1e-3) and context.unit("t") in (None, "s"):
        return "the times look like milliseconds, so write the header as 't [ms]'"
    return "check the units of t, u, v, x and y"


#: A stretch without samples longer than this many median steps (and than the resampling
#: step) is a gap that resampling bridges with a straight line, which the reader is told.
GAP_STEPS = 5.0


def resampling_gap_note(t: np.ndarray, step: float, source: str) -> str | None:
    """The note that resampling bridges the record's longest gap (None when it has none)."""
    if t.size < 3:
        return None
    steps = np.diff(t)
    longest = int(np.argmax(steps))
    median = float(np.median(steps))
    if steps[longest] <= max(GAP_STEPS * median, step):
        return None
    return (f"{source}: no sample between t = {t[longest]:.6g} s and {t[longest + 1]:.6g} s "
            f"({steps[longest]:.3g} s, {steps[longest] / median:.0f} times the median step); "
            "resampling interpolates straight across it, so rows are probably missing there.")

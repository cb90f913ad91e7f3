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
    1.1 U0, with noise or a current); knots under a m/s header read 1.94 U0.  A record with
    revolutions above the ship's own raises the limit in proportion (the KVLCC2 simulated at
    its published revolutions runs at 1.51 U0, with 10 % more at 1.67 U0), by at most
    ``MAX_HARDER`` = 1.2 (knots at U0 still read above it).
``revolutions`` (only with a ship that has a propeller, and records with ``n``)
    Refuses a median n above ``MAX_REVOLUTION_RATIO`` = 5 times the ship's propeller
    revolutions: rpm under a bare header read 60 times too high (91.5 rpm of the full-scale
    KVLCC2 pass the reader's absolute limit of 100 rps); and a largest n below
    ``MIN_REVOLUTION_RATIO`` = 0.1 times them, unless n is zero throughout (a stopped
    propeller): rps under an ``n [rpm]`` header read 60 times too low.
``forward-speed``
    Refuses u <= 0 at every sample: the models describe a ship going ahead.
``rudder-sign``
    A positive rudder turns the ship to starboard: each rudder column (``delta``, ``delta_c``)
    the motion contradicts is refused by name (:mod:`sindyship.rudder_sign`: held over while
    the ship turned half a circle the other way, or a yaw acceleration that follows it with
    the opposite sign, ``RUDDER_SIGN_T`` = 5 standard errors below zero).
``rudder-size`` (only with a ship)
    Refuses a rudder column whose largest angle [rad] times ``MAX_YAW_PER_RUDDER`` = 20 stays
    below the yaw rate r L/U0 the ship reaches to both sides (the smaller of the largest
    5-sample means to starboard and to port) while the yaw acceleration follows it
    (:func:`sindyship.rudder_sign.yaw_follows_rudder` above ``RUDDER_SIGN_T``): radians under
    a degree header read 57 times too small (a 20/20 zig-zag of the KCS reads 0.35 deg against
    r' = 0.33 to both sides).  A ship turning to one side is not judged (a turning circle, or
    an unstable ship in its loop with a small rudder), nor a pull-out with the rudder
    amidships, which the yaw does not follow.
``jumps`` (only with a ship; a note, never a refusal)
    Notes samples of u or v that change faster than a ship accelerates: a sample whose distance
    from the running median of ``2 JUMP_NEIGHBOURS + 1`` = 7 samples (mirrored at the ends)
    exceeds ``JUMP_NOISE`` = 10 times the channel's noise (the robust spread of its steps) and
    ``JUMP_SPEED`` = 0.1 U0 plus the change an acceleration of ``JUMP_ACCELERATION`` =
    1 U0^2/L makes in one sample interval; or a change over at most ``JUMP_WINDOW`` = 0.1 L/U0
    (a ramp, or a plateau too wide for the median; judged over at most ``JUMP_MOST_LAGS`` = 50
    intervals spread across the window) beyond the same bounds over its own time.  A record of
    fewer than 7 samples is not judged.  Ships accelerate far more slowly: the
    KCS and KVLCC2 protocols and the simulated trials from rest reach 0.12 to 0.25 U0^2/L, and
    no good record of ``benchmarks/bench_plausibility.py`` is noted (5 % noise, a current,
    the protocol sampled every 0.25 to 0.95 L/U0, the simulated trials from rest).  The MARIN
    35 deg turn to starboard (``tc_-35``) ends with v ramping from -0.1 to -2.48 m/s in its
    last 2 s (6.6 U0^2/L), which the 1 s grid makes one sample leaping away by 0.28 U0.  The
    samples are used as recorded, so the note names them (those within the window of the
    record's start or end to it) and says to delete the rows at an end, or to correct them
    in between (a record with rows missing is irregular, refused unless resampled).

Decimal-comma files are recognised by the reader itself (:mod:`sindyship.measurements`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping

import numpy as np

from sindyship.errors import SindyshipInputError
from sindyship.jump_checks import (
    JUMP_ACCELERATION,
    JUMP_MOST_LAGS,
    JUMP_NEIGHBOURS,
    JUMP_NOISE,
    JUMP_SPEED,
    JUMP_WINDOW,
    JumpNote,
    jump_notes,
    sample_jumps,
)
from sindyship.kinematics_checks import (
    _KNOT,
    FRAME_SEGMENTS,
    FRAME_TOLERANCE,
    HEADING_GAIN_TOLERANCE,
    HEADING_MAX_DRIFT,
    HEADING_MIN_SPAN,
    UNIT_MATCH,
    WRAP_TOLERANCE,
    check_frame,
    check_heading,
    frame_misfit,
    heading_gain,
    unwrap_heading,
)
from sindyship.rudder_sign import RUDDER_SIGN_T, against_rudder, yaw_follows_rudder
from sindyship.units import unit_factor

__all__ = [
    "CHECKS",
    "FRAME_SEGMENTS",
    "GAP_STEPS",
    "FRAME_TOLERANCE",
    "HEADING_GAIN_TOLERANCE",
    "HEADING_MAX_DRIFT",
    "HEADING_MIN_SPAN",
    "JUMP_ACCELERATION",
    "JUMP_MOST_LAGS",
    "JUMP_NEIGHBOURS",
    "JUMP_NOISE",
    "JUMP_SPEED",
    "JUMP_WINDOW",
    "JumpNote",
    "MAX_DURATION",
    "MAX_REVOLUTION_RATIO",
    "MAX_YAW_PER_RUDDER",
    "MIN_REVOLUTION_RATIO",
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
    "sample_jumps",
]

#: Names of the checks, in the order they run.
CHECKS = ("motion", "sampling", "heading", "frame", "speed", "revolutions", "forward-speed",
          "rudder-sign", "rudder-size", "jumps")

MOTION_TOLERANCE = 1e-9
MAX_STEP = 1.0  # L/U0
MIN_STEP = 1e-5  # L/U0
MAX_DURATION = 1e5  # L/U0
MAX_SPEED_RATIO = 1.6  # of U0
#: Most the speed limit is raised for revolutions recorded above the ship's own (a factor):
#: 1.6 x 1.2 = 1.92 U0 stays below the 1.94 U0 that knots at U0 read as m/s give.
MAX_HARDER = 1.2
#: Most a record's median propeller revolutions may exceed the ship's own (a ratio): rpm read
#: as rps are 60 times too high.
MAX_REVOLUTION_RATIO = 5.0
#: Least share of the ship's propeller revolutions a record's largest n must reach when it is
#: not zero throughout: rps under an rpm header read 60 times too low.
MIN_REVOLUTION_RATIO = 0.1
#: Most the yaw rate r L/U0 a record reaches to both sides may be per radian of its largest
#: rudder angle when its yaw acceleration follows the rudder: radians under a degree header
#: read 57 times too small (the KCS protocol's zig-zags give 0.66 to 1.1).
MAX_YAW_PER_RUDDER = 20.0


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
        data["psi"], note = unwrap_heading(data, context)
        if note:
            notes.append(note)
        check_heading(data, context)
    if "frame" not in skip:
        check_frame(data, context)
    if ship is not None and "speed" not in skip:
        _check_speed(data["u"], ship, context, data.get("n"))
    if ship is not None and "revolutions" not in skip and "n" in data:
        _check_revolutions(data["n"], ship, context)
        _check_too_few_revolutions(data["n"], ship, context)
    if "forward-speed" not in skip:
        _check_forward_speed(data["u"], context)
    if "rudder-sign" not in skip:
        _check_rudder_sign(data, context)
    if ship is not None and "rudder-size" not in skip:
        _check_rudder_size(data, ship, context)
    if ship is not None and "jumps" not in skip:
        notes += jump_notes(data, ship, context)
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

    def factor(self, name: str) -> float:
        """The factor to SI of the unit the header gave (1 for a bare header)."""
        unit = self.unit(name)
        return 1.0 if unit is None else unit_factor(name, self.header(name), unit, self.source)

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


def _five_sample_mean(values: np.ndarray) -> np.ndarray:
    """Running means of five consecutive samples (fewer in a shorter record): the largest
    speed or yaw rate a check judges, noise averaged."""
    window = min(5, len(values))
    return np.convolve(values, np.full(window, 1.0 / window), mode="valid")


def _check_speed(u: np.ndarray, ship, context: _Context, n: np.ndarray | None) -> None:
    """The largest u against ``MAX_SPEED_RATIO`` U0, a limit raised in proportion to
    revolutions recorded above the ship's own (a ship driven harder runs faster)."""
    high = float(np.max(_five_sample_mean(u)))
    ratio = high / ship.U0
    harder = 1.0
    if n is not None and ship.has_mmg:  # at most MAX_HARDER: knots at U0 still read 1.94 U0
        harder = min(max(1.0, float(np.max(np.abs(n))) / ship.propeller.n_P), MAX_HARDER)
    if ratio <= MAX_SPEED_RATIO * harder:
        return
    knots = (context.unit("u") in (None, "m/s")
             and ratio * _KNOT <= MAX_SPEED_RATIO * harder)
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


def _check_too_few_revolutions(n: np.ndarray, ship, context: _Context) -> None:
    """Propeller revolutions that never reach a tenth of the ship's own although they turn:
    rps under an ``n [rpm]`` header (a stopped propeller, n = 0 throughout, passes)."""
    if not ship.has_mmg:
        return  # a ship file for identification only gives no revolutions
    largest, own = float(np.max(np.abs(n))), ship.propeller.n_P
    if largest == 0.0 or largest >= MIN_REVOLUTION_RATIO * own:
        return
    rps = context.factor("n") == 1.0 / 60.0 and largest * 60.0 >= MIN_REVOLUTION_RATIO * own
    context.refuse(
        "revolutions",
        f"column '{context.header('n')}' never exceeds {largest:.4g} rps, "
        f"{largest / own:.2g} times the ship's propeller revolutions n = {own:.4g} rps",
        "the values look like rps, so write the header as 'n [rps]' or a bare 'n'" if rps else
        "check the unit of n and that the ship (full or model scale) is right",
    )


def _check_rudder_size(data, ship, context: _Context) -> None:
    """A rudder column too small for the turning to both sides its yaw acceleration follows:
    radians under a degree header (a zig-zag of 20 deg reads 0.35 deg).  The yaw rate of the
    side turned to less is compared: a directionally unstable ship turns in its loop at
    r' = 0.2 to one side whatever its rudder (the KVLCC2 with 0.3 to 0.7 deg of random rudder
    or a 0.3/10 zig-zag: at most 0.05 to the other side), while a zig-zag turns both ways."""
    mean = _five_sample_mean(data["r"])
    turning = min(float(np.max(mean)), float(-np.min(mean))) * ship.L / ship.U0
    for name in [n for n in ("delta", "delta_c") if n in data]:
        largest = float(np.max(np.abs(data[name])))
        if largest == 0.0 or turning <= MAX_YAW_PER_RUDDER * largest:
            continue
        follows = yaw_follows_rudder(data[name], data["r"], data["t"])
        if not follows > RUDDER_SIGN_T:
            continue  # a pull-out: the ship turns on with the rudder amidships
        degrees = context.factor(name) == math.radians(1.0)
        context.refuse(
            "rudder-size",
            f"column '{context.header(name)}' never exceeds {math.degrees(largest):.3g} deg "
            f"while the ship turns to both sides at up to r' = r L/U0 = {turning:.2g} and its yaw "
            f"acceleration follows the rudder ({follows:.0f} standard errors above zero): no "
            "rudder that small turns a ship that fast",
            "the values look like radians, so write the header as "
            f"'{name} [rad]' or a bare '{name}'" if degrees else
            f"check the unit of '{context.header(name)}'",
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

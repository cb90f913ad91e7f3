"""Trials as logged: find the part of a record a model can fly, and recognise a zig-zag.

A logged trial is rarely the clean record a simulator writes: it starts at rest or at low
speed with the propeller stopped, the helmsman steers by hand before the zig-zag, the rudder
plateaus sit a degree or so off the nominal angle, and the log ends with blank rows.
:func:`underway_window` and :func:`trim` cut a record to the part under way;
:func:`recognise_zigzag` recognises a zig-zag despite a manual lead-in and imperfect plateaus
(the strict recognition that flies zig-zags closed loop is
:func:`sindyship.flights.detect_zigzag`).

Thresholds (module constants) and why:

- ``UNDERWAY_SPEED = 0.25``: under way means the surge speed, averaged over one L/U0, is at
  least 0.25 U0.  A 35 deg turning circle slows the KCS to 0.53 U0 and a full tanker to about
  0.35 U0, so a manoeuvre never drops below it; a ship getting under way passes it early.
- ``STEADY_ACCELERATION = 0.03``: the window starts once the ship no longer speeds up by more
  than 0.03 U0 per L/U0 (slope of a straight line fitted to u over one L/U0), for one L/U0
  on end (a single low sample, such as a dip in u at the first row, does not count).  Getting under
  way takes 0.1 to 0.2 U0 per L/U0; 1 % noise on u moves the fitted slope by about 0.008.
- ``PROPELLER_RUNNING = 0.5``: where ``n`` is recorded the propeller runs when n (averaged
  over one L/U0) is at least half its median while under way.
- Zig-zag: the rudder (commanded if recorded) holds an angle when it stays within a range of
  ``HOLD_RANGE = 1`` deg for at least ``HOLD_SAMPLES = 5`` samples (a rudder turning at
  2.3 deg/s passes any 1 deg band in under 0.5 s at model scale and in one sample at 1 s
  logging).  A plateau is a hold within ``PLATEAU_SPREAD = 2.5`` deg of the amplitude (the
  median magnitude of the holds at least half the largest one).  The zig-zag is the longest
  run of at least three plateaus that alternate in sign; its amplitude and check angle are
  rounded to the nearest multiple of 5 deg when one lies within ``ROUNDING = 1.5`` deg,
  else to 0.1 deg.  The heading change (from the execute) at the rudder reversals must
  agree within ``CHECK_SPREAD = 3`` deg plus the largest yaw rate times the sampling step
  (a reversal falls between two samples), and each must lie at least ``MIN_CHECK = 0.5`` deg
  toward the side the leg's rudder turns the ship (a rudder reversed on the other side, or
  at the execute heading, as random steps of a rudder can be, is no zig-zag's).  A logged
  command's execute is its step to the first plateau (flown from the first sample after it,
  whatever the wheel did before); an actual rudder's is where it left its last hold not on
  its way to the plateau.  An actual rudder logged alone whose holds are fragments (more
  than ``FRAGMENTED_HOLDS = 4`` to a leg) is read in means of consecutive samples first,
  about ``READINGS_PER_LEG = 80`` to a leg (:func:`sindyship.rudder_holds.samples_per_reading`):
  a full-scale servo approaches its angle so slowly that, logged at 20 Hz, every degree on
  the way holds for five samples, and 0.3 deg of noise breaks every hold.  Its readings may
  leave a hold one reading either way of the rudder, so the heading tolerance takes twice
  the reading step.
- Turn: the record holds a rudder angle of at least ``TURN_RUDDER = 5`` deg for at least
  ``TURN_SHARE = 0.25`` of its samples (a spiral's steps last a seventh of it each; a
  turning circle may end in a pull-out); its execute is the last sample at the approach value
  before the rudder moved to the hardest such hold (:func:`recognise_turn`).  A turn from its
  execute is the standard turning test: whatever was steered before (course keeping by hand)
  is not part of it.  A record that starts already turning at ``MID_TURN = 0.25`` of its
  largest yaw rate or more (a time range cut after the execute) holds no execute, and no turn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from sindyship.errors import SindyshipInputError
from sindyship.rudder_holds import (
    HOLD_RANGE,
    HOLD_SAMPLES,
    back_to_peak,
    cut_short,
    execute,
    find_holds,
    left_hold,
    longest_alternation,
    ramp_start,
    read_in_blocks,
    reversals,
    samples_per_reading,
    settled,
)
from sindyship.trajectory import Trajectory

__all__ = [
    "FlightStart",
    "detect_zigzag",
    "flight_start",
    "recognised_zigzag",
    "UNDERWAY_SPEED",
    "STEADY_ACCELERATION",
    "PROPELLER_RUNNING",
    "Turn",
    "Window",
    "ZigZag",
    "explain_zigzag",
    "recognise_turn",
    "recognise_zigzag",
    "zigzag_command",
    "zigzag_levels",
    "zigzag_to_fly",
    "trim",
    "underway_window",
]

UNDERWAY_SPEED = 0.25  # of U0
STEADY_ACCELERATION = 0.03  # U0 per L/U0
PROPELLER_RUNNING = 0.5  # of the median n under way
PLATEAU_SPREAD = 2.5  # deg
ROUNDING = 1.5  # deg
CHECK_SPREAD = 3.0  # deg
TURN_RUDDER = 5.0  # deg
TURN_SHARE = 0.25
#: A record whose first sample turns faster than this share of its fastest starts in a turn.
MID_TURN = 0.25
#: Least heading change [deg] toward a leg's side at which a zig-zag's rudder reverses.
MIN_CHECK = 0.5


class Window(NamedTuple):
    """The part of a record under way: ``start`` and ``stop`` times [s] and why."""

    start: float
    stop: float
    reason: str


class Turn(NamedTuple):
    """A recognised turn: the rudder angle it holds [deg] and its execute [s]."""

    rudder_deg: float
    start_time: float


class ZigZag(NamedTuple):
    """A recognised zig-zag: amplitude and check angle [deg], first rudder sign, execute [s]."""

    amplitude_deg: float
    check_deg: float
    first_sign: int
    start_time: float


def _samples(record: Trajectory, ship) -> int:
    """An odd number of samples spanning about one L/U0."""
    count = int(round(ship.time_scale / record.dt))
    count = max(1, min(count, record.n_samples))
    return count if count % 2 else max(1, count - 1)


def _moving_mean(values: np.ndarray, count: int) -> np.ndarray:
    half = count // 2
    padded = np.pad(values, half, mode="edge")
    return np.convolve(padded, np.full(count, 1.0 / count), mode="valid")


def _moving_slope(t: np.ndarray, values: np.ndarray, count: int) -> np.ndarray:
    """Slope of a straight line fitted over ``count`` samples centred on each sample."""
    half = count // 2
    if half == 0:
        return np.gradient(values, t)
    offsets = np.arange(-half, half + 1, dtype=float)
    padded = np.pad(values, half, mode="edge")
    step = float(np.median(np.diff(t)))
    return np.convolve(padded, offsets[::-1], mode="valid") / (np.sum(offsets**2) * step)


def underway_window(record: Trajectory, ship) -> Window:
    """The part of ``record`` a model can fly: under way, propeller running, not from rest.

    Parameters
    ----------
    record : Trajectory
        A record in SI units (as :func:`sindyship.measurements.read_csv` returns it).
    ship : Ship or str
        The ship measured (its L/U0 sets the averaging window, its U0 the speed threshold).

    Returns
    -------
    Window
        ``(start, stop, reason)``: times [s] of the first and last sample of the longest
        stretch under way, the start moved past any speeding up (module docstring).

    Raises
    ------
    SindyshipInputError
        When the ship is never under way.

    Examples
    --------
    >>> import pandas as pd
    >>> t = np.arange(400.0)
    >>> u = np.clip((t - 100.0) / 100.0, 0.0, 1.0) * 12.348
    >>> frame = pd.DataFrame({"t": t, "u": u, "v": 0.0, "r": 0.0, "x": np.cumsum(u), "y": 0.0,
    ...                       "psi": 0.0, "delta": 0.0})
    >>> start, stop, reason = underway_window(Trajectory(frame, "run"), "kcs")
    >>> 200.0 <= start <= 210.0, stop
    (True, 399.0)
    """
    ship = _as_ship(ship)
    t, count = record.t, _samples(record, ship)
    speed = _moving_mean(record["u"], count) / ship.U0
    underway = speed >= UNDERWAY_SPEED
    running = np.ones_like(underway)
    n_text = ""
    if record.has("n") and underway.any():
        n = _moving_mean(record["n"], count)
        reference = float(np.median(n[underway]))
        running = n >= PROPELLER_RUNNING * reference
        n_text = f", n >= {PROPELLER_RUNNING:g} x {reference:.3g} rps"
    usable = underway & running
    if not usable.any():
        raise SindyshipInputError(
            f"{record.name or '<data>'}: the ship is never under way (u averaged over L/U0 "
            f"stays below {UNDERWAY_SPEED:g} U0 = {UNDERWAY_SPEED * ship.U0:.3g} m/s"
            f"{' or the propeller is stopped' if n_text else ''}); give a record under way."
        )
    first, last = _longest_run(usable)
    slope = _moving_slope(t, record["u"], count) * ship.time_scale / ship.U0
    begin = _steady_from(slope[first:last + 1], count) + first
    ends = "at the end of the record" if last == len(t) - 1 else (
        "where the propeller slows" if not running[last + 1] else "where the ship slows")
    reason = (
        f"under way (u >= {UNDERWAY_SPEED:g} U0{n_text}) from t = {t[first]:.6g} s, no longer "
        f"speeding up (< {STEADY_ACCELERATION:g} U0 per L/U0) from t = {t[begin]:.6g} s, "
        f"until t = {t[last]:.6g} s {ends}"
    )
    return Window(float(t[begin]), float(t[last]), reason)


def _steady_from(slope: np.ndarray, count: int) -> int:
    """The first sample from which the slope stays at most :data:`STEADY_ACCELERATION` for
    ``count`` samples (one L/U0): a single low sample (a dip in u at the first row) does not
    end the speeding up; the last sample when it never settles."""
    steady = (slope <= STEADY_ACCELERATION).astype(int)
    if len(steady) <= count:
        return int(np.argmax(steady)) if steady.any() else max(len(steady) - 1, 0)
    runs = np.convolve(steady, np.ones(count, dtype=int), mode="valid")
    settled = np.flatnonzero(runs == count)
    return int(settled[0]) if settled.size else len(steady) - 1


def trim(record: Trajectory, window: Window | tuple[float, float]) -> Trajectory:
    """The samples of ``record`` with ``start <= t <= stop``, times and channels unchanged.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0, 2.0, 3.0], "u": 1.0})
    >>> trim(Trajectory(frame, "run"), (1.0, 2.0))["t"].tolist()
    [1.0, 2.0]
    """
    start, stop = float(window[0]), float(window[1])
    t = record.t
    keep = (t >= start - 1e-9) & (t <= stop + 1e-9)
    data = record.data.loc[keep].reset_index(drop=True)
    return Trajectory(data, name=record.name, meta={**record.meta, "trimmed": (start, stop)})


def _longest_run(mask: np.ndarray) -> tuple[int, int]:
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    best = int(np.argmax(stops - starts))
    return int(starts[best]), int(stops[best])


def _as_ship(ship):
    if isinstance(ship, str):
        from sindyship.ships import load_ship

        return load_ship(ship)
    return ship


# ---------------------------------------------------------------------------------------------
# zig-zag recognition


def recognise_zigzag(record: Trajectory) -> ZigZag | None:
    """``(amplitude_deg, check_deg, first_sign, start_time)`` of a zig-zag, else None.

    Tolerates a manual lead-in before the zig-zag and plateaus a degree or two off the
    nominal angle (module docstring); :func:`explain_zigzag` says why a record is not one.

    Examples
    --------
    >>> from sindyship import MMGModel, Manoeuvre, fly, load_ship
    >>> plan = [Manoeuvre("zigzag", rudder=20, check=20, duration=600)]
    >>> (run,) = fly(MMGModel(load_ship("kcs")), plan)
    >>> recognise_zigzag(run)
    ZigZag(amplitude_deg=20.0, check_deg=20.0, first_sign=1, start_time=0.0)
    """
    return explain_zigzag(record)[0]


def recognise_turn(record: Trajectory) -> Turn | None:
    """``(rudder_deg, start_time)`` of a turn (module docstring), else None.

    Examples
    --------
    >>> import pandas as pd
    >>> t = np.arange(100.0)
    >>> delta = np.where(t < 40.0, 0.002 * np.sin(t), np.radians(np.minimum(35.0, t - 39.0)))
    >>> frame = pd.DataFrame({"t": t, "u": 1.0, "v": 0.0, "r": 0.0, "x": t, "y": 0.0,
    ...                       "psi": 0.0, "delta": delta})
    >>> recognise_turn(Trajectory(frame, "tc"))
    Turn(rudder_deg=35.0, start_time=39.0)
    """
    command = np.degrees(record["delta_c"] if record.has("delta_c") else record.rudder)
    n = len(command)
    holds = [h for h in find_holds(command)
             if abs(h[2]) >= TURN_RUDDER and (h[1] - h[0] + 1) >= TURN_SHARE * n]
    if not holds:
        return None
    first, _, level = max(holds, key=lambda h: abs(h[2]))  # a helmsman's wheel is gentler
    sign = int(np.sign(level))
    # the rudder first reached the hold's angle here (it may wander a degree before the hold)
    arrived = int(np.argmax(sign * (command[: first + 1] - level) >= -HOLD_RANGE))
    start = execute(command, arrived, sign)
    if start == 0 and abs(record["r"][0]) > MID_TURN * np.max(np.abs(record["r"])):
        return None  # the record starts in the turn: its execute is not in it
    return Turn(round(float(level), 1), float(record.t[start]))


def zigzag_levels(record: Trajectory) -> tuple[float, ...]:
    """The rudder angles [deg] the recognised zig-zag held, plateau by plateau (signed), or ()
    when the record is no zig-zag: a logged zig-zag is flown with the angles it held."""
    return _recognise(record)[1]


def zigzag_command(record: Trajectory) -> np.ndarray | None:
    """The rudder command [rad] a recognised zig-zag implies, sample by sample: the record's
    own ``delta_c``, or, from the actual rudder alone, zero before the execute and each leg's
    held angle from the sample it was put over (where the actual rudder, lagging its command,
    crosses zero seconds later); None when no zig-zag is recognised."""
    if record.has("delta_c"):
        return record["delta_c"]
    zigzag, levels, _, switches = _recognise(record)
    if zigzag is None:
        return None
    command = np.zeros(len(record.t))
    for begin, level in zip(switches, levels, strict=True):
        command[begin:] = math.radians(level)
    return command


def explain_zigzag(record: Trajectory) -> tuple[ZigZag | None, str]:
    """The recognised zig-zag (or None) and a sentence saying what was found or missing."""
    zigzag, _, reason, _ = _recognise(record)
    return zigzag, reason


def _recognise(record: Trajectory) -> tuple[ZigZag | None, tuple[float, ...], str, tuple]:
    """The zig-zag, the levels of its plateaus, the sentence of :func:`explain_zigzag` and the
    samples where the rudder was put over (the execute, then each reversal).  An actual
    rudder logged alone whose holds are fragments is recognised on its readings
    (:func:`sindyship.rudder_holds.samples_per_reading`), each switch where its reading
    begins (:func:`sindyship.rudder_holds.read_in_blocks`)."""
    commanded = record.has("delta_c")
    command = np.degrees(record["delta_c"] if commanded else record.rudder)
    t, psi, r = record.t, record["psi"], record["r"]
    samples = 1 if commanded else samples_per_reading(t, command)
    if samples == 1:
        return _recognise_rudder(t, psi, r, command, commanded, t)
    firsts, centres, reading = read_in_blocks(command, samples)
    zigzag, levels, reason, switches = _recognise_rudder(
        t[centres], psi[centres], r[centres], reading, commanded, t[firsts], read=True)
    return zigzag, levels, (f"{reason} (the actual rudder read in means of {samples} "
                            "samples)"), tuple(int(firsts[i]) for i in switches)


def _recognise_rudder(t, psi, r, command, commanded: bool, switch_t, read: bool = False):
    """:func:`_recognise` on the times, heading, yaw rate and rudder angles [deg] given;
    ``switch_t`` is the time [s] a switch at each sample is taken to have happened, and
    ``read`` says the angles are readings (means of several samples)."""
    raw = find_holds(command)
    found = raw if commanded else settled(raw)
    if not found:
        return None, (), (f"the rudder never holds an angle of at least 1 deg for "
                      f"{HOLD_SAMPLES} samples"), ()
    largest = max(abs(level) for _, _, level in found)
    amplitude = float(np.median([abs(level) for _, _, level in found
                                 if abs(level) >= 0.5 * largest]))
    plateaus = [h for h in found if abs(abs(h[2]) - amplitude) <= PLATEAU_SPREAD]
    chain = longest_alternation(plateaus)
    chain = chain if commanded else cut_short(command, raw, chain, amplitude)
    if len(chain) < 3:
        return None, (), (f"the rudder holds no run of three or more alternating angles near "
                      f"+-{amplitude:.1f} deg (longest: {len(chain)})"), ()
    # a helmsman may hold the zig-zag's angle before its execute (weather helm in a gusty
    # wind): while the reversals from the first plateau share no check angle, the zig-zag is
    # looked for from the next one, the plateaus before it the approach
    first = None
    for k in range(len(chain) - 2):
        found = _zigzag_from(chain[k:], t, psi, r, command, raw, commanded, switch_t, read)
        if found[0] is not None:
            return found
        first = first or found
    return first


def _zigzag_from(chain, t, psi, r, command, raw, commanded: bool, switch_t, read: bool):
    """The zig-zag executed at ``chain``'s first plateau, or None and why not."""
    first_sign = int(np.sign(chain[0][2]))
    # a command steps from its approach value at the execute, flown from its first sample
    # after the step (a helmsman's wheel may wander more than half a degree before it); an
    # actual rudder leaves its last hold
    start = (min(execute(command, chain[0][0], first_sign) + 1, chain[0][0]) if commanded
             else ramp_start(command, raw, chain[0][0], first_sign))
    reversals = [left_hold(command, before[1], h[0], int(np.sign(h[2])))
                 for before, h in zip(chain[:-1], chain[1:], strict=True)]
    if not commanded:  # a slow servo leaves a hold only after it has turned: back to its peak
        reversals = [back_to_peak(command, i, before[0], int(np.sign(h[2])))
                     for i, before, h in zip(reversals, chain[:-1], chain[1:], strict=True)]
    psi = np.degrees(psi - psi[start])
    at = np.abs(psi[reversals])
    before = np.abs(psi[np.maximum(np.array(reversals) - 1, 0)])
    # the heading moves by up to r dt between the samples a reversal falls between; a noisy
    # reading's mean leaves a hold up to one reading either way of where the rudder did
    spread = CHECK_SPREAD + (2.0 if read else 1.0) * float(np.degrees(np.max(np.abs(r)))
                                                           * np.median(np.diff(t)))
    if np.ptp(at) > spread:
        return None, (), (f"the heading change at the {len(reversals)} rudder reversals spreads "
                      f"over {np.ptp(at):.1f} deg (more than {spread:.3g}): no common "
                      "check angle"), ()
    # the rudder reverses as the heading passes the check angle on the side the leg's rudder
    # turns it to: a reversal on the other side, or at the execute heading, is no zig-zag's
    toward = psi[reversals] * np.sign([h[2] for h in chain[:-1]])
    if np.any(toward < MIN_CHECK):
        return None, (), (f"the heading at a rudder reversal is {float(np.min(toward)):.2f} deg "
                          "toward the side the leg's rudder turns it, less than "
                          f"{MIN_CHECK:g}: the rudder does not reverse at a check angle"), ()
    levels = [abs(h[2]) for h in chain]
    check = _roundest(float(np.median(before)), float(np.median(at)))
    rudder = _roundest(float(np.mean(levels)), float(np.mean(levels)))
    zigzag = ZigZag(rudder, check, first_sign, float(switch_t[start]))
    return zigzag, tuple(h[2] for h in chain), (
        f"a {rudder:g}/{check:g} zig-zag from t = {zigzag.start_time:.6g} s: {len(chain)} "
        f"plateaus at {', '.join(f'{v:.1f}' for v in levels)} deg"), (start, *reversals)


def _roundest(low: float, high: float) -> float:
    """The multiple of 5 deg within ROUNDING of [low, high], else the midpoint to 0.1 deg;
    never 0 (a 1 or 2 deg check angle is not rounded to none)."""
    middle = 0.5 * (low + high)
    candidate = 5.0 * round(middle / 5.0)
    if candidate > 0.0 and low - ROUNDING <= candidate <= high + ROUNDING:
        return float(candidate)
    return round(middle, 1)


# ---------------------------------------------------------------------------------------------
# where a flight starts


def detect_zigzag(record: Trajectory) -> tuple[float, float, int] | None:
    """``(rudder_deg, check_deg, first_sign)`` if the record is a zig-zag, else None.

    Examples
    --------
    >>> from sindyship import MMGModel, Manoeuvre, fly, load_ship
    >>> plan = [Manoeuvre("zigzag", rudder=20, check=20, duration=600)]
    >>> (run,) = fly(MMGModel(load_ship("kcs")), plan)
    >>> detect_zigzag(run)
    (20.0, 20.0, 1)
    """
    command = record["delta_c"] if record.has("delta_c") else record.rudder
    cmd = np.degrees(command)
    moving = np.flatnonzero(np.abs(cmd) >= 1.0)
    if moving.size == 0:
        return None
    values = cmd[moving[0]:]
    magnitude = np.abs(values)
    if magnitude.min() < 1.0 or magnitude.max() - magnitude.min() > 0.5:
        return None
    sign = np.sign(values)
    reversals = np.flatnonzero(np.diff(sign) != 0) + 1 + moving[0]
    if len(reversals) < 2:
        return None
    psi = np.degrees(record["psi"] - record["psi"][0])
    at_reversal = np.abs(psi[reversals])
    before = np.abs(psi[reversals - 1])
    if at_reversal.max() - at_reversal.min() > 2.0:
        return None
    rudder = round(float(magnitude.mean()), 1)
    return rudder, _check_angle(before.max(), at_reversal.min()), int(sign[0])


def _check_angle(low: float, high: float) -> float:
    """The check angle the samples allow: the roundest value in (low, high], to 0.1 deg.

    The rudder reverses at the first sample past the check angle C, so C lies between the
    heading change one sample before each reversal and the one at it.
    """
    if high <= low:
        return round(0.5 * (low + high), 1)
    for step in (5.0, 1.0, 0.5, 0.1):
        candidate = math.ceil(low / step + 1e-9) * step
        if candidate <= high:
            return round(candidate, 1)
    return round(0.5 * (low + high), 1)


def recognised_zigzag(record: Trajectory) -> tuple[float, float, int, float] | None:
    """``(rudder_deg, check_deg, first_sign, execute_time)`` of a zig-zag record, else None.

    The strict recognition (:func:`detect_zigzag`, a zig-zag from the first row) first, then
    the tolerant one of logged trials (:func:`sindyship.trials.recognise_zigzag`: a manual
    lead-in, plateaus a degree or two off the nominal angle).
    """
    found = zigzag_to_fly(record)
    if found is None:
        return None
    start, zigzag = found
    return zigzag["amplitude_deg"], zigzag["check_deg"], zigzag["first_sign"], start


@dataclass(frozen=True)
class FlightStart:
    """Where a record's flight starts and why.

    Attributes
    ----------
    time : float
        The first flown (and scored) sample [s].
    kind : {"zigzag", "turn", "record"}
        A recognised zig-zag or turn flown from its rudder execute, or any other record from
        its first row.
    reason : str
        One sentence for reports.
    zigzag : dict or None
        A zig-zag's ``amplitude_deg``, ``check_deg``, ``first_sign`` and the angles its legs
        held, ``levels_deg`` (None for a zig-zag from its first row with exact plateaus): what
        the flight flies, so that the part from the execute is never recognised again.
    """

    time: float
    kind: str
    reason: str
    zigzag: dict | None = None

    def as_meta(self) -> dict:
        """The start as a record's ``meta["flight_start"]`` keeps it."""
        return {"time": self.time, "kind": self.kind, "reason": self.reason,
                "zigzag": self.zigzag}


def zigzag_to_fly(record: Trajectory) -> tuple[float, dict] | None:
    """The execute [s] and what a flight flies of a zig-zag (:attr:`FlightStart.zigzag`):
    the strict recognition first, then the tolerant one (:func:`recognised_zigzag`)."""
    strict = detect_zigzag(record)
    if strict is not None:
        rudder, check, sign = strict
        return float(record.t[0]), {"amplitude_deg": rudder, "check_deg": check,
                                    "first_sign": sign, "levels_deg": None}
    found, held, _, _ = _recognise(record)
    if found is None:
        return None
    rudder, check, sign, start = found
    return float(start), {"amplitude_deg": rudder, "check_deg": check, "first_sign": sign,
                          "levels_deg": [abs(level) for level in held]}


def flight_start(record: Trajectory) -> FlightStart:
    """Where a record is flown and scored from: a zig-zag or a turn from its rudder execute
    with the measured state there (whatever was steered before it, by hand or otherwise, is
    neither flown nor scored), any other record from its first row.

    A record read with its automatic time range carries the recognition made on all its rows
    before the cut (``meta["flight_start"]``, :func:`sindyship.records.read_record`).

    Examples
    --------
    >>> from sindyship import MMGModel, Manoeuvre, fly, load_ship
    >>> plan = [Manoeuvre("turning-circle", rudder=35, duration=300)]
    >>> (run,) = fly(MMGModel(load_ship("kcs")), plan)
    >>> start = flight_start(run)
    >>> start.time, start.kind
    (0.0, 'turn')
    >>> start.reason
    'a turn with 35 deg rudder, flown from its execute at t = 0 s'
    """
    saved = record.meta.get("flight_start")
    t = record.t
    if saved is not None and t[0] - 1e-9 <= saved["time"] <= t[-1]:
        return FlightStart(float(saved["time"]), saved["kind"], saved["reason"],
                           saved.get("zigzag"))
    zigzag = zigzag_to_fly(record)
    if zigzag is not None:
        start, flown = zigzag
        return FlightStart(start, "zigzag", f"a {flown['amplitude_deg']:g}/"
                           f"{flown['check_deg']:g} zig-zag, flown closed loop from its execute "
                           f"at t = {start:.6g} s", flown)
    turn = recognise_turn(record)
    if turn is not None:
        return FlightStart(turn.start_time, "turn", f"a turn with {turn.rudder_deg:g} deg "
                           f"rudder, flown from its execute at t = {turn.start_time:.6g} s")
    rudder = np.degrees(record["delta_c"] if record.has("delta_c") else record.rudder)
    like = (f" (as a zig-zag: {explain_zigzag(record)[1]})"
            if reversals(rudder, 1.0) >= MIN_REVERSALS_EXPLAINED else "")
    return FlightStart(float(t[0]), "record", f"no zig-zag or turn recognised{like}: flown "
                       f"from the first row, t = {t[0]:.6g} s")


#: Reversals of the rudder (across 1 deg either side) from which a record the recognition
#: refuses looks like a zig-zag, and its flight start says why it is none.
MIN_REVERSALS_EXPLAINED = 2

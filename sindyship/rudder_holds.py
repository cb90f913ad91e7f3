"""Where a logged rudder holds an angle, and where it left one for the next.

A zig-zag or a turn is recognised from the rudder's holds (:mod:`sindyship.trials`): the
stretches where the rudder, commanded if recorded, stays within ``HOLD_RANGE = 1`` deg for at
least ``HOLD_SAMPLES = 5`` samples.  A step command holds exactly; an actual rudder reaches
each angle through its steering gear (a rate-limited ramp, then a servo's slow approach that
holds a few samples at every degree on the way, :func:`settled`); a helmsman's wheel wanders
before the execute.  The execute and each reversal are where the rudder left its last hold
(:func:`left_hold`).  An actual rudder logged alone whose holds are fragments (a servo's slow
approach logged so fast that it holds at every degree, or noise that breaks every hold) is
first read in means of consecutive samples (:func:`samples_per_reading`,
:func:`read_in_blocks`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["FRAGMENTED_HOLDS", "HOLD_RANGE", "HOLD_SAMPLES", "MIN_SAMPLES_PER_READING",
           "READINGS_PER_LEG", "back_to_peak", "cut_short", "execute", "find_holds",
           "leg_time", "left_hold", "longest_alternation", "ramp_start", "read_in_blocks",
           "reversals", "samples_per_reading", "settled", "stretch_end"]

HOLD_RANGE = 1.0  # deg
HOLD_SAMPLES = 5
#: Samples of a stretch compared one by one before the rest is read in windows.
SHORT_STRETCH = 8
#: A rudder moving toward a plateau by more than this is on its ramp [deg per sample].
_MOVING = 0.25
#: A rudder still on its way to a hold moves by more than this toward it [deg per sample].
_RAMP_STEP = 1e-3
#: The execute is the last sample within this [deg] of the rudder's approach value.
_EXECUTE_BAND = 0.5
#: An actual rudder logged alone is read in means of consecutive samples, about this many
#: readings to a leg of its zig-zag (:func:`samples_per_reading`).
READINGS_PER_LEG = 80
#: Fewer samples than this to a reading are read one by one: a reading of two would need a
#: hold twice as long (a helmsman's last second before the execute is lost) to halve the
#: noise's variance only.
MIN_SAMPLES_PER_READING = 3
#: Holds to a leg above which an actual rudder's holds are fragments: one holding each leg's
#: angle makes one a leg and a helmsman's lead-in a few more (measured trials: up to 2.7).
FRAGMENTED_HOLDS = 4


def execute(command: np.ndarray, hold: int, sign: int) -> int:
    """The last sample at the approach value before the rudder moved to the hold that starts
    at ``hold``: back along the ramp while the rudder keeps moving toward the hold (a step,
    or a servo's exponential approach; a helmsman's held wheel or a wobble ends it), then
    forward to the last sample within :data:`_EXECUTE_BAND` of where it began."""
    i = hold
    while i > 0 and sign * (command[i] - command[i - 1]) > _RAMP_STEP:
        i -= 1
    j = i
    while j < hold and sign * (command[j + 1] - command[i]) <= _EXECUTE_BAND:
        j += 1
    return j


def find_holds(command: np.ndarray) -> list[tuple[int, int, float]]:
    """(first, last, level) of each stretch of at least HOLD_SAMPLES samples within HOLD_RANGE."""
    holds = []
    i, n = 0, len(command)
    while i < n:
        j = stretch_end(command, i)
        level = float(np.median(command[i:j]))
        if j - i >= HOLD_SAMPLES and abs(level) >= 1.0:
            holds.append((i, j - 1, level))
        i = j
    return holds


def stretch_end(command: np.ndarray, i: int) -> int:
    """The end (exclusive) of the stretch from sample ``i`` whose spread (largest minus
    smallest angle) stays within HOLD_RANGE: the first sample that widens it beyond.

    A NaN sample inside a stretch is passed over; a stretch that starts at NaN or infinity is
    that sample alone.  The first samples are compared one by one (a moving or noisy rudder
    makes short stretches), the rest in windows of up to 65536 samples carrying the running
    extremes, so a long hold costs a few array operations instead of a comparison per sample.
    """
    n = len(command)
    if not np.isfinite(command[i]):
        return i + 1
    low = high = command[i]
    lead = min(n, i + SHORT_STRETCH)
    for j in range(i + 1, lead):
        value = command[j]  # Python's max and min pass over NaN, as fmax and fmin do
        if max(high, value) - min(low, value) > HOLD_RANGE:
            return j
        low, high = min(low, value), max(high, value)
    j, size = lead, 32
    while j < n:
        window = command[j:j + size]
        highs = np.fmax(np.fmax.accumulate(window), high)
        lows = np.fmin(np.fmin.accumulate(window), low)
        wider = np.flatnonzero(highs - lows > HOLD_RANGE)
        if wider.size:
            return j + int(wider[0])
        low, high = lows[-1], highs[-1]
        j += len(window)
        size = min(8 * size, 65536)
    return n


def settled(holds: list[tuple[int, int, float]]) -> list[tuple[int, int, float]]:
    """The holds of an actual rudder with each run creeping toward a larger angle of the same
    sign (by at most two hold ranges, a few samples apart) made one at the angle it settled
    at: a rudder that a servo's lag brings to its command slowly holds for a few samples at
    each degree on the way (a helmsman's step to another angle is a new hold)."""
    merged: list[tuple[int, int, float]] = []
    for first, last, level in holds:
        if merged:
            a, b, previous = merged[-1]
            if (np.sign(previous) == np.sign(level) and first - b <= HOLD_SAMPLES
                    and 0.0 < abs(level) - abs(previous) <= 2 * HOLD_RANGE):
                merged[-1] = (a, last, level)
                continue
        merged.append((first, last, level))
    return merged


def cut_short(command: np.ndarray, raw: list, chain: list, amplitude: float) -> list:
    """The chain of plateaus with a first leg the rudder never held put in front: an actual
    rudder that a servo brings to its command slowly can be reversed at the check angle on
    its way out, before it settles (a 35/10 zig-zag's first leg peaks near 26 deg).  Such a
    leg peaks at least half the amplitude out on the other side, after the last hold before
    the first plateau; it is taken to have been commanded to the amplitude."""
    if not chain:
        return chain
    sign = -np.sign(chain[0][2])
    end = _last_hold_end(raw, chain[0][0])
    begin = 0 if end is None else end + 1
    if begin >= chain[0][0]:
        return chain
    peak = begin + int(np.argmax(sign * command[begin:chain[0][0]]))
    if sign * command[peak] < 0.5 * amplitude:
        return chain
    return [(peak, peak, float(sign * amplitude)), *chain]


def _on_the_way(command: np.ndarray, hold: tuple, index: int, sign: float) -> bool:
    """Whether ``hold`` is a servo creeping toward the angle the rudder holds at ``index``:
    on its side, within two :data:`HOLD_RANGE` short of it (as :func:`settled` merges such
    holds), and never fallen back from by more than a hold range before ``index`` (a
    helmsman's wheel held a few degrees off, such as weather helm, is a hold of its own)."""
    _, last, level = hold
    target = sign * command[index]
    return bool(np.sign(level) == sign and last < index
                and 0.0 <= target - abs(level) <= 2 * HOLD_RANGE
                and np.min(sign * command[last:index + 1]) >= abs(level) - HOLD_RANGE)


def _last_hold_end(raw: list, index: int) -> int | None:
    """The last sample of the last hold of ``raw`` that ends before ``index`` (None: none)."""
    return next((last for _, last, _ in reversed(raw) if last < index), None)


def left_hold(command: np.ndarray, last: int, first: int, sign: int) -> int:
    """The first sample after ``last`` (the end of a hold) at which the rudder has moved more
    than :data:`_EXECUTE_BAND` from where it was there toward the sign of a plateau starting
    at ``first``: where it was put over, whether a step, a rate-limited ramp or a servo's
    slow, noisy approach follows; ``first`` when it never moved that far."""
    moved = np.flatnonzero(sign * (command[last + 1:first + 1] - command[last]) > _EXECUTE_BAND)
    return last + 1 + int(moved[0]) if moved.size else first


def back_to_peak(command: np.ndarray, moved: int, floor: int, sign: int) -> int:
    """The sample after the rudder's last turning point before ``moved`` (not before
    ``floor``): back while each step went toward ``sign``.  An actual rudder peaks where its
    command reversed (a lagging servo turns at once, slowly), while the sample it has moved
    far enough from its hold can come seconds later."""
    i = moved
    while i - 1 > floor and sign * (command[i - 1] - command[i - 2]) > 0:
        i -= 1
    return i


def longest_alternation(plateaus):
    """The longest run of plateaus alternating in sign.

    Neighbours of the same sign are merged into one plateau; a gap between two plateaus
    longer than twice the longer of them (the rudder left elsewhere) ends a run.
    """
    runs: list[list[tuple[int, int, float]]] = []
    for hold in plateaus:
        run = runs[-1] if runs else None
        if run is not None:
            first, last, level = run[-1]
            gap = hold[0] - last
            if gap > 2 * max(last - first, hold[1] - hold[0]) + 2:
                run = None
            elif np.sign(level) == np.sign(hold[2]):
                run[-1] = (first, hold[1], level)
                continue
        if run is None:
            runs.append([hold])
        else:
            run.append(hold)
    return max(runs, key=len) if runs else []


def ramp_start(command: np.ndarray, raw: list, plateau: int, sign: int) -> int:
    """The first sample at which the rudder left its previous value toward a plateau: where
    it left the last hold before that is not on its way (:func:`left_hold`,
    :func:`_on_the_way`), else back over the ramp's end while it is more than half way from
    the record's first value (a servo's slow approach) and then while it moves toward the
    plateau by more than :data:`_MOVING` per sample; sample 0 when the record starts on the
    ramp."""
    end = _last_hold_end([h for h in raw if not _on_the_way(command, h, plateau, sign)],
                         plateau)
    if end is not None:
        return left_hold(command, end, plateau, sign)
    index = plateau
    half = 0.5 * sign * (command[plateau] + command[0])
    while index > 0 and sign * command[index - 1] > half:
        index -= 1
    while index > 0 and sign * (command[index] - command[index - 1]) > _MOVING:
        index -= 1
    return index if index in (0, plateau) else index + 1


def reversals(command: np.ndarray, beyond: float) -> int:
    """How many times the rudder ``command`` [deg] crosses from one side to the other,
    counting only angles at least ``beyond`` [deg] from amidships.

    Examples
    --------
    >>> reversals(np.array([0.0, 10.0, 10.0, 0.2, -10.0, -0.5, 10.0]), 1.0)
    2
    """
    sides = np.sign(command[np.abs(command) >= beyond])
    return int(np.count_nonzero(np.diff(sides)))


def leg_time(t: np.ndarray, command: np.ndarray) -> float | None:
    """The median time [s] the rudder takes from one side to the other: between its
    crossings of the bands a quarter of its range (2nd to 98th percentile) above and below
    the middle, a swing counted once however it wobbles inside a band; None for fewer than
    two swings or a range under two :data:`HOLD_RANGE`."""
    finite = np.isfinite(command)
    if finite.sum() < 2:
        return None
    low, high = np.percentile(command[finite], [2.0, 98.0])
    if high - low < 2 * HOLD_RANGE:
        return None
    middle, quarter = 0.5 * (low + high), 0.25 * (high - low)
    side = np.where(command > middle + quarter, 1, np.where(command < middle - quarter, -1, 0))
    outside = np.flatnonzero(side)
    swings = outside[1:][np.diff(side[outside]) != 0]
    return float(np.median(np.diff(t[swings]))) if len(swings) >= 2 else None


def samples_per_reading(t: np.ndarray, command: np.ndarray) -> int:
    """How many consecutive samples of an actual rudder make one reading: a leg of the
    zig-zag (:func:`leg_time`) read in about :data:`READINGS_PER_LEG` readings when its holds
    are fragments (more than :data:`FRAGMENTED_HOLDS` to a leg); else 1, as when that is fewer
    than :data:`MIN_SAMPLES_PER_READING` samples or the record holds no swings to time.

    A hold is :data:`HOLD_SAMPLES` readings within :data:`HOLD_RANGE`.  Logged at 1 s, a
    full-scale servo's slow approach to its angle holds at the end of each leg; logged at
    20 Hz, every degree of the approach holds and 0.3 deg of noise breaks every hold.  Read
    in means over about a second, both look as they do at 1 s (``benchmarks/
    bench_recognition.py``).  A rudder that holds each leg's angle is read sample by sample:
    a reading five times as long as a sample would lose a helmsman's last seconds before the
    execute."""
    if len(t) < 2:
        return 1
    leg = leg_time(t, command)
    step = float(np.median(np.diff(t)))
    if leg is None or not step > 0:
        return 1
    samples = int(round(leg / (READINGS_PER_LEG * step)))
    if samples < MIN_SAMPLES_PER_READING:
        return 1
    legs = (t[-1] - t[0]) / leg
    return samples if len(find_holds(command)) > FRAGMENTED_HOLDS * legs else 1


def read_in_blocks(command: np.ndarray,
                   samples: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The first and the centre sample of each block of ``samples`` consecutive samples (the
    last block may be shorter), and the mean of its finite angles (NaN for a block without
    any): a reading's mean is the rudder at its centre, and a rudder that moved between two
    readings moved about where the later one begins."""
    first = np.arange(0, len(command), samples)
    centre = first + np.diff(np.append(first, len(command))) // 2
    finite = np.isfinite(command)
    sums = np.add.reduceat(np.where(finite, command, 0.0), first)
    counts = np.add.reduceat(finite.astype(float), first)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = np.where(counts > 0, sums / np.maximum(counts, 1.0), np.nan)
    return first, centre, means


#: Share of a record's samples with the rudder put to one side (half a degree or more) for
#: the record to count as putting it to that side.
SIDE_SHARE = 0.1


def rudder_side(rudder: np.ndarray) -> int:
    """The side a record's rudder angles [rad] put the rudder to: 1 starboard, -1 port, 2 both
    (a zig-zag), 0 neither (a straight run): each side counts where a tenth of the samples or
    more hold the rudder half a degree or more to it."""
    starboard = float(np.mean(rudder > math.radians(0.5))) >= SIDE_SHARE
    port = float(np.mean(rudder < -math.radians(0.5))) >= SIDE_SHARE
    return 2 if starboard and port else 1 if starboard else -1 if port else 0

"""The ``jumps`` note of a record's plausibility (:mod:`sindyship.plausibility`, whose
docstring gives its thresholds and reasons): samples of u or v that change faster than a ship
accelerates, a logging glitch that every other check passes.  A note, never a refusal: the
samples are used as recorded, and the note names them and how to leave them out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

__all__ = ["JUMP_ACCELERATION", "JUMP_MOST_LAGS", "JUMP_NEIGHBOURS", "JUMP_NOISE", "JUMP_SPEED",
           "JUMP_WINDOW", "JumpNote", "jump_notes", "sample_jumps"]

#: Samples on each side of the running median a sample of u or v is judged against.
JUMP_NEIGHBOURS = 3
#: Least distance [U0] of a sample of u or v from its running median that is a jump.
JUMP_SPEED = 0.1
#: Least distance of a jump in noise levels (the robust spread of the channel's steps).
JUMP_NOISE = 10.0
#: Most acceleration [U0^2/L] a ship makes: the change it allows over a sample interval.
JUMP_ACCELERATION = 1.0
#: Longest interval [L/U0] a change spread over several samples (a ramp) is judged over.
JUMP_WINDOW = 0.1
#: Most sample intervals a ramp is judged over (bounds the work on records sampled fast).
JUMP_MOST_LAGS = 200


class JumpNote(str):
    """The ``jumps`` note, with the times [s] of the samples it names (``times``): a time
    range that leaves them all out leaves the note out too."""

    times: tuple[float, ...] = ()


def sample_jumps(data: Mapping[str, np.ndarray], ship) -> dict[str, tuple]:
    """The samples of u and v that change faster than a ship accelerates (the ``jumps``
    check): for each channel with any, their indices and the largest change [m/s].

    A sample that leaps away from the running median of its neighbours is named alone; a
    change spread over a few samples (a ramp) that exceeds the same bound within
    ``JUMP_WINDOW`` L/U0 is named from its first sample to its last.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> t = np.arange(400.0)
    >>> u, v = np.full(400, 12.0), np.zeros(400)
    >>> v[-1] = -3.0
    >>> {name: (i.tolist(), change) for name, (i, change) in
    ...  sample_jumps({"t": t, "u": u, "v": v}, load_ship("kcs")).items()}
    {'v': ([399], 3.0)}
    """
    from scipy.ndimage import median_filter

    t = np.asarray(data["t"], dtype=float)
    size = 2 * JUMP_NEIGHBOURS + 1
    if t.size < size:
        return {}
    step = float(np.median(np.diff(t)))
    lags = min(max(1, math.ceil(JUMP_WINDOW * ship.time_scale / step)), JUMP_MOST_LAGS)
    out = {}
    for name in ("u", "v"):
        values = np.asarray(data[name], dtype=float)
        noise = JUMP_NOISE * 1.4826 * float(np.median(np.abs(np.diff(values)))) / math.sqrt(2.0)
        distance = np.abs(values - median_filter(values, size=size, mode="mirror"))
        allowed = _allowed_change(step, ship)
        spikes = distance > max(allowed, noise)
        largest = float(np.max(distance[spikes], initial=0.0))
        spans = np.zeros_like(spikes)
        for lag in range(1, lags + 1):
            change = np.abs(values[lag:] - values[:-lag])
            ramp = (change > np.maximum(_allowed_change(t[lag:] - t[:-lag], ship), noise)) \
                & ~spikes[lag:] & ~spikes[:-lag]
            for start in np.flatnonzero(ramp):
                spans[start + 1:start + lag + 1] = True
            largest = max(largest, float(np.max(change[ramp], initial=0.0)))
        # of a ramp's span, the samples its steps leap into (all of it where none stands out)
        leaps = spans & np.concatenate([[False], np.abs(np.diff(values)) > noise])
        found = spikes | (leaps if np.any(leaps) else spans)
        if np.any(found):
            out[name] = (np.flatnonzero(found), largest)
    return out


def _allowed_change(interval, ship):
    """The largest change of u or v [m/s] over ``interval`` [s] that is no jump:
    ``JUMP_SPEED`` U0 plus what ``JUMP_ACCELERATION`` makes in that time."""
    return ship.U0 * (JUMP_SPEED + JUMP_ACCELERATION * np.asarray(interval) / ship.time_scale)


def jump_notes(data, ship, context) -> list[JumpNote]:
    """The ``jumps`` note (none when no sample leaps), its rows named by the plausibility
    check's ``context``."""
    jumps = sample_jumps(data, ship)
    if not jumps:
        return []
    t = data["t"]
    found = np.unique(np.concatenate([index for index, _ in jumps.values()]))
    name = max(jumps, key=lambda key: jumps[key][1])
    largest = jumps[name][1]
    first, last = int(found[0]), int(found[-1])
    where = (f"at {context.row(first)}, t = {t[first]:.6g} s," if found.size == 1 else
             f"at {found.size} samples from {context.row(first)}, t = {t[first]:.6g} s, to "
             f"{context.row(last)}, t = {t[last]:.6g} s,")
    single = len(jumps) == 1
    columns = " and ".join(f"'{context.header(key)}'" for key in jumps)
    it = "it" if found.size == 1 else "them"
    span = t[-1] - t[0]
    keep = ""
    if first > 0 and t[first] - t[0] > 0.9 * span:  # at the end: the time before them
        keep = (f", or keep the time before {it} (--time-range {t[0]:.6g}:{t[first - 1]:.6g} "
                "on the command line)")
    elif last < t.size - 1 and t[last] - t[0] < 0.1 * span:  # at the start: the time after
        keep = (f", or keep the time after {it} (--time-range {t[last + 1]:.6g}:{t[-1]:.6g} "
                "on the command line)")
    note = JumpNote(
        f"{context.source}: {columns} {where} change{'s' if single else ''} faster than a ship "
        f"accelerates, {'' if single else f'{context.header(name)!r} '}by "
        f"{'' if found.size == 1 else 'up to '}{largest:.3g} m/s ({largest / ship.U0:.2f} U0) "
        "against the neighbouring samples (a logging glitch?); "
        f"{'it is' if found.size == 1 else 'they are'} used as recorded, so delete "
        f"{'that row' if found.size == 1 else 'those rows'}{keep}; --skip-check jumps "
        "(skip_checks=['jumps'] in Python) silences this note.")
    note.times = tuple(float(t[i]) for i in found)
    return [note]

"""The ``jumps`` note of a record's plausibility (:mod:`sindyship.plausibility`, whose
docstring gives its thresholds and reasons): samples of u or v that change faster than a ship
accelerates, a logging glitch that every other check passes.  A note, never a refusal: the
samples are used as recorded, and the note names them and what to do with them.
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
#: Most intervals a ramp is judged over: a record sampled faster is judged over intervals
#: spread evenly across the window (bounds the work on records logged at kHz).
JUMP_MOST_LAGS = 50


class JumpNote(str):
    """The ``jumps`` note, with the times [s] of the samples it names (``times``): a time
    range that leaves them all out leaves the note out too."""

    times: tuple[float, ...] = ()


def sample_jumps(data: Mapping[str, np.ndarray], ship) -> dict[str, tuple[np.ndarray, float]]:
    """The samples of u and v that change faster than a ship accelerates (the ``jumps``
    check).

    A sample that leaps away from the running median of its neighbours is named alone; a
    change over at most ``JUMP_WINDOW`` L/U0 (a ramp, or a plateau too wide for the median)
    beyond the same bounds over its own time is named from the sample it starts at to the
    last it reaches; samples named within that window of the record's start or end are named
    to it (there a plateau of glitches has no good samples on its far side).

    Parameters
    ----------
    data : mapping of str to ndarray
        The record's ``t`` [s], ``u`` and ``v`` [m/s].
    ship : Ship
        Gives U0 and the time scale L/U0.

    Returns
    -------
    dict of str to (ndarray, float)
        For u and v where any sample changes too fast: the indices of the samples named, and
        the largest change [m/s].  Empty for a record of fewer than ``2 JUMP_NEIGHBOURS + 1``
        samples, which is not judged.

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
    widest = max(1, math.ceil(JUMP_WINDOW * ship.time_scale / step))
    lags = np.unique(np.round(np.linspace(1, widest, min(widest, JUMP_MOST_LAGS))).astype(int))
    out = {}
    for name in ("u", "v"):
        values = np.asarray(data[name], dtype=float)
        noise = JUMP_NOISE * 1.4826 * float(np.median(np.abs(np.diff(values)))) / math.sqrt(2.0)
        distance = np.abs(values - median_filter(values, size=size, mode="mirror"))
        spikes = distance > max(_allowed_change(step, ship), noise)
        largest = float(np.max(distance[spikes], initial=0.0))
        edges = np.zeros(t.size + 1, dtype=int)  # +1 where a ramp's span begins, -1 after it
        for lag in lags[lags < t.size]:
            change = np.abs(values[lag:] - values[:-lag])
            ramp = (change > np.maximum(_allowed_change(t[lag:] - t[:-lag], ship), noise)) \
                & ~spikes[lag:] & ~spikes[:-lag]
            starts = np.flatnonzero(ramp)
            np.add.at(edges, starts, 1)
            np.add.at(edges, starts + lag + 1, -1)
            largest = max(largest, float(np.max(change[ramp], initial=0.0)))
        found = spikes | (np.cumsum(edges)[:-1] > 0)
        named = np.flatnonzero(found)
        if named.size and named[0] < widest:
            found[:named[0]] = True
        if named.size and named[-1] >= t.size - widest:
            found[named[-1]:] = True
        if np.any(found):
            out[name] = (np.flatnonzero(found), largest)
    return out


def _allowed_change(interval, ship):
    """The largest change of u or v [m/s] over ``interval`` [s] that is no jump:
    ``JUMP_SPEED`` U0 plus what ``JUMP_ACCELERATION`` makes in that time."""
    return ship.U0 * (JUMP_SPEED + JUMP_ACCELERATION * np.asarray(interval) / ship.time_scale)


def jump_notes(data, ship, context) -> list[JumpNote]:
    """The ``jumps`` note (none when no sample changes too fast), its rows named by the
    plausibility check's ``context``."""
    jumps = sample_jumps(data, ship)
    if not jumps:
        return []
    t, n = data["t"], len(data["t"])
    found = np.unique(np.concatenate([index for index, _ in jumps.values()]))
    runs = np.split(found, np.flatnonzero(np.diff(found) > 1) + 1)
    name = max(jumps, key=lambda key: jumps[key][1])
    largest = jumps[name][1]

    def at(i: int) -> str:
        return f"{context.row(i)}, t = {t[i]:.10g} s"

    def span(run) -> str:
        return f"at {at(run[0])}" if len(run) == 1 else f"from {at(run[0])}, to {at(run[-1])}"

    where = span(runs[0]) if len(runs) == 1 else (
        f"in {len(runs)} places, the first {span(runs[0])}, the last {span(runs[-1])}")
    start, end = runs[0][0] == 0, runs[-1][-1] == n - 1
    end = end and not (start and len(runs) == 1)  # one run over the whole record: its start
    ends = [*([f"first {_rows(len(runs[0]))}"] if start else []),
            *([f"last {_rows(n - runs[-1][0])}"] if end else [])]
    actions = [*([f"delete its {' and its '.join(ends)}"] if ends else []),
               *(["correct the samples " + ("in between" if ends else "named")]
                 if len(runs) > start + end else [])]
    single = len(jumps) == 1
    columns = " and ".join(f"'{context.header(key)}'" for key in jumps)
    note = JumpNote(
        f"{context.source}: {columns} change{'s' if single else ''} faster than a ship "
        f"accelerates {where} ({'' if single else f'{context.header(name)!r} '}by up to "
        f"{largest:.3g} m/s, {largest / ship.U0:.2f} U0; a logging glitch?); the samples are "
        f"used as recorded, so {' and '.join(actions)} (--skip-check jumps, skip_checks="
        "['jumps'] in Python, silences this note).")
    note.times = tuple(float(t[i]) for i in found)
    return [note]


def _rows(count: int) -> str:
    return "row" if count == 1 else f"{count} rows"

"""Reading the measurement CSVs a verb is given: plausibility checks, the part under way."""

from __future__ import annotations

import warnings

from ..errors import SindyshipInputError
from ._common import progress


def add_record_options(p) -> None:
    """``--skip-check`` and ``--time-range``: how records are read."""
    from ..plausibility import CHECKS

    p.add_argument("--skip-check", action="append", default=[], metavar="NAME",
                   choices=[*CHECKS, "all"],
                   help="plausibility check not to run on the records, repeatable: "
                   f"{', '.join(CHECKS)} or all (default: run every check)")
    p.add_argument("--time-range", default="auto", metavar="auto|all|START:STOP",
                   help="the part of each record to use [s]: 'auto' keeps the part under way "
                   "with the propeller running (never from rest), 'all' every sample, "
                   "START:STOP the samples between two times (default: auto)")


def _time_range(text: str) -> tuple[float, float] | str:
    if text in ("auto", "all"):
        return text
    start, sep, stop = text.partition(":")
    try:
        window = (float(start), float(stop))
    except ValueError:
        window = None
    if not sep or window is None or not window[0] < window[1]:
        raise SindyshipInputError(
            f"--time-range {text!r} is not auto, all or START:STOP in seconds with START < STOP "
            "(e.g. 120:1800)."
        )
    return window


def read_records(paths, resample=None, *, ship=None, skip_checks=(), time_range="auto"):
    """The records of ``paths``, in order, checked for plausibility and cut to the part a
    model can fly (:func:`sindyship.trials.underway_window`), with a notice for each cut.

    Parameters
    ----------
    paths : sequence of path
    resample : float, optional
        Resampling interval [s] (:func:`sindyship.measurements.read_csv`).
    ship : Ship, optional
        The ship measured: enables the ship-scaled checks and the automatic time range.
    skip_checks : sequence of str
        Plausibility checks not to run.
    time_range : str
        ``"auto"``, ``"all"`` or ``"START:STOP"`` (see :func:`add_record_options`).
    """
    from ..measurements import PlausibilityNote, read_csv
    from ..trials import trim, underway_window

    window = _time_range(time_range)
    skip = "all" if "all" in skip_checks else tuple(skip_checks)
    records = []
    for path in paths:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlausibilityNote)  # printed below, one line each
            record = read_csv(path, resample=resample, ship=ship, skip_checks=skip)
        for note in record.meta.get("notes", ()):
            progress(f"{path}: {note}")
        if window == "auto" and ship is not None:
            cut = underway_window(record, ship)
            if cut.start > record.t[0] + 1e-9 or cut.stop < record.t[-1] - 1e-9:
                progress(f"{path}: using {cut.start:g}-{cut.stop:g} s: {cut.reason} "
                         "(--time-range to choose)")
                record = trim(record, cut)
        elif window not in ("auto", "all"):
            record = trim(record, window)
            if record.n_samples < 2:
                raise SindyshipInputError(
                    f"{path}: --time-range {time_range} keeps fewer than two samples; choose "
                    f"times between {record.meta.get('trimmed')} and the record's."
                )
        records.append(record)
    return records

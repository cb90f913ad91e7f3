"""Reading the measurement CSVs a verb is given: each under a name of its own, checked for
plausibility, and cut to the part under way.

Results are keyed by record name.  A record is named after its file stem
(:func:`sindyship.measurements.read_csv`); where two inputs share a stem they are told apart
by the shortest trailing part of their paths that does (``a/run``, ``b/run``), so results never
merge.  The same file given twice is refused.
"""

from __future__ import annotations

import csv
import os
import warnings
from dataclasses import replace
from pathlib import Path

from ..errors import SindyshipInputError
from ._common import check_memory, progress

__all__ = ["add_record_options", "read_record_sets", "read_records", "record_keys"]


def _refuse_repeats(paths: list[Path]) -> None:
    for i, a in enumerate(paths):
        for b in paths[:i]:
            try:
                same = os.path.samefile(a, b)
            except OSError:
                same = a.absolute() == b.absolute()
            if same:
                raise SindyshipInputError(
                    f"{a}: is given twice (also as {b}); give each record once."
                )


def record_keys(paths) -> list[str]:
    """One name per path: the file stem, lengthened where stems collide.

    Examples
    --------
    >>> record_keys(["a/run.csv", "b/run.csv", "zz.csv"])
    ['a/run', 'b/run', 'zz']
    >>> record_keys(["x/a/run.csv", "y/a/run.csv"])
    ['x/a/run', 'y/a/run']
    >>> record_keys(["run.csv", "run.CSV"])
    ['run.csv', 'run.CSV']
    """
    paths = [Path(os.path.abspath(p)) for p in paths]
    keys = [p.stem for p in paths]
    groups: dict[str, list[int]] = {}
    for i, key in enumerate(keys):
        groups.setdefault(key, []).append(i)
    for members in groups.values():
        if len(members) < 2:
            continue
        depth = max(len(paths[i].parents) for i in members)
        for k in range(1, depth + 1):
            trial = ["/".join([*paths[i].parent.parts[-k:], paths[i].stem]).lstrip("/")
                     for i in members]
            if len(set(trial)) == len(trial):
                break
        else:  # same folder and stem, different suffix
            trial = [paths[i].name for i in members]
        for i, key in zip(members, trial, strict=True):
            keys[i] = key
    return keys


def _check_resample_memory(path: Path, resample: float) -> None:
    """Refuse resampling that would need more memory than the machine has, before reading:
    the time span comes from the first and last rows' ``t`` (in seconds when unmarked)."""
    try:
        with open(path, encoding="utf-8-sig", newline="") as handle:
            reader = csv.reader(handle)
            header = next(reader)
            names = [h.split("[")[0].strip() for h in header]
            if "t" not in names or header[names.index("t")].strip() not in ("t", "t [s]"):
                return
            column = names.index("t")
            first = last = None
            for row in reader:
                if len(row) > column and row[column].strip():
                    last = row[column]
                    first = first if first is not None else row[column]
            span = float(last) - float(first)
    except (OSError, UnicodeDecodeError, StopIteration, ValueError, TypeError, csv.Error):
        return  # the reader reports what is wrong with the file
    if span > 0:
        check_memory(span / resample, f"{path}: resampling {span:g} s at {resample:g} s")


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


def reading(args, ship) -> dict:
    """The keyword arguments of :func:`read_records` that a verb's options give."""
    return {"ship": ship, "skip_checks": args.skip_check, "time_range": args.time_range}


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


def _read_one(path: Path, resample, ship, skip, window, time_range):
    """One record, checked, with its notes on stderr, cut to the time range."""
    from ..measurements import PlausibilityNote, read_csv
    from ..trials import trim, underway_window

    if resample is not None:
        _check_resample_memory(path, resample)
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
                "times within the record."
            )
    return record


def read_records(paths, resample=None, *, keys=None, ship=None, skip_checks=(),
                 time_range="auto"):
    """The records of ``paths``, in order, named by :func:`record_keys`, checked for
    plausibility and cut to the part a model can fly (:func:`sindyship.trials.underway_window`),
    with a notice for each cut.

    Parameters
    ----------
    paths : sequence of str or Path
    resample : float, optional
        Step [s] to resample onto (:func:`sindyship.measurements.read_csv`).
    keys : sequence of str, optional
        The names to give (default: :func:`record_keys` of ``paths``).
    ship : Ship, optional
        The ship measured: enables the ship-scaled checks and the automatic time range.
    skip_checks : sequence of str
        Plausibility checks not to run.
    time_range : str
        ``"auto"``, ``"all"`` or ``"START:STOP"`` (see :func:`add_record_options`).
    """
    paths = [Path(p) for p in paths]
    _refuse_repeats(paths)
    keys = record_keys(paths) if keys is None else list(keys)
    window = _time_range(time_range)
    skip = "all" if "all" in skip_checks else tuple(skip_checks)
    records = []
    for path, key in zip(paths, keys, strict=True):
        record = _read_one(path, resample, ship, skip, window, time_range)
        records.append(record if record.name == key else replace(record, name=key))
    return records


def read_record_sets(*path_sets, resample=None, **options):
    """Several lists of records (training and held-out) named together, so that no two
    records anywhere share a name and no file is in two lists."""
    flat = [Path(p) for paths in path_sets for p in paths]
    _refuse_repeats(flat)
    keys = record_keys(flat)
    out, start = [], 0
    for paths in path_sets:
        out.append(read_records(paths, resample, keys=keys[start:start + len(paths)],
                                **options))
        start += len(paths)
    return out

"""Reading the records a verb is given (measurement CSVs, or Parquet files with the same
columns): each under a name of its own, checked for plausibility, and cut to the part under way.

Results are keyed by record name.  A record is named after its file stem
(:func:`sindyship.measurements.read_csv`); where two inputs share a stem they are told apart
by the shortest trailing part of their paths that does (``a/run``, ``b/run``), so results never
merge.  The same file given twice is refused.
"""

from __future__ import annotations

import csv
import os
from dataclasses import replace
from pathlib import Path

from ..errors import SindyshipInputError
from ._common import check_memory, progress

__all__ = ["read_record_sets", "read_records", "record_keys"]


def _refuse_repeats(paths: list[Path]) -> None:
    seen: dict[object, Path] = {}
    for a in paths:
        try:
            status = os.stat(a)
            key: object = (status.st_dev, status.st_ino)
        except (OSError, ValueError):
            key = a.absolute()
        if key in seen:
            raise SindyshipInputError(
                f"{a}: is given twice (also as {seen[key]}); give each record once."
            )
        seen[key] = a


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


def _record_span(path: Path) -> float | None:
    """The time a measurement CSV spans [s], from its first and last rows' ``t`` (in seconds
    when unmarked); None for a Parquet file or one the reader will report on."""
    from ..records import PARQUET_SUFFIXES

    if path.suffix.lower() in PARQUET_SUFFIXES:
        return None
    try:
        with open(path, encoding="utf-8-sig", newline="") as handle:
            reader = csv.reader(handle)
            header = next(reader)
            names = [h.split("[")[0].strip() for h in header]
            if "t" not in names or header[names.index("t")].strip() not in ("t", "t [s]"):
                return None
            column = names.index("t")
            first = last = None
            for row in reader:
                if len(row) > column and row[column].strip():
                    last = row[column]
                    first = first if first is not None else row[column]
            return float(last) - float(first)
    except (OSError, UnicodeDecodeError, StopIteration, ValueError, TypeError, csv.Error):
        return None  # the reader reports what is wrong with the file


def _check_resample_memory(paths: list[Path], resample: float) -> None:
    """Refuse resampling that would need more memory than the machine has, before reading:
    the samples of every record together (each record's span from its CSV)."""
    spans = [span for span in map(_record_span, paths) if span is not None and span > 0]
    if not spans:
        return
    what = (f"{paths[0]}: resampling {spans[0]:g} s" if len(paths) == 1 else
            f"resampling {len(spans)} record{'s' if len(spans) > 1 else ''} "
            f"({sum(spans):g} s)")
    check_memory(sum(spans) / resample, f"{what} at {resample:g} s")


def reading(args, ship) -> dict:
    """The keyword arguments of :func:`read_records` that a verb's options give."""
    return {"ship": ship, "skip_checks": args.skip_check, "time_range": args.time_range}


def _time_range(text: str) -> tuple[float, float] | str:
    from ..records import time_window

    return time_window(text)


def _read_one(path: Path, resample, ship, skip, window, time_range):
    """One record (a measurement CSV or a Parquet file), checked, with its notes on stderr,
    cut to the time range."""
    from ..records import read_record

    record, notes, cut = read_record(path, ship=ship, resample=resample, skip_checks=skip,
                                     time_range=window)
    report_reading(path, notes, cut)
    return record


def report_reading(path, notes, cut) -> None:
    """A record's plausibility notes and its automatic cut, one line each on stderr."""
    for note in notes:  # a note of the reader names its source already
        progress(note if note.startswith(f"{path}: ") else f"{path}: {note}")
    if cut is not None:
        start, stop, reason = cut
        progress(f"{path}: using {start:g}-{stop:g} s: {reason} (--time-range to choose)")


def read_records(paths, resample=None, *, keys=None, ship=None, skip_checks=(),
                 time_range="auto", memory_checked=False):
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
        ``"auto"``, ``"all"`` or ``"START:STOP"`` (the option ``--time-range``).
    memory_checked : bool
        The caller has checked the resampling's memory over these records and others.
    """
    paths = [Path(p) for p in paths]
    _refuse_repeats(paths)
    keys = record_keys(paths) if keys is None else list(keys)
    window = _time_range(time_range)
    skip = "all" if "all" in skip_checks else tuple(skip_checks)
    if resample is not None and not memory_checked:
        _check_resample_memory(paths, resample)
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
    if resample is not None:  # all the sets together
        _check_resample_memory(flat, resample)
    keys = record_keys(flat)
    out, start = [], 0
    for paths in path_sets:
        out.append(read_records(paths, resample, keys=keys[start:start + len(paths)],
                                memory_checked=True, **options))
        start += len(paths)
    return out

"""Record files: which files a list of paths and patterns names, and reading one of them.

Every verb reads its records here, in memory or on the workers of a streamed fit
(:mod:`sindyship.streaming`).  A record is one file: a measurement CSV
(docs/measurement-csv.md) or a Parquet file with the same columns (``.parquet``, ``.pq``;
the column names may carry units in brackets as CSV headers do).  Both go through
:func:`sindyship.measurements.trajectory_from_frame`, so the unit conversions, the checks and
their one-line errors are those of the CSV reader.
"""

from __future__ import annotations

import glob
import os
import warnings
from collections.abc import Iterable, Sequence
from pathlib import Path

import pandas as pd

from .errors import SindyshipInputError
from .trajectory import Trajectory

__all__ = ["MIN_RECORD_LENGTH", "PARQUET_SUFFIXES", "expand_paths", "read_record",
           "time_window"]

#: File suffixes read as Parquet; every other file is read as a measurement CSV.
PARQUET_SUFFIXES = (".parquet", ".pq")
#: The shortest record a verb takes, in ship-length times L/U0: a shorter one cannot show the
#: ship's response to its rudder (a flight of it is a few samples from its measured start, and
#: scores near zero whatever the model; a fit or a held-out error of it says nothing).
MIN_RECORD_LENGTH = 1.0

#: How to install what reading Parquet needs.
PARQUET_INSTALL = 'python3 -m pip install "sindyship[parquet]"'


def expand_paths(patterns: Iterable[str | os.PathLike]) -> list[str]:
    """The files named by paths and glob patterns, in order (each pattern's matches sorted).

    A path that exists is kept as it is; a pattern (with ``*``, ``?`` or ``[``; ``**``
    spans folders) is replaced by the files it matches; any other path is kept for the reader
    to report.

    Raises
    ------
    SindyshipInputError
        When a pattern matches no file.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     for name in ("b.csv", "a.csv", "c.txt"):
    ...         _ = (Path(folder) / name).write_text("")
    ...     [Path(p).name for p in expand_paths([Path(folder) / "*.csv"])]
    ['a.csv', 'b.csv']
    """
    out: list[str] = []
    for pattern in patterns:
        text = os.fspath(pattern)
        if os.path.exists(text) or not glob.has_magic(text):
            out.append(text)
            continue
        matches = sorted(p for p in glob.glob(os.path.expanduser(text), recursive=True)
                         if os.path.isfile(p))
        if not matches:
            raise SindyshipInputError(
                f"no files match {text!r}; check the folder and the pattern (quote it, "
                "'fleet/*.parquet', so that the shell passes it on)."
            )
        out.extend(matches)
    return out


def time_window(text: str) -> tuple[float, float] | str:
    """``"auto"``, ``"all"`` or the ``(start, stop)`` [s] of ``"START:STOP"``.

    Raises
    ------
    SindyshipInputError
        For anything else, or ``START >= STOP``.

    Examples
    --------
    >>> time_window("120:1800"), time_window("auto")
    ((120.0, 1800.0), 'auto')
    """
    if text in ("auto", "all"):
        return text
    start, sep, stop = str(text).partition(":")
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


def record_columns(path: str | os.PathLike) -> set[str] | None:
    """The channel names of a record file's header (units stripped), read without its rows;
    None for a file whose header cannot be read (its reader says why when it is read)."""
    import csv

    from .units import parse_headers

    path = Path(path)
    try:
        if path.suffix.lower() in PARQUET_SUFFIXES:
            import pyarrow.parquet as pq

            headers = [str(name) for name in pq.read_schema(path).names]
        else:
            with path.open(encoding="utf-8-sig", newline="") as handle:
                headers = next((row for row in csv.reader(handle) if any(c.strip() for c in row)),
                               [])
        return {column.name for column in parse_headers(headers, str(path))}
    except (OSError, ValueError, ImportError, csv.Error, SindyshipInputError):
        return None


def _read_parquet(path: Path, name: str, **options) -> Trajectory:
    """A Parquet record through the checks of the CSV reader."""
    from .measurements import trajectory_from_frame

    source = str(path)
    if not path.is_file():
        raise SindyshipInputError(f"{source}: no such file; check the path.")
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise SindyshipInputError(
            f"{source}: reading Parquet needs pyarrow; install it with {PARQUET_INSTALL}."
        ) from None
    try:
        frame = pq.read_table(path).to_pandas()
    except (OSError, ValueError) as exc:
        reason = " ".join(str(exc).split())[:200]
        raise SindyshipInputError(
            f"{source}: cannot be read as Parquet ({reason}); give a Parquet file with the "
            "columns of a measurement CSV."
        ) from None
    time = next((c for c in frame.columns if str(c).split("[")[0].strip() == "t"), None)
    if time is not None and pd.api.types.is_datetime64_any_dtype(frame[time]):
        # a timestamp column: seconds from the record's first sample
        stamps = frame[time]
        frame = frame.drop(columns=[time]).assign(
            t=(stamps - stamps.iloc[0]).dt.total_seconds().to_numpy())
    return trajectory_from_frame(frame, name, source=source, **options)


def read_record(path: str | os.PathLike, *, name: str | None = None, ship=None,
                resample: float | None = None, skip_checks: str | Sequence[str] = (),
                time_range: tuple[float, float] | str = "auto"
                ) -> tuple[Trajectory, list[str], tuple[float, float, str] | None]:
    """One record file, checked for plausibility and cut to the time range.

    Parameters
    ----------
    path : str or os.PathLike
        A measurement CSV, or a Parquet file (:data:`PARQUET_SUFFIXES`) with the same columns.
    name : str, optional
        The record's name (default: the file stem).
    ship : Ship, optional
        The ship measured: enables the ship-scaled checks and the automatic time range.
    resample : float, optional
        Step [s] to resample onto (:func:`sindyship.measurements.read_csv`).
    skip_checks : str or sequence of str
        Plausibility checks not to run, or ``"all"``.
    time_range : "auto", "all" or (start, stop)
        ``"auto"`` keeps the part under way with the propeller running
        (:func:`sindyship.trials.underway_window`, with a ship), ``"all"`` every sample.

    Returns
    -------
    record : Trajectory
    notes : list of str
        What the plausibility checks repaired (e.g. an unwrapped heading).
    cut : (start, stop, reason) or None
        The automatic cut, when it removed samples.

    Raises
    ------
    SindyshipInputError
        For a file the reader refuses (one sentence naming the file), a time range that
        keeps fewer than two samples, or, with a ship, a record shorter than
        :data:`MIN_RECORD_LENGTH` ship-length times after its cut.
    """
    from .measurements import PlausibilityNote, read_csv
    from .trials import flight_start, trim, underway_window

    path = Path(path)
    if path.suffix.lower() == ".json":
        raise SindyshipInputError(f"{path} is a saved model (JSON), not a record; give "
                                  "measurement CSV or Parquet files here.")
    name = path.stem if name is None else name
    skip = "all" if "all" in skip_checks else tuple(skip_checks)
    options = {"resample": resample, "ship": ship, "skip_checks": skip}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityNote)  # returned as notes
        if path.suffix.lower() in PARQUET_SUFFIXES:
            record = _read_parquet(path, name, **options)
        else:
            record = read_csv(path, **options)
    if record.name != name:
        record = record.with_name(name)
    notes = list(record.meta.get("notes", ()))
    cut = None
    if time_range == "auto" and ship is not None:
        # the manoeuvre is recognised on all the rows, before any cut: a cut never takes its
        # rudder execute and heading reference away
        start = flight_start(record)
        window = underway_window(record, ship)
        begin, reason = window.start, window.reason
        if start.kind != "record" and start.time < begin <= window.stop:
            begin = start.time
            reason += f"; from t = {begin:.6g} s, the execute of {start.reason.split(',')[0]}"
        if begin > record.t[0] + 1e-9 or window.stop < record.t[-1] - 1e-9:
            cut = (begin, window.stop, reason)
            record = trim(record, (begin, window.stop))
        record = Trajectory(record.data, name=record.name, meta={
            **record.meta, "flight_start": start.as_meta()})
    elif time_range not in ("auto", "all"):
        record = trim(record, time_range)
        if record.n_samples < 2:
            start, stop = time_range
            raise SindyshipInputError(
                f"{path}: --time-range {start:g}:{stop:g} keeps fewer than two samples; "
                "choose times within the record."
            )
    if ship is not None:
        _check_length(record, ship, path, cut)
    return record, _notes_kept(notes, record), cut


def _notes_kept(notes: list[str], record: Trajectory) -> list[str]:
    """The notes, less those on samples the time range left out (a ``jumps`` note whose
    samples all lie outside the record kept)."""
    from .plausibility import JumpNote

    first, last = float(record.t[0]), float(record.t[-1])
    return [note for note in notes if not isinstance(note, JumpNote)
            or any(first <= t <= last for t in note.times)]


def _check_length(record: Trajectory, ship, path: Path, cut) -> None:
    """Refuse a record shorter than :data:`MIN_RECORD_LENGTH` ship-length times."""
    scale = ship.L / ship.U0
    lasts = float(record.t[-1] - record.t[0]) if record.n_samples > 1 else 0.0
    if lasts >= MIN_RECORD_LENGTH * scale:
        return
    after = "" if cut is None else f" after the automatic cut ({cut[2]})"
    hint = (" (or --time-range all, if the cut took too much)" if cut is not None else "")
    raise SindyshipInputError(
        f"{path}: the record lasts {lasts:.3g} s{after}, shorter than one ship-length time "
        f"L/U0 = {scale:.3g} s of ship {ship.name}, too short to show the ship's response to "
        f"its rudder: give a longer record{hint}."
    )

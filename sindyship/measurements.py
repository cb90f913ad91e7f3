"""Measurement CSV: read, validate, convert to SI and write manoeuvre records.

A measurement CSV has one header row of column names and one row per sample (the contract in
docs/measurement-csv.md).  Required columns are ``t, u, v, r, x, y, psi`` and at least one
of ``delta`` (actual rudder angle) and ``delta_c`` (commanded rudder angle); any other named
channel is kept.  A header may carry its unit in brackets, ``psi [deg]``; recognised units are
converted to SI on load (see ``UNITS``), so a :class:`~sindyship.trajectory.Trajectory` always
holds angles in rad, angular rates in rad/s, speeds in m/s, lengths in m, time in s,
propeller revolutions in rps and forces in N.  Files written by :func:`write_csv` have bare SI
headers.

Bad input raises :class:`~sindyship.errors.SindyshipInputError` with one sentence that names
the file (or ``source``), the column and the row, and says how to fix it.  Rows are numbered as
a spreadsheet numbers them: the header is row 1 and the first sample is row 2 (this is also
the line number in a text editor).  For an in-memory DataFrame the row is named by its index
label.

Plausibility thresholds (module constants):

- ``MAX_RUDDER_ANGLE = 1.0`` rad (57 deg).  No conventional rudder turns that far (hard over
  is 35 to 45 deg), so a larger value in a radian column is taken for degrees.
- ``MAX_YAW_RATE = 0.5`` rad/s (29 deg/s).  A steady turn has r' = r L / U below about 1 (a
  turning diameter of at least two ship lengths), so r stays below U / L: about 0.02 rad/s for
  a full-scale tanker, about 0.2 rad/s for a 7 m model at 1.2 m/s and about 0.35 rad/s for a
  2 m model at 0.7 m/s.  Values above 0.5 are taken for deg/s.  The test misses degrees when
  a full-scale ship never yaws faster than 0.5 deg/s; the rudder test covers most such records.
- ``MAX_SPEED = 100`` m/s for ``u`` and ``v`` (194 kn) and ``MAX_REVOLUTIONS = 100`` rps for
  ``n`` (6000 rpm): larger values are no ship's and point at a wrong unit.
- ``SAMPLING_TOLERANCE = 0.01``: the sampling is irregular when some time step differs from
  the median step by more than 1 % of it.  Pass ``resample`` to interpolate onto a regular grid.

The checks of ``delta``, ``delta_c`` and ``r`` (never of the unwrapped heading ``psi``, which
may legitimately exceed 2 pi) can be switched off with ``rudder_check=False`` for unusual craft.
"""

from __future__ import annotations

import csv
import io
import math
import os
import warnings
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pandas as pd

from sindyship._io import write_text_atomic
from sindyship.csv_text import DECIMAL_COMMA, FILE_ROW, REQUIRED_TEXT, parse_csv_text, read_text
from sindyship.errors import SindyshipInputError
from sindyship.plausibility import check_record, resampling_gap_note, resolve_skip
from sindyship.trajectory import (
    REQUIRED_COLUMNS,
    RUDDER_COLUMNS,
    Trajectory,
    checked_for,
    checks_done,
)
from sindyship.units import UNITS, Column, parse_headers, renaming_hint

__all__ = ["PlausibilityNote", "MAX_REVOLUTIONS", "MAX_RUDDER_ANGLE", "MAX_SPEED", "MAX_YAW_RATE",
           "SAMPLING_TOLERANCE", "UNITS", "check_trajectory", "read_csv", "trajectory_from_frame",
           "write_csv"]

MAX_RUDDER_ANGLE = 1.0  # rad
MAX_YAW_RATE = 0.5  # rad/s
MAX_SPEED = 100.0  # m/s
MAX_REVOLUTIONS = 100.0  # rps
MAX_WIND_DIRECTION = 4.0 * math.pi  # rad: two turns (a direction in degrees passes 12.6)
SAMPLING_TOLERANCE = 0.01  # fraction of the median time step
#: The channels of a record in memory that its checks read (others pass unread).
CHECKED_CHANNELS = ("t", "u", "v", "r", "x", "y", "psi", "delta", "delta_c", "n", "wind_dir")
#: A record in memory in its checks' messages (their headers and options: a table's, read).
IN_MEMORY = ("a Trajectory, in SI units; read a table with other units, or with the options "
             "named here, by sindyship.measurements.trajectory_from_frame")


class PlausibilityNote(UserWarning):
    """A one-line note about something the reader repaired on load (a wrapped heading)."""


def read_csv(
    path: str | os.PathLike[str],
    *,
    resample: float | None = None,
    rudder_check: bool = True,
    ship=None,
    skip_checks: str | Iterable[str] = (),
) -> Trajectory:
    """Read a measurement CSV into a validated :class:`Trajectory` in SI units.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file: comma-separated, UTF-8, one header row of column names (optionally with
        a unit in brackets, ``psi [deg]``), then one row per sample.  Blank rows are ignored.
    resample : float, optional
        A time step [s].  When given, every column is linearly interpolated onto the grid
        ``t0 + k * resample`` (k = 0, 1, ... up to the last sample time) instead of raising on
        irregular sampling.  Interpolation is linear in each column, including the unwrapped
        heading ``psi``; the last sample is dropped when it does not fall on the grid.
    rudder_check : bool, default True
        Refuse ``delta``/``delta_c`` beyond 1 rad and ``r`` beyond 0.5 rad/s, which look like
        degrees or deg/s in a radian column.  Switch off only for craft that really turn
        their rudder past 57 deg or yaw faster than 29 deg/s.
    ship : Ship or str, optional
        The ship measured (a :class:`~sindyship.ships.Ship`, a built-in name or a TOML path).
        Enables the checks scaled by its L, U0 and revolutions (``sampling``, ``speed``,
        ``revolutions``).
    skip_checks : str or iterable of str, optional
        Plausibility checks not to run, by name (:data:`sindyship.plausibility.CHECKS`), or
        ``"all"``.  The checks and their thresholds are described in
        :mod:`sindyship.plausibility`; a wrapped heading is unwrapped with a
        :class:`PlausibilityNote` warning and the note kept in ``meta["notes"]``.

    Returns
    -------
    Trajectory
        Named after the file stem; ``meta`` holds ``source`` (the path), ``units`` (the units
        the headers gave, by column), ``resampled`` (the step, or None), ``logged_step`` (the
        median step of the file's own times, before any resampling) and ``notes`` (what the
        plausibility checks changed, e.g. an unwrapped heading).

    Raises
    ------
    SindyshipInputError
        For any problem with the file or its contents: missing or unreadable file, empty file,
        header only or one data row, missing or duplicate column, unknown unit, text, NaN or
        inf in a column, non-increasing time, irregular sampling, degree-like rudder angles or
        yaw rates, absurd values, decimal commas, a record that fails a plausibility check.
        The message names the file, the column and the row (numbered as in a spreadsheet:
        the header is row 1).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> text = ("t,u [kn],v,r [deg/s],x,y,psi [deg],delta [deg]\\n"
    ...         "0,15,0,0,0,0,90,0\\n"
    ...         "1,15,0,0,0,7.7,90,0\\n")
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "straight.csv"
    ...     _ = path.write_text(text)
    ...     record = read_csv(path)
    >>> record.name
    'straight'
    >>> round(float(record["u"][0]), 4), round(float(record["psi"][0]), 4)
    (7.7167, 1.5708)
    """
    source = str(path)
    frame = parse_csv_text(read_text(Path(path), source), source)
    return trajectory_from_frame(
        frame, Path(path).stem, source=source, resample=resample, rudder_check=rudder_check,
        ship=ship, skip_checks=skip_checks,
    )


def trajectory_from_frame(
    frame: pd.DataFrame,
    name: str = "",
    *,
    source: str = "<data>",
    resample: float | None = None,
    rudder_check: bool = True,
    ship=None,
    skip_checks: str | Iterable[str] = (),
) -> Trajectory:
    """Validate an in-memory table and return it as a :class:`Trajectory` in SI units.

    The same checks and unit conversions as :func:`read_csv`, which delegates to this
    function.  Column names may carry units in brackets; values may be numbers or numeric text.

    Parameters
    ----------
    frame : pandas.DataFrame
        One row per sample.  Rows are named in messages by their index label.
    name : str, optional
        The trajectory's name.
    source : str, optional
        What to call the data in error messages (a file name, or ``"<data>"``).
    resample : float, optional
        Time step [s] of a regular grid to interpolate onto; see :func:`read_csv`.
    rudder_check : bool, default True
        Refuse degree-like ``delta``, ``delta_c`` and ``r``; see :func:`read_csv`.
    ship : Ship or str, optional
        Enables the plausibility checks scaled by the ship; see :func:`read_csv`.
    skip_checks : str or iterable of str, optional
        Plausibility checks not to run; see :func:`read_csv`.

    Returns
    -------
    Trajectory
        With bare column names in the order given, float values in SI units and a fresh
        integer index.

    Raises
    ------
    SindyshipInputError
        As described in :func:`read_csv`.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 0.5, 1.0], "u": [8.0, 8.0, 8.0], "v": 0.0,
    ...                       "r [deg/s]": [0.0, 0.1, 0.2], "x": [0.0, 4.0, 8.0], "y": 0.0,
    ...                       "psi": 0.0, "delta [deg]": [0.0, 5.0, 10.0]})
    >>> record = trajectory_from_frame(frame, "demo")
    >>> [round(float(value), 4) for value in record["delta"]]
    [0.0, 0.0873, 0.1745]
    >>> frame.loc[2, "delta [deg]"] = float("nan")
    >>> trajectory_from_frame(frame, "demo")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: <data>: column 'delta [deg]' has no value (NaN) ...
    """
    if not isinstance(frame, pd.DataFrame):
        raise TypeError(f"expected a pandas DataFrame, got {type(frame).__name__}")
    columns = parse_headers([str(header) for header in frame.columns], source)
    _check_required(columns, frame, source)
    if len(frame) < 2:
        raise SindyshipInputError(f"{source}: " + ("has no data rows" if len(frame) == 0 else (
            "has only one data row")) + "; a trajectory needs at least two samples, one per row "
            "after the header.")
    if resample is not None:
        _check_step(resample, source)
    skip = resolve_skip(skip_checks)
    if isinstance(ship, (str, os.PathLike)):
        from sindyship.ships import load_ship

        ship = load_ship(ship)

    index = frame.index
    raw: dict[str, np.ndarray] = {}
    for position, column in enumerate(columns):
        values = column_as_float(frame.iloc[:, position].to_numpy(), column, index, source)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            value = values[bad[0]]
            what = "no value (NaN)" if np.isnan(value) else f"an infinite value ({value})"
            raise SindyshipInputError(
                f"{source}: column '{column.header}' has {what} in {_row(index, bad[0])}; "
                "fill in the value or delete the row."
            )
        raw[column.name] = values
    si = {column.name: raw[column.name] * column.factor for column in columns}

    _check_time(si["t"], columns, index, source, resample)
    _check_plausible(si, raw, columns, index, source, rudder_check)
    headers = {column.name: (column.header, column.unit) for column in columns}
    si, notes = check_record(si, headers, source=source, ship=ship, skip=skip,
                             row=lambda position: _row(index, position))
    gap = None if resample is None else resampling_gap_note(si["t"], resample, source)
    notes = notes if gap is None else [*notes, gap]
    for note in notes:
        warnings.warn(note, PlausibilityNote, stacklevel=2)
    logged = float(np.median(np.diff(si["t"]))) if len(si["t"]) > 1 else None
    if resample is not None:
        si = _resample(si, resample, source)

    data = pd.DataFrame(si)
    meta = {
        "source": source,
        "units": {column.name: column.unit for column in columns if column.unit is not None},
        "resampled": None if resample is None else float(resample),
        "logged_step": logged,
        "notes": notes,
        "checks": checks_done(ship, skip, rudder_check),
    }
    return Trajectory(data, name=name, meta=meta)


def check_trajectory(record: Trajectory, ship=None) -> Trajectory:
    """A record built in memory, checked as :func:`read_csv` checks a file.

    A :class:`Trajectory` made by hand holds SI units without headers to say so, and nothing
    checks it when it is made; :func:`sindyship.fit`, :func:`sindyship.evaluate`,
    :func:`sindyship.refine` and the diagnosis check it here first, so that a rudder in
    degrees, a yaw rate in deg/s, times in milliseconds, speeds in knots, a flipped sign,
    shuffled or missing rows are refused instead of fitted.  A record that passed them for
    ``ship`` (read by :func:`read_csv` or :func:`trajectory_from_frame`, or flown by the
    simulator; ``meta["checks"]``, :func:`~sindyship.trajectory.checks_done`) is returned as it is.

    Parameters
    ----------
    record : Trajectory
        Channels in SI; those of :data:`CHECKED_CHANNELS` are checked, others pass unread.
    ship : Ship, optional
        Enables the checks scaled by its L, U0 and revolutions.

    Returns
    -------
    Trajectory
        The record (its heading unwrapped where it wrapped), ``meta["checks"]`` set.

    Raises
    ------
    SindyshipInputError
        Naming the record, the check and the fix; a record in other units is read with
        :func:`trajectory_from_frame`, whose headers name them (``delta [deg]``) and which
        takes ``skip_checks``.

    Examples
    --------
    >>> frame = pd.DataFrame({"t": [0.0, 1.0, 2.0], "u": 8.0, "v": 0.0, "r": 0.0,
    ...                       "x": [0.0, 8.0, 16.0], "y": 0.0, "psi": 0.0,
    ...                       "delta": [0.0, 5.0, 10.0]})
    >>> check_trajectory(Trajectory(frame, "run"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: record 'run' (a Trajectory, in SI units; ...
    """
    done = record.meta.get("checks")
    if done is not None and (ship is None or checked_for(record, ship)):
        return record
    data = record.data.reset_index(drop=True)
    read = [c for c in data.columns if c in CHECKED_CHANNELS]
    checked = trajectory_from_frame(
        data[read], record.name, source=record.meta.get("source") or f"record {record.name!r} "
        f"({IN_MEMORY})", ship=ship, skip_checks=() if done is None else done["skipped"],
        rudder_check=True if done is None else done["rudder_check"])
    data = data.assign(**{c: checked.data[c].to_numpy() for c in read})  # psi unwrapped
    meta = {**record.meta, "checks": checked.meta["checks"],
            "notes": [*record.meta.get("notes", []), *checked.meta["notes"]]}
    return Trajectory(data, name=record.name, meta=meta)


def write_csv(trajectory: Trajectory, path: str | os.PathLike[str]) -> Path:
    """Write a trajectory as a measurement CSV with bare SI headers, atomically.

    Values are written with ``repr``, the shortest text that reads back to the identical
    float, so ``read_csv(write_csv(x, p))`` reproduces the data of ``x`` exactly.  The file is
    first written to a hidden temporary file in the same folder and then renamed over
    ``path`` (:func:`sindyship._io.write_text_atomic`), so a failure never leaves a
    half-written file; a missing folder is created.

    Parameters
    ----------
    trajectory : Trajectory
        The record to write (its ``data``; ``name`` and ``meta`` are not written).
    path : str or os.PathLike
        Destination; an existing file is replaced.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    SindyshipInputError
        When the file cannot be written (no permission, a file in the way of its folder, ...).

    Examples
    --------
    >>> import tempfile
    >>> import pandas as pd
    >>> from pathlib import Path
    >>> frame = pd.DataFrame({"t": [0.0, 0.1], "u": [1.0, 1.0], "v": 0.0, "r": 0.0,
    ...                       "x": [0.0, 0.1], "y": 0.0, "psi": 0.0, "delta": 0.0})
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = write_csv(Trajectory(frame, "run"), Path(folder) / "run.csv")
    ...     print(path.read_text().splitlines()[:2])
    ...     again = read_csv(path)
    ['t,u,v,r,x,y,psi,delta', '0.0,1.0,0.0,0.0,0.0,0.0,0.0,0.0']
    >>> again.data.equals(frame)
    True
    """
    target = Path(path)
    data = trajectory.data
    columns = [
        [repr(value) for value in data.iloc[:, position].to_numpy(dtype=float).tolist()]
        for position in range(data.shape[1])
    ]
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow([str(column) for column in data.columns])
    writer.writerows(zip(*columns, strict=True))
    try:
        write_text_atomic(target, text.getvalue())
    except OSError as error:
        reason = error.strerror or str(error)
        raise SindyshipInputError(
            f"{target}: cannot write the file ({reason}); check that its folder can be written."
        ) from error
    return target


# ---------------------------------------------------------------------------------------------
# Validation


def _check_required(columns: list[Column], frame: pd.DataFrame, source: str) -> None:
    names = [column.name for column in columns]
    missing = [f"'{name}'" for name in REQUIRED_COLUMNS if name not in names]
    wanted = [name for name in REQUIRED_COLUMNS if name not in names]
    if not any(name in names for name in RUDDER_COLUMNS):
        missing.append("'delta' or 'delta_c'")
        wanted.extend(RUDDER_COLUMNS)
    if not missing:
        return
    hint = renaming_hint(wanted, names)
    lower = {name.lower(): name for name in names}
    for name in wanted:
        if name.lower() in lower:
            hint = f" (there is '{lower[name.lower()]}'; names are case-sensitive)"
            break
    if "t" in wanted and frame.index.name in ("t", "time"):
        hint = " (time is the frame's index; call frame.reset_index() first)"
    if {"X", "Y", "N"} <= set(names) and "t" in wanted:
        raise SindyshipInputError(
            f"{source}: this is a captive-test table (forces X, Y, N and no time column), not "
            "a measured trajectory; give a trajectory record here, and captive tests where a "
            "command takes them (sindyship forces MODEL CAPTIVE.csv)."
        )
    if str(source).lower().endswith(".dat"):  # the MARIN files' own layout
        hint = (" (a MARIN .dat file is made into measurement CSVs by python3 -m "
                "sindyship.marin OUT --data FOLDER)")
    noun = "column" if len(missing) == 1 else "columns"
    raise SindyshipInputError(
        f"{source}: missing {noun} {', '.join(missing)}{hint}; a measurement needs the "
        f"columns {REQUIRED_TEXT}."
    )


def _row(index: pd.Index, position: int) -> str:
    """Name a row for a message: spreadsheet row for files, index label for frames."""
    label = index[position]
    if index.name == FILE_ROW:
        return f"row {label} (counting the header as row 1)"
    return f"the row with index label {label}"


def _is_date_time(value) -> bool:
    """Whether a cell reads as a date or a time of day ("2024-05-01 10:00:00", "10:00:03")."""
    text = str(value).strip()
    if not any(mark in text for mark in "-:/") or not any(c.isdigit() for c in text):
        return False
    try:
        pd.Timestamp(text)
    except (ValueError, TypeError, OverflowError):
        return False
    return True


def column_as_float(values: np.ndarray, column: Column, index: pd.Index, source: str) -> np.ndarray:
    if values.dtype != object or "_" not in "\x00".join(map(str, values)):  # 2_8: no CSV number
        try:
            return np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            pass
    for position, value in enumerate(values):
        try:
            float(str(value).replace("_", " "))
        except (TypeError, ValueError):
            if value is None or value is pd.NA or (isinstance(value, str) and not value.strip()):
                what = "an empty cell"
            elif DECIMAL_COMMA.fullmatch(str(value).strip()):
                what = f"the decimal comma '{str(value).strip()}'"
            else:
                what = f"the text '{str(value).strip()}'"
            if column.name == "t" and _is_date_time(value):
                raise SindyshipInputError(
                    f"{source}: column '{column.header}' holds the date-time "
                    f"'{str(value).strip()}' in {_row(index, position)}; write t as seconds "
                    "(from the first sample, say), or give the records as Parquet, whose "
                    "timestamp column t is read as seconds from the first sample."
                ) from None
            raise SindyshipInputError(
                f"{source}: column '{column.header}' has {what} in {_row(index, position)} "
                "where a number is expected; write a number there or delete the row."
            ) from None
    raise SindyshipInputError(  # pragma: no cover - numpy refused what float() accepts
        f"{source}: column '{column.header}' cannot be read as numbers; write plain numbers."
    )


def _check_step(step: float, source: str) -> None:
    try:
        ok = math.isfinite(step) and step > 0
    except TypeError:
        ok = False
    if not ok:
        raise SindyshipInputError(
            f"{source}: the resampling step {step!r} is not a positive number of seconds; "
            "give --resample DT (resample=DT in Python) with DT > 0."
        )


def _check_time(
    t: np.ndarray,
    columns: list[Column],
    index: pd.Index,
    source: str,
    resample: float | None,
) -> None:
    header = next(column.header for column in columns if column.name == "t")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = bad[0] + 1
        kind = "repeats" if steps[bad[0]] == 0 else "goes back"
        rounded = kind == "repeats" and np.count_nonzero(steps == 0) > 0.05 * steps.size
        raise SindyshipInputError(
            f"{source}: time in column '{header}' {kind} in {_row(index, i)}, where "
            f"t = {t[i]:.10g} s follows t = {t[i - 1]:.10g} s; " + (
                f"{np.count_nonzero(steps == 0)} of {steps.size} steps repeat: write the time "
                "with more digits if it was rounded, or remove rows written twice." if rounded else
                "sort the rows by time and remove duplicate samples."))
    if resample is not None:
        return
    median = float(np.median(steps))
    deviation = np.abs(steps - median)
    worst = int(np.argmax(deviation))
    if deviation[worst] > SAMPLING_TOLERANCE * median:
        raise SindyshipInputError(
            f"{source}: the sampling is irregular: the time step into {_row(index, worst + 1)} "
            f"is {steps[worst]:.6g} s while the median step is {median:.6g} s (more than "
            f"{SAMPLING_TOLERANCE:.0%} apart); give --resample DT (resample=DT in Python) to "
            "interpolate it onto a regular grid."
        )


def _check_plausible(
    si: dict[str, np.ndarray],
    raw: dict[str, np.ndarray],
    columns: list[Column],
    index: pd.Index,
    source: str,
    rudder_check: bool,
) -> None:
    by_name = {column.name: column for column in columns}

    def refuse(name: str, limit: str, fix_unitless: str, fix_with_unit: str) -> None:
        column = by_name[name]
        position = int(np.argmax(np.abs(si[name])))
        value = f"{raw[name][position]:.6g}" + (f" {column.unit}" if column.unit else "")
        fix = fix_unitless if column.unit is None else fix_with_unit
        raise SindyshipInputError(
            f"{source}: column '{column.header}' reaches {value} in {_row(index, position)}, "
            f"beyond {limit}; {fix}."
        )

    bypass = " (or, reading in Python, pass rudder_check=False if the values are right)"
    for name in ("u", "v"):
        if np.max(np.abs(si[name])) > MAX_SPEED:
            refuse(
                name,
                f"any ship speed ({MAX_SPEED:.0f} m/s)",
                f"check the values and give their unit in the header, e.g. '{name} [kn]'",
                f"check the values and the unit '{by_name[name].unit}'",
            )
    if "n" in si and np.max(np.abs(si["n"])) > MAX_REVOLUTIONS:
        refuse(
            "n",
            f"any propeller ({MAX_REVOLUTIONS:.0f} rps)",
            "the values look like rpm, so write the header as 'n [rpm]'",
            f"check the values and the unit '{by_name['n'].unit}'",
        )
    if "wind_dir" in si and np.max(np.abs(si["wind_dir"])) > MAX_WIND_DIRECTION:
        refuse(
            "wind_dir",
            f"two turns of a direction ({MAX_WIND_DIRECTION:.4g} rad = 720 deg)",
            "the values look like degrees, so write the header as 'wind_dir [deg]'",
            f"check the values and the unit '{by_name['wind_dir'].unit}'",
        )
    if not rudder_check:
        return
    for name in RUDDER_COLUMNS:
        if name in si and np.max(np.abs(si[name])) > MAX_RUDDER_ANGLE:
            refuse(
                name,
                f"any rudder angle ({MAX_RUDDER_ANGLE:g} rad = 57 deg)",
                f"the values look like degrees, so write the header as '{name} [deg]'" + bypass,
                f"check the values and the unit '{by_name[name].unit}'" + bypass,
            )
    if np.max(np.abs(si["r"])) > MAX_YAW_RATE:
        refuse(
            "r",
            f"any ship's yaw rate ({MAX_YAW_RATE:g} rad/s = 29 deg/s)",
            "the values look like deg/s, so write the header as 'r [deg/s]'" + bypass,
            f"check the values and the unit '{by_name['r'].unit}'" + bypass,
        )


def _resample(si: dict[str, np.ndarray], step: float, source: str) -> dict[str, np.ndarray]:
    t = si["t"]
    count = int(math.floor((t[-1] - t[0]) / step * (1.0 + 1e-12))) + 1
    if count < 2:
        raise SindyshipInputError(
            f"{source}: the resampling step {step:g} s is longer than the record "
            f"({t[-1] - t[0]:g} s); choose a smaller step."
        )
    grid = t[0] + step * np.arange(count)
    return {
        name: grid.copy() if name == "t" else np.interp(grid, t, values)
        for name, values in si.items()
    }

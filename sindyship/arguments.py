"""The arguments of the public functions, checked once: a ship by name or object, records as
objects or files, a model as an object or a saved file.

Every check raises ``TypeError`` for an argument of the wrong kind and ``ValueError``
(:class:`~sindyship.errors.SindyshipInputError`) for one of the right kind with a wrong value,
each naming the argument and saying what to pass.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable

import numpy as np

from .errors import SindyshipInputError
from .ships import Ship, load_ship
from .trajectory import RUDDER_COLUMNS, Trajectory, checked_for

__all__ = ["as_records", "as_ship", "check_distinct_names", "check_motion", "check_records",
           "check_scale", "check_training_speed", "check_two_records", "positive_number"]

#: Channels a record needs finite in every sample to be fitted or flown against.
MOTION_CHANNELS = ("t", "u", "v", "r", "x", "y", "psi")
#: A record whose speed peaks above this many design speeds belongs to another ship (or scale).
OTHER_SHIP_SPEED_RATIO = 3.0
#: Training records none of which goes faster than this share of U0 are refused: the fit,
#: the automatic time range and the sampling notes all scale with U0 (a U0 in knots read as
#: m/s leaves the records at 0.51 of it; trials at another approach speed give that as U0).
SLOWEST_TRAINING = 0.6
#: Why a verb that leaves one manoeuvre out needs two training records or more.
LEAVE_ONE_OUT = {
    "diagnose": "effects are scored by leave-one-manoeuvre-out cross-validation",
    "discover": "findings are judged leaving one manoeuvre out",
}


def as_ship(ship, name: str = "ship") -> Ship:
    """A :class:`Ship` from a ship, a built-in name or a TOML file's path.

    Examples
    --------
    >>> as_ship("kcs").name
    'kcs'
    >>> as_ship(230.0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    TypeError: ship must be a Ship, a built-in ship name such as 'kcs' or a ship TOML file, ...
    """
    if isinstance(ship, Ship):
        return ship
    if isinstance(ship, str | os.PathLike):
        return load_ship(ship)
    raise TypeError(f"{name} must be a Ship, a built-in ship name such as 'kcs' or a ship TOML "
                    f"file, not {type(ship).__name__}.")


def as_records(records, name: str = "records", *, allow_empty: bool = False
               ) -> list[Trajectory]:
    """A list of records from one record, a file's path, or an iterable of them (read once:
    a generator is not consumed twice).

    Examples
    --------
    >>> as_records("asymmetry")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: asymmetry: no such file; records are Trajectory ...
    """
    from .measurements import read_csv

    if isinstance(records, Trajectory | str | os.PathLike):
        records = [records]
    if isinstance(records, dict):
        raise TypeError(f"{name} must be a list of Trajectory (or of measurement CSV paths), "
                        f"not a dict; pass list({name}.values()).")
    if not isinstance(records, Iterable):
        raise TypeError(f"{name} must be a list of Trajectory (or of measurement CSV paths), "
                        f"not {type(records).__name__}.")
    out = []
    for item in records:
        if isinstance(item, Trajectory):
            out.append(item)
        elif isinstance(item, str | os.PathLike):
            if not os.path.isfile(item):
                raise SindyshipInputError(f"{os.fspath(item)}: no such file; records are "
                                          "Trajectory objects or the paths of measurement CSVs.")
            out.append(read_csv(item))
        else:
            raise TypeError(f"{name} must hold Trajectory objects (or measurement CSV paths), "
                            f"not {type(item).__name__}.")
    if not out and not allow_empty:
        raise SindyshipInputError(f"{name} is empty; pass at least one record.")
    return out


def check_distinct_names(records) -> None:
    """No two records share a name (results are reported, and flights matched, by name).

    Examples
    --------
    >>> import pandas as pd
    >>> run = Trajectory(pd.DataFrame({"t": [0.0, 1.0]}), name="zz20")
    >>> check_distinct_names([run, run])
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: two records share a name; give each file a distinct name.
    """
    names = [r.name for r in records]
    if len(set(names)) != len(names):
        raise SindyshipInputError("two records share a name; give each file a distinct name.")


def check_two_records(records, verb: str) -> None:
    """At least two training records for ``verb`` (a key of :data:`LEAVE_ONE_OUT`), which
    leaves one manoeuvre out.

    Examples
    --------
    >>> check_two_records(["zz20"], "discover")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: discover needs at least two training records: ...
    """
    if len(records) < 2:
        raise SindyshipInputError(
            f"{verb} needs at least two training records: {LEAVE_ONE_OUT[verb]}.")


def check_motion(records, name: str = "records") -> None:
    """Every record's time, motion, position, heading and rudder angles are finite numbers.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": [1.0, float("nan")], "v": 0.0, "r": 0.0,
    ...                       "x": 0.0, "y": 0.0, "psi": 0.0, "delta": 0.0})
    >>> check_motion([Trajectory(frame, "run")])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: records: run has a missing or infinite u at t = 1 s; ...
    """
    for record in records:
        for channel in MOTION_CHANNELS:
            if not record.has(channel):
                raise SindyshipInputError(
                    f"{name}: {record.name or 'a record'} has no column {channel!r}; a record "
                    "needs t, u, v, r, x, y, psi and a rudder angle."
                )
        for channel in [*MOTION_CHANNELS, *(c for c in RUDDER_COLUMNS if record.has(c))]:
            values = record[channel]
            bad = ~np.isfinite(values)
            if bad.any():
                k = int(np.argmax(bad))
                when = f"t = {record.t[k]:g} s" if channel != "t" else f"sample {k}"
                raise SindyshipInputError(
                    f"{name}: {record.name or 'a record'} has a missing or infinite {channel} at "
                    f"{when}; give records with every sample of u, v, r, x, y, psi and the "
                    "rudder angle."
                )


def check_scale(records, ship: Ship, name: str = "records") -> None:
    """Refuse records far faster than the ship's design speed, or never under way at it
    (another ship, or records of one scale given the other scale's particulars).

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": 1.18, "v": 0.0, "r": 0.0, "x": [0.0, 1.18],
    ...                       "y": 0.0, "psi": 0.0, "delta": 0.0})
    >>> check_scale([Trajectory(frame, "zz20")], load_ship("kcs"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: records: zz20 never goes faster than 1.18 m/s, 0.0956 ...
    """
    from .trials import UNDERWAY_SPEED

    for record in records:
        if not (record.has("u") and record.has("v")) or record.n_samples == 0:
            continue
        top = record.fastest
        if top > OTHER_SHIP_SPEED_RATIO * ship.U0:
            raise SindyshipInputError(
                f"{name}: {record.name or 'a record'} reaches {top:.4g} m/s, "
                f"{top / ship.U0:.3g} times the design speed U0 = {ship.U0:.4g} m/s of ship "
                f"{ship.name!r}; give the ship (and scale) the records were measured on."
            )
        if top < UNDERWAY_SPEED * ship.U0:
            raise SindyshipInputError(
                f"{name}: {record.name or 'a record'} never goes faster than {top:.4g} m/s, "
                f"{top / ship.U0:.3g} times the design speed U0 = {ship.U0:.4g} m/s of ship "
                f"{ship.name!r}, and is no record of it under way; give the ship (and scale) "
                "the records were measured on, with U0 their approach speed."
            )


def check_training_speed(ship: Ship, records=(), *, fastest: float | None = None) -> None:
    """Refuse training records none of which reaches :data:`SLOWEST_TRAINING` times the
    ship's design speed U0: a U0 in knots (1.94 times too large), or another ship's records,
    made the automatic time range keep 124 s of a 3200 s turn and fitted the rest.  A
    streamed fit gives the ``fastest`` speed of its records instead.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": 6.0, "v": 0.0, "r": 0.0, "x": [0.0, 6.0],
    ...                       "y": 0.0, "psi": 0.0, "delta": 0.0})
    >>> check_training_speed(load_ship("kcs"), [Trajectory(frame, "zz")])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: no training record goes faster than 6 m/s, 0.49 times...
    """
    if fastest is None:
        fastest = max((record.fastest for record in records), default=None)
    if fastest is not None and fastest < SLOWEST_TRAINING * ship.U0:
        raise SindyshipInputError(
            f"no training record goes faster than {fastest:.4g} m/s, {fastest / ship.U0:.2f} "
            f"times the design speed U0 = {ship.U0:.4g} m/s of ship {ship.name!r}; give the "
            "ship the records are of, with its approach speed U0 in m/s."
        )


def check_records(records, ship: Ship, name: str = "records") -> list[Trajectory]:
    """Records of ``ship``, each checked as a measurement CSV is (those built in memory;
    :func:`sindyship.measurements.check_trajectory`): a speed of another ship
    (:func:`check_scale`), motion that is not finite (:func:`check_motion`), then units,
    signs, order and sampling.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1000.0, 2000.0], "u": 12.0, "v": 0.0, "r": 0.0,
    ...                       "x": [0.0, 12.0, 24.0], "y": 0.0, "psi": 0.0, "delta": 0.0})
    >>> check_records([Trajectory(frame, "run")], load_ship("kcs"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: record 'run' (...): the sampling check refuses ...
    """
    from .measurements import check_trajectory

    check_scale([r for r in records if not checked_for(r, ship)], ship, name)  # unless it flew it
    check_motion(records, name)
    return [check_trajectory(record, ship) for record in records]


def positive_number(value, name: str, *, allow_zero: bool = False) -> float:
    """A finite positive number (or zero when allowed), else an error naming the argument.

    Examples
    --------
    >>> positive_number(-1, "window")
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: window must be a positive number, not -1.
    """
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise TypeError(f"{name} must be a number, not {type(value).__name__}.")
    number = float(value)
    ok = math.isfinite(number) and (number > 0 or (allow_zero and number == 0))
    if not ok:
        raise SindyshipInputError(
            f"{name} must be a {'non-negative' if allow_zero else 'positive'} number, not "
            f"{value!r}.")
    return number

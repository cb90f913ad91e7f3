"""Smoothing records: one entry point that dispatches to the smoothers (Savitzky-Golay,
Kalman RTS)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from ..errors import SindyshipInputError
from ..trajectory import Trajectory
from ._filters import _savgol_record
from ._kalman import _rts_records
from ._settings import RTS_CHANNELS, SmoothingSetting


def smooth_record(record: Trajectory, method: str = "savgol", window: float = 21.0, *,
                  order: int = 3, noise: Mapping[str, float] | None = None,
                  channels: Sequence[str] | None = None) -> Trajectory:
    """A smoothed copy of a record (see the module docstring for the methods).

    Parameters
    ----------
    record : Trajectory
        The record (SI).  Other channels than the smoothed ones are copied unchanged.
    method : {"savgol", "rts", "none"}
        The smoother.
    window : float
        Savitzky-Golay window [s]; for ``"rts"``, the Savitzky-Golay window of about the same
        cut-off frequency.  A window longer than the record is shortened to the record.
    order : int
        Savitzky-Golay polynomial order.
    noise : mapping, optional
        ``"rts"`` only: measurement noise standard deviations (SI) of any of x, y, psi, u, v,
        r; the others are estimated by :func:`estimate_noise`.
    channels : sequence of str, optional
        ``"savgol"`` only: the channels to smooth (default u, v, r).  ``"rts"`` always
        smooths x, y, psi, u, v and r.

    Returns
    -------
    Trajectory
        Same name, times and columns; ``meta["smoothing"]`` records the setting and, for
        ``"rts"``, the noise levels used; ``meta["accelerations"]`` holds the smoother's
        (du/dt, dv/dt, dr/dt) in SI for ``"rts"``.

    Raises
    ------
    SindyshipInputError
        For an unknown method, a bad window or order, a record too short for the filter,
        non-finite samples (``"savgol"``) or irregular sampling (``"savgol"``).

    Examples
    --------
    >>> import numpy as np
    >>> from sindyship.ships import load_ship
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> (run,) = fly(MMGModel(load_ship("kcs")), [Manoeuvre("turning-circle", rudder=35,
    ...                                                     duration=400)])
    >>> smooth = smooth_record(run, "rts", window=21.0)  # nearly transparent on clean data
    >>> bool(np.max(np.abs(smooth["r"] - run["r"])) < 0.01 * np.max(np.abs(run["r"])))
    True
    >>> bool(np.max(np.hypot(smooth["x"] - run["x"], smooth["y"] - run["y"])) < 0.01)
    True
    """
    setting = SmoothingSetting(method, window, order)
    name = record.name or "the record"
    if setting.method == "none":
        return Trajectory(record.data.copy(), name=record.name,
                          meta={**record.meta, "smoothing": setting.as_dict()})
    if record.n_samples < 5:
        raise SindyshipInputError(
            f"{name}: {record.n_samples} samples are too few to smooth; a record needs at "
            "least 5."
        )
    if setting.method == "savgol":
        return _savgol_record(record, setting, channels)
    if channels is not None and set(channels) != set(RTS_CHANNELS):
        raise SindyshipInputError(
            f"{name}: the Kalman smoother always estimates {', '.join(RTS_CHANNELS)}; "
            "leave channels unset for method 'rts'."
        )
    (smoothed,) = _rts_records([record], setting, noise or {})
    return smoothed


def smooth_records(records: Iterable[Trajectory], setting: SmoothingSetting | str,
                   **options: Any) -> list[Trajectory]:
    """:func:`smooth_record` with one setting (or its text, ``"savgol:21"``) on every record."""
    if not isinstance(setting, SmoothingSetting):
        setting = SmoothingSetting.parse(setting)
    records = list(records)
    if setting.method == "rts" and records and all(r.n_samples >= 5 for r in records):
        unknown = sorted(set(options) - {"noise"})
        if unknown:
            raise SindyshipInputError(f"method 'rts' takes no option {unknown[0]!r}.")
        return _rts_records(records, setting, options.get("noise") or {})
    return [smooth_record(record, setting.method, setting.window, order=setting.order, **options)
            for record in records]

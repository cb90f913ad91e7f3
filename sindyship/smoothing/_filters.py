"""Smoothing a record: the noise estimate, the Savitzky-Golay filter, dispatch to the smoothers."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import SindyshipInputError
from ..trajectory import Trajectory
from ._settings import _UNIFORM_TOLERANCE, RTS_CHANNELS, SAVGOL_CHANNELS, SmoothingSetting


# ---------------------------------------------------------------------------------------------
# Noise levels
# ---------------------------------------------------------------------------------------------
def estimate_noise(values: np.ndarray, *, trim: float = 0.01) -> float:
    """Standard deviation of white measurement noise on a smooth, densely sampled signal.

    The third difference of a smooth signal sampled well above its bandwidth is nearly zero,
    while that of white noise of standard deviation sigma has variance 20 sigma^2.  The
    estimate is the root of the mean squared third difference over 20, after discarding the
    largest ``trim`` share of them (steps of the rudder make kinks in the accelerations and
    single large third differences), corrected for the trimming as for Gaussian noise.
    Quantisation counts as noise of the step over sqrt(12) where the signal crosses steps.

    Parameters
    ----------
    values : ndarray
        Samples at a (nearly) uniform interval; NaN samples are ignored.
    trim : float
        Share of the largest squared third differences left out.

    Returns
    -------
    float
        The estimated standard deviation (0 for a polynomial of degree < 3).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> t = np.arange(5000.0)
    >>> round(estimate_noise(np.sin(t / 100) + rng.normal(0, 0.01, t.size)), 3)
    0.01
    """
    y = np.asarray(values, dtype=float)
    d3 = np.diff(y[np.isfinite(y)], 3)
    if d3.size == 0:
        return 0.0
    sq = np.sort(d3 * d3)
    keep = max(int(math.ceil((1.0 - trim) * sq.size)), 1)
    mean = float(np.mean(sq[:keep]))
    if keep < sq.size:
        from scipy.stats import chi2

        cut = chi2.ppf(keep / sq.size, 1)
        # E[z^2 | z^2 <= cut] for a standard normal z: the trimmed mean's shrink factor
        shrink = float(chi2.cdf(cut, 3) / chi2.cdf(cut, 1))
        mean /= shrink
    return math.sqrt(mean / 20.0)


# ---------------------------------------------------------------------------------------------
# Smoothing
# ---------------------------------------------------------------------------------------------
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
    from ._kalman import _rts_records  # the Kalman smoother uses this module
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
        from ._kalman import _rts_records  # the Kalman smoother uses this module

        return _rts_records(records, setting, options.get("noise") or {})
    return [setting.apply(record, **options) for record in records]


def _uniform_dt(record: Trajectory, what: str) -> float:
    t = record.t
    steps = np.diff(t)
    dt = float(np.median(steps))
    if not (dt > 0) or np.max(np.abs(steps - dt)) > _UNIFORM_TOLERANCE * dt:
        raise SindyshipInputError(
            f"{record.name or 'the record'}: {what} needs uniform sampling but the time step "
            f"varies from {steps.min():.6g} s to {steps.max():.6g} s; resample the record "
            "(--resample DT) or use method 'rts'."
        )
    return dt


def _savgol_points(window: float, dt: float, order: int, n: int) -> int:
    """Odd number of samples of a window, at least order + 2 and at most the record."""
    points = max(int(round(window / dt)) | 1, (order + 2) | 1)
    return min(points, n if n % 2 else n - 1)


def _savgol_record(record: Trajectory, setting: SmoothingSetting,
                   channels: Sequence[str] | None) -> Trajectory:
    from scipy.signal import savgol_filter

    name = record.name or "the record"
    dt = _uniform_dt(record, "Savitzky-Golay smoothing")
    points = _savgol_points(setting.window, dt, setting.order, record.n_samples)
    if points <= setting.order:
        raise SindyshipInputError(
            f"{name}: {record.n_samples} samples are too few for a Savitzky-Golay filter of "
            f"order {setting.order}."
        )
    data = record.data.copy()
    for column in SAVGOL_CHANNELS if channels is None else channels:
        if column == "t":
            raise SindyshipInputError("time cannot be smoothed; leave 't' out of channels.")
        if column not in data.columns:
            raise SindyshipInputError(f"{name}: there is no channel {column!r} to smooth.")
        values = data[column].to_numpy(dtype=float)
        if not np.all(np.isfinite(values)):
            raise SindyshipInputError(
                f"{name}: channel {column!r} has missing or infinite samples; the "
                "Savitzky-Golay filter needs every sample (use method 'rts')."
            )
        data[column] = savgol_filter(values, points, setting.order, mode="interp")
    meta = {**record.meta, "smoothing": {**setting.as_dict(), "points": points}}
    return Trajectory(data, name=record.name, meta=meta)

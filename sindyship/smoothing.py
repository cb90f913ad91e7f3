"""Smoothing noisy records before identification, and choosing how much to smooth.

The regression targets of eq. 16 need accelerations, and 5-point differences (paper section
3.2) amplify measurement noise: at 1 Hz, white noise of standard deviation sigma on u gives
du/dt noise of about sigma per second, which for a 1 % noise level is larger than the surge
accelerations of most manoeuvres.  Noise in u, v and r also enters the library columns
(errors in variables).  :func:`smooth_record` returns a smoothed copy of a record, so that
both the library columns and the usual 5-point targets are computed from smoothed signals:

``"savgol"``
    A Savitzky-Golay filter (local polynomial of ``order`` over ``window`` seconds) on u, v
    and r.  Positions and heading are left as recorded.  Needs uniform sampling.
``"rts"``
    An extended Kalman filter and Rauch-Tung-Striebel smoother over the state
    ``[x, y, psi, u, v, r, du/dt, dv/dt, dr/dt]``: constant accelerations over a step (u, v
    and the turn rate r change linearly), the accelerations driven by white jerk, and the
    exact kinematics ``dx/dt = u cos psi - v sin psi``, ``dy/dt = u sin psi + v cos psi``,
    ``dpsi/dt = r`` coupling the body-fixed velocities to the earth-fixed track.  So an
    accurate position (GPS) or heading (gyro) improves the velocities it constrains.  All six
    channels are smoothed.  Measurement noise levels are estimated from the record
    (:func:`estimate_noise`) or given; the jerk levels follow from ``window`` (below).
    Handles irregular sampling and missing (NaN) samples.
``"none"``
    The record unchanged (the paper's setting for noise-free data).

What ``window`` means for ``"rts"``.  For a velocity measured with white noise of standard
deviation sigma every dt seconds and driven by white jerk of spectral density q, the
stationary smoother is a low-pass filter with gain ``1 / (1 + (w / w_c)^4)`` and cut-off
``w_c = (q / (sigma^2 dt))^(1/4)`` (a cubic smoothing spline).  The jerk density is set so
that ``w_c = 2 pi f_c`` with ``f_c = 2.5 / window`` Hz, about the -3 dB frequency of a cubic
Savitzky-Golay filter of the same window (Schafer 2011, IEEE Signal Process. Mag. 28(4):111),
so one window means roughly the same smoothing for both methods.

Choosing the setting.  :func:`choose_smoothing` compares candidate settings by
leave-one-manoeuvre-out cross-validation on the training records alone: for every candidate
and every record, the model is fitted on the other records (smoothed with that candidate)
and flown the way the held-out record was flown (:func:`sindyship.evaluation.fly_like`),
from the candidate's estimate of the record's first state; the fold's error is the mean
distance between that flight and the held-out record's *measured* track, in ship lengths (the
Table-10 metric, with the recorded positions as the reference), and a candidate's score is
the geometric mean of its folds' errors.

Why a flight and not a force residual: the force residual of a held-out record computed from
its own smoothed targets rewards smoothing for its own sake (a heavily smoothed target is
easy to predict, and the residuals of different settings are not even measured against the
same numbers).  The measured track is the same reference for every candidate, it is what the
identified model is for, and position noise (metres) is negligible against the distances that
separate good and bad models (a fraction of a ship length).  Why a geometric mean: it weighs
every held-out manoeuvre alike, so a fold that no model flies well (a straight run of a
course-unstable ship drifts away tens of ship lengths whatever the coefficients) neither
dominates nor decides.  A flight that diverges (the protocol's divergence rule) counts as the
worst complete flight of any candidate on that record, so an early divergence never looks
like a small error.

Examples
--------
>>> import numpy as np
>>> import pandas as pd
>>> from sindyship.trajectory import Trajectory
>>> t = np.arange(600.0)
>>> rng = np.random.default_rng(0)
>>> frame = pd.DataFrame({"t": t, "u": 10 + np.sin(t / 60) + rng.normal(0, 0.05, t.size),
...                       "v": 0.0, "r": 0.0, "x": 10 * t, "y": 0.0, "psi": 0.0,
...                       "delta": 0.0})
>>> smooth = smooth_record(Trajectory(frame, "demo"), "savgol", window=31.0)
>>> clean = 10 + np.sin(t / 60)
>>> bool(np.std(smooth["u"] - clean) < 0.3 * np.std(frame["u"] - clean))
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

import numpy as np
import pandas as pd

from .errors import SindyshipInputError
from .ships import Ship
from .trajectory import Trajectory

__all__ = [
    "DEFAULT_CANDIDATES",
    "SHIP_TIME_WINDOWS",
    "default_candidates",
    "SMOOTHING_METHODS",
    "SmoothingSetting",
    "choose_smoothing",
    "estimate_noise",
    "smooth_record",
    "smooth_records",
]

SMOOTHING_METHODS = ("none", "savgol", "rts")
#: Channels the Kalman smoother estimates, in its state order.
RTS_CHANNELS = ("x", "y", "psi", "u", "v", "r")
#: Channels the Savitzky-Golay filter smooths unless told otherwise.
SAVGOL_CHANNELS = ("u", "v", "r")
#: f_c * window of a cubic Savitzky-Golay filter, used to set the Kalman smoother's cut-off.
_CUTOFF_TIMES_WINDOW = 2.5
#: Sampling is uniform when no step differs from the median step by more than this fraction.
_UNIFORM_TOLERANCE = 0.01


@dataclass(frozen=True)
class SmoothingSetting:
    """One way to smooth a record (see :func:`smooth_record`).

    Parameters
    ----------
    method : {"none", "savgol", "rts"}
        Smoother.
    window : float
        Savitzky-Golay window [s], or the window of the same cut-off for ``"rts"``.
    order : int
        Savitzky-Golay polynomial order (unused by the other methods).

    Examples
    --------
    >>> SmoothingSetting("savgol", 21.0).label
    'savgol 21 s'
    >>> SmoothingSetting.parse("rts:41")
    SmoothingSetting(method='rts', window=41.0, order=3)
    """

    method: str = "none"
    window: float = 21.0
    order: int = 3

    def __post_init__(self) -> None:
        if self.method not in SMOOTHING_METHODS:
            raise SindyshipInputError(
                f"unknown smoothing method {self.method!r}; choose one of "
                f"{', '.join(SMOOTHING_METHODS)}."
            )
        if not (isinstance(self.window, Real) and math.isfinite(self.window)
                and self.window > 0):
            raise SindyshipInputError(
                f"the smoothing window must be a positive number of seconds, not {self.window!r}."
            )
        if not (isinstance(self.order, Integral) and 1 <= self.order <= 6):
            raise SindyshipInputError(
                f"the Savitzky-Golay order must be a whole number from 1 to 6, not {self.order!r}."
            )

    @property
    def label(self) -> str:
        """A short name such as ``"savgol 21 s"``, ``"rts 41 s"`` or ``"none"``."""
        if self.method == "none":
            return "none"
        suffix = f" order {self.order}" if self.method == "savgol" and self.order != 3 else ""
        return f"{self.method} {self.window:g} s{suffix}"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready parameters."""
        if self.method == "none":
            return {"method": "none"}
        out: dict[str, Any] = {"method": self.method, "window_s": float(self.window)}
        if self.method == "savgol":
            out["order"] = self.order
        return out

    def apply(self, record: Trajectory, **options: Any) -> Trajectory:
        """The smoothed copy of ``record`` (:func:`smooth_record` with this setting)."""
        return smooth_record(record, self.method, self.window, order=self.order, **options)

    @classmethod
    def parse(cls, text: str) -> SmoothingSetting:
        """A setting from ``"none"``, ``"savgol:21"``, ``"savgol:21:2"`` or ``"rts:41"``."""
        parts = [p.strip() for p in str(text).split(":")]
        method = parts[0]
        try:
            window = float(parts[1]) if len(parts) > 1 else 21.0
            order = int(parts[2]) if len(parts) > 2 else 3
        except ValueError:
            raise SindyshipInputError(
                f"cannot read the smoothing setting {text!r}; write METHOD[:WINDOW_S[:ORDER]], "
                "e.g. savgol:21 or rts:41."
            ) from None
        if len(parts) > 3:
            raise SindyshipInputError(
                f"cannot read the smoothing setting {text!r}; write METHOD[:WINDOW_S[:ORDER]]."
            )
        return cls(method, window, order)


#: Windows of the default candidates in ship time, units of L/U0: 11, 21, 41 and 81 s for the
#: full-scale KCS (L/U0 = 18.6 s), 3.6 to 26 s for the 7 m KVLCC2 model (L/U0 = 5.9 s).  A
#: manoeuvre's motions change over a few L/U0, so a window of a fixed number of seconds smooths
#: a model-scale record far more than a full-scale one.
SHIP_TIME_WINDOWS = (0.6, 1.13, 2.2, 4.35)

#: The candidates :func:`choose_smoothing` compares by default for the full-scale KCS
#: (:func:`default_candidates` of another ship scales the windows with its L/U0).
DEFAULT_CANDIDATES: tuple[SmoothingSetting, ...] = (
    SmoothingSetting("none"),
    SmoothingSetting("savgol", 11.0),
    SmoothingSetting("savgol", 21.0),
    SmoothingSetting("savgol", 41.0),
    SmoothingSetting("savgol", 81.0),
    SmoothingSetting("rts", 21.0),
    SmoothingSetting("rts", 41.0),
)


def default_candidates(ship: Ship) -> tuple[SmoothingSetting, ...]:
    """The default candidates of :func:`choose_smoothing` with windows in ship time.

    Savitzky-Golay over 0.6, 1.13, 2.2 and 4.35 L/U0 and Kalman (RTS) over 1.13 and 2.2 L/U0,
    rounded to 0.1 s (:data:`SHIP_TIME_WINDOWS`), and no smoothing.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> [s.window for s in default_candidates(load_ship("kvlcc2"))][1:5]
    [3.6, 6.7, 13.1, 25.8]
    """
    windows = [round(factor * ship.time_scale, 1) for factor in SHIP_TIME_WINDOWS]
    return (
        SmoothingSetting("none"),
        *(SmoothingSetting("savgol", w) for w in windows),
        *(SmoothingSetting("rts", w) for w in windows[1:3]),
    )


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


# ---------------------------------------------------------------------------------------------
# Kalman filter and Rauch-Tung-Striebel smoother
# ---------------------------------------------------------------------------------------------
# State order: x, y, psi, u, v, r, a_u, a_v, a_r; the first six are measured.  Every function
# works on a batch of records of equal length (leading axis B).
_N = 9
_M = 6
_IX, _IY, _IPSI, _IU, _IV, _IR, _IAU, _IAV, _IAR = range(_N)
# Taylor weights of the Van Loan integral for a nilpotent A (A^4 = 0):
# Q = sum_{j,k} A^j G A^kT dt^(j+k+1) / (j! k! (j+k+1)).
_POW = np.arange(4)
_FACT = np.array([1.0, 1.0, 2.0, 6.0])
#: Variance (in units of the noise variance) that stands for a missing measurement.
_MISSING = 1e12


def _kinematics(z: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Earth-fixed velocity at time s into a step with constant accelerations."""
    psi = z[:, _IPSI] + z[:, _IR] * s + 0.5 * z[:, _IAR] * s * s
    u = z[:, _IU] + z[:, _IAU] * s
    v = z[:, _IV] + z[:, _IAV] * s
    c, sn = np.cos(psi), np.sin(psi)
    return u * c - v * sn, u * sn + v * c


def _propagate(z: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """Mean state after dt: exact for the chains, Simpson's rule for the positions."""
    out = z.copy()
    x0, y0 = _kinematics(z, 0.0 * dt)
    xm, ym = _kinematics(z, 0.5 * dt)
    x1, y1 = _kinematics(z, dt)
    out[:, _IX] += dt / 6.0 * (x0 + 4.0 * xm + x1)
    out[:, _IY] += dt / 6.0 * (y0 + 4.0 * ym + y1)
    out[:, _IPSI] += z[:, _IR] * dt + 0.5 * z[:, _IAR] * dt * dt
    out[:, _IU] += z[:, _IAU] * dt
    out[:, _IV] += z[:, _IAV] * dt
    out[:, _IR] += z[:, _IAR] * dt
    return out


def _jacobian(z: np.ndarray) -> np.ndarray:
    """Continuous-time Jacobians of the dynamics, shape (B, 9, 9); nilpotent (A^4 = 0)."""
    A = np.zeros((z.shape[0], _N, _N))
    c, s = np.cos(z[:, _IPSI]), np.sin(z[:, _IPSI])
    u, v = z[:, _IU], z[:, _IV]
    A[:, _IX, _IPSI] = -u * s - v * c
    A[:, _IX, _IU] = c
    A[:, _IX, _IV] = -s
    A[:, _IY, _IPSI] = u * c - v * s
    A[:, _IY, _IU] = s
    A[:, _IY, _IV] = c
    A[:, _IPSI, _IR] = 1.0
    A[:, _IU, _IAU] = 1.0
    A[:, _IV, _IAV] = 1.0
    A[:, _IR, _IAR] = 1.0
    return A


def _transition(A: np.ndarray, G: np.ndarray, dt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact F = expm(A dt) and the Van Loan process covariance, for nilpotent A."""
    B = A.shape[0]
    powers = np.empty((B, 4, _N, _N))
    powers[:, 0] = np.eye(_N)
    for k in range(1, 4):
        powers[:, k] = powers[:, k - 1] @ A
    tau = dt[:, None] ** _POW / _FACT  # (B, 4)
    F = np.einsum("bj,bjac->bac", tau, powers)
    jk = _POW[:, None] + _POW[None, :]
    weights = (dt[:, None, None] ** (jk + 1)
               / (_FACT[:, None] * _FACT[None, :] * (jk + 1)))  # (B, 4, 4)
    left = powers @ G[:, None]  # A^j G, (B, 4, N, N)
    right = np.einsum("bjk,bkdc->bjcd", weights, powers)  # sum_k w_jk (A^k)^T
    Q = (np.swapaxes(left, 1, 2).reshape(B, _N, 4 * _N)
         @ right.reshape(B, 4 * _N, _N))
    return F, 0.5 * (Q + np.swapaxes(Q, 1, 2))


def _noise_levels(record: Trajectory, noise: Mapping[str, float]) -> tuple[np.ndarray,
                                                                             np.ndarray]:
    """(levels used, levels given or estimated) of x, y, psi, u, v, r for one record."""
    unknown = sorted(set(noise) - set(RTS_CHANNELS))
    if unknown:
        raise SindyshipInputError(
            f"no measurement noise can be given for {unknown[0]!r}; the Kalman smoother "
            f"measures {', '.join(RTS_CHANNELS)}."
        )
    estimated = np.empty(_M)
    for j, channel in enumerate(RTS_CHANNELS):
        given = noise.get(channel)
        if given is None:
            estimated[j] = estimate_noise(record[channel])
            continue
        if not (isinstance(given, int | float) and math.isfinite(given) and given >= 0):
            raise SindyshipInputError(
                f"the noise level of {channel!r} must be a finite number >= 0, not {given!r}."
            )
        estimated[j] = float(given)
    # a floor keeps the filter well posed on noise-free data
    meas = np.column_stack([record[c] for c in RTS_CHANNELS])
    rms = np.sqrt(np.nanmean(meas**2, axis=0))
    floor = 1e-9 * np.where(np.isfinite(rms) & (rms > 0), rms, 1.0)
    return np.maximum(estimated, floor), estimated


def _rts_batch(t: np.ndarray, meas: np.ndarray, sigma: np.ndarray, window: float
               ) -> np.ndarray:
    """Extended Kalman filter and RTS smoother for B records of N samples.

    Parameters
    ----------
    t : ndarray, shape (B, N)
        Sample times [s], increasing.
    meas : ndarray, shape (B, N, 6)
        Measured x, y, psi, u, v, r (SI); NaN where missing.
    sigma : ndarray, shape (B, 6)
        Measurement noise standard deviations (positive).
    window : float
        Savitzky-Golay window of the same cut-off [s] (module docstring).

    Returns
    -------
    ndarray, shape (B, N, 9)
        Smoothed states in SI.
    """
    B, n, _ = meas.shape
    dt_typ = np.median(np.diff(t, axis=1), axis=1)  # (B,)
    omega = 2.0 * math.pi * _CUTOFF_TIMES_WINDOW / window
    # jerk spectral densities from the cut-off, w_c^4 = q / (sigma^2 dt), and a trace of
    # position diffusion for numerical health (model error of the kinematics)
    G = np.zeros((B, _N, _N))
    for j, i in ((3, _IAU), (4, _IAV), (5, _IAR)):
        G[:, i, i] = sigma[:, j] ** 2 * dt_typ * omega**4
    q_p = 1e-6 * np.minimum(sigma[:, 0], sigma[:, 1]) ** 2 / dt_typ
    G[:, _IX, _IX] = q_p
    G[:, _IY, _IY] = q_p
    # scaled coordinates: measured states in units of their noise, accelerations in units of
    # sigma * omega, so that R = I and every covariance entry is of order one
    D = np.concatenate([sigma, sigma[:, 3:] * omega], axis=1)  # (B, N)
    Dinv = 1.0 / D
    scaled = meas * Dinv[:, None, :_M]
    missing = ~np.isfinite(scaled)
    scaled = np.where(missing, 0.0, scaled)

    # a vague prior: the first complete sample with ten noise standard deviations, and
    # accelerations as large as the steepest finite difference of the record
    m = np.zeros((B, _N))
    P = np.zeros((B, _N, _N))
    eye = np.eye(_N)
    for b in range(B):
        complete = np.flatnonzero(~missing[b].any(axis=1))
        m[b, :_M] = scaled[b, complete[0]]
        rates = np.abs(np.diff(meas[b, complete, 3:], axis=0)) / np.diff(t[b, complete])[:, None]
        acc = np.maximum(np.nanmax(rates, axis=0, initial=0.0), sigma[b, 3:] * omega)
        P[b] = np.diag(np.concatenate([np.full(_M, 100.0), (10.0 * acc * Dinv[b, _M:]) ** 2]))
    m_pred = np.empty((B, n, _N))
    P_pred = np.empty((B, n, _N, _N))
    m_filt = np.empty((B, n, _N))
    P_filt = np.empty((B, n, _N, _N))
    F_all = np.empty((B, n, _N, _N))
    rows = np.arange(_M)
    for k in range(n):
        if k > 0:
            dt = t[:, k] - t[:, k - 1]
            z = m_filt[:, k - 1] * D
            F, Q = _transition(_jacobian(_propagate(z, 0.5 * dt)), G, dt)
            Fs = F * Dinv[:, :, None] * D[:, None, :]
            m = _propagate(z, dt) * Dinv
            P = Fs @ P_filt[:, k - 1] @ np.swapaxes(Fs, 1, 2) + Q * (Dinv[:, :, None]
                                                                      * Dinv[:, None, :])
            F_all[:, k] = Fs
        m_pred[:, k] = m
        P_pred[:, k] = P
        # measurement update, H = [I 0], R = I (a missing value: a huge variance)
        R = np.where(missing[:, k], _MISSING, 1.0)
        S = P[:, :_M, :_M].copy()
        S[:, rows, rows] += R
        K = np.swapaxes(np.linalg.solve(S, P[:, :_M, :]), 1, 2)  # (B, N, M)
        innovation = np.where(missing[:, k], 0.0, scaled[:, k] - m[:, :_M])
        m = m + np.einsum("bij,bj->bi", K, innovation)
        IKH = np.broadcast_to(eye, P.shape).copy()
        IKH[:, :, :_M] -= K
        P = IKH @ P @ np.swapaxes(IKH, 1, 2) + (K * R[:, None, :]) @ np.swapaxes(K, 1, 2)
        P = 0.5 * (P + np.swapaxes(P, 1, 2))
        m_filt[:, k] = m
        P_filt[:, k] = P
    smooth = np.empty((B, n, _N))
    smooth[:, -1] = m_filt[:, -1]
    for k in range(n - 2, -1, -1):
        gain_t = np.linalg.solve(P_pred[:, k + 1], F_all[:, k + 1] @ P_filt[:, k])
        step = smooth[:, k + 1] - m_pred[:, k + 1]
        smooth[:, k] = m_filt[:, k] + np.einsum("bji,bj->bi", gain_t, step)
    return smooth * D[:, None, :]


def _rts_records(records: Sequence[Trajectory], setting: SmoothingSetting,
                 noise: Mapping[str, float]) -> list[Trajectory]:
    """The Kalman smoother on records, batching records of equal length."""
    levels = []
    for record in records:
        name = record.name or "the record"
        steps = np.diff(record.t)
        if not np.all(steps > 0):
            raise SindyshipInputError(f"{name}: time must increase from sample to sample.")
        meas = np.column_stack([record[c] for c in RTS_CHANNELS])
        if np.count_nonzero(np.all(np.isfinite(meas), axis=1)) < 5:
            raise SindyshipInputError(
                f"{name}: fewer than 5 samples have all of {', '.join(RTS_CHANNELS)}; "
                "there is too little to smooth."
            )
        levels.append(_noise_levels(record, noise))
    out: list[Trajectory | None] = [None] * len(records)
    groups: dict[int, list[int]] = {}
    for i, record in enumerate(records):
        groups.setdefault(record.n_samples, []).append(i)
    for idx in groups.values():
        t = np.stack([records[i].t for i in idx])
        meas = np.stack([np.column_stack([records[i][c] for c in RTS_CHANNELS]) for i in idx])
        sigma = np.stack([levels[i][0] for i in idx])
        with np.errstate(over="ignore", invalid="ignore"):
            states = _rts_batch(t, meas, sigma, setting.window)
        for b, i in enumerate(idx):
            record = records[i]
            data = record.data.copy()
            for j, channel in enumerate(RTS_CHANNELS):
                data[channel] = states[b, :, j]
            meta = {
                **record.meta,
                "smoothing": {**setting.as_dict(),
                              "noise": dict(zip(RTS_CHANNELS, levels[i][1].tolist(),
                                                strict=True)),
                              "noise_given": sorted(noise)},
                "accelerations": tuple(states[b, :, j].copy() for j in (_IAU, _IAV, _IAR)),
            }
            out[i] = Trajectory(data, name=record.name, meta=meta)
    return out  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------
# Choosing the setting by leave-one-manoeuvre-out cross-validation
# ---------------------------------------------------------------------------------------------
def _as_setting(candidate: SmoothingSetting | str | Mapping | tuple) -> SmoothingSetting:
    if isinstance(candidate, SmoothingSetting):
        return candidate
    if isinstance(candidate, str):
        return SmoothingSetting.parse(candidate)
    if isinstance(candidate, Mapping):
        return SmoothingSetting(candidate.get("method", "none"),
                                float(candidate.get("window", candidate.get("window_s", 21.0))),
                                int(candidate.get("order", 3)))
    return SmoothingSetting(*candidate)


def _fold_task(smoothed: Sequence[Trajectory], raw: Trajectory, held_out: int, ship: Ship,
               library, optimizer: str, params: dict | None, rudder_signal: str,
               step: float | None) -> dict:
    """Fit on all smoothed records but one, fly like the raw held-out one, measure."""
    from threadpoolctl import threadpool_limits

    from .evaluation import distance_errors, fly_like
    from .identify import fit

    train = [r for k, r in enumerate(smoothed) if k != held_out]
    start = _with_initial_state(raw, smoothed[held_out])
    with threadpool_limits(limits=1, user_api="blas"):
        model = fit(train, ship, library=library, optimizer=optimizer, params=params,
                    rudder_signal=rudder_signal)
        channels = _flight_channels(model, raw)
        (flown,) = fly_like(model.dynamics(channels), [start], step=step)
    return distance_errors(flown, raw, ship.L)


def _with_initial_state(raw: Trajectory, smoothed: Trajectory) -> Trajectory:
    """The raw record with its first row's motion state taken from the smoothed record.

    A flight starts from the first row; the smoother's estimate of the initial velocities is
    better than one noisy sample (a single sample's yaw-rate noise can turn a course-unstable
    model away from a straight run).  Everything else, and so the rudder programme and the
    zig-zag detection, stays as recorded.
    """
    data = raw.data.copy()
    for column in ("u", "v", "r", "x", "y", "psi"):
        data.loc[data.index[0], column] = float(smoothed[column][0])
    return Trajectory(data, name=raw.name, meta=dict(raw.meta))


def _flight_channels(model, record: Trajectory) -> dict[str, float] | None:
    """Extra library channels held at their record mean for a flight (None if none)."""
    from .library import nondimensional_variables

    extra = sorted(set(model.library.channels) - {"psi"})
    if not extra:
        return None
    values = nondimensional_variables(record, model.ship.L, model.ship.U0, needed=extra)
    return {name: float(np.mean(values[name])) for name in extra}


def _cv_scores(means: np.ndarray, failed: np.ndarray) -> np.ndarray:
    """Geometric mean over folds of the held-out flight distance, per candidate.

    ``means[i, k]`` is candidate i's mean distance on held-out record k.  A flight that
    diverged counts as the worst complete flight of any candidate on that record (at least
    its own distance before diverging); where every candidate diverged, the largest distance
    before divergence.  The geometric mean weighs every held-out manoeuvre alike, whatever
    its scale: a record whose flights all miss by tens of ship lengths (a straight run of a
    course-unstable ship, where any model drifts) neither dominates nor decides the choice.
    """
    filled = np.where(failed | ~np.isfinite(means), np.nan, means)
    worst = np.nanmax(np.where(np.isfinite(means), means, np.nan), axis=0, initial=0.0)
    complete_worst = np.nanmax(filled, axis=0, initial=-np.inf)
    penalty = np.where(np.isfinite(complete_worst), complete_worst, worst)
    own = np.where(np.isfinite(means), means, 0.0)
    values = np.where(failed | ~np.isfinite(means), np.maximum(penalty[None, :], own), means)
    values = np.maximum(values, 1e-12)
    return np.exp(np.mean(np.log(values), axis=1))


def choose_smoothing(records: Sequence[Trajectory], ship: Ship,
                     candidates: Iterable[SmoothingSetting | str] | None = None,
                     optimizer: str = "ls", *, library="abkowitz", effects: Sequence[str] = (),
                     params: dict | None = None, rudder_signal: str = "actual",
                     n_jobs: int | None = None, step: float | None = None
                     ) -> tuple[SmoothingSetting, pd.DataFrame]:
    """The smoothing setting with the smallest leave-one-manoeuvre-out flight error.

    Uses the training records only (module docstring): for every candidate and record, the
    model is fitted on the other records smoothed with the candidate, then flown the way the
    held-out record was flown (zig-zags closed loop) from its first row, and compared with
    the held-out record's measured track.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records (at least two); nothing else is used.
    ship : Ship
        The ship (L, U0, inertia, rudder servo).
    candidates : iterable of SmoothingSetting or str, optional
        Settings to compare (``"savgol:21"`` style text is accepted); default
        :func:`default_candidates` of the ship (windows in ship time).
    optimizer : str
        Regression method of the folds (:func:`sindyship.optimizers.make_optimizer`).
    library, effects, params, rudder_signal
        As for :func:`sindyship.identify.fit`.
    n_jobs : int, optional
        joblib workers for the smoothing and the folds (``None``: joblib's default, one
        unless inside a ``joblib.parallel_config`` block; ``-1``: every core).  The result does
        not depend on it.
    step : float, optional
        Runge-Kutta step of the flights [s].

    Returns
    -------
    best : SmoothingSetting
        The candidate with the smallest score.
    table : pandas.DataFrame
        One row per candidate: ``setting``, ``method``, ``window_s``, ``order``, ``score_L``
        (the geometric mean over held-out records of the flight's mean distance in ship
        lengths, a diverged flight counting as the worst complete one on its record),
        ``n_diverged``, one column per held-out record (its mean distance, over the samples
        before any divergence) and ``chosen``.

    Raises
    ------
    SindyshipInputError
        For fewer than two records, no candidates, or a bad candidate.
    """
    from joblib import Parallel, delayed

    from .identify import resolve_library

    records = list(records)
    if len(records) < 2:
        raise SindyshipInputError(
            "choosing the smoothing by leave-one-manoeuvre-out cross-validation needs at "
            f"least two training records, not {len(records)}."
        )
    settings = [_as_setting(c) for c in (default_candidates(ship) if candidates is None
                                         else candidates)]
    if not settings:
        raise SindyshipInputError("give at least one smoothing candidate.")
    names = [r.name or f"record {k}" for k, r in enumerate(records)]
    lib = resolve_library(library, effects)

    parallel = Parallel(n_jobs=n_jobs)
    smoothed = parallel(delayed(smooth_records)(records, setting) for setting in settings)
    folds = parallel(
        delayed(_fold_task)(smoothed[i], records[k], k, ship, lib, optimizer, params,
                            rudder_signal, step)
        for i in range(len(settings)) for k in range(len(records))
    )
    n_rec = len(records)
    means = np.array([[e["mean_distance_L"] for e in folds[i * n_rec:(i + 1) * n_rec]]
                      for i in range(len(settings))])
    failed = np.array([[e["diverged_at_s"] is not None or not math.isfinite(e["mean_distance_L"])
                        for e in folds[i * n_rec:(i + 1) * n_rec]]
                       for i in range(len(settings))])
    score = _cv_scores(means, failed)
    rows = []
    for i, setting in enumerate(settings):
        row = {"setting": setting.label, "method": setting.method,
               "window_s": setting.window if setting.method != "none" else math.nan,
               "order": setting.order if setting.method == "savgol" else math.nan,
               "score_L": float(score[i]),
               "n_diverged": int(failed[i].sum())}
        row.update({name: float(means[i, k]) for k, name in enumerate(names)})
        rows.append(row)
    table = pd.DataFrame(rows)
    best = int(np.argmin(np.where(np.isfinite(score), score, np.inf)))
    table["chosen"] = False
    table.loc[best, "chosen"] = True
    return settings[best], table

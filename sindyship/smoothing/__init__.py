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
and flown the way the held-out record was flown (:func:`sindyship.flights.fly_like`),
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

from ._apply import smooth_record, smooth_records
from ._choice import (  # noqa: F401  (_cv_scores for the tests)
    _cv_scores,
    choose_smoothing,
    resolve_smoothing,
)
from ._noise import estimate_noise
from ._settings import (
    DEFAULT_CANDIDATES,
    RTS_CHANNELS,
    SAVGOL_CHANNELS,
    SHIP_TIME_WINDOWS,
    SMOOTHING_METHODS,
    SmoothingSetting,
    default_candidates,
)

__all__ = [
    "DEFAULT_CANDIDATES",
    "RTS_CHANNELS",
    "SAVGOL_CHANNELS",
    "SHIP_TIME_WINDOWS",
    "SMOOTHING_METHODS",
    "SmoothingSetting",
    "choose_smoothing",
    "default_candidates",
    "resolve_smoothing",
    "estimate_noise",
    "smooth_record",
    "smooth_records",
]

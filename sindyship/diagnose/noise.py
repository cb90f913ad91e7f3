"""The noise floor of the force residual: how much of it no term can explain.

Measurement noise on u, v and r becomes noise on the accelerations of paper eq. 16 (a
finite difference amplifies it), so on noisy records part of the leave-one-manoeuvre-out force
error is noise that no effect can explain: a real effect then explains a smaller share of the
whole error than of the part that can be explained at all.  The noise is rough (it changes
from sample to sample) while the error of a missing effect varies with the manoeuvre, over
many ship-length times L/U0.  So the noise part of a residual is estimated as what is left
after a centred moving average over one ship-length time L/U0 (per record, never across
records)::

    SSE_noise = sum (e - moving_average(e, L/U0))**2

On noise-free records this floor holds only the brief spikes at rudder steps (a few per cent
of the error); with 1 % noise on u, v and r it is most of the surge force error.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import uniform_filter1d

__all__ = ["channel_noise", "noise_sse"]


def noise_sse(errors: np.ndarray, groups: np.ndarray, window: int) -> float:
    """Summed squared rough part of a residual (see the module docstring).

    Parameters
    ----------
    errors : ndarray, shape (n_samples,)
        A residual, records stacked.
    groups : ndarray of int, shape (n_samples,)
        The record of each sample.
    window : int
        Moving-average length in samples (one L/U0).

    Returns
    -------
    float

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(2000.0)
    >>> smooth = np.sin(t / 200.0)
    >>> noise = 0.1 * rng.normal(size=t.size)
    >>> floor = noise_sse(smooth + noise, np.zeros(t.size, dtype=int), 19)
    >>> bool(0.85 < floor / float(noise @ noise) < 1.0)
    True
    """
    total = 0.0
    width = max(int(window), 1)
    for g in np.unique(groups):
        part = errors[groups == g]
        rough = part - uniform_filter1d(part, size=width, mode="nearest")
        total += float(rough @ rough)
    return total


def channel_noise(records) -> dict[str, float]:
    """Noise level of the measured motion: the RMS of white noise on u, v and r relative to
    each channel's RMS, and on the heading in degrees.

    Estimated from second differences, ``sigma**2 = mean((x[k+1] - 2 x[k] + x[k-1])**2) / 6``
    (white noise of variance sigma**2 gives exactly that; a signal that varies over many
    samples adds little).

    Parameters
    ----------
    records : sequence of Trajectory

    Returns
    -------
    dict
        ``u``, ``v``, ``r`` (fractions of the channel's RMS) and ``psi_deg``.

    Examples
    --------
    >>> import pandas as pd
    >>> from sindyship.trajectory import Trajectory
    >>> rng = np.random.default_rng(1)
    >>> t = np.arange(5000.0)
    >>> frame = pd.DataFrame({"t": t, "u": 10 + 0.1 * rng.normal(size=t.size),
    ...                       "v": np.sin(t / 50), "r": np.cos(t / 50), "psi": t / 1000})
    >>> level = channel_noise([Trajectory(frame)])
    >>> round(level["u"] * 10 / 0.1, 1), level["v"] < 1e-3
    (1.0, True)
    """
    out = {}
    for channel in ("u", "v", "r", "psi"):
        curvature, total, n = 0.0, 0.0, 0
        for record in records:
            values = np.asarray(record[channel], dtype=float)
            second = np.diff(values, 2)
            curvature += float(second @ second)
            total += float(values @ values)
            n += len(second)
        sigma = np.sqrt(curvature / (6.0 * max(n, 1)))
        n_all = sum(len(record.t) for record in records)
        if channel == "psi":
            out["psi_deg"] = float(np.degrees(sigma))
        else:
            out[channel] = float(sigma / np.sqrt(total / n_all)) if total > 0 else 0.0
    return out

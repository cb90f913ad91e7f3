"""The noise level of a recorded channel (what the smoothers and the noise floor need)."""

from __future__ import annotations

import math

import numpy as np


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

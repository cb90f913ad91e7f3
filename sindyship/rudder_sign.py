"""Whether a recorded rudder angle turns the ship the way sindyship takes it to: a positive
rudder angle turns the ship to starboard (r > 0).  The plausibility check ``rudder-sign``
(:mod:`sindyship.plausibility`) refuses a rudder column that the motion contradicts.

- ``RUDDER_SIGN_ANGLE = 10`` deg: a rudder held this far over for a quarter of the record is a
  turn.  Turning ``RUDDER_SIGN_TURN`` = half a circle the other way over the hold is refused
  (weather helm on a course change turns far less against the rudder); a quarter circle
  (``RUDDER_SIGN_WITH``) or more with it passes; anything between is left to the next test.
- With a rudder that moves 10 deg or more, the gain b of dr/dt = a r + b delta + c (least
  squares on the means of at most 200 blocks of samples, whose errors are then nearly
  independent and whose noise is averaged, whatever the sampling rate) must not lie
  ``RUDDER_SIGN_T = 5`` standard errors below zero (good zig-zags: +7 to +90).  A block
  lasts at most 1/``RUDDER_SIGN_BLOCKS_PER_LEG`` of the time the rudder takes from one side
  to the other (:func:`sindyship.rudder_holds.leg_time`): longer blocks of a long record of
  a quick zig-zag average over a leg, and their yaw acceleration lags the rudder into the
  opposite sign.
"""

from __future__ import annotations

import math

import numpy as np

from .rudder_holds import leg_time

__all__ = ["RUDDER_SIGN_ANGLE", "RUDDER_SIGN_BLOCKS_PER_LEG", "RUDDER_SIGN_T", "RUDDER_SIGN_TURN",
           "RUDDER_SIGN_WITH", "against_rudder", "yaw_follows_rudder"]

RUDDER_SIGN_ANGLE = math.radians(10.0)
RUDDER_SIGN_TURN = math.pi  # rad: half a circle
RUDDER_SIGN_WITH = math.pi / 2  # rad: a quarter circle with the rudder settles it
RUDDER_SIGN_T = 5.0  # standard errors
RUDDER_SIGN_BLOCKS_PER_LEG = 8  # fewest blocks of samples to a leg of the rudder


def against_rudder(delta: np.ndarray, r: np.ndarray, t: np.ndarray, header: str) -> str | None:
    """Why the rudder ``delta`` [rad] (column ``header``) looks flipped against the yaw rate
    ``r`` [rad/s] over time ``t`` [s], else None: held over while the ship turned half a circle
    the other way, or followed by a yaw acceleration of the opposite sign."""
    held = np.abs(delta) >= RUDDER_SIGN_ANGLE
    side = np.sign(delta) * held
    edges = np.flatnonzero(np.diff(np.concatenate(([0.0], side, [0.0]))) != 0)
    holds = [(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True) if side[a] != 0]
    first, last = max(holds, key=lambda e: e[1] - e[0], default=(0, 0))
    if last - first >= 0.25 * len(t):  # a turn: which way did it go over the hold?
        turned = side[first] * float(np.trapezoid(r[first:last], t[first:last]))
        level = math.degrees(float(np.median(delta[first:last])))
        if turned >= RUDDER_SIGN_WITH:
            return None
        if turned <= -RUDDER_SIGN_TURN:
            return (f"with column '{header}' held at {level:.0f} deg from t = {t[first]:.6g} s, "
                    f"the ship turned {math.degrees(-turned):.0f} deg the other way")
    if np.ptp(delta) < RUDDER_SIGN_ANGLE:
        return None
    below = yaw_follows_rudder(delta, r, t)
    return None if not -below > RUDDER_SIGN_T else (
        f"the yaw acceleration follows column '{header}' with the opposite sign ({-below:.0f} "
        "standard errors below zero)")


def yaw_follows_rudder(delta: np.ndarray, r: np.ndarray, t: np.ndarray) -> float:
    """How many standard errors above zero the gain b of the yaw response
    dr/dt = a r + b delta + c lies (negative below; NaN for fewer than five blocks): least
    squares on the means of at most 200 blocks of samples, whose errors are nearly
    independent and whose noise is averaged, whatever the sampling rate (module docstring).

    Examples
    --------
    >>> t = np.arange(0.0, 400.0, 0.5)
    >>> delta = np.radians(10.0) * np.sign(np.sin(2 * np.pi * t / 100.0))
    >>> r = np.zeros_like(t)
    >>> for k in range(1, len(t)):  # a first-order yaw response to the rudder
    ...     r[k] = r[k - 1] + 0.5 * (0.02 * delta[k - 1] - 0.05 * r[k - 1])
    >>> bool(yaw_follows_rudder(delta, r, t) > RUDDER_SIGN_T)
    True
    """
    size = max(1, len(t) // 200)
    leg = leg_time(t, np.degrees(delta))
    if leg is not None:  # never averaged over a leg of the rudder
        step = float(np.median(np.diff(t)))
        size = max(1, min(size, int(leg / (RUDDER_SIGN_BLOCKS_PER_LEG * step))))
    tb, rb, db = (np.mean(x[: len(t) // size * size].reshape(-1, size), axis=1)
                  for x in (t, r, delta))
    if len(tb) < 5:
        return math.nan
    design, rate = np.column_stack([rb, db, np.ones_like(rb)]), np.gradient(rb, tb)
    fitted, *_ = np.linalg.lstsq(design, rate, rcond=None)
    error = rate - design @ fitted
    spread = float(error @ error) / max(len(error) - 3, 1) * np.linalg.pinv(design.T @ design)
    return float(fitted[1] / math.sqrt(max(spread[1, 1], 1e-300)))

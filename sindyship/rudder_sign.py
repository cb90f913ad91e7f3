"""Whether a recorded rudder angle turns the ship the way sindyship takes it to: a positive
rudder angle turns the ship to starboard (r > 0).  The plausibility check ``rudder-sign``
(:mod:`sindyship.plausibility`) refuses a rudder column that the motion contradicts.

- ``RUDDER_SIGN_ANGLE = 10`` deg: a rudder held this far over for a quarter of the record is a
  turn, which must not turn ``RUDDER_SIGN_TURN`` = half a circle the other way over the hold's
  second half (weather helm on a course change turns far less against the rudder); half a
  circle with it passes.
- Otherwise, with a rudder that moves 10 deg or more, the gain b of dr/dt = a r + b delta + c
  (least squares on 200 samples at most, whose errors are then nearly independent) must not
  lie ``RUDDER_SIGN_T = 5`` standard errors below zero (good zig-zags: +7 to +90).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["RUDDER_SIGN_ANGLE", "RUDDER_SIGN_T", "RUDDER_SIGN_TURN", "against_rudder"]

RUDDER_SIGN_ANGLE = math.radians(10.0)
RUDDER_SIGN_TURN = math.pi  # rad: half a circle
RUDDER_SIGN_T = 5.0  # standard errors


def against_rudder(delta: np.ndarray, r: np.ndarray, t: np.ndarray, header: str) -> str | None:
    """Why the rudder ``delta`` [rad] (column ``header``) looks flipped against the yaw rate
    ``r`` [rad/s] over time ``t`` [s], else None: held over while the ship turned half a circle
    the other way, or followed by a yaw acceleration of the opposite sign."""
    held = np.abs(delta) >= RUDDER_SIGN_ANGLE
    side = np.sign(delta) * held
    edges = np.flatnonzero(np.diff(np.concatenate(([0.0], side, [0.0]))) != 0)
    holds = [(a, b) for a, b in zip(edges[:-1], edges[1:], strict=True) if side[a] != 0]
    first, last = max(holds, key=lambda e: e[1] - e[0], default=(0, 0))
    if last - first >= 0.25 * len(t):  # a turn: which way did it go?
        middle = (first + last) // 2
        turned = side[first] * float(np.trapezoid(r[middle:last], t[middle:last]))
        level = math.degrees(float(np.median(delta[first:last])))
        if turned >= RUDDER_SIGN_TURN:
            return None
        if turned <= -RUDDER_SIGN_TURN:
            return (f"with column '{header}' held at {level:.0f} deg from t = {t[first]:.6g} s, "
                    f"the ship turned {math.degrees(-turned):.0f} deg the other way over the "
                    "hold's second half")
    if np.ptp(delta) < RUDDER_SIGN_ANGLE:
        return None
    # the yaw response dr/dt = a r + b delta + c on at most 200 samples, whose errors are
    # nearly independent whatever the sampling rate
    k = slice(None, None, max(1, len(t) // 200))
    design = np.column_stack([r, delta, np.ones_like(r)])[k]
    fitted, *_ = np.linalg.lstsq(design, np.gradient(r, t)[k], rcond=None)
    error = np.gradient(r, t)[k] - design @ fitted
    spread = float(error @ error) / max(len(error) - 3, 1) * np.linalg.pinv(design.T @ design)
    below = -fitted[1] / math.sqrt(max(spread[1, 1], 1e-300))
    return None if not below > RUDDER_SIGN_T else (
        f"the yaw acceleration follows column '{header}' with the opposite sign ({below:.0f} "
        "standard errors below zero)")

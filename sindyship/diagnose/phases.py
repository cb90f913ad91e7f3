"""Manoeuvre phases: rudder steps and reversals, steady turns, straight runs."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..ships import Ship
from ..trajectory import Trajectory


# =============================================================================== phases
@dataclass(frozen=True)
class Phase:
    """A phase of a manoeuvre: an instant (rudder change) or an interval (steady turn).

    Attributes
    ----------
    kind : {"rudder step", "rudder reversal", "steady turn", "straight run"}
    start, end : float
        Times [s]; equal for an instant.
    label : str
        A short description for people.
    """

    kind: str
    start: float
    end: float
    label: str = ""


def manoeuvre_phases(record: Trajectory, ship: Ship) -> tuple[Phase, ...]:
    """Rudder steps and reversals, steady turns and straight runs of a record.

    Rudder changes come from the commanded rudder when recorded (a change of more than
    0.1 deg between samples; a reversal when the side changes), else from the actual rudder
    (each time it crosses to the other side beyond 1 deg, and the first move of more than
    1 deg).  A steady turn is a stretch of at least 2 L/U0 where |r'| > 0.05 and the yaw
    rate, averaged over 0.25 L/U0, changes by less than 0.005 per unit of L/U0; a straight
    run is a stretch as long with |r'| < 0.01 and the rudder within 1 deg of zero.

    Parameters
    ----------
    record : Trajectory
    ship : Ship
        Gives L and U0.

    Returns
    -------
    tuple of Phase
        In order of start time.

    Examples
    --------
    >>> from sindyship import load_ship, MMGModel, Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> (zz,) = fly(MMGModel(ship), [Manoeuvre("zigzag", rudder=20, check=20, duration=600)])
    >>> [p.kind for p in manoeuvre_phases(zz, ship)][:3]
    ['rudder step', 'rudder reversal', 'rudder reversal']
    """
    t = record.t
    deg = math.radians(1.0)
    phases: list[Phase] = []
    if record.has("delta_c"):
        cmd = record["delta_c"]
        if abs(cmd[0]) > 0.1 * deg:
            phases.append(
                Phase(
                    "rudder step",
                    float(t[0]),
                    float(t[0]),
                    f"rudder {math.degrees(cmd[0]):.1f} deg from the start",
                )
            )
        for k in np.flatnonzero(np.abs(np.diff(cmd)) > 0.1 * deg) + 1:
            before, after = cmd[k - 1], cmd[k]
            reversal = before * after < 0 and abs(before) > deg and abs(after) > deg
            kind = "rudder reversal" if reversal else "rudder step"
            phases.append(
                Phase(
                    kind,
                    float(t[k]),
                    float(t[k]),
                    f"rudder {math.degrees(before):.1f} -> {math.degrees(after):.1f} deg",
                )
            )
    else:
        delta = record.rudder
        moved = np.flatnonzero(np.abs(delta - delta[0]) > deg)
        if moved.size:
            k = int(moved[0])
            phases.append(Phase("rudder step", float(t[k]), float(t[k]), "rudder execute"))
        side = np.where(delta > deg, 1, np.where(delta < -deg, -1, 0))
        last = 0
        for k in np.flatnonzero(side):
            if last and side[k] != last:
                phases.append(
                    Phase(
                        "rudder reversal",
                        float(t[k]),
                        float(t[k]),
                        f"rudder to {'starboard' if side[k] > 0 else 'port'}",
                    )
                )
            last = side[k]
    scale = ship.time_scale
    r_nd = record["r"] * scale
    dt = record.dt
    width = max(1, int(round(0.25 * scale / dt)))
    smooth = np.convolve(r_nd, np.ones(width) / width, mode="same")
    rate = np.gradient(smooth, t / scale) if len(t) > 1 else np.zeros_like(t)
    rudder = record.rudder
    steady = (np.abs(r_nd) > 0.05) & (np.abs(rate) < 0.005)
    straight = (np.abs(r_nd) < 0.01) & (np.abs(rudder) < deg)
    for mask, kind in ((steady, "steady turn"), (straight, "straight run")):
        for start, stop in _runs(mask):
            if t[stop - 1] - t[start] < 2.0 * scale:
                continue
            label = kind
            if kind == "steady turn":
                mean = float(np.mean(r_nd[start:stop]))
                label = f"steady turn to {'starboard' if mean > 0 else 'port'}, r' = {mean:.2f}"
            phases.append(Phase(kind, float(t[start]), float(t[stop - 1]), label))
    return tuple(sorted(phases, key=lambda p: (p.start, p.end)))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Start and stop (exclusive) indices of the runs of True in ``mask``."""
    padded = np.concatenate([[False], mask, [False]]).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))



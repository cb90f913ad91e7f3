"""The Trajectory: one manoeuvre record in SI units (the measurement-CSV contract in memory).

Columns follow the measurement CSV contract: ``t`` [s], ``u``, ``v`` [m/s] (body-fixed surge
and sway, v positive to starboard), ``r`` [rad/s] (positive turning to starboard), ``x``, ``y``
[m] (earth-fixed, x north, y east), ``psi`` [rad, unwrapped], the actual rudder angle ``delta``
[rad] and/or the commanded angle ``delta_c`` [rad]; optional ``n`` [rps] and any other named
channel (``wind_speed``, ``wind_dir``, ``depth``, ...).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

REQUIRED_COLUMNS = ("t", "u", "v", "r", "x", "y", "psi")
RUDDER_COLUMNS = ("delta", "delta_c")
STATE_COLUMNS = ("u", "v", "r", "x", "y", "psi", "delta")


@dataclass(frozen=True)
class Trajectory:
    """A manoeuvre record: a table of samples in SI units plus a name.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per sample with at least the columns of ``REQUIRED_COLUMNS`` and one of
        ``delta`` or ``delta_c``.
    name : str
        A short identifier (a file stem, or a manoeuvre name such as ``"tc35_stbd"``).
    meta : dict
        Free-form facts about how the record was made (manoeuvre, rudder and check angles,
        effects); written nowhere by the CSV contract, kept for reports.  ``meta["checks"]``
        says which checks of a measurement CSV it passed (:func:`checks_done`).

    Notes
    -----
    Nothing is checked when a Trajectory is made: the functions that fit or fly records check
    one made by hand as a measurement CSV is checked, the first time they see it
    (:func:`sindyship.measurements.check_trajectory`).  A table in other units is read with
    :func:`sindyship.measurements.trajectory_from_frame`, whose headers name them.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": [1.0, 1.0], "v": [0.0, 0.0],
    ...                       "r": [0.0, 0.0], "x": [0.0, 1.0], "y": [0.0, 0.0],
    ...                       "psi": [0.0, 0.0], "delta": [0.0, 0.0]})
    >>> Trajectory(frame, name="demo").duration
    1.0
    """

    data: pd.DataFrame
    name: str = ""
    meta: dict = field(default_factory=dict, compare=False)

    def __getitem__(self, column: str) -> np.ndarray:
        return self.data[column].to_numpy(dtype=float)

    def has(self, column: str) -> bool:
        """Whether the record holds the channel ``column``."""
        return column in self.data.columns

    @property
    def t(self) -> np.ndarray:
        return self["t"]

    @property
    def n_samples(self) -> int:
        return len(self.data)

    @property
    def duration(self) -> float:
        t = self.t
        return float(t[-1] - t[0])

    @property
    def dt(self) -> float:
        """Median sample interval [s]."""
        return float(np.median(np.diff(self.t)))

    @property
    def fastest(self) -> float:
        """The largest speed through the water sqrt(u^2 + v^2) [m/s] (missing samples left out)."""
        return float(np.nanmax(np.hypot(self["u"], self["v"])))

    @property
    def rudder(self) -> np.ndarray:
        """The actual rudder angle if recorded, else the commanded one [rad]."""
        return self["delta"] if self.has("delta") else self["delta_c"]

    def state(self) -> np.ndarray:
        """The simulator state ``[u, v, r, x, y, psi, delta]`` as an array of shape (7, N)."""
        return np.vstack([self[c] if c != "delta" else self.rudder for c in STATE_COLUMNS])

    def with_name(self, name: str) -> Trajectory:
        return Trajectory(self.data, name=name, meta=dict(self.meta))


def checks_done(ship, skipped=(), rudder_check: bool = True) -> dict:
    """The checks a record passed, kept in its ``meta["checks"]``: the ship they were scaled
    by (name, L, U0; None without one), those skipped, and whether degree-like rudder angles
    and yaw rates were refused (:func:`sindyship.measurements.check_trajectory` reads it).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> checks_done(load_ship("kcs"), ["heading"])
    {'ship': ['kcs', 230.0, 12.348], 'skipped': ['heading'], 'rudder_check': True}
    """
    key = None if ship is None else [ship.name, float(ship.L), float(ship.U0)]
    return {"ship": key, "skipped": sorted(skipped), "rudder_check": bool(rudder_check)}


def checked_for(record: Trajectory, ship) -> bool:
    """Whether ``record`` passed the checks of a measurement CSV scaled by ``ship``
    (:func:`checks_done`)."""
    done = record.meta.get("checks")
    return done is not None and done["ship"] == checks_done(ship)["ship"]

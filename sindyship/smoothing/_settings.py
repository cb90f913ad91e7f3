"""Smoothing settings and the default candidates, with windows in ship time."""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Any

from ..errors import SindyshipInputError
from ..ships import Ship

SMOOTHING_METHODS = ("none", "savgol", "rts")
#: Channels the Kalman smoother estimates, in its state order.
RTS_CHANNELS = ("x", "y", "psi", "u", "v", "r")
#: Channels the Savitzky-Golay filter smooths unless told otherwise.
SAVGOL_CHANNELS = ("u", "v", "r")
#: f_c * window of a cubic Savitzky-Golay filter, used to set the Kalman smoother's cut-off.
_CUTOFF_TIMES_WINDOW = 2.5
#: Sampling is uniform when no step differs from the median step by more than this fraction.
_UNIFORM_TOLERANCE = 0.01


#: The longest smoothing window [s]: a day, longer than any trial.
MAX_WINDOW_S = 86400.0


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
                and 0 < self.window <= MAX_WINDOW_S):
            raise SindyshipInputError(
                f"the smoothing window must be a number of seconds above 0 and at most "
                f"{MAX_WINDOW_S:g} (a day), not {self.window!r}."
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
        if method in ("none", "auto") and len(parts) > 1:
            raise SindyshipInputError(
                f"the smoothing setting {text!r} gives {method} a window; write {method} alone "
                "(or savgol:W or rts:W for a window of your own)."
            )
        if method == "rts" and len(parts) > 2:
            raise SindyshipInputError(
                f"the smoothing setting {text!r} gives the RTS smoother an order, which only "
                "the Savitzky-Golay filter has; write rts:W."
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

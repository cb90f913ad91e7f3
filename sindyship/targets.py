"""Regression targets by inverse dynamics (paper eq. 14 and 16).

The Abkowitz model (eq. 14) in Prime I units is

    M a' = F'(du, v', r', delta) + C'(u', v', r')

with the mass matrix M of added-mass derivatives (Table 6) and the Coriolis terms C' of the
reproduction protocol (rigid body plus added mass, with the Munk moment, on the right-hand
side).  Given measured velocities, the accelerations a' come from finite differences, and the
hydrodynamic forces F' = M a' - C' are the regression targets of eq. 16, one per degree of
freedom.  Everything here is non-dimensional in Prime I with the constant design speed U0.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import SindyshipInputError
from .ships import Ship
from .trajectory import Trajectory

DOFS = ("X", "Y", "N")
DERIVATIVE_METHODS = ("five-point", "savgol")


def abkowitz_mass_matrix(ship: Ship) -> np.ndarray:
    """Mass matrix of paper eq. 14, Prime I.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> M = abkowitz_mass_matrix(load_ship("kcs"))
    >>> [round(float(x) * 1e5, 2) for x in M.diagonal()]
    [885.32, 1587.92, 96.68]
    """
    p = ship.prime_i_inertia()
    m, mxg = p["m"], p["m"] * p["x_G"]
    return np.array([
        [m - p["X_udot"], 0.0, 0.0],
        [0.0, m - p["Y_vdot"], mxg - p["Y_rdot"]],
        [0.0, mxg - p["N_vdot"], p["I_zz"] - p["N_rdot"]],
    ])


def coriolis(ship: Ship, u, v, r) -> tuple:
    """Right-hand-side Coriolis and centripetal terms, rigid body plus added mass (Prime I).

    X'_C = (m' - Y'_vdot) v' r' + (m'x'_G - Y'_rdot) r'^2,
    Y'_C = -(m' - X'_udot) u' r',
    N'_C = -(m'x'_G - Y'_rdot) u' r' - (X'_udot - Y'_vdot) u' v'  (Fossen 2011, with the Munk
    moment), with u' the total surge speed over U0.
    """
    c_vr, c_rr, c_ur, c_uv = coriolis_factors(ship)
    X = c_vr * v * r + c_rr * r * r
    Y = -c_ur * u * r
    N = -c_rr * u * r - c_uv * u * v
    return X, Y, N


def coriolis_factors(ship: Ship) -> tuple[float, float, float, float]:
    """The Prime I factors of :func:`coriolis`, ``(m' - Y'_vdot, m'x'_G - Y'_rdot,
    m' - X'_udot, X'_udot - Y'_vdot)``; the compiled path (``sindyship._forces_compiled``)
    takes the same numbers."""
    p = ship.prime_i_inertia()
    m, mxg = p["m"], p["m"] * p["x_G"]
    return (m - p["Y_vdot"], mxg - p["Y_rdot"], m - p["X_udot"], p["X_udot"] - p["Y_vdot"])


def five_point_derivative(y: np.ndarray, dt: float) -> np.ndarray:
    """Derivative by 5-point finite differences: forward at the first two samples, central
    inside, backward at the last two (paper section 3.2); fourth-order accurate.

    Examples
    --------
    >>> t = np.arange(10.0)
    >>> np.allclose(five_point_derivative(t**3, 1.0), 3 * t**2)
    True
    """
    y = np.asarray(y, dtype=float)
    n = len(y)
    if n < 5:
        raise SindyshipInputError(
            f"a record needs at least 5 samples for 5-point differences, not {n}."
        )
    d = np.empty(n)
    d[2:-2] = (y[:-4] - 8 * y[1:-3] + 8 * y[3:-1] - y[4:]) / 12.0
    d[0] = (-25 * y[0] + 48 * y[1] - 36 * y[2] + 16 * y[3] - 3 * y[4]) / 12.0
    d[1] = (-3 * y[0] - 10 * y[1] + 18 * y[2] - 6 * y[3] + y[4]) / 12.0
    d[-1] = (25 * y[-1] - 48 * y[-2] + 36 * y[-3] - 16 * y[-4] + 3 * y[-5]) / 12.0
    d[-2] = (3 * y[-1] + 10 * y[-2] - 18 * y[-3] + 6 * y[-4] - y[-5]) / 12.0
    return d / dt


#: The coarsest sampling interval, in ship-length times L/U0, at which finite differences
#: resolve a ship's accelerations: eight samples per L/U0.  On the KVLCC2's zig-zags, 35 deg
#: turn and random rudder (exact records of its MMG model) the 5-point yaw acceleration misses
#: the exact one by 0.9 % of its RMS sampled every 0.05 L/U0, 4 % at 0.125, 9 % at 0.2 and
#: 18 % at 0.34 (``tests/test_sampling.py``); coarser, the forces fitted to the records are
#: biased and the motion between samples reads as noise.
RESOLVED_STEP = 0.125


def sampling_steps(records, ship: Ship) -> dict[str, float]:
    """Each record's sampling interval in ship-length times L/U0: its median time step, or
    the step it was logged at (``meta["logged_step"]``, kept when a record is read with
    ``resample``) where that is coarser: interpolating onto a finer grid adds no motion.

    Examples
    --------
    >>> import pandas as pd
    >>> from sindyship.ships import load_ship
    >>> frame = pd.DataFrame({"t": np.arange(0.0, 60.0, 0.25)})
    >>> logged = Trajectory(frame, name="zz", meta={"logged_step": 2.0})
    >>> round(sampling_steps([logged], load_ship("kvlcc2"))["zz"], 3)  # 2 s on a 7 m model
    0.337
    """
    return {record.name: max(record.dt, float(record.meta.get("logged_step") or 0.0))
            * ship.U0 / ship.L for record in records}


def is_under_resolved(step: float) -> bool:
    """Whether a sampling interval in L/U0 (:func:`sampling_steps`) is coarser than
    :data:`RESOLVED_STEP`, up to rounding."""
    return step > RESOLVED_STEP * (1.0 + 1e-9)


def _down(value: float) -> str:
    """``value`` rounded down to three significant digits (a limit never rounded past)."""
    digits = 2 - math.floor(math.log10(value))
    return f"{math.floor(value * 10.0**digits) / 10.0**digits:g}"


def under_resolved(steps: dict[str, float], ship: Ship) -> str:
    """Why records sampled at ``steps`` (:func:`sampling_steps`) resolve the ship's
    accelerations poorly, or "" when every step is at most :data:`RESOLVED_STEP` (up to
    rounding).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> under_resolved({"zz": 0.125 + 1e-15}, load_ship("kvlcc2"))
    ''
    >>> print(under_resolved({"zz": 0.337, "tc": 0.337}, load_ship("kvlcc2")))
    ... # doctest: +NORMALIZE_WHITESPACE
    the records are sampled every 2 s (0.337 L/U0: zz, tc), too coarsely for finite
    differences to resolve the ship's accelerations (at most 0.125 L/U0, 0.742 s for this
    ship): the forces fitted to them are biased and part of the motion reads as noise; log
    every 0.742 s or faster (and resample no coarser)
    """
    coarse = {name: step for name, step in steps.items() if is_under_resolved(step)}
    if not coarse:
        return ""
    time_scale = ship.L / ship.U0
    low, high = min(coarse.values()), max(coarse.values())
    seconds, shares = f"{high * time_scale:.3g} s", f"{high:.3g} L/U0"
    if f"{low:.3g}" != f"{high:.3g}":
        seconds, shares = f"{low * time_scale:.3g} to {seconds}", f"{low:.3g} to {shares}"
    names = ", ".join(list(coarse)[:4]) + (", ..." if len(coarse) > 4 else "")
    finest = _down(RESOLVED_STEP * time_scale)
    return (f"the records are sampled every {seconds} ({shares}: {names}), too coarsely "
            "for finite differences to resolve the ship's accelerations (at most "
            f"{RESOLVED_STEP:g} L/U0, {finest} s for this ship): the forces fitted to them are "
            f"biased and part of the motion reads as noise; log every {finest} s or faster "
            "(and resample no coarser)")


def savgol_points(window: float, dt: float, order: int, n_samples: int, what: str) -> int:
    """The odd number of samples of a Savitzky-Golay window of ``window`` seconds at the step
    ``dt``, refusing a window too short for a polynomial of ``order`` or longer than the
    record of ``n_samples``; ``what`` begins the message (the record's name).

    Examples
    --------
    >>> savgol_points(21.0, 1.0, 3, 3200, "zz20")
    21
    >>> savgol_points(3.0, 1.0, 3, 3200, "zz20")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: zz20: a Savitzky-Golay window of 3 s ... 4 s or more.
    """
    points, least = int(round(window / dt)) | 1, (order + 2) | 1
    if points < least:
        raise SindyshipInputError(
            f"{what}: a Savitzky-Golay window of {window:g} s holds {points} sample"
            f"{'' if points == 1 else 's'} at {dt:g} s, too few for a polynomial of order "
            f"{order}; give a window of {(least - 1) * dt:g} s or more."
        )
    if points > n_samples:
        raise SindyshipInputError(
            f"{what}: a Savitzky-Golay window of {window:g} s is longer than the record "
            f"({(n_samples - 1) * dt:g} s); give a window shorter than the record."
        )
    return points


def derivative(y: np.ndarray, dt: float, method: str = "five-point", window: float = 21.0,
               order: int = 3) -> np.ndarray:
    """Time derivative of a uniformly sampled channel.

    Parameters
    ----------
    method : {"five-point", "savgol"}
        5-point differences (noise-free data), or a Savitzky-Golay smoothed derivative
        (noisy data) over ``window`` seconds with polynomial ``order``.
    """
    if method == "five-point":
        return five_point_derivative(y, dt)
    if method == "savgol":
        from scipy.signal import savgol_filter

        n = savgol_points(window, dt, order, len(y), "the derivative")
        return savgol_filter(np.asarray(y, dtype=float), n, order, deriv=1, delta=dt,
                             mode="interp")
    raise SindyshipInputError(
        f"unknown derivative method {method!r}; choose one of {', '.join(DERIVATIVE_METHODS)}."
    )


def smoothed_states(traj: Trajectory, method: str = "five-point", window: float = 21.0,
                    order: int = 3) -> dict[str, np.ndarray]:
    """u, v, r smoothed consistently with their derivative (unchanged for five-point)."""
    out = {c: traj[c] for c in ("u", "v", "r")}
    if method == "savgol":
        from scipy.signal import savgol_filter

        n = savgol_points(window, traj.dt, order, traj.n_samples,
                          f"{traj.name or 'the record'}: the derivative (--window)")
        out = {c: savgol_filter(v, n, order, mode="interp") for c, v in out.items()}
    return out


def regression_targets(traj: Trajectory, ship: Ship, *, method: str = "five-point",
                       window: float = 21.0, order: int = 3,
                       accelerations: tuple | None = None) -> dict[str, np.ndarray]:
    """Hydrodynamic forces F' = M a' - C' of paper eq. 16 for one record (Prime I).

    Parameters
    ----------
    traj : Trajectory
        A uniformly sampled record (SI).
    ship : Ship
        Gives L, U0 and the Prime I inertia (paper Table 6).
    method, window, order
        Derivative estimate (:func:`derivative`).
    accelerations : tuple of ndarray, optional
        Known (du/dt, dv/dt, dr/dt) in SI instead of finite differences (for tests of the
        regression with a generating model's exact accelerations).

    Returns
    -------
    dict
        ``{"X": ..., "Y": ..., "N": ...}`` arrays over the samples.
    """
    L, U0 = ship.L, ship.U0
    if method == "five-point" and traj.n_samples < 5 and accelerations is None:
        raise SindyshipInputError(
            f"{traj.name or 'the record'} has {traj.n_samples} sample"
            f"{'' if traj.n_samples == 1 else 's'}; 5-point differences need at least 5: give "
            "a longer record."
        )
    dt = traj.dt
    states = smoothed_states(traj, method, window, order)
    u = states["u"] / U0
    v = states["v"] / U0
    r = states["r"] * L / U0
    t_scale = L / U0
    if accelerations is not None:
        a_u, a_v, a_r = (np.asarray(a, dtype=float) for a in accelerations)
        du, dv, dr = a_u * t_scale / U0, a_v * t_scale / U0, a_r * t_scale * L / U0
    else:
        du = derivative(traj["u"] / U0, dt / t_scale, method, window / t_scale, order)
        dv = derivative(traj["v"] / U0, dt / t_scale, method, window / t_scale, order)
        dr = derivative(traj["r"] * L / U0, dt / t_scale, method, window / t_scale, order)
    M = abkowitz_mass_matrix(ship)
    X_C, Y_C, N_C = coriolis(ship, u, v, r)
    return {
        "X": M[0, 0] * du - X_C,
        "Y": M[1, 1] * dv + M[1, 2] * dr - Y_C,
        "N": M[2, 1] * dv + M[2, 2] * dr - N_C,
    }

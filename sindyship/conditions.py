"""Conditions that change during a simulated run: gusty wind and varying propeller revolutions.

The simulator's hidden effects (:mod:`sindyship.effects`) that a ship logs on board as channels
of the measurement CSV: the true wind (``wind_speed`` [m/s], ``wind_dir`` [rad, the direction it
comes FROM, clockwise from north]) and the propeller revolutions (``n`` [rps]).  This module
makes their time series, seeded and reproducible, and the aerodynamic force the wind exerts.

Random parts are Ornstein-Uhlenbeck processes (Gaussian, exponentially correlated), sampled
exactly on the record's times: gusts with a correlation time of one ship time L/U0, the wind
direction wandering with 20 L/U0 and slow revolution changes with 5 L/U0.
"""

from __future__ import annotations

import math

import numpy as np

#: Air and sea-water densities [kg/m^3] of the wind force.
RHO_AIR = 1.225

#: Windage of a container ship (Isherwood 1972 order of magnitude): lateral area 2.8 L d and
#: frontal area 2.8 B d above water, longitudinal and lateral force coefficients 0.7 and 0.9,
#: centre of effort 0.05 L aft of midship.
LATERAL_AREA_PER_LD = 2.8
FRONTAL_AREA_PER_BD = 2.8
C_X_WIND = 0.7
C_Y_WIND = 0.9
X_WIND_ARM = -0.05

#: Correlation times in ship times L/U0: gusts, wind direction, slow revolution changes.
GUST_TIME = 1.0
WANDER_TIME = 20.0
REVOLUTION_TIME = 5.0


def ornstein_uhlenbeck(times: np.ndarray, std: float, correlation_time: float,
                       rng: np.random.Generator) -> np.ndarray:
    """A stationary zero-mean Ornstein-Uhlenbeck process sampled exactly at ``times``.

    Parameters
    ----------
    times : ndarray
        Increasing sample times [s].
    std : float
        Standard deviation of the process.
    correlation_time : float
        e-folding time of its autocorrelation [s].
    rng : numpy.random.Generator
        Source of the normal draws (one per sample).

    Examples
    --------
    >>> x = ornstein_uhlenbeck(np.arange(20000.0), 2.0, 5.0, np.random.default_rng(0))
    >>> round(float(x.std()), 1), round(float(np.corrcoef(x[:-5], x[5:])[0, 1]), 2)
    (2.0, 0.37)
    """
    times = np.asarray(times, dtype=float)
    draws = rng.standard_normal(len(times))
    out = np.empty(len(times))
    if not len(times):
        return out
    out[0] = std * draws[0]
    decay = np.exp(-np.diff(times) / correlation_time)
    spread = std * np.sqrt(1.0 - decay * decay)
    for k in range(1, len(times)):
        out[k] = decay[k - 1] * out[k - 1] + spread[k - 1] * draws[k]
    return out


def wind_series(times: np.ndarray, speed: float, from_deg: float, gust: float, wander_deg: float,
                time_scale: float, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """True wind over a run: a mean speed with gusts and a direction that wanders.

    Parameters
    ----------
    times : ndarray
        Sample times [s].
    speed : float
        Mean true wind speed [m/s].
    from_deg : float
        Mean direction the wind comes FROM [deg, clockwise from north].
    gust : float
        Standard deviation of the gusts as a fraction of ``speed`` (correlation time L/U0);
        the speed never drops below zero.
    wander_deg : float
        Standard deviation of the direction's wander [deg] (correlation time 20 L/U0).
    time_scale : float
        The ship's L/U0 [s].
    rng : numpy.random.Generator

    Returns
    -------
    dict
        ``wind_speed`` [m/s] and ``wind_dir`` [rad, in [0, 2 pi)], as the measurement CSV
        names them.
    """
    gusts = ornstein_uhlenbeck(times, gust * speed, GUST_TIME * time_scale, rng)
    wander = ornstein_uhlenbeck(times, math.radians(wander_deg), WANDER_TIME * time_scale, rng)
    return {"wind_speed": np.maximum(speed + gusts, 0.0),
            "wind_dir": np.mod(math.radians(from_deg) + wander, 2.0 * math.pi)}


def revolution_series(times: np.ndarray, design: float, level: float, step: float,
                      step_at: float, vary: float, time_scale: float,
                      rng: np.random.Generator) -> np.ndarray:
    """Propeller revolutions over a run [rps].

    ``n(t) = design * (level + step * [t >= t_step] + e(t))``, with ``t_step`` at the fraction
    ``step_at`` of the record and ``e`` an Ornstein-Uhlenbeck process of standard deviation
    ``vary`` (correlation time 5 L/U0).

    Examples
    --------
    >>> n = revolution_series(np.arange(10.0), 2.0, 1.0, -0.25, 0.5, 0.0, 18.6,
    ...                       np.random.default_rng(0))
    >>> n.tolist()
    [2.0, 2.0, 2.0, 2.0, 2.0, 1.5, 1.5, 1.5, 1.5, 1.5]
    """
    times = np.asarray(times, dtype=float)
    level_t = np.full(len(times), float(level))
    if step and len(times):
        t_step = times[0] + step_at * (times[-1] - times[0])
        level_t = level_t + step * (times >= t_step)
    if vary:
        level_t = level_t + ornstein_uhlenbeck(times, vary, REVOLUTION_TIME * time_scale, rng)
    return design * level_t


def wind_force(ship, u, v, psi, wind_speed, wind_dir) -> tuple:
    """Aerodynamic force of the true wind on the hull above water, Prime II (0.5 rho L d U0^2).

    The force follows the apparent wind ``a`` (the true wind less the ship's velocity, body
    axes): ``X' = k_X |a'| a'_x``, ``Y' = k_Y |a'| a'_y``, ``N' = x_A Y'`` with
    ``k = C (rho_air / rho) A / (L d)`` (container-ship windage, :data:`C_X_WIND`,
    :data:`C_Y_WIND`, :data:`LATERAL_AREA_PER_LD`, :data:`FRONTAL_AREA_PER_BD`) and the centre
    of effort ``x_A`` = :data:`X_WIND_ARM` L.  A head wind pushes astern, a wind from starboard
    pushes to port.

    Parameters
    ----------
    ship : Ship
    u, v : float or ndarray
        Surge and sway velocity over U0.
    psi : float or ndarray
        Heading [rad].
    wind_speed : float or ndarray
        True wind speed [m/s].
    wind_dir : float or ndarray
        Direction the wind comes from [rad, clockwise from north].

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> X, Y, N = wind_force(kcs, 0.0, 0.0, 0.0, 12.348, math.pi / 2)  # from the east, at rest
    >>> round(abs(float(X)), 9), round(float(Y), 5), bool(N > 0)
    (0.0, -0.00301, True)
    """
    particulars = ship.particulars
    ratio = RHO_AIR / particulars.rho
    k_x = C_X_WIND * ratio * FRONTAL_AREA_PER_BD * particulars.B / particulars.L
    k_y = C_Y_WIND * ratio * LATERAL_AREA_PER_LD
    w = wind_speed / particulars.U0
    a_x = -w * np.cos(wind_dir - psi) - u
    a_y = -w * np.sin(wind_dir - psi) - v
    size = np.sqrt(a_x * a_x + a_y * a_y)
    Y = k_y * size * a_y
    return k_x * size * a_x, Y, X_WIND_ARM * Y

"""The library's integrator: a ship's servo and step around the numerical kernel
(:mod:`sindyship.simulation.kernels`)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .kernels import RudderCommand, SimulationResult, _Integrator, integrate


def default_step(ship) -> float:
    """Default Runge-Kutta step [s]: 0.1 L / U0 (1.86 s for the KCS), and at most a quarter of
    the rudder servo's time constant.

    With it, halving the step moves no position of the protocol's manoeuvres by more than
    1e-4 L (``benchmarks/bench_simulate.py`` measures it).
    """
    return min(0.1, 0.25 * ship.servo.T_R) * ship.time_scale


def servo_of(ship) -> tuple[float, float, float]:
    """The rudder servo of paper eq. 12-13 in the kernel's units: time constant [s], rate
    limit [rad/s] and largest angle [rad]."""
    return (ship.servo.T_R * ship.time_scale, math.radians(ship.servo.rate_max),
            math.radians(ship.servo.delta_max))


def integrator_for(dynamics, commands: Sequence[RudderCommand]) -> _Integrator:
    """The kernel's integrator of a dynamics object (its ship gives the servo)."""
    return _Integrator(dynamics, commands, servo_of(dynamics.ship))


def simulate_batch(
    dynamics,
    commands: Sequence[RudderCommand],
    t: np.ndarray,
    state0: np.ndarray,
    *,
    step: float | None = None,
    check_divergence: bool = True,
    on_step=None,
) -> list[SimulationResult]:
    """Fly several manoeuvres of one model together.

    Parameters
    ----------
    dynamics : object
        Provides ``ship`` and ``accelerations(u, v, r, delta, psi, branch=None)``; optionally
        ``switching(state)`` (a function whose sign selects a branch of a discontinuous
        right-hand side), ``current`` (north, east) [m/s] and ``fly_compiled(integ,
        commands, t, state0, step, check_divergence, on_step)``, which flies the batch as
        the kernel would (compiled) or returns None to leave it to the kernel.
    commands : sequence of RudderCommand
        One per manoeuvre.
    t : ndarray
        Increasing output times [s]; the first is the initial time.
    state0 : ndarray, shape (7,) or (7, B)
        Initial state(s), SI.
    step : float, optional
        Runge-Kutta step [s]; default :func:`default_step`.  States at output times inside a
        step come from the step's cubic Hermite interpolant.
    check_divergence : bool
        Stop a member whose state leaves the plausible range (:func:`diverged`) at an output
        time; its later samples are NaN and ``diverged_at`` holds that time.
    on_step : callable, optional
        Called with the length [s] of every Runge-Kutta step taken (a progress bar's
        ``update``), or of every few hundred steps where the dynamics fly compiled.

    Returns
    -------
    list of SimulationResult
        One per command, in order.
    """
    ship = dynamics.ship
    integ = integrator_for(dynamics, commands)
    h_max = float(step) if step is not None else default_step(ship)
    t = np.asarray(t, dtype=float)
    if not np.isfinite(t).all():
        raise ValueError("output times must be finite numbers")
    compiled = getattr(dynamics, "fly_compiled", None)  # the same flights, compiled
    if compiled is not None:
        results = compiled(integ, commands, t, state0, h_max, check_divergence, on_step)
        if results is not None:
            return results
    return integrate(integ, commands, t, state0, h_max, check_divergence, ship.L, ship.U0,
                     on_step)

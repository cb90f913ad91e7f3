"""A scalar ``scipy.integrate.solve_ivp`` reference for the speed of sindyship's flights.

Flies manoeuvres one at a time with RK45 (adaptive step, ``rtol`` 1e-6, ``atol`` 1e-9) on
[u, v, r, x, y, psi, delta] in SI units: the same MMG accelerations (paper eq. 1-11,
``MMGModel.accelerations`` called with floats), the rudder servo of paper eq. 12-13, the
rudder command of each manoeuvre held between its scheduled changes, and a zig-zag's heading
checks as terminal events from which the integration restarts.  This is how a scalar
simulator is usually written with scipy; ``benchmarks/bench_speed.py`` times it beside
:func:`sindyship.manoeuvres.fly`, which flies every manoeuvre together, and reports how far
apart the two flights end (so that the faster one is not the less accurate one).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp

from sindyship.manoeuvres import Manoeuvre, initial_state
from sindyship.trajectory import Trajectory

RTOL, ATOL = 1e-6, 1e-9


def fly_scalar(mmg, manoeuvre: Manoeuvre) -> Trajectory:
    """One manoeuvre flown by ``solve_ivp`` (RK45), sampled at ``manoeuvre.times``."""
    ship = mmg.ship
    time_constant = ship.servo.T_R * ship.time_scale
    rate_max = math.radians(ship.servo.rate_max)
    delta_max = math.radians(ship.servo.delta_max)
    command = manoeuvre.command()
    times = np.asarray(manoeuvre.times, dtype=float)
    state = np.asarray(initial_state(ship), dtype=float)
    command.reset(state)
    held = [command.value(times[0], state)]

    def rhs(_t, y):
        u, v, r, _x, _y, psi, delta = y
        a_u, a_v, a_r = mmg.accelerations(u, v, r, delta, psi)
        target = min(max(held[0], -delta_max), delta_max)
        rate = min(max((target - delta) / time_constant, -rate_max), rate_max)
        c, s = math.cos(psi), math.sin(psi)
        return [float(a_u), float(a_v), float(a_r), u * c - v * s, u * s + v * c, r, rate]

    def heading_check(_t, y):
        value = command.event(y)
        return 1.0 if value is None else value

    heading_check.terminal, heading_check.direction = True, 1
    out = np.full((7, len(times)), np.nan)
    out[:, 0] = state
    start, end = times[0], times[-1]
    while start < end:
        stop = min(command.next_change(start), end)
        sol = solve_ivp(rhs, (start, stop), state, method="RK45", rtol=RTOL, atol=ATOL,
                        events=heading_check, dense_output=True)
        inside = (times > start) & (times <= sol.t[-1])
        if inside.any():
            out[:, inside] = sol.sol(times[inside])
        if sol.status == -1:
            break
        if sol.status == 1:
            command.on_event()
        start, state = sol.t[-1], sol.y[:, -1]
        held[0] = command.value(start, state)
    frame = {name: out[k] for k, name in enumerate(("u", "v", "r", "x", "y", "psi", "delta"))}

    return Trajectory(pd.DataFrame({"t": times, **frame}), name=manoeuvre.label)

"""Whole flights of identified models by a compiled loop (numba): the arithmetic of
:func:`sindyship.simulation.integrate`, member by member.

The kernel (:mod:`sindyship.simulation.kernels`) is the reference and can fly every model;
it flies whatever :func:`fly` leaves to it.  For the dynamics of identified models in the
design or instantaneous-speed form (:class:`sindyship.model.AbkowitzDynamics`, alone or
several side by side) this module repeats its steps with the same operations in the same
order: classical RK4, the first stage taken from the last one's end, steps split at scheduled
command changes and at a zig-zag's check angle (regula falsi on the step's cubic Hermite
interpolant), cubic Hermite outputs and the protocol's divergence test at the output times.
The forces are those of :func:`sindyship._forces_compiled.accelerations`.  A flight thus gives
the kernel's numbers (to the rounding of the library functions sin and cos) while a step costs
microseconds instead of a millisecond of Python.

:func:`fly` returns None, and the kernel flies, where numba is missing or switched off
(``SINDYSHIP_NO_COMPILE=1``), for dynamics with a switching function, a model with a
variable the loop does not make (a shape, the apparent wind, a factor of a number:
:attr:`sindyship.model.AbkowitzModel._compiled_flights`), recorded
channels on different grids, and commands it does not know (feedback, subclasses, empty steps,
replays of fewer than two samples).
"""

from __future__ import annotations

import math

import numpy as np

from ._flight_tables import (
    CONSTANT,
    FIXED,
    POSITION_X,
    POSITION_Y,
    PRESCRIBED,
    RUDDER_RATE,
    SERIES,
    STEP,
    ZIGZAG,
    command_form,
    model_tables,
)
from ._forces_compiled import COMPILED
from .simulation import RecordedZigZag, SimulationResult, ZigZagCommand, diverged

try:  # optional: pip install "sindyship[fast]"
    import numba
except ImportError:
    numba = None

#: Steps flown between two reports of progress.
STEPS_PER_REPORT = 200


# -------------------- rudder commands (the kernel's RudderCommand methods) ----------------
def _after(a, x):
    """How many of the increasing ``a`` (no NaN) are <= x: ``np.searchsorted(a, x,
    side="right")``, also for a NaN ``x`` (all of them: numpy sorts NaN last)."""
    low, high = 0, a.shape[0]
    while low < high:
        middle = (low + high) // 2
        if x < a[middle]:
            high = middle
        else:
            low = middle + 1
    return low


def _value(m, t, commands, loop):
    """The command's angle [rad] held from time ``t`` (``value``)."""
    kind, start, times, angles, rates, param, level_start, levels = commands
    sign, leg = loop[0], loop[1]
    if kind[m] == CONSTANT:
        return param[m, 0]
    if kind[m] == ZIGZAG:
        n_levels = level_start[m + 1] - level_start[m]
        if n_levels == 0:
            return sign[m] * param[m, 0]
        return sign[m] * levels[level_start[m] + min(leg[m], n_levels - 1)]
    lo, hi = start[m], start[m + 1]
    ts = times[lo:hi]
    if kind[m] == STEP:
        k = _after(ts, t + 1e-9) - 1
        return angles[lo + max(k, 0)]
    n = hi - lo
    k = _after(ts, t) - 1
    if t != t or k < 0 or k >= n - 1 or ts[k] == t:
        return math.nan if t != t else angles[lo + min(max(k, 0), n - 1)]
    return rates[lo + k] * (t - ts[k]) + angles[lo + k]


def _next_change(m, t, commands):
    """The next scheduled change after ``t`` (inf if none)."""
    kind, start, times = commands[0], commands[1], commands[2]
    if kind[m] != STEP and kind[m] != PRESCRIBED:
        return math.inf
    ts = times[start[m]:start[m + 1]]
    k = _after(ts, t + 1e-9)
    return ts[k] if k < ts.shape[0] else math.inf


def _rate(m, t, commands):
    """A prescribed rudder's rate at ``t`` (its interval's slope)."""
    start, times, rates = commands[1], commands[2], commands[4]
    lo, hi = start[m], start[m + 1]
    k = _after(times[lo:hi], t + 1e-9) - 1
    return rates[lo + min(max(k, 0), hi - lo - 2)]


def _event(m, psi, commands, loop):
    """A zig-zag's heading function: the check angle is reached where it crosses zero."""
    return loop[0][m] * (psi - loop[2][m]) - commands[5][m, 1]


# -------------------- right-hand side ------------------------------------------------------
def _copy(source, target):
    """``target[:] = source`` for a state's seven numbers."""
    for i in range(7):
        target[i] = source[i]


def _clip(x, low, high):
    """``np.minimum(np.maximum(x, low), high)`` of a number (NaN passes)."""
    if x != x:
        return x
    return min(max(x, low), high)


def _series_at(row, m, t, series_times, series_values):
    """A recorded channel of member ``m`` at ``t`` (:meth:`ChannelSeries.at`)."""
    n = series_times.shape[0]
    if n < 2:
        return series_values[row, m, 0]
    k = min(max(_after(series_times, t) - 1, 0), n - 2)
    w = min(max((t - series_times[k]) / (series_times[k + 1] - series_times[k]), 0.0), 1.0)
    return (1.0 - w) * series_values[row, m, k] + w * series_values[row, m, k + 1]


def _extra_variables(p, x, y, rate, m, t, models, channels, variables, ratio):
    """The model's variables beyond the state's into ``variables[5:]`` (the library's
    scaling, as :func:`sindyship._forces_compiled.run_accelerations` forms them; those the
    instantaneous form reads over the speed divided by ``ratio``, U/U0)."""
    extra_start, extra_kind, extra_source, extra_value = models[0], models[1], models[2], \
        models[3]
    U0, L, over_speed = models[15], models[16], models[18]
    for k in range(extra_start[p], extra_start[p + 1]):
        kind = extra_kind[k]
        value = 0.0
        if kind == SERIES:
            value = _series_at(extra_source[k], m, t, channels[0], channels[1])
        elif kind == FIXED:
            value = extra_value[k]
        elif kind == POSITION_X:
            value = x
        elif kind == POSITION_Y:
            value = y
        elif kind == RUDDER_RATE:
            value = rate * L / U0
        if over_speed[k]:
            value = value / ratio
        variables[5 + k - extra_start[p]] = value


def _factors(p, variables, models, base, factor):
    """Every distinct factor of model ``p``'s terms into ``factor`` (a factor of one last)."""
    base_start, base_variable, base_function = models[4], models[5], models[6]
    factor_start, factor_base, factor_power = models[7], models[8], models[9]
    b0 = base_start[p]
    for k in range(base_start[p + 1] - b0):
        value = variables[base_variable[b0 + k]]
        code = base_function[b0 + k]
        if code == 1:
            value = abs(value)
        elif code == 2:
            value = (value > 0.0) - (value < 0.0) if value == value else value
        elif code == 3:
            value = math.sin(value)
        elif code == 4:
            value = math.cos(value)
        base[k] = value
    f0 = factor_start[p]
    n_factors = factor_start[p + 1] - f0
    for f in range(n_factors):
        value = base[factor_base[f0 + f]]
        power = value
        for _ in range(factor_power[f0 + f] - 1):
            power *= value
        factor[f] = power
    factor[n_factors] = 1.0


def _accelerations(p, z, rudder, rate, m, t, models, channels, work, a):
    """Accelerations (3,) in SI of model ``p`` at the state ``z`` into ``a``
    (:func:`sindyship._forces_compiled.accelerations` with its extra variables)."""
    term_start, slots, weights, inertia, minv = models[10], models[11], models[12], \
        models[13], models[14]
    U0, L = models[15], models[16]
    variables, base, factor = work[0], work[1], work[2]
    variables[0] = z[0] / U0 - 1.0
    speed2 = 1.0  # the instantaneous form's (U/U0)^2, and its square root as the kernel's
    ratio = 1.0
    if models[17][p]:  # v and r over the instantaneous speed U (motion_variables)
        ratio = max(math.hypot(z[0], z[1]) / U0, models[19])
        speed2 = ratio * ratio
        variables[1] = z[1] / (U0 * ratio)
        variables[2] = z[2] * L / (U0 * ratio)
        ratio = math.sqrt(speed2)
    else:
        variables[1] = z[1] / U0
        variables[2] = z[2] * L / U0
    variables[3] = rudder
    variables[4] = z[5]
    _extra_variables(p, z[3], z[4], rate, m, t, models, channels, variables, ratio)
    _factors(p, variables, models, base, factor)
    X = 0.0
    Y = 0.0
    N = 0.0
    for j in range(term_start[p], term_start[p + 1]):
        column = factor[slots[0, j]]
        for s in range(1, slots.shape[0]):
            column *= factor[slots[s, j]]
        X += weights[0, j] * column
        Y += weights[1, j] * column
        N += weights[2, j] * column
    # the forces scale with U^2, the Coriolis terms take the motion over U0 (both factors 1,
    # exactly, in the design form)
    X *= speed2
    Y *= speed2
    N *= speed2
    un = variables[0] + 1.0
    vn = variables[1] * ratio
    rn = variables[2] * ratio
    X = X + (inertia[p, 0] * vn * rn + inertia[p, 1] * rn * rn)
    Y = Y + (-inertia[p, 2] * un * rn)
    N = N + (-inertia[p, 1] * un * rn - inertia[p, 3] * un * vn)
    scale = U0 * U0 / L
    a[0] = minv[p, 0, 0] * X * scale
    a[1] = (minv[p, 1, 1] * Y + minv[p, 1, 2] * N) * scale
    a[2] = (minv[p, 2, 1] * Y + minv[p, 2, 2] * N) * scale / L


def _rhs(m, t, z, delta_c, rate_time, flight, out):
    """dz/dt of member ``m`` (``_Integrator.rhs``); a prescribed rudder moves at its rate at
    ``rate_time``."""
    commands, loop, models, channels, physics, work = flight
    servo_T, rate_max, delta_max, current_north, current_east, commanded = physics
    rudder = delta_c if commanded else z[6]
    target = _clip(delta_c, -delta_max, delta_max)
    ddelta = _clip((target - z[6]) / servo_T, -rate_max, rate_max)
    if commands[0][m] == PRESCRIBED:
        ddelta = _rate(m, rate_time, commands)
    a = work[3]
    _accelerations(loop[3][m], z, rudder, ddelta, m, t, models, channels, work, a)
    c = math.cos(z[5])
    s = math.sin(z[5])
    out[0], out[1], out[2] = a[0], a[1], a[2]
    out[3] = z[0] * c - z[1] * s + current_north
    out[4] = z[0] * s + z[1] * c + current_east
    out[5] = z[2]
    out[6] = ddelta


def _step(m, t, z, h, delta_c, f0, flight, stages, out):
    """One RK4 step from its first stage ``f0`` into ``out``; ``stages`` holds scratch rows
    (k2, k3, k4, the stage state)."""
    mid = t + 0.5 * h
    k2, k3, k4, zs = stages[0], stages[1], stages[2], stages[3]
    for i in range(7):
        zs[i] = z[i] + 0.5 * h * f0[i]
    _rhs(m, mid, zs, delta_c, mid, flight, k2)
    for i in range(7):
        zs[i] = z[i] + 0.5 * h * k2[i]
    _rhs(m, mid, zs, delta_c, mid, flight, k3)
    for i in range(7):
        zs[i] = z[i] + h * k3[i]
    _rhs(m, t + h, zs, delta_c, mid, flight, k4)
    for i in range(7):
        out[i] = z[i] + (h / 6.0) * (f0[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


def _hermite(y0, f0, y1, f1, h, theta):
    """Cubic Hermite interpolation of one component (the kernel's ``_hermite``)."""
    t2 = theta * theta
    t3 = t2 * theta
    return ((2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + theta) * h * f0
            + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * h * f1)


def _crossing(m, z0, f0, z1, f1, h, commands, loop):
    """Fraction of a step where the zig-zag's heading function reaches zero (the kernel's
    ``_crossing``: Illinois regula falsi on the Hermite interpolant, to 1e-12)."""
    a, b = 0.0, 1.0
    ga = _event(m, z0[5], commands, loop)
    if ga >= 0.0:
        return 0.0
    gb = _event(m, z1[5], commands, loop)
    side = 0
    for _ in range(100):
        c = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not a < c < b:
            c = 0.5 * (a + b)
        gc = _event(m, _hermite(z0[5], f0[5], z1[5], f1[5], h, c), commands, loop)
        if gc >= 0.0:
            b, gb = c, gc
            if side == 1:
                ga *= 0.5
            side = 1
        else:
            a, ga = c, gc
            if side == -1:
                gb *= 0.5
            side = -1
        if b - a < 1e-12 or gc == 0.0:
            break
    return b


def _write(m, t_out, k_first, k_stop, time, h, tol, z0, f0, z1, f1, delta_c, out, out_cmd):
    """States at the output times in [k_first, k_stop) that fall inside the piece
    [time, time + h] (to ``tol``), from its cubic Hermite interpolant."""
    for k in range(k_first, k_stop):
        if not time - tol <= t_out[k] <= time + h + tol:
            continue
        theta = (t_out[k] - time) / h
        for i in range(7):
            out[i, k, m] = _hermite(z0[i], f0[i], z1[i], f1[i], h, theta)
        out_cmd[k, m] = delta_c


def _advance_one(m, time, h, z, first_end, first_f, t_out, k_first, k_stop, out, out_cmd,
                 flight, scratch, f_last):
    """Member ``m`` over [time, time + h], stopping at every discontinuity (the kernel's
    ``_advance_one``); the end state into ``z``, its derivative into ``f_last``.  Returns
    (whether ``f_last`` holds it, the last piece's command)."""
    commands, loop = flight[0], flight[1]
    stages, z_try, f0, f1, z_new = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4]
    t_end = time + h
    tol = 1e-9 * max(1.0, h)
    first = True
    has_f1 = False
    delta_c = math.nan
    for _ in range(64):  # a bounded number of switches per step
        remaining = t_end - time
        if remaining <= tol:
            break
        delta_c = _value(m, time, commands, loop)
        t_change = _next_change(m, time, commands)
        h_try = min(remaining, t_change - time) if t_change < t_end - tol else remaining
        if first:
            _copy(first_f, f0)
        else:  # the first stage at the piece's middle for a prescribed rudder's rate
            _rhs(m, time, z, delta_c, time + 0.5 * h_try, flight, f0)
        if first and h_try == remaining:
            _copy(first_end, z_try)
        else:
            _step(m, time, z, h_try, delta_c, f0, flight, stages, z_try)
        first = False
        _rhs(m, time + h_try, z_try, delta_c, time + 0.5 * h_try, flight, f1)
        theta = 1.0
        kind = 2 if h_try < remaining else 0  # 0: the step's end, 1: an event, 2: a change
        if commands[0][m] == ZIGZAG and _event(m, z_try[5], commands, loop) >= 0.0:
            theta = _crossing(m, z, f0, z_try, f1, h_try, commands, loop)
            kind = 1
        h_taken = theta * h_try
        if theta < 1.0:
            _step(m, time, z, h_taken, delta_c, f0, flight, stages, z_new)
            _rhs(m, time + h_taken, z_new, delta_c, time + 0.5 * h_taken, flight, f1)
        else:
            _copy(z_try, z_new)
        if h_taken > 0:
            _write(m, t_out, k_first, k_stop, time, h_taken, tol, z, f0, z_new, f1, delta_c,
                   out, out_cmd)
        time += h_taken
        _copy(z_new, z)
        has_f1 = kind == 0
        if kind == 1:
            loop[0][m] = -loop[0][m]
            loop[1][m] += 1
        if kind == 0:
            break
    if has_f1:
        _copy(f1, f_last)
    return has_f1, delta_c


def _common_step(h, time, active, commands):
    """The step, cut where every member's replayed rudder changes if all change at one time
    inside it (the kernel's ``_common_change``)."""
    for m in range(active.shape[0]):
        if active[m] and commands[0][m] != PRESCRIBED:
            return h
    first, last = math.inf, -math.inf
    for m in range(active.shape[0]):
        if active[m]:
            change = _next_change(m, time, commands)
            first, last = min(first, change), max(last, change)
    tol = 1e-9 * max(1.0, h)
    return first - time if time + tol < first < time + h - tol and last - first <= tol else h


def _advance(m, y, time, h, t_out, k_next, k_stop, flight, cache, out, out_cmd, scratch):
    """Member ``m`` over one step of the batch (the kernel's ``_advance``): whole when no
    discontinuity falls inside it, else piece by piece."""
    commands, loop = flight[0], flight[1]
    fsal_f, fsal_command, fsal_valid = cache[0], cache[1], cache[2]
    z, f_start, z_end, f_end = scratch[5], scratch[6], scratch[7], scratch[8]
    prescribed = commands[0][m] == PRESCRIBED
    tol = 1e-9 * max(1.0, h)
    _copy(y[:, m], z)
    delta_c = _value(m, time, commands, loop)
    if fsal_valid[m] and fsal_command[m] == delta_c:
        _copy(fsal_f[:, m], f_start)
    else:
        _rhs(m, time, z, delta_c, time, flight, f_start)
    _step(m, time, z, h, delta_c, f_start, flight, scratch[0], z_end)
    split = _next_change(m, time, commands) < time + h - tol or (
        commands[0][m] == ZIGZAG and _event(m, z_end[5], commands, loop) >= 0.0)
    if split:
        has_f, delta_c = _advance_one(m, time, h, z, z_end, f_start, t_out, k_next, k_stop,
                                      out, out_cmd, flight, scratch, f_end)
        _copy(z, z_end)
    else:
        _rhs(m, time + h, z_end, delta_c, time + 0.5 * h, flight, f_end)
        _write(m, t_out, k_next, k_stop, time, h, tol, z, f_start, z_end, f_end, delta_c,
               out, out_cmd)  # every sample of the step lies inside it
        has_f = True
    _copy(z_end, y[:, m])
    fsal_valid[m] = has_f and not prescribed
    if has_f:
        _copy(f_end, fsal_f[:, m])
        fsal_command[m] = delta_c


def _diverged(z, U0, L):
    """The protocol's divergence rule (:func:`sindyship.simulation.diverged`)."""
    for i in range(7):
        if not math.isfinite(z[i]):
            return True
    un, vn, rn = z[0] / U0, z[1] / U0, z[2] * L / U0
    return un <= 0.0 or un >= 2.0 or abs(vn) > 1.0 or abs(rn) > 2.0


def _stop_diverged(m, t_out, k_next, k_stop, U0, L, out, out_cmd, active, diverged_at):
    """Stop member ``m`` at the first new output sample out of the plausible range."""
    for k in range(k_next, k_stop):
        if _diverged(out[:, k, m], U0, L):
            diverged_at[m] = t_out[k]
            for later in range(k, out_cmd.shape[0]):
                for i in range(7):
                    out[i, later, m] = math.nan
                out_cmd[later, m] = math.nan
            active[m] = False
            return


def _run(y, t_out, clock, h_max, check, flight, state, out, out_cmd, max_steps):
    """At most ``max_steps`` steps of the batch's loop (``integrate``); returns the seconds
    flown.  ``clock`` holds the time and the next output index, ``state`` the members'
    first-stage cache, activity and divergence times."""
    U0, L = flight[2][15], flight[2][16]
    active, diverged_at = state[3], state[4]
    n_out = t_out.shape[0]
    scratch = (np.empty((4, 7)), np.empty(7), np.empty(7), np.empty(7), np.empty(7),
               np.empty(7), np.empty(7), np.empty(7), np.empty(7))
    flown = 0.0
    for _ in range(max_steps):
        time, k_next = clock[0], int(clock[1])
        if k_next >= n_out or not active.any():
            break
        h = _common_step(min(h_max, t_out[n_out - 1] - time), time, active, flight[0])
        k_stop = _after(t_out, time + h + 1e-9 * max(1.0, h))
        stepped = np.flatnonzero(active)
        for m in stepped:
            _advance(m, y, time, h, t_out, k_next, k_stop, flight, state, out, out_cmd,
                     scratch)
        clock[0], clock[1] = time + h, k_stop
        flown += h
        if check:
            for m in stepped:
                _stop_diverged(m, t_out, k_next, k_stop, U0, L, out, out_cmd, active,
                               diverged_at)
    return flown


if COMPILED:
    _jit = numba.njit(cache=True, nogil=True, error_model="numpy")
    _value, _next_change, _rate, _event = _jit(_value), _jit(_next_change), _jit(_rate), \
        _jit(_event)
    _after, _copy = _jit(_after), _jit(_copy)
    _clip, _series_at, _accelerations = _jit(_clip), _jit(_series_at), _jit(_accelerations)
    _extra_variables, _factors = _jit(_extra_variables), _jit(_factors)
    _common_step, _advance, _stop_diverged = _jit(_common_step), _jit(_advance), \
        _jit(_stop_diverged)
    _rhs, _step, _hermite, _crossing = _jit(_rhs), _jit(_step), _jit(_hermite), _jit(_crossing)
    _write, _advance_one, _diverged, _run = _jit(_write), _jit(_advance_one), \
        _jit(_diverged), _jit(_run)


# -------------------- the flights' tables ---------------------------------------------------
def fly(parts, integ, commands, t, state0, h_max, check_divergence, on_step=None):
    """:func:`sindyship.simulation.integrate` of identified models through the compiled loop.

    Parameters
    ----------
    parts : sequence of (AbkowitzDynamics, int, int)
        Each model's dynamics and the range of members it flies (all members, covered once).
    integ : sindyship.simulation._Integrator
        The kernel's integrator of these dynamics (servo, current, rudder input, inputs; its
        dynamics' ship gives L and U0).
    commands, t, state0, h_max, check_divergence, on_step
        As :func:`sindyship.simulation.integrate`; ``on_step`` is called with the seconds of
        every few hundred steps.

    Returns
    -------
    list of SimulationResult or None
        None when a model, a variable or a command has no form in the loop.
    """
    if not COMPILED or integ.switching is not None:
        return None
    L, U0 = integ.dynamics.ship.L, integ.dynamics.ship.U0
    n_members = len(commands)
    model_of = np.full(n_members, -1, dtype=np.int64)  # the part flying each member
    for p, (_, start, stop) in enumerate(parts):
        model_of[start:stop] = p
    if (model_of < 0).any():
        return None
    tables = model_tables(parts, integ, n_members, L, U0)
    command_tables = command_form(commands)
    if tables is None or command_tables is None:
        return None
    models, channels, work = tables
    t = np.array(t, dtype=float)  # contiguous and writable: one compiled form of the loop
    n_out = len(t)
    y = _first_states(commands, t, state0)
    out = np.full((7, n_out, n_members), np.nan)
    out_cmd = np.full((n_out, n_members), np.nan)
    out[:, 0, :] = y
    out_cmd[0] = [c.value(t[0], y[:, j]) for j, c in enumerate(commands)]
    loop = (np.array([c.sign if isinstance(c, ZigZagCommand) else 1 for c in commands],
                     dtype=np.int64),  # as reset
            np.zeros(n_members, dtype=np.int64), y[5].copy(), model_of)
    diverged_at = np.full(n_members, np.nan)
    active = np.ones(n_members, dtype=bool)
    if check_divergence:
        bad = diverged(y, L, U0)
        diverged_at[bad], active[bad] = t[0], False
    physics = (max(float(integ.T), 1e-9), float(integ.rate_max), float(integ.delta_max),
               *integ.current, integ.rudder_input == "commanded")
    flight = (command_tables, loop, models, channels, physics, work)
    state = (np.zeros((7, n_members)), np.full(n_members, np.nan),
             np.zeros(n_members, dtype=bool), active, diverged_at)
    clock = np.array([float(t[0]), 1.0])
    with np.errstate(all="ignore"):
        while clock[1] < n_out and active.any():
            flown = _run(y, t, clock, float(h_max), bool(check_divergence), flight, state, out,
                         out_cmd, STEPS_PER_REPORT)
            if on_step is not None:
                on_step(flown)
    for j, cmd in enumerate(commands):  # the zig-zags' last leg, as the kernel leaves them
        if isinstance(cmd, ZigZagCommand):
            cmd.sign = int(loop[0][j])
        if isinstance(cmd, RecordedZigZag):
            cmd.leg = int(loop[1][j])
    return [SimulationResult(t=t.copy(), states=out[:, :, j], delta_c=out_cmd[:, j],
                             diverged_at=None if np.isnan(diverged_at[j])
                             else float(diverged_at[j])) for j in range(n_members)]


def _first_states(commands, t, state0) -> np.ndarray:
    """The members' first states (7, M), the commands reset to them, a replayed rudder at its
    record's angle (as the kernel's ``integrate`` starts)."""
    n_members = len(commands)
    y = np.array(state0, dtype=float).reshape(7, -1)
    if y.shape[1] == 1 and n_members > 1:
        y = np.repeat(y, n_members, axis=1)
    if y.shape[1] != n_members:
        raise ValueError("state0 must have one column per command")
    if len(t) > 1 and np.any(np.diff(t) <= 0):
        raise ValueError("output times must increase")
    for j, cmd in enumerate(commands):
        cmd.reset(y[:, j])
        if cmd.prescribed:
            y[6, j] = cmd.value(t[0], y[:, j])
    return y

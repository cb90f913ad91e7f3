"""The segments of multiple shooting flown by a compiled loop (numba), with their
sensitivities: the arithmetic of :func:`sindyship.shooting.fly_segments`, state by state.

:mod:`sindyship.shooting` is the reference: it makes the library's variables with
:meth:`sindyship.model.AbkowitzModel.flight_variables`, the forces with the model's term
columns, and differentiates the accelerations in the state by forward differences.  Here the
same steps run as one loop over the segments, each with its own state and sensitivities, so a
Jacobian of a few hundred segments costs a fraction of a second.  Every segment is flown on
its own: its numbers do not depend on the other segments of the batch.
"""

from __future__ import annotations

import math
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ._forces_compiled import COMPILED

try:  # optional: pip install "sindyship[fast]"
    import numba
except ImportError:
    numba = None

#: How an extra variable (beyond du, v, r, delta, psi) is made from a segment's inputs.
(CHANNEL, CHANNEL_OVER_SPEED, POSITION_X, POSITION_Y, RUDDER_RATE, WIND_SPEED, WIND_ANGLE,
 SHAPE_EDGE, SHAPE_BANK) = range(9)


def _variables(z, rudder, rate, extras, kinds, sources, shapes, wind_rows, instantaneous,
               floor, U0, L, out):
    """The library's variables of one state into ``out``; returns the speed factor
    (U/U0)^2 (1 in the design form).  ``shapes`` holds each shape variable's (cos and sin of
    its bearing, distance, and an edge's width or a bank's nearest distance)
    (:func:`sindyship.terms.shape_values`)."""
    u, v, r, x, y, psi = z[0], z[1], z[2], z[3], z[4], z[5]
    ratio = 1.0
    if instantaneous:
        ratio = max(math.sqrt(u * u + v * v) / U0, floor)
    out[0] = u / U0 - 1.0
    out[1] = v / (U0 * ratio)
    out[2] = r * L / (U0 * ratio)
    out[3] = rudder
    out[4] = psi
    for k in range(kinds.shape[0]):
        kind = kinds[k]
        if kind == CHANNEL:
            value = extras[sources[k]]
        elif kind == CHANNEL_OVER_SPEED:
            value = extras[sources[k]] / ratio
        elif kind == POSITION_X:
            value = x
        elif kind == POSITION_Y:
            value = y
        elif kind == RUDDER_RATE:
            value = rate * L / U0 / ratio
        elif kind == SHAPE_EDGE or kind == SHAPE_BANK:
            across = (x * shapes[k, 0] + y * shapes[k, 1]) / L - shapes[k, 2]
            if kind == SHAPE_EDGE:
                value = 0.5 * (1.0 + math.tanh(across / shapes[k, 3]))
            else:
                value = 1.0 / max(abs(across), shapes[k, 3]) ** 2
                value = -value if across > 0.0 else (value if across < 0.0 else 0.0)
        else:  # the apparent wind, from the true wind and the motion
            speed = extras[wind_rows[0]] * U0
            relative = extras[wind_rows[1]] - psi
            u_air = -speed * math.cos(relative) - u
            v_air = -speed * math.sin(relative) - v
            if kind == WIND_SPEED:
                value = math.sqrt(u_air * u_air + v_air * v_air) / U0 / ratio
            else:
                value = math.atan2(-v_air, -u_air)
        out[5 + k] = value
    return ratio * ratio


def _columns(variables, base_variable, base_function, factor_base, factor_power, slots,
             base, factor, out):
    """The term columns of one state (as :func:`sindyship._forces_compiled.forces`)."""
    for k in range(base_variable.shape[0]):
        x = variables[base_variable[k]]
        code = base_function[k]
        if code == 1:
            x = abs(x)
        elif code == 2:
            x = (x > 0.0) - (x < 0.0) if x == x else x
        elif code == 3:
            x = math.sin(x)
        elif code == 4:
            x = math.cos(x)
        base[k] = x
    for f in range(factor_base.shape[0]):
        x = base[factor_base[f]]
        value = x
        for _ in range(factor_power[f] - 1):
            value *= x
        factor[f] = value
    width, n_terms = slots.shape
    for j in range(n_terms):
        column = factor[slots[0, j]]
        for s in range(1, width):
            column *= factor[slots[s, j]]
        out[j] = column


def _accelerations(z, rudder, rate, extras, tables, weights, inertia, minv, U0, L, variables,
                   base, factor, columns, a):
    """Accelerations (3,) in SI of one state into ``a``, its term columns (times the speed
    factor) into ``columns``."""
    (kinds, sources, shapes, wind_rows, instantaneous, floor, base_variable, base_function,
     factor_base, factor_power, slots) = tables
    speed2 = _variables(z, rudder, rate, extras, kinds, sources, shapes, wind_rows,
                        instantaneous, floor, U0, L, variables)
    _columns(variables, base_variable, base_function, factor_base, factor_power, slots, base,
             factor, columns)
    X = 0.0
    Y = 0.0
    N = 0.0
    for j in range(columns.shape[0]):
        columns[j] *= speed2
        X += weights[0, j] * columns[j]
        Y += weights[1, j] * columns[j]
        N += weights[2, j] * columns[j]
    un = z[0] / U0
    vn = z[1] / U0
    rn = z[2] * L / U0
    X += inertia[0] * vn * rn + inertia[1] * rn * rn
    Y += -inertia[2] * un * rn
    N += -inertia[1] * un * rn - inertia[3] * un * vn
    scale = U0 * U0 / L
    a[0] = minv[0, 0] * X * scale
    a[1] = (minv[1, 1] * Y + minv[1, 2] * N) * scale
    a[2] = (minv[2, 1] * Y + minv[2, 2] * N) * scale / L


def _stage(zs, ss, inputs, physics, sensitivity, work, k_out, ks_out):
    """dz/dt of one state into ``k_out`` and, when asked, d(sens)/dt into ``ks_out``."""
    rudder, rate, extras = inputs
    tables, weights, inertia, minv, U0, L = physics
    perturbed, steps, rows, cols, with_sens = sensitivity
    variables, base, factor, columns, scratch, a, a_moved, moved, jac = work
    _accelerations(zs, rudder, rate, extras, tables, weights, inertia, minv, U0, L, variables,
                   base, factor, columns, a)
    c = math.cos(zs[5])
    s = math.sin(zs[5])
    k_out[0], k_out[1], k_out[2] = a[0], a[1], a[2]
    k_out[3] = zs[0] * c - zs[1] * s
    k_out[4] = zs[0] * s + zs[1] * c
    k_out[5] = zs[2]
    if not with_sens:
        return
    jac[:, :] = 0.0
    for i in range(perturbed.shape[0]):
        q = perturbed[i]
        _copy(zs, moved)
        moved[q] += steps[q]
        _accelerations(moved, rudder, rate, extras, tables, weights, inertia, minv, U0, L,
                       variables, base, factor, scratch, a_moved)
        for row in range(3):
            jac[row, q] = (a_moved[row] - a[row]) / steps[q]
    jac[3, 0], jac[3, 1], jac[3, 5] = c, -s, -zs[0] * s - zs[1] * c
    jac[4, 0], jac[4, 1], jac[4, 5] = s, c, zs[0] * c - zs[1] * s
    jac[5, 2] = 1.0
    _sensitivity_rate(jac, ss, columns, rows, cols, minv, U0 * U0 / L, L, ks_out)


def _sensitivity_rate(jac, ss, columns, rows, cols, minv, scale, L, ks_out):
    """d(sens)/dt = (df/dz) sens + df/dtheta (the variational equations); the kinematic rows
    of df/dz have two or three entries, and its force rows only the perturbed columns."""
    for p in range(rows.shape[0]):
        s0, s1, s2, s3, s4, s5 = ss[0, p], ss[1, p], ss[2, p], ss[3, p], ss[4, p], ss[5, p]
        column = columns[cols[p]] * scale
        for i in range(3):
            ks_out[i, p] = (jac[i, 0] * s0 + jac[i, 1] * s1 + jac[i, 2] * s2 + jac[i, 3] * s3
                            + jac[i, 4] * s4 + jac[i, 5] * s5)
        ks_out[0, p] += minv[0, rows[p]] * column
        ks_out[1, p] += minv[1, rows[p]] * column
        ks_out[2, p] += minv[2, rows[p]] * column / L
        ks_out[3, p] = jac[3, 0] * s0 + jac[3, 1] * s1 + jac[3, 5] * s5
        ks_out[4, p] = jac[4, 0] * s0 + jac[4, 1] * s1 + jac[4, 5] * s5
        ks_out[5, p] = s2


def _copy(source, target):
    """``target[:] = source[:len(target)]`` as a loop (a slice copy compiles numba's messages
    for mismatched shapes); :func:`_copy_matrix` the same for matrices."""
    for i in range(target.shape[0]):
        target[i] = source[i]


def _copy_matrix(source, target):
    for i in range(target.shape[0]):
        for j in range(target.shape[1]):
            target[i, j] = source[i, j]


def _diverged(z, U0, L) -> bool:
    """The protocol's divergence rule (:func:`sindyship.simulation.diverged`)."""
    for i in range(6):
        if not math.isfinite(z[i]):
            return True
    un, vn, rn = z[0] / U0, z[1] / U0, z[2] * L / U0
    return un <= 0.0 or un >= 2.0 or abs(vn) > 1.0 or abs(rn) > 2.0


def _rk4(z, sens, m, j, h, data, physics, sensitivity, work, k, ks, zs, ss):
    """One RK4 step of segment ``m`` (its state and sensitivities), in place."""
    rudder, rate, extras = data
    with_sens = sensitivity[4]
    for stage in range(4):
        half = 2 * j + (0 if stage == 0 else (1 if stage < 3 else 2))
        weight = 0.0 if stage == 0 else (0.5 * h if stage < 3 else h)
        for i in range(6):
            zs[i] = z[i] + weight * k[max(stage - 1, 0), i]
            if with_sens:
                for p in range(sens.shape[1]):
                    ss[i, p] = sens[i, p] + weight * ks[max(stage - 1, 0), i, p]
        inputs = (rudder[m, half], rate[m, half], extras[:, m, half])
        _stage(zs, ss, inputs, physics, sensitivity, work, k[stage], ks[stage])
    for i in range(6):
        z[i] += h / 6.0 * (k[0, i] + 2.0 * k[1, i] + 2.0 * k[2, i] + k[3, i])
        if with_sens:
            for p in range(sens.shape[1]):
                sens[i, p] += h / 6.0 * (ks[0, i, p] + 2.0 * ks[1, i, p] + 2.0 * ks[2, i, p]
                                         + ks[3, i, p])


def _fly(members, state0, data, physics, sensitivity, closed, h, n_steps, every, states,
         jacobian, stopped):
    """The segments ``members`` flown by RK4 from their first states (with sensitivities)
    into ``states`` (M, n_out, 6; from a divergence on, the last state in range), ``jacobian``
    (M, n_out, 6, P) and ``stopped`` (M; the step at whose end a segment diverged, untouched
    if none), each on its own; a zig-zag in ``closed`` flies closed loop (_fly_closed_one)."""
    rudder, rate, extras = data
    sign, check, psi0, levels, count, delta0, servo, commanded = closed
    for m in members:
        if sign[m] == 0:
            _fly_one(m, state0, (rudder, rate, extras), physics, sensitivity, h, n_steps,
                     every, states, jacobian, stopped)
        else:
            _fly_closed_one(m, state0, extras, physics, sensitivity,
                            (sign[m], check[m], psi0[m], levels[m, :count[m]], delta0[m],
                             servo, commanded), h, n_steps, every, states, jacobian, stopped)


def _fly_in_threads(n_segments: int, *arguments) -> None:
    """:func:`_fly` of every segment, in shares that this thread and as many others as numba
    may use (``numba.get_num_threads()``: the cores unless ``NUMBA_NUM_THREADS`` or
    ``numba.set_num_threads`` say fewer) take in turn, one that finishes early taking more:
    the compiled loop releases the GIL, and every segment writes its own rows."""
    n_threads = min(numba.get_num_threads() if numba is not None else 1, n_segments)
    n_shares, lock = max(min(n_segments, 4 * n_threads), 1), threading.Lock()
    shares = iter([np.arange(k, n_segments, n_shares, dtype=np.int64)  # one compiled form
                   for k in range(n_shares)])

    def fly_shares():
        while True:
            with lock:
                share = next(shares, None)
            if share is None:
                return
            _fly(share, *arguments)

    with ThreadPoolExecutor(max(n_threads - 1, 1)) as pool:
        others = [pool.submit(fly_shares) for _ in range(n_threads - 1)]
        fly_shares()
        for done in others:
            done.result()


def _fly_one(m, state0, data, physics, sensitivity, h, n_steps, every, states, jacobian,
             stopped):
    """Segment ``m`` flown from its first state (:func:`_fly`)."""
    tables, _, _, _, U0, L = physics
    n_par = sensitivity[2].shape[0]
    n_terms = tables[10].shape[1]
    work = (np.empty(5 + tables[0].shape[0]), np.empty(max(tables[6].shape[0], 1)),
            np.ones(tables[8].shape[0] + 1), np.empty(n_terms), np.empty(n_terms), np.empty(3),
            np.empty(3), np.empty(6), np.zeros((6, 6)))
    z, zs = state0[m].copy(), np.empty(6)
    sens, ss = np.zeros((6, n_par)), np.zeros((6, n_par))
    k, ks = np.zeros((4, 6)), np.zeros((4, 6, n_par))
    held, held_sens = np.empty(6), np.zeros((6, n_par))
    for j in range(n_steps):
        _copy(z, held)
        if sensitivity[4]:
            _copy_matrix(sens, held_sens)
        _rk4(z, sens, m, j, h, data, physics, sensitivity, work, k, ks, zs, ss)
        if _diverged(z, U0, L):  # every later sample holds the last state in range
            stopped[m] = j
            for out in range(j // every, n_steps // every):
                _copy(held, states[m, out])
                if sensitivity[4]:
                    _copy_matrix(held_sens, jacobian[m, out])
            break
        if (j + 1) % every == 0:
            _copy(z, states[m, (j + 1) // every - 1])
            if sensitivity[4]:
                _copy_matrix(sens, jacobian[m, (j + 1) // every - 1])


# --------------------------------------------------------------- zig-zags flown closed loop
def _servo_rate(delta, command, servo):
    """The servo's rudder rate [rad/s] (paper eq. 12-13): ``servo`` = (T [s], rate limit
    [rad/s], largest angle [rad])."""
    time_constant, rate_max, delta_max = servo
    return _servo_slope(delta, min(max(command, -delta_max), delta_max), time_constant, rate_max)


def _servo_slope(value, target, time_constant, rate_max):
    """The servo's rate [rad/s] from angle ``value`` toward ``target`` (paper eq. 12-13),
    limited as Python's ``min(max(s, -rate_max), rate_max)`` limits it (NaN passes)."""
    s = (target - value) / max(time_constant, 1e-9)
    if -rate_max > s:
        s = -rate_max
    if rate_max < s:
        s = rate_max
    return s


def servo_angles(t, command, delta0, time_constant, rate_max, angle, rate):
    """The servo's angle and rate at the samples ``t`` into ``angle`` and ``rate``, from
    ``delta0``, each sample's ``command`` held to the next one: RK4 in equal steps of at most
    a quarter of the time constant [s] (:func:`sindyship.shooting.servo_rudder`)."""
    h_max = 0.25 * max(time_constant, 1e-9)
    delta = delta0
    n = t.shape[0]
    for i in range(n):
        angle[i] = delta
        rate[i] = _servo_slope(delta, command[i], time_constant, rate_max)
        if i + 1 == n:
            break
        n_sub = max(1, math.ceil((t[i + 1] - t[i]) / h_max))
        h = (t[i + 1] - t[i]) / n_sub
        for _ in range(n_sub):
            k1 = _servo_slope(delta, command[i], time_constant, rate_max)
            k2 = _servo_slope(delta + 0.5 * h * k1, command[i], time_constant, rate_max)
            k3 = _servo_slope(delta + 0.5 * h * k2, command[i], time_constant, rate_max)
            k4 = _servo_slope(delta + h * k3, command[i], time_constant, rate_max)
            delta += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def _extras_at(extras, m, t, h, out):
    """The channels of segment ``m`` at time ``t`` from its start (linear between the half
    steps they are given at)."""
    position = t / (0.5 * h)
    i = min(max(int(position), 0), extras.shape[2] - 2)
    w = min(max(position - i, 0.0), 1.0)
    for k in range(extras.shape[0]):
        out[k] = (1.0 - w) * extras[k, m, i] + w * extras[k, m, i + 1]


def _closed_rate(zs, ss, command, ext, physics, sensitivity, loop, work, k_out, ks_out):
    """dz/dt of the seven states (the rudder angle last) and, when asked, d(sens)/dt."""
    servo, commanded = loop[5], loop[6]
    tables, weights, inertia, minv, U0, L = physics
    perturbed, steps, rows, cols, with_sens = sensitivity
    variables, base, factor, columns, scratch, a, a_moved, moved, jac = work
    rate = _servo_rate(zs[6], command, servo)
    _accelerations(zs, command if commanded else zs[6], rate, ext, tables, weights, inertia,
                   minv, U0, L, variables, base, factor, columns, a)
    c, s = math.cos(zs[5]), math.sin(zs[5])
    k_out[0], k_out[1], k_out[2] = a[0], a[1], a[2]
    k_out[3] = zs[0] * c - zs[1] * s
    k_out[4] = zs[0] * s + zs[1] * c
    k_out[5] = zs[2]
    k_out[6] = rate
    if not with_sens:
        return
    jac[:, :] = 0.0
    for i in range(perturbed.shape[0] + 1):
        q = perturbed[i] if i < perturbed.shape[0] else 6  # and the rudder angle
        _copy(zs, moved)
        moved[q] += steps[q] if q < 6 else 1e-7
        moved_rate = _servo_rate(moved[6], command, servo)
        _accelerations(moved, command if commanded else moved[6], moved_rate, ext, tables,
                       weights, inertia, minv, U0, L, variables, base, factor, scratch,
                       a_moved)
        for row in range(3):
            jac[row, q] = (a_moved[row] - a[row]) / (steps[q] if q < 6 else 1e-7)
    jac[3, 0], jac[3, 1], jac[3, 5] = c, -s, -zs[0] * s - zs[1] * c
    jac[4, 0], jac[4, 1], jac[4, 5] = s, c, zs[0] * c - zs[1] * s
    jac[5, 2] = 1.0
    unsaturated = abs(rate) < servo[1] and abs(command) <= servo[2]
    jac[6, 6] = -1.0 / servo[0] if unsaturated else 0.0
    scale = U0 * U0 / L
    for p in range(rows.shape[0]):
        for i in range(7):
            total = 0.0
            for q in range(7):
                total += jac[i, q] * ss[q, p]
            ks_out[i, p] = total
        column = columns[cols[p]] * scale
        ks_out[0, p] += minv[0, rows[p]] * column
        ks_out[1, p] += minv[1, rows[p]] * column
        ks_out[2, p] += minv[2, rows[p]] * column / L


def _closed_step(z, sens, t, h_sub, h, m, command, extras, physics, sensitivity, loop, work,
                 k, ks, zs, ss, ext):
    """One RK4 step of length ``h_sub`` from time ``t`` with the command held, in place."""
    with_sens = sensitivity[4]
    for stage in range(4):
        weight = 0.0 if stage == 0 else (0.5 * h_sub if stage < 3 else h_sub)
        time = t + (0.0 if stage == 0 else (0.5 * h_sub if stage < 3 else h_sub))
        for i in range(7):
            zs[i] = z[i] + weight * k[max(stage - 1, 0), i]
            if with_sens:
                for p in range(sens.shape[1]):
                    ss[i, p] = sens[i, p] + weight * ks[max(stage - 1, 0), i, p]
        _extras_at(extras, m, time, h, ext)
        _closed_rate(zs, ss, command, ext, physics, sensitivity, loop, work, k[stage],
                     ks[stage])
    for i in range(7):
        z[i] += h_sub / 6.0 * (k[0, i] + 2.0 * k[1, i] + 2.0 * k[2, i] + k[3, i])
        if with_sens:
            for p in range(sens.shape[1]):
                sens[i, p] += h_sub / 6.0 * (ks[0, i, p] + 2.0 * ks[1, i, p]
                                             + 2.0 * ks[2, i, p] + ks[3, i, p])


def _crossing(psi_start, r_start, psi_end, r_end, h, sign, psi0, check):
    """The fraction of a step where sign (psi - psi0) reaches the check angle, on the cubic
    Hermite interpolant of the heading (its derivative is the yaw rate)."""
    low, high = 0.0, 1.0
    for _ in range(60):
        theta = 0.5 * (low + high)
        t2, t3 = theta * theta, theta * theta * theta
        psi = ((2 * t3 - 3 * t2 + 1) * psi_start + (t3 - 2 * t2 + theta) * h * r_start
               + (-2 * t3 + 3 * t2) * psi_end + (t3 - t2) * h * r_end)
        if sign * (psi - psi0) - check >= 0.0:
            high = theta
        else:
            low = theta
    return high


def _fly_closed_one(m, state0, extras, physics, sensitivity, loop, h, n_steps, every, states,
                    jacobian, stopped):
    """Segment ``m`` flown as a zig-zag, closed loop: the rudder (a state, through the servo)
    reverses when the heading change reaches the check angle, located inside the step; the
    sensitivities jump there by the change of the rudder rate times the event time's own
    sensitivity (dt_e/dtheta = -dpsi/dtheta / r)."""
    sign, check, psi0, levels, delta0, servo, commanded = loop
    tables, _, _, _, U0, L = physics
    n_par = sensitivity[2].shape[0]
    n_terms = tables[10].shape[1]
    work = (np.empty(5 + tables[0].shape[0]), np.empty(max(tables[6].shape[0], 1)),
            np.ones(tables[8].shape[0] + 1), np.empty(n_terms), np.empty(n_terms), np.empty(3),
            np.empty(3), np.empty(7), np.zeros((7, 7)))
    z = np.empty(7)
    _copy(state0[m], z[:6])
    z[6] = delta0
    sens, ss = np.zeros((7, n_par)), np.zeros((7, n_par))
    k, ks = np.zeros((4, 7)), np.zeros((4, 7, n_par))
    zs, ext = np.empty(7), np.empty(max(extras.shape[0], 1))
    start, start_sens = np.empty(7), np.zeros((7, n_par))
    held, held_sens = np.empty(7), np.zeros((7, n_par))
    leg = 0
    for j in range(n_steps):
        _copy(z, held)
        _copy_matrix(sens, held_sens)
        t, left = j * h, h
        for _ in range(4):  # a bounded number of reversals in one step
            _copy(z, start)
            _copy_matrix(sens, start_sens)
            command = sign * levels[min(leg, levels.shape[0] - 1)]
            _closed_step(z, sens, t, left, h, m, command, extras, physics, sensitivity, loop,
                         work, k, ks, zs, ss, ext)
            if sign * (z[5] - psi0) - check < 0.0 or sign * (start[5] - psi0) - check >= 0.0:
                break
            theta = _crossing(start[5], start[2], z[5], z[2], left, sign, psi0, check)
            _copy(start, z)
            _copy_matrix(start_sens, sens)
            _closed_step(z, sens, t, theta * left, h, m, command, extras, physics, sensitivity,
                         loop, work, k, ks, zs, ss, ext)
            before = _servo_rate(z[6], command, servo)
            sign, leg = -sign, leg + 1
            after = _servo_rate(z[6], sign * levels[min(leg, levels.shape[0] - 1)], servo)
            if z[2] != 0.0:
                for p in range(n_par):
                    sens[6, p] -= (before - after) * sens[5, p] / z[2]
            t, left = t + theta * left, (1.0 - theta) * left
        if _diverged(z, U0, L):  # every later sample holds the last state in range
            stopped[m] = j
            for out in range(j // every, n_steps // every):
                _copy(held, states[m, out])
                if sensitivity[4]:
                    _copy_matrix(held_sens, jacobian[m, out])
            break
        if (j + 1) % every == 0:
            _copy(z, states[m, (j + 1) // every - 1])
            if sensitivity[4]:
                _copy_matrix(sens, jacobian[m, (j + 1) // every - 1])


if COMPILED:
    _jit = numba.njit(cache=True, nogil=True, error_model="numpy")
    (_variables, _columns, _accelerations, _sensitivity_rate, _stage, _diverged, _copy,
     _copy_matrix, _rk4, _fly_one, _servo_rate, _extras_at, _servo_slope, servo_angles,
     _closed_rate, _closed_step, _crossing, _fly_closed_one, _fly) = (_jit(f) for f in (
        _variables, _columns, _accelerations, _sensitivity_rate, _stage, _diverged, _copy,
        _copy_matrix, _rk4, _fly_one, _servo_rate, _extras_at, _servo_slope, servo_angles,
        _closed_rate, _closed_step, _crossing, _fly_closed_one, _fly))


def fly_compiled(model, segments, weights, slots, perturbed, steps, sensitivities, *,
                 python: bool = False):
    """:func:`sindyship.shooting.fly_segments` through the compiled loop (its states,
    sensitivities or None, and the step each segment diverged at, -1 where none did), or None
    when the model has no compiled tables (numba missing, or a factor of a number).  With
    ``python`` the same loop runs where numba is missing, as Python (slowly): the zig-zags
    flown closed loop have no other implementation; None there too when a variable or factor
    has no form in the loop (:func:`loop_flies`)."""
    from ._forces_compiled import tables as factor_tables
    from .simulation import servo_of

    if python:
        compiled = factor_tables(model._bases, model._factors, model._slots)
        if compiled is None:
            return None
        names, integer_tables = list(compiled[0]), compiled[1]
    elif not COMPILED or model._compiled is None:
        return None
    else:
        names, integer_tables = model._compiled
    tables = _tables(model, names, integer_tables, list(segments.channels))
    if tables is None:
        return None
    m = segments.n_segments
    extras = np.zeros((max(len(segments.channels), 1), m, segments.rudder.shape[1]))
    for k, name in enumerate(segments.channels):
        extras[k] = segments.channels[name]
    n_out = segments.n_steps // segments.every
    rows, cols = (np.asarray(a, dtype=np.int64) for a in slots)
    states = np.full((m, n_out, 6), np.nan)
    jacobian = np.zeros((m, n_out, 6, len(rows))) if sensitivities else np.zeros((1, 1, 6, 1))
    data = (np.ascontiguousarray(segments.rudder, dtype=float),
            np.ascontiguousarray(segments.rudder_rate, dtype=float), extras)
    physics = (tables, np.ascontiguousarray(weights, dtype=float), model._inertia,
               model.inverse_mass, float(model.ship.U0), float(model.ship.L))
    sensitivity = (np.asarray(perturbed, dtype=np.int64), np.asarray(steps, dtype=float),
                   rows, cols, bool(sensitivities))
    zigzag = segments.zigzag
    closed = (zigzag.sign.astype(np.int64), zigzag.check.astype(float),
              zigzag.psi0.astype(float), np.ascontiguousarray(zigzag.levels, dtype=float),
              zigzag.count.astype(np.int64), zigzag.delta0.astype(float),
              tuple(float(x) for x in servo_of(model.ship)), model.rudder_signal == "commanded")
    stopped = np.full(m, -1, dtype=np.int64)
    _fly_in_threads(m, np.ascontiguousarray(segments.state0, dtype=float), data, physics,
                    sensitivity, closed, float(segments.step), int(segments.n_steps),
                    int(segments.every), states, jacobian, stopped)
    return states, (jacobian if sensitivities else None), stopped


def loop_flies(model) -> bool:
    """Whether the loop, compiled or run as Python, can fly the model: every factor and
    variable of its library has a form in it (a factor of a number has none)."""
    from ._forces_compiled import tables as factor_tables

    compiled = factor_tables(model._bases, model._factors, model._slots)
    return compiled is not None and _tables(model, list(compiled[0]), compiled[1],
                                            list(model.recorded_channels)) is not None


def _tables(model, names, integer_tables, channel_names):
    """How the compiled loop makes each of the model's variables beyond the state's, and the
    model's factor tables (None when a variable has no compiled form)."""
    from .library import SPEED_FLOOR
    from .terms import BANK_NEAREST, describe_variable, parse_shape

    kinds, sources, shapes = [], [], np.zeros((max(len(names) - 5, 1), 4))
    for k, name in enumerate(names[5:]):
        shape = parse_shape(name)
        if name in ("x", "y"):
            kinds.append(POSITION_X if name == "x" else POSITION_Y)
        elif shape is not None:
            kinds.append(SHAPE_EDGE if shape.kind == "edge" else SHAPE_BANK)
            bearing = math.radians(shape.bearing)
            shapes[k] = (math.cos(bearing), math.sin(bearing), shape.distance,
                         shape.width if shape.kind == "edge" else BANK_NEAREST)
        elif name == "delta_rate":
            kinds.append(RUDDER_RATE)
        elif name in ("wind_app_speed", "wind_app_angle"):
            kinds.append(WIND_SPEED if name == "wind_app_speed" else WIND_ANGLE)
        elif name in channel_names:
            rescale = model.library.speed == "instantaneous" and \
                describe_variable(name).scaling in ("speed", "rate")
            kinds.append(CHANNEL_OVER_SPEED if rescale else CHANNEL)
        else:
            return None
        sources.append(channel_names.index(name) if name in channel_names else 0)
    wind_rows = np.array([channel_names.index(n) if n in channel_names else 0
                          for n in ("wind_speed", "wind_dir")], dtype=np.int64)
    return (np.array(kinds, dtype=np.int64), np.array(sources, dtype=np.int64), shapes,
            wind_rows,
            model.library.speed == "instantaneous", float(SPEED_FLOOR), *integer_tables)

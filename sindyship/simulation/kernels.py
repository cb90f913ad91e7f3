"""The numerical kernel of every flight: rudder commands, the servo, classical RK4 with exact
splitting at discontinuities, cubic Hermite outputs and the divergence test (paper eq. 12-14).

It imports only numpy and the standard library and knows nothing of sindyship: the library's
integrator (:func:`sindyship.simulation.simulate_batch`) runs it (or its compiled copy,
:mod:`sindyship._flights_compiled`), and the simulator :func:`sindyship.export.generate_python`
writes carries its source (all below the kernel's start mark): all fly a model alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

# ----------------------------------------------------------------------------- kernel begins
#: The line above, where the source the generated simulators carry begins.
KERNEL_MARK = "# " + "-" * 77 + " kernel begins"
N_STATE = 7


# -------------------- Rudder commands --------------------------------------------------------
class RudderCommand:
    """A piecewise-constant commanded rudder angle, possibly closed loop.

    Subclasses implement :meth:`value`; scheduled changes are announced by
    :meth:`next_change`, heading events by :meth:`event` and :meth:`on_event`.  A command is
    reset at the start of every simulation, so one object can fly several times.
    """

    #: If True the rudder angle itself is prescribed (no servo): see :class:`PrescribedRudder`.
    prescribed = False

    def reset(self, state0: np.ndarray) -> None:
        """Prepare for a new simulation starting from ``state0``."""

    def value(self, t: float, state: np.ndarray) -> float:
        """Commanded angle [rad] held from time ``t`` on."""
        raise NotImplementedError

    def next_change(self, t: float) -> float:
        """The next scheduled time > t at which the command changes (inf if none)."""
        return math.inf

    def event(self, state: np.ndarray) -> float | None:
        """A state function whose crossing of zero from below switches the command."""
        return None

    def on_event(self) -> None:
        """Switch after an event."""


class ConstantCommand(RudderCommand):
    """A constant commanded angle [rad] from t = 0 (a turning circle or a straight run)."""

    def __init__(self, angle: float):
        self.angle = angle

    def value(self, t, state):
        return self.angle


class StepCommand(RudderCommand):
    """Commanded angles ``angles[k]`` [rad] held from ``times[k]`` [s] (times[0] is the start)."""

    def __init__(self, times: Sequence[float], angles: Sequence[float]):
        times = np.asarray(times, dtype=float)
        angles = np.asarray(angles, dtype=float)
        # only the samples where the command changes: they are the steps' breakpoints
        keep = np.concatenate([np.ones(min(len(angles), 1), dtype=bool), angles[1:] != angles[:-1]])
        self.times = times[keep]
        self.angles = angles[keep]

    def value(self, t, state):  # the method, not np.searchsorted: called per member and step
        k = int(self.times.searchsorted(t + 1e-9, side="right")) - 1
        return float(self.angles[max(k, 0)])

    def next_change(self, t):
        k = int(self.times.searchsorted(t + 1e-9, side="right"))
        return float(self.times[k]) if k < len(self.times) else math.inf


class ZigZagCommand(RudderCommand):
    """Closed-loop zig-zag: rudder +-A, reversed when the heading change reaches +-C.

    Parameters
    ----------
    rudder : float
        Rudder amplitude A [rad].
    check : float
        Heading check angle C [rad].
    first_sign : int
        +1: first rudder to starboard (the heading then grows to +C); -1: to port.
    """

    def __init__(self, rudder: float, check: float, first_sign: int = 1):
        self.rudder = rudder
        self.check = check
        self.first_sign = first_sign
        self.sign = 1  # the leg flown: +1 while the rudder is to starboard, -1 to port
        self._psi0 = 0.0

    def reset(self, state0):
        self.sign = 1 if self.first_sign >= 0 else -1
        self._psi0 = float(state0[5])

    def value(self, t, state):
        return self.sign * self.rudder

    def event(self, state):
        return self.sign * (state[5] - self._psi0) - self.check

    def on_event(self):
        self.sign = -self.sign


class FeedbackCommand(RudderCommand):
    """A command from a function ``f(t, state) -> angle [rad]``, held over each integration step."""

    def __init__(self, function: Callable[[float, np.ndarray], float]):
        self.function = function

    def value(self, t, state):
        return float(self.function(t, state))


class PrescribedRudder(RudderCommand):
    """The rudder angle itself follows a record (linear interpolation), bypassing the servo."""

    prescribed = True

    def __init__(self, times: np.ndarray, angles: np.ndarray):
        self.times = np.asarray(times, dtype=float)
        self.angles = np.asarray(angles, dtype=float)
        self._rate = np.diff(self.angles) / np.diff(self.times)

    def value(self, t, state):  # np.interp's arithmetic, each interval's slope computed once
        k = int(self.times.searchsorted(t, side="right")) - 1
        if t != t or k < 0 or k >= len(self._rate) or self.times[k] == t:  # NaN, ends, samples
            return math.nan if t != t else float(self.angles[min(max(k, 0), len(self.angles) - 1)])
        return float(self._rate[k] * (t - self.times[k]) + self.angles[k])

    def rate(self, t: float) -> float:
        k = int(self.times.searchsorted(t + 1e-9, side="right")) - 1
        return float(self._rate[min(max(k, 0), len(self._rate) - 1)])  # ints: no np.clip

    def next_change(self, t):
        k = int(self.times.searchsorted(t + 1e-9, side="right"))
        return float(self.times[k]) if k < len(self.times) else math.inf


# -------------------- Results ----------------------------------------------------------------
class ChannelSeries:
    """Recorded channels as time series for a batch of flights (one row per member).

    Values are in the library's scaling (:func:`sindyship.library.nondimensional_variables`)
    and are interpolated linearly at the integrator's stage times, held at the end values
    outside the record.

    Examples
    --------
    >>> import numpy as np
    >>> series = ChannelSeries(np.array([0.0, 10.0]), {"n": np.array([[1.0, 3.0]])})
    >>> float(series.at(2.5, np.array([0]))["n"][0])
    1.5
    """

    def __init__(self, times: np.ndarray, values: Mapping[str, np.ndarray]):
        self.times = np.asarray(times, dtype=float)
        self.values = {name: np.atleast_2d(np.asarray(v, dtype=float))
                       for name, v in values.items()}

    def at(self, t: float, members: np.ndarray) -> dict[str, np.ndarray]:
        """The channels of ``members`` at time ``t``."""
        times = self.times
        if len(times) < 2:
            return {name: v[members, 0] for name, v in self.values.items()}
        k = min(max(int(times.searchsorted(t, side="right")) - 1, 0), len(times) - 2)
        w = min(max((t - times[k]) / (times[k + 1] - times[k]), 0.0), 1.0)
        return {name: (1.0 - w) * v[members, k] + w * v[members, k + 1]
                for name, v in self.values.items()}


class SimulationResult:
    """States at the output times of one simulated manoeuvre.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Output times [s] (all requested times, also after a divergence).
    states : ndarray, shape (7, N)
        ``[u, v, r, x, y, psi, delta]``; NaN after a divergence.
    delta_c : ndarray, shape (N,)
        Commanded rudder angle held at each output time [rad].
    diverged_at : float or None
        Time of the first output sample where the state left the plausible range.
    """

    def __init__(self, t: np.ndarray, states: np.ndarray, delta_c: np.ndarray,
                 diverged_at: float | None = None):
        self.t = t
        self.states = states
        self.delta_c = delta_c
        self.diverged_at = diverged_at

    @property
    def valid(self) -> np.ndarray:
        """Mask of the samples before any divergence."""
        return np.ones(self.t.shape, dtype=bool) if self.diverged_at is None \
            else self.t < self.diverged_at


def diverged(state: np.ndarray, L: float, U0: float) -> np.ndarray:
    """Whether each member's state is implausible (protocol's divergence rule).

    A state has diverged when it is not finite, u' = u / U0 leaves (0, 2), |v'| > 1 or
    |r'| = |r| L / U0 > 2.
    """
    u = state[0] / U0
    v = state[1] / U0
    r = state[2] * L / U0
    finite = np.all(np.isfinite(state), axis=0)
    with np.errstate(invalid="ignore"):
        bad = (u <= 0.0) | (u >= 2.0) | (np.abs(v) > 1.0) | (np.abs(r) > 2.0)
    return ~finite | bad


# -------------------- Integration ------------------------------------------------------------
def _hermite(y0, f0, y1, f1, h, theta):
    """Cubic Hermite interpolation on a step of length h at fraction theta."""
    t2 = theta * theta
    t3 = t2 * theta
    return ((2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + theta) * h * f0
            + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * h * f1)


class _Integrator:
    """Classical RK4 for one dynamics object and a batch of rudder commands.

    Discontinuities are never stepped over: a step is split at scheduled command changes, at
    command events (zig-zag check angles) and where the dynamics change branch (the MMG rudder's
    port/starboard flow straightening factor, switching with the sign of beta_R).  Inside a
    (sub)step the command and the branch are frozen, so every piece is smooth and the scheme
    keeps its fourth order.
    """

    def __init__(self, dynamics, commands: Sequence[RudderCommand], servo: tuple):
        self.dynamics = dynamics
        time_constant, rate_max, delta_max = servo  # [s], [rad/s], [rad]
        self.T = max(float(time_constant), 1e-9)
        self.rate_max = float(rate_max)
        self.delta_max = float(delta_max)
        self.current = tuple(float(c) for c in getattr(dynamics, "current", (0.0, 0.0)))
        self.switching = getattr(dynamics, "switching", None)
        # what the dynamics take: the time and members (recorded channels), the position,
        # the rate the servo moves at
        self.time_varying = bool(getattr(dynamics, "time_varying", False))
        self.uses_position = bool(getattr(dynamics, "uses_position", False))
        self.uses_rudder_rate = bool(getattr(dynamics, "uses_rudder_rate", False))
        # a model identified on the commanded angle takes the command as its rudder input
        self.rudder_input = getattr(dynamics, "rudder_input", "actual")
        self.commands = list(commands)
        self.prescribed = np.array([c.prescribed for c in self.commands])
        self.any_prescribed = bool(self.prescribed.any())

    def branch(self, y):
        """Sign branch of the dynamics' switching function (None if it has none)."""
        if self.switching is None:
            return None
        return self.switching(y) > 0.0

    def rhs(self, t, y, delta_c, members, branch, rate_time=None):
        """Time derivative of the state columns ``y`` (7, k); a prescribed rudder moves at its
        rate at ``rate_time`` (default ``t``), a time inside the step, not at its end sample."""
        u, v, r, x, y_east, psi, delta = y
        rudder = delta_c if self.rudder_input == "commanded" else delta
        target = np.minimum(np.maximum(delta_c, -self.delta_max), self.delta_max)
        ddelta = np.minimum(np.maximum((target - delta) / self.T, -self.rate_max), self.rate_max)
        if self.any_prescribed and self.prescribed[members].any():
            for j, m in enumerate(members):
                if self.prescribed[m]:
                    ddelta[j] = self.commands[m].rate(t if rate_time is None else rate_time)
        extra = {"position": (x, y_east)} if self.uses_position else {}
        if self.uses_rudder_rate:
            extra["rudder_rate"] = ddelta
        if self.time_varying:
            a_u, a_v, a_r = self.dynamics.accelerations(u, v, r, rudder, psi, branch=branch, t=t,
                                                        members=members, **extra)
        else:
            a_u, a_v, a_r = self.dynamics.accelerations(u, v, r, rudder, psi, branch=branch,
                                                        **extra)
        c, s = np.cos(psi), np.sin(psi)
        out = np.empty_like(y)
        out[0], out[1], out[2] = a_u, a_v, a_r
        out[3] = u * c - v * s + self.current[0]
        out[4] = u * s + v * c + self.current[1]
        out[5] = r
        out[6] = ddelta
        return out

    def step(self, t, y, h, delta_c, members, branch, f0=None):
        mid = t + 0.5 * h
        k1 = self.rhs(t, y, delta_c, members, branch, mid) if f0 is None else f0
        k2 = self.rhs(mid, y + 0.5 * h * k1, delta_c, members, branch)
        k3 = self.rhs(mid, y + 0.5 * h * k2, delta_c, members, branch)
        k4 = self.rhs(t + h, y + h * k3, delta_c, members, branch, mid)
        return y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4), k1


class _FirstSameAsLast:
    """Right-hand sides at a step's end, reused at the next start (not a prescribed rudder's)."""

    def __init__(self, n_members: int, prescribed: np.ndarray):
        self.prescribed = prescribed
        self.f = np.zeros((N_STATE, n_members))
        self.delta_c = np.full(n_members, np.nan)
        self.branch = np.zeros(n_members, dtype=bool)
        self.valid = np.zeros(n_members, dtype=bool)

    def start(self, integ, time, y_start, delta_c, members, branch):
        """Derivatives at the step start, computing only those not cached."""
        ok = self.valid[members] & (self.delta_c[members] == delta_c)
        if branch is not None:
            ok &= self.branch[members] == branch
        f0 = self.f[:, members]
        if not ok.all():
            need = ~ok
            f0[:, need] = integ.rhs(time, y_start[:, need], delta_c[need], members[need],
                                    None if branch is None else branch[need])
        return f0

    def store(self, members, f_end, delta_c, branch):
        self.f[:, members] = f_end
        self.delta_c[members] = delta_c
        if branch is not None:
            self.branch[members] = branch
        self.valid[members] = ~self.prescribed[members]


def _advance(integ: _Integrator, commands, time, y, h, members, t_out, samples, out, out_cmd,
             fsal):
    """One RK4 step of length h for the active members, splitting at discontinuities.

    Writes the states at the output times ``t_out[samples]`` (inside the step) into ``out``.
    """
    y_start = y[:, members]
    delta_c = np.array([commands[j].value(time, y[:, j]) for j in members])
    branch = integ.branch(y_start)
    f_start = fsal.start(integ, time, y_start, delta_c, members, branch)
    y_end, _ = integ.step(time, y_start, h, delta_c, members, branch, f0=f_start)
    y = y.copy()
    y[:, members] = y_end
    tol = 1e-9 * max(1.0, h)
    flipped = None if branch is None else integ.branch(y_end) != branch
    is_split = np.zeros(len(members), dtype=bool) if flipped is None else flipped.copy()
    for idx, j in enumerate(members):
        if is_split[idx]:
            continue
        cmd = commands[j]
        g_end = cmd.event(y_end[:, idx])
        is_split[idx] = (cmd.next_change(time) < time + h - tol
                         or (g_end is not None and g_end >= 0.0))
    split = np.flatnonzero(is_split)
    smooth = np.flatnonzero(~is_split)
    if smooth.size:
        sub_branch = None if branch is None else branch[smooth]
        f_end = integ.rhs(time + h, y_end[:, smooth], delta_c[smooth], members[smooth],
                          sub_branch, time + 0.5 * h)
        fsal.store(members[smooth], f_end, delta_c[smooth], sub_branch)
        for k in samples:
            theta = (t_out[k] - time) / h
            out[:, k, members[smooth]] = _hermite(y_start[:, smooth], f_start[:, smooth],
                                                  y_end[:, smooth], f_end, h, theta)
            out_cmd[k, members[smooth]] = delta_c[smooth]
    for idx in split:
        j = members[idx]
        first = (y_end[:, idx : idx + 1], f_start[:, idx : idx + 1])
        y[:, j], f_end_j, delta_c_j, branch_j = _advance_one(
            integ, commands[j], j, time, h, y_start[:, idx], t_out, samples, out, out_cmd,
            first=first)
        if f_end_j is None:
            fsal.valid[j] = False
        else:
            fsal.store(np.array([j]), f_end_j, delta_c_j, branch_j)
    return y


def _advance_one(integ, cmd, j, time, h, y0, t_out, samples, out, out_cmd, first=None):
    """Advance one member over [time, time + h], stopping at every discontinuity.

    ``first`` holds the batch's full step from the same start (end state and start
    derivative), reused for the first piece.  Returns the final state, its derivative, and the
    command and branch that derivative belongs to (for the next step's first stage).
    """
    col = np.array([j])
    t_end = time + h
    tol = 1e-9 * max(1.0, h)
    y = y0.reshape(N_STATE, 1)
    forced_branch = None
    f1 = delta_c = branch = None
    for _ in range(64):  # a bounded number of switches per step
        remaining = t_end - time
        if remaining <= tol:
            break
        delta_c = np.array([cmd.value(time, y[:, 0])])
        branch = integ.branch(y) if forced_branch is None else forced_branch
        forced_branch = None
        t_change = cmd.next_change(time)
        h_try = min(remaining, t_change - time) if t_change < t_end - tol else remaining
        if first is not None and h_try == remaining:
            y_try, f0 = first
        else:
            y_try, f0 = integ.step(time, y, h_try, delta_c, col, branch,
                                   f0=None if first is None else first[1])
        first = None
        f1 = integ.rhs(time + h_try, y_try, delta_c, col, branch, time + 0.5 * h_try)
        theta, kind = _piece_end(integ, cmd, y, f0, y_try, f1, h_try, branch,
                                 "change" if h_try < remaining else None)
        h_taken = theta * h_try
        if theta < 1.0:
            y_new, _ = integ.step(time, y, h_taken, delta_c, col, branch, f0=f0)
            f1 = integ.rhs(time + h_taken, y_new, delta_c, col, branch, time + 0.5 * h_taken)
        else:
            y_new = y_try
        _write_samples(out, out_cmd, j, t_out, samples, time, h_taken, tol, y, f0, y_new, f1,
                       delta_c)
        time += h_taken
        y = y_new
        if kind == "event":
            cmd.on_event()
            f1 = None  # the command changed: the derivative at the end is stale
        elif kind == "branch":
            forced_branch = ~branch  # the state sits on the switching surface
            f1 = None
        elif kind == "change":
            f1 = None
        if kind is None:
            break
    return y[:, 0], f1, delta_c, branch


def _piece_end(integ, cmd, y, f0, y_try, f1, h_try, branch, kind):
    """Where a piece of step ends: ``(theta, kind)`` with theta the fraction of ``h_try`` and
    kind ``"event"`` (the command's heading event), ``"branch"`` (the dynamics' switching
    function changes sign), ``"change"`` (a scheduled change) or None (the step's end)."""
    theta = 1.0
    g_end = cmd.event(y_try[:, 0])
    if g_end is not None and g_end >= 0.0:
        theta = _crossing(cmd.event, y, f0, y_try, f1, h_try)
        kind = "event"
    if branch is not None and bool(integ.branch(y_try)[0]) != bool(branch[0]):
        sign = -1.0 if branch[0] else 1.0  # g < 0 on the present branch

        def g_branch(state):
            return sign * float(integ.switching(state.reshape(N_STATE, 1))[0])

        theta_b = _crossing(g_branch, y, f0, y_try, f1, h_try)
        if theta_b < theta:
            theta, kind = theta_b, "branch"
    return theta, kind


def _write_samples(out, out_cmd, j, t_out, samples, time, h_taken, tol, y, f0, y_new, f1,
                   delta_c) -> None:
    """The member's states at the output times inside a piece, from its Hermite interpolant."""
    if h_taken <= 0:
        return
    for k in samples:
        if time - tol <= t_out[k] <= time + h_taken + tol:
            s = (t_out[k] - time) / h_taken
            out[:, k, j] = _hermite(y[:, 0], f0[:, 0], y_new[:, 0], f1[:, 0], h_taken, s)
            out_cmd[k, j] = delta_c[0]


def _crossing(g, y0, f0, y1, f1, h) -> float:
    """Fraction of a step where ``g`` (negative at its start) reaches zero.

    The state inside the step is the cubic Hermite interpolant of the step's end points and
    derivatives (fourth-order accurate, like the step); the root is bracketed and found by the
    Illinois variant of regula falsi, to 1e-12 of the step.
    """
    a, b = 0.0, 1.0
    ga = g(y0[:, 0])
    if ga >= 0.0:
        return 0.0
    gb = g(y1[:, 0])
    side = 0
    for _ in range(100):
        c = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
        if not a < c < b:
            c = 0.5 * (a + b)
        gc = g(_hermite(y0[:, 0], f0[:, 0], y1[:, 0], f1[:, 0], h, c))
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


def _common_change(commands, members, time: float, h: float) -> float:
    """The step, cut where every member's replayed rudder changes if all change at one time
    inside it (they step there together, not one by one; no flight depends on others)."""
    if not all(commands[j].prescribed for j in members):
        return h
    tol, changes = 1e-9 * max(1.0, h), [commands[j].next_change(time) for j in members]
    first, last = min(changes), max(changes)
    return first - time if time + tol < first < time + h - tol and last - first <= tol else h


def integrate(integ: _Integrator, commands: Sequence[RudderCommand], t: np.ndarray,
              state0: np.ndarray, h_max: float, check_divergence: bool, L: float, U0: float,
              on_step: Callable[[float], None] | None = None) -> list[SimulationResult]:
    """Fly the commands' manoeuvres together with one integrator (see the module docstring).

    Parameters
    ----------
    integ : _Integrator
        The dynamics, the servo and the commands.
    commands : sequence of RudderCommand
        One per manoeuvre (the integrator's).
    t : ndarray
        Increasing output times [s]; the first is the initial time.
    state0 : ndarray, shape (7,) or (7, B)
        Initial state(s), SI.
    h_max : float
        Runge-Kutta step [s].
    check_divergence : bool
        Stop a member whose state leaves the plausible range (:func:`diverged`).
    L, U0 : float
        Ship length [m] and design speed [m/s] of the divergence test.
    on_step : callable, optional
        Called with the length [s] of every step taken (progress).

    Returns
    -------
    list of SimulationResult
    """
    t = np.asarray(t, dtype=float)
    n_out = len(t)
    n_members = len(commands)
    y = np.array(state0, dtype=float).reshape(N_STATE, -1)
    if y.shape[1] == 1 and n_members > 1:
        y = np.repeat(y, n_members, axis=1)
    if y.shape[1] != n_members:
        raise ValueError("state0 must have one column per command")
    if n_out > 1 and np.any(np.diff(t) <= 0):
        raise ValueError("output times must increase")
    for j, cmd in enumerate(commands):
        cmd.reset(y[:, j])
        if cmd.prescribed:
            y[6, j] = cmd.value(t[0], y[:, j])
    out = np.full((N_STATE, n_out, n_members), np.nan)
    out_cmd = np.full((n_out, n_members), np.nan)
    diverged_at: list[float | None] = [None] * n_members
    active = np.ones(n_members, dtype=bool)
    out[:, 0, :] = y
    out_cmd[0] = [c.value(t[0], y[:, j]) for j, c in enumerate(commands)]
    if check_divergence:
        for j in np.flatnonzero(diverged(y, L, U0)):
            diverged_at[j] = float(t[0])
            active[j] = False
    time = float(t[0])
    t_end = float(t[-1])
    k_next = 1
    fsal = _FirstSameAsLast(n_members, integ.prescribed)
    with np.errstate(all="ignore"):
        while k_next < n_out and active.any():
            h = min(h_max, t_end - time)
            members = np.flatnonzero(active)
            h = _common_change(commands, members, time, h)
            t_new = time + h
            k_stop = int(np.searchsorted(t, t_new + 1e-9 * max(1.0, h), side="right"))
            samples = range(k_next, k_stop)
            y = _advance(integ, commands, time, y, h, members, t, samples, out, out_cmd, fsal)
            time = t_new
            k_next = k_stop
            if on_step is not None:
                on_step(h)
            if check_divergence and len(samples):
                block = out[:, samples.start:samples.stop][:, :, members]
                bad = diverged(block.reshape(N_STATE, -1), L, U0).reshape(
                    len(samples), len(members))
                for idx in np.flatnonzero(bad.any(axis=0)):
                    j = members[idx]
                    k_bad = samples.start + int(np.argmax(bad[:, idx]))
                    diverged_at[j] = float(t[k_bad])
                    out[:, k_bad:, j] = np.nan
                    out_cmd[k_bad:, j] = np.nan
                    active[j] = False
    return [SimulationResult(t=t.copy(), states=out[:, :, j], delta_c=out_cmd[:, j],
                             diverged_at=diverged_at[j]) for j in range(n_members)]

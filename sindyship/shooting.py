"""Multiple shooting: a fitted model flown over short segments of records, each from its
measured state, with the sensitivities of the flights to the coefficients.

A flight of a whole record integrates every small force error; a model whose training flight
diverges after a few minutes says little about how to improve it (every sample after the
divergence costs the same).  Multiple shooting (Bock & Plitt 1984; for flight vehicles
Jategaonkar 2015, ch. 4 and 9) cuts every record from its flight start
(:func:`sindyship.trials.flight_start`: a zig-zag or turn from its rudder execute, never a
manual approach) into segments of ``segment_s`` seconds, flies each from the state measured at
its start with the recorded rudder angle and channels (no zig-zag logic: a segment is shorter
than a reversal takes to go wrong), and compares u, v, r, x, y and psi at every step.  A
diverging model still gives a useful gradient on every segment.

The sensitivities of the flights to the coefficients come from the variational equations
integrated beside the state with the same Runge-Kutta steps: with f the right-hand side of
eq. 14 and the kinematics, dS/dt = (df/dz) S + df/dtheta.  Since the forces of eq. 15 are
linear in the coefficients, df/dtheta is the inverse mass matrix times the term columns; df/dz
comes from forward differences of the accelerations in the state (three to six extra force
evaluations per stage, whatever the number of coefficients).  One integration of the segments
gives the flights and their exact Jacobian, to the accuracy of the integrator.

Everything is vectorised over the segments (one batch per step and sample grid); the force of
every segment is summed term by term in a fixed order, so a segment's flight does not depend
on the other segments of its batch (the refinement splits them across processes and gets the
same numbers).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .errors import SindyshipInputError
from .library import SPEED_FACTOR
from .simulation import default_step, servo_of
from .targets import DOFS, coriolis_factors
from .trajectory import STATE_COLUMNS, Trajectory
from .trials import flight_start

__all__ = ["CHANNEL_SCALES", "Segments", "make_segments", "fly_segments", "servo_rudder"]

#: The states a segment flies, in the loop's order (the record's columns without delta).
SHOOTING_STATES = STATE_COLUMNS[:6]
#: The compared channels u, v, r, x, y, psi, and how each is made non-dimensional (1/U0,
#: 1/U0, L/U0, 1/L, 1/L, 1 rad): (power of L, power of U0).
CHANNEL_SCALES = ((0, -1), (0, -1), (1, -1), (-1, 0), (-1, 0), (0, 0))
#: Relative step of the forward differences of the accelerations in the state.
STATE_STEP = 1e-6


@dataclass(frozen=True)
class ClosedLoop:
    """The zig-zags among a batch of segments, flown closed loop (one entry per segment; a
    ``sign`` of 0 replays the segment's rudder).

    Attributes
    ----------
    sign : ndarray of int
        The first rudder's side (+1 starboard, -1 port), 0 for a replayed segment.
    check, psi0 : ndarray
        The check angle [rad] and the heading at the execute the heading change is measured
        from [rad].
    levels : ndarray, shape (M, K)
        The rudder angles [rad] of the legs (the last held after them), ``count`` of them.
    count : ndarray of int
    delta0 : ndarray
        The actual rudder angle at the start [rad] (the servo's state).
    """

    sign: np.ndarray
    check: np.ndarray
    psi0: np.ndarray
    levels: np.ndarray
    count: np.ndarray
    delta0: np.ndarray

    @classmethod
    def none(cls, m: int) -> ClosedLoop:
        """``m`` segments that all replay their rudder."""
        return cls(np.zeros(m, dtype=int), np.zeros(m), np.zeros(m), np.zeros((m, 1)),
                   np.ones(m, dtype=int), np.zeros(m))

    def take(self, members: np.ndarray) -> ClosedLoop:
        return ClosedLoop(self.sign[members], self.check[members], self.psi0[members],
                          self.levels[members], self.count[members], self.delta0[members])


@dataclass(frozen=True)
class Segments:
    """Pieces of records to fly from their measured first state, on one grid of steps.

    Attributes
    ----------
    step : float
        Runge-Kutta step [s].
    n_steps : int
        Steps per segment; the states compared are those at the end of every ``every``-th
        step.
    every : int
        Steps per compared sample.
    state0 : ndarray, shape (M, 6)
        u, v, r, x, y, psi (SI) at each segment's start.
    rudder : ndarray, shape (M, 2 n_steps + 1)
        The model's rudder input [rad] at the half steps (the recorded actual angle, the
        servo's response to the recorded command, or the command itself).
    rudder_rate : ndarray, shape (M, 2 n_steps + 1)
        The rate of the actual rudder angle [rad/s] at the half steps.
    channels : dict of str to ndarray, shape (M, 2 n_steps + 1)
        The recorded channels the library uses (library scaling, over U0) at the half steps.
    measured : ndarray, shape (M, n_out, 6)
        u, v, r, x, y, psi recorded at the compared samples.
    valid : ndarray of bool, shape (M, n_out)
        Whether a compared sample lies inside its record.
    record : ndarray of int, shape (M,)
        The record each segment comes from.
    start : ndarray, shape (M,)
        Each segment's first time [s].
    zigzag : ClosedLoop
        The segments flown as zig-zags, closed loop (whole flights only).
    """

    step: float
    n_steps: int
    every: int
    state0: np.ndarray
    rudder: np.ndarray
    rudder_rate: np.ndarray
    channels: dict = field(repr=False)
    measured: np.ndarray = field(repr=False)
    valid: np.ndarray = field(repr=False)
    record: np.ndarray = field(repr=False)
    start: np.ndarray = field(repr=False)
    zigzag: ClosedLoop | None = field(default=None, repr=False)

    def __post_init__(self):
        if self.zigzag is None:
            object.__setattr__(self, "zigzag", ClosedLoop.none(self.state0.shape[0]))

    @property
    def n_segments(self) -> int:
        return self.state0.shape[0]

    def take(self, members: np.ndarray) -> Segments:
        """The segments ``members`` only (for splitting a batch across workers)."""
        return Segments(self.step, self.n_steps, self.every, self.state0[members],
                        self.rudder[members], self.rudder_rate[members],
                        {k: v[members] for k, v in self.channels.items()},
                        self.measured[members], self.valid[members], self.record[members],
                        self.start[members], self.zigzag.take(members))


def servo_rudder(record: Trajectory, ship) -> tuple[np.ndarray, np.ndarray]:
    """The actual rudder angle [rad] and its rate [rad/s] at the record's samples that the
    ship's servo (paper eq. 12-13) makes of the recorded command ``delta_c``, from the first
    sample's rudder angle (actual if recorded) as a flight starts; the servo does not depend
    on the ship's motion.  RK4 on the command held from sample to sample, in steps of at
    most a quarter of the servo's time constant, as the flights' servo
    (:func:`sindyship._shooting_compiled.servo_angles`)."""
    from ._shooting_compiled import servo_angles

    time_constant, rate_max, delta_max = servo_of(ship)
    t = np.array(record.t, dtype=float)  # a writable copy: the loop's one compiled form
    command = np.ascontiguousarray(np.clip(record["delta_c"], -delta_max, delta_max),
                                   dtype=float)
    angle, rate = np.empty(len(t)), np.empty(len(t))
    # the flights' first state: the actual angle if recorded
    servo_angles(t, command, float(record.rudder[0]), time_constant, rate_max, angle, rate)
    return angle, rate


def _grid(record: Trajectory, ship) -> tuple[float, int, int]:
    """``(step, samples per compared sample, steps per compared sample)`` of a record: steps
    of the whole number of samples nearest the default step
    (:func:`sindyship.simulation.default_step`, 0.1 L/U0), or a sample split into equal
    steps when it is longer."""
    dt, target = record.dt, default_step(ship)
    if dt <= target:
        samples = max(1, int(round(target / dt)))
        return samples * dt, samples, 1
    steps = math.ceil(dt / target)
    return dt / steps, 1, steps


def _inputs(model, record: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """The model's rudder input and the actual rudder's rate at the record's samples."""
    if record.has("delta"):
        actual = record["delta"]
        rate = np.gradient(actual, record.t) if record.n_samples > 1 else 0.0 * actual
    else:
        actual, rate = servo_rudder(record, model.ship)
    if model.rudder_signal == "commanded":
        return record["delta_c"], rate
    return actual, rate


def make_segments(model, records: Sequence[Trajectory], segment_s: float | None,
                  zigzag_s: float | None = None) -> list[Segments]:
    """The records cut into segments of about ``segment_s`` seconds from their flight start,
    one :class:`Segments` batch per grid of steps.

    Parameters
    ----------
    model : AbkowitzModel
        The model to fly (its library's delays, channels and rudder signal, its ship).
    records : sequence of Trajectory
        The records (each uniformly sampled).
    segment_s : float or None
        Length of a segment [s] (a record's last segment may be shorter); None flies every
        record whole from its flight start, as :func:`sindyship.evaluation.evaluate` flies
        it: a zig-zag closed loop (:class:`ClosedLoop`), any other record replaying its
        commanded rudder through the servo (else its actual rudder).
    zigzag_s : float, optional
        The longest segment of a zig-zag [s]: a segment replays the recorded rudder, and a
        zig-zag replayed open loop for long drifts off without bound (its heading errors
        grow), which weighs that drift over the dynamics.
    """
    if segment_s is not None and not (math.isfinite(segment_s) and segment_s > 0):
        raise SindyshipInputError(f"segment_s must be a positive number of seconds, not "
                                  f"{segment_s!r}.")
    batches: dict[tuple, list] = {}
    for index, whole in enumerate(records):
        record = model.library.aligned(_from_start(whole))
        if record.n_samples < 2:
            continue
        step, samples, steps = _grid(record, model.ship)
        if segment_s is None:  # the whole record from its flight start
            n_out = max(1, (record.n_samples - 1) // samples)
        else:
            length = segment_s
            if zigzag_s is not None and flight_start(whole).kind == "zigzag":
                length = min(segment_s, zigzag_s)
            n_out = max(1, int(round(length / (samples * record.dt))))
        key = (round(step, 12), samples, steps, n_out, segment_s is None)
        batches.setdefault(key, []).append((index, record))
    return [_batch(model, key, members) for key, members in batches.items()]


def _from_start(record: Trajectory) -> Trajectory:
    from .trials import trim

    start = flight_start(record)
    if start.time <= record.t[0] + 1e-9:
        return record
    return trim(record, (start.time, float(record.t[-1])))


def _batch(model, key, members) -> Segments:
    """The segments of records that share a grid (whole flights: one per record)."""
    step, samples, steps, n_out, whole = key
    n_steps = n_out * steps
    half = np.arange(2 * n_steps + 1) * 0.5 * step
    names = model.recorded_channels
    rows = {"state0": [], "rudder": [], "rate": [], "measured": [], "valid": [], "record": [],
            "start": [], "loop": [], **{f"c:{n}": [] for n in names}}
    for index, record in members:
        t = record.t
        rudder, rate = _whole_inputs(model, record) if whole else _inputs(model, record)
        loop = _closed_loop(record) if whole else None
        channels = _channel_values(model, record, names)
        states = np.column_stack([record[c] for c in SHOOTING_STATES])
        firsts = [0] if whole else range(0, record.n_samples - 1, samples * n_out)
        for first in firsts:
            times = t[first] + half
            rows["state0"].append(states[first])
            rows["rudder"].append(_interp(times, t, rudder, model.rudder_signal == "commanded"))
            rows["rate"].append(np.interp(times, t, rate))
            for name in names:
                rows[f"c:{name}"].append(np.interp(times, t, channels[name]))
            out = first + samples * np.arange(1, n_out + 1)
            inside = out < record.n_samples
            rows["measured"].append(states[np.minimum(out, record.n_samples - 1)])
            rows["valid"].append(inside)
            rows["record"].append(index)
            rows["start"].append(t[first])
            rows["loop"].append(loop)
    return Segments(step, n_steps, steps, np.array(rows["state0"]), np.array(rows["rudder"]),
                    np.array(rows["rate"]), {n: np.array(rows[f"c:{n}"]) for n in names},
                    np.array(rows["measured"]), np.array(rows["valid"]),
                    np.array(rows["record"]), np.array(rows["start"]),
                    _closed_loops(rows["loop"]))


def _whole_inputs(model, record: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """A whole flight's rudder as :func:`sindyship.flights.command_for` replays it: the
    commanded angle through the servo where recorded (the model's input is then the servo's
    angle, or the command itself for a model of the command), else the actual angle."""
    if not record.has("delta_c"):
        return _inputs(model, record)
    actual, rate = servo_rudder(record, model.ship)
    if model.rudder_signal == "commanded":
        return record["delta_c"], rate
    return actual, rate


def _closed_loop(record: Trajectory):
    """``(sign, check, psi0, levels, delta0)`` of a zig-zag flown closed loop from the
    record's first row (its execute), or None for a record replayed."""
    from .flights import command_for
    from .simulation import RecordedZigZag, ZigZagCommand

    command = command_for(record)
    if not isinstance(command, ZigZagCommand):
        return None
    levels = command.levels if isinstance(command, RecordedZigZag) and command.levels \
        else (command.rudder,)
    sign = 1 if command.first_sign >= 0 else -1
    return sign, command.check, float(record["psi"][0]), tuple(levels), float(record.rudder[0])


def _closed_loops(loops) -> ClosedLoop:
    width = max([len(loop[3]) for loop in loops if loop is not None], default=1)
    m = len(loops)
    out = ClosedLoop.none(m)
    levels = np.zeros((m, width))
    for k, loop in enumerate(loops):
        if loop is None:
            continue
        out.sign[k], out.check[k], out.psi0[k] = loop[0], loop[1], loop[2]
        levels[k, : len(loop[3])] = loop[3]
        out.count[k], out.delta0[k] = len(loop[3]), loop[4]
    return ClosedLoop(out.sign, out.check, out.psi0, levels, out.count, out.delta0)


def _interp(times, t, values, held: bool) -> np.ndarray:
    """Values at ``times``: linear between samples, or held from the last sample (a command)."""
    if not held:
        return np.interp(times, t, values)
    k = np.clip(np.searchsorted(t, times + 1e-9, side="right") - 1, 0, len(t) - 1)
    return values[k]


def _channel_values(model, record: Trajectory, names) -> dict:
    from .library import nondimensional_variables

    if not names:
        return {}
    return nondimensional_variables(record, model.ship.L, model.ship.U0, needed=names)


# --------------------------------------------------------------------------------- flights
class _RightHandSide:
    """The right-hand side of eq. 14 and the kinematics for a batch of segments, and its
    derivatives in the state and the coefficients."""

    def __init__(self, model, segments: Segments, weights: np.ndarray, slots):
        self.model = model
        self.segments = segments
        self.weights = weights  # (3, n_terms) of the model's active terms
        self.slots = slots  # per coefficient: (row, column) in weights
        ship = model.ship
        self.L, self.U0 = ship.L, ship.U0
        self.scale = np.array([self.U0**2 / self.L, self.U0**2 / self.L,
                               self.U0**2 / self.L**2])
        self.minv = model.inverse_mass
        self.inertia = np.array(coriolis_factors(ship))
        variables = model.library.variables
        self.perturbed = [0, 1, 2]  # u, v, r always; psi and the position when used
        if "psi" in variables or {"wind_app_speed", "wind_app_angle"} & set(variables):
            self.perturbed.append(5)
        if {"x", "y"} & model.library.sources:
            self.perturbed += [3, 4]
        steps = np.array([self.U0, self.U0, self.U0 / self.L, self.L, self.L, 1.0])
        self.steps = STATE_STEP * steps

    def accelerations(self, z: np.ndarray, half: int, columns: bool = False):
        """Accelerations (3, n) in SI at states ``z`` (n, 6) (n a multiple of the segments),
        and the term columns (n_terms, n) when asked."""
        seg = self.segments
        repeat = z.shape[0] // seg.n_segments
        def pick(a):
            return np.tile(a[:, half], repeat)

        u, v, r, x, y, psi = z.T
        channels = {name: pick(values) for name, values in seg.channels.items()}
        values = self.model.flight_variables(u, v, r, pick(seg.rudder), psi, channels,
                                             (x, y), pick(seg.rudder_rate))
        cols = self.model.term_columns(values)
        forces = np.einsum("dt,tn->dn", self.weights, cols, optimize=False)
        ratio = np.sqrt(values[SPEED_FACTOR]) if SPEED_FACTOR in values else 1.0
        un, vn, rn = values["du"] + 1.0, values["v"] * ratio, values["r"] * ratio
        m_v, m_xg, m_u, munk = self.inertia
        forces[0] += m_v * vn * rn + m_xg * rn * rn
        forces[1] += -m_u * un * rn
        forces[2] += -m_xg * un * rn - munk * un * vn
        a = np.empty_like(forces)
        a[0] = self.minv[0, 0] * forces[0]
        a[1] = self.minv[1, 1] * forces[1] + self.minv[1, 2] * forces[2]
        a[2] = self.minv[2, 1] * forces[1] + self.minv[2, 2] * forces[2]
        a *= self.scale[:, None]
        return (a, cols) if columns else a

    def __call__(self, z: np.ndarray, half: int) -> np.ndarray:
        """dz/dt (M, 6)."""
        return self._assemble(z, self.accelerations(z, half))

    def _assemble(self, z, a) -> np.ndarray:
        u, v, r, _, _, psi = z.T
        c, s = np.cos(psi), np.sin(psi)
        return np.column_stack([a[0], a[1], a[2], u * c - v * s, u * s + v * c, r])

    def with_derivatives(self, z: np.ndarray, half: int):
        """dz/dt (M, 6), d(dz/dt)/dz (M, 6, 6) and d(dz/dt)/dtheta (M, 6, P)."""
        m = z.shape[0]
        stacked = [z]
        for k in self.perturbed:
            moved = z.copy()
            moved[:, k] += self.steps[k]
            stacked.append(moved)
        a_all, cols_all = self.accelerations(np.vstack(stacked), half, columns=True)
        a = a_all[:, :m]
        f = self._assemble(z, a)
        jac = np.zeros((m, 6, 6))
        for j, k in enumerate(self.perturbed, start=1):
            jac[:, :3, k] = ((a_all[:, j * m:(j + 1) * m] - a) / self.steps[k]).T
        u, v, _, _, _, psi = z.T
        c, s = np.cos(psi), np.sin(psi)
        jac[:, 3, 0], jac[:, 3, 1], jac[:, 3, 5] = c, -s, -u * s - v * c
        jac[:, 4, 0], jac[:, 4, 1], jac[:, 4, 5] = s, c, u * c - v * s
        jac[:, 5, 2] = 1.0
        cols = cols_all[:, :m]
        rows, columns = self.slots
        # d(accelerations)/d(coefficient k) = scale * Minv[:, row_k] * column_k
        effect = (self.minv[:, rows] * self.scale[:, None])  # (3, P)
        dtheta = np.zeros((m, 6, len(rows)))
        dtheta[:, :3, :] = effect[None, :, :] * cols[columns].T[:, None, :]
        return f, jac, dtheta


def fly_segments(model, segments: Segments, weights: np.ndarray | None = None, slots=None,
                 *, sensitivities: bool = False, compiled: bool = True,
                 stopped: np.ndarray | None = None):
    """Fly every segment from its first state (RK4, :class:`Segments`' grid).

    Parameters
    ----------
    model : AbkowitzModel
    segments : Segments
    weights : ndarray, shape (3, n_active_terms), optional
        The coefficients to fly in the layout of the model's active terms (default the
        model's own).
    slots : (rows, columns), optional
        With ``sensitivities``: the place in ``weights`` of every coefficient to
        differentiate by (default every active coefficient, :meth:`AbkowitzModel.active`).
    sensitivities : bool
        Also integrate the sensitivities of the states to those coefficients.
    compiled : bool
        Fly through the compiled loop of :mod:`sindyship._shooting_compiled` where numba is
        installed (the same numbers to rounding); False flies the numpy reference (zig-zags
        flown closed loop: that loop's own code, run as Python).
    stopped : ndarray of int, shape (M,), optional
        Filled with the RK4 step at whose end each segment diverged (-1: it did not); its
        first held compared sample is ``step // segments.every``.

    Returns
    -------
    states : ndarray, shape (M, n_out, 6)
        u, v, r, x, y, psi at the compared samples; from a segment's divergence on
        (:func:`sindyship.simulation.diverged`) the last state in range, so that the error
        keeps a gradient.
    jacobian : ndarray, shape (M, n_out, 6, P), or None
        d(states)/d(coefficients), held from a divergence on as the states are.
    """
    from ._shooting_compiled import fly_compiled

    if weights is None:
        weights = model._weights
    if slots is None:
        slots = model_slots(model)
    rhs = _RightHandSide(model, segments, weights, slots)
    done = fly_compiled(model, segments, weights, slots, rhs.perturbed, rhs.steps,
                        sensitivities) if compiled else None
    if done is None:
        closed = segments.zigzag.sign != 0
        if closed.any():  # zig-zags flown closed loop: the loop, as Python without numba
            flown = fly_compiled(model, segments.take(closed), weights, slots, rhs.perturbed,
                                 rhs.steps, sensitivities, python=True)
            if flown is None:
                raise SindyshipInputError(
                    "the model's library has a term the shooting loop cannot evaluate (a "
                    "factor of a number, or a variable it has no form for), so its zig-zags "
                    "cannot be flown closed loop; refine on segments (segment_s) instead of "
                    "whole flights.")
            done = _merged(closed, _fly_numpy(model, segments.take(~closed), weights, slots,
                                              sensitivities), flown)
        else:
            done = _fly_numpy(model, segments, weights, slots, sensitivities)
    if stopped is not None:
        stopped[:] = done[2]
    return done[0], done[1]


def _merged(closed, replayed, flown):
    """The results of the replayed and the closed-loop segments in the batch's order."""
    states = np.empty((len(closed), *flown[0].shape[1:]))
    states[~closed], states[closed] = replayed[0], flown[0]
    stopped = np.empty(len(closed), dtype=np.int64)
    stopped[~closed], stopped[closed] = replayed[2], flown[2]
    if flown[1] is None:
        return states, None, stopped
    jacobian = np.empty((len(closed), *flown[1].shape[1:]))
    jacobian[~closed], jacobian[closed] = replayed[1], flown[1]
    return states, jacobian, stopped


def _fly_numpy(model, segments, weights, slots, sensitivities):
    """The numpy reference of :func:`fly_segments` (segments replaying their rudder): states,
    sensitivities (or None) and the step each segment diverged at (-1: none)."""
    from .simulation import diverged

    z = segments.state0.astype(float).copy()
    m, h = z.shape[0], segments.step
    n_out = segments.n_steps // segments.every
    states = np.empty((m, n_out, 6))
    jacobian = np.zeros((m, n_out, 6, len(slots[0]))) if sensitivities else None
    stopped = np.full(m, -1, dtype=np.int64)
    if m == 0:
        return states, jacobian, stopped
    rhs = _RightHandSide(model, segments, weights, slots)
    sens = np.zeros((m, 6, len(slots[0]))) if sensitivities else None
    alive = np.ones(m, dtype=bool)
    with np.errstate(all="ignore"):
        for j in range(segments.n_steps):
            i0, i1, i2 = 2 * j, 2 * j + 1, 2 * j + 2
            if sensitivities:
                z_new, sens_new = _rk4_with_sensitivities(rhs, z, sens, h, (i0, i1, i2))
            else:
                k1 = rhs(z, i0)
                k2 = rhs(z + 0.5 * h * k1, i1)
                k3 = rhs(z + 0.5 * h * k2, i1)
                k4 = rhs(z + h * k3, i2)
                z_new = z + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            bad = diverged(np.vstack([z_new[:, :6].T, np.zeros(m)]), model.ship.L,
                           model.ship.U0)
            stopped[bad & alive] = j
            alive &= ~bad
            z = np.where(alive[:, None], z_new, z)  # a diverged segment holds its last state
            if sensitivities:
                sens = np.where(alive[:, None, None], sens_new, sens)
            if (j + 1) % segments.every == 0:
                k = (j + 1) // segments.every - 1
                states[:, k] = z
                if sensitivities:
                    jacobian[:, k] = sens
    return states, jacobian, stopped


def _rk4_with_sensitivities(rhs, z, sens, h, halves):
    """One RK4 step of the state and of its sensitivities (the variational equations)."""
    i0, i1, i2 = halves
    f1, a1, b1 = rhs.with_derivatives(z, i0)
    s1 = np.einsum("mij,mjp->mip", a1, sens) + b1
    f2, a2, b2 = rhs.with_derivatives(z + 0.5 * h * f1, i1)
    s2 = np.einsum("mij,mjp->mip", a2, sens + 0.5 * h * s1) + b2
    f3, a3, b3 = rhs.with_derivatives(z + 0.5 * h * f2, i1)
    s3 = np.einsum("mij,mjp->mip", a3, sens + 0.5 * h * s2) + b3
    f4, a4, b4 = rhs.with_derivatives(z + h * f3, i2)
    s4 = np.einsum("mij,mjp->mip", a4, sens + h * s3) + b4
    z_new = z + (h / 6.0) * (f1 + 2.0 * f2 + 2.0 * f3 + f4)
    sens_new = sens + (h / 6.0) * (s1 + 2.0 * s2 + 2.0 * s3 + s4)
    return z_new, sens_new


def model_slots(model) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, columns)`` in the model's weights of its active coefficients, in the order of
    :func:`active_keys`."""
    keys = active_keys(model)
    places = [model._weight_slots[key] for key in keys]
    return (np.array([p[0] for p in places], dtype=int),
            np.array([p[1] for p in places], dtype=int))


def active_keys(model) -> list[tuple[str, str]]:
    """The model's non-zero coefficients as ``(dof, term)``, X, Y, N in library order."""
    return [(dof, term.text) for dof in DOFS for term in model.library.terms[dof]
            if model.coefficients[dof][term.text] != 0.0]

"""Standard manoeuvres, flying them, and their standard figures.

A :class:`Manoeuvre` names a rudder programme (turning circle, zig-zag flown closed loop,
stepped spiral, pull-out, straight run, seeded random rudder) and makes the
:class:`~sindyship.simulation.RudderCommand` that the integrator follows.  :func:`fly` flies
manoeuvres with any dynamics (the MMG model or an identified one) and returns
:class:`~sindyship.trajectory.Trajectory` records in the measurement-CSV layout.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import SindyshipInputError
from .simulation import (
    ConstantCommand,
    RudderCommand,
    SimulationResult,
    StepCommand,
    ZigZagCommand,
    simulate_batch,
)
from .trajectory import Trajectory, checks_done

MANOEUVRE_KINDS = ("turning-circle", "zigzag", "spiral", "pull-out", "straight", "random")


#: The helmsman's course keeping: his gain [rad of rudder per rad of heading error], how far
#: ahead he looks [s] (the yaw rate times it counts as heading error), the most rudder he
#: gives [deg], how often he moves the wheel [s] and the spread of his hand [deg]; a model
#: steered on a lake.
HELMSMAN = {"gain": 1.5, "lead_s": 4.0, "limit": 6.0, "period": 1.5, "hand": 0.5}


class HelmsmanThen(RudderCommand):
    """Course keeping by hand until the execute, then the manoeuvre's own command.

    The helmsman steers toward the heading he started on: every ``period`` seconds he sets the
    rudder to ``-gain (psi - psi_0 + lead_s r)`` within +-``limit``, off by a seeded hand
    error (:data:`HELMSMAN`).  At the execute the manoeuvre's command starts from the state
    there (a zig-zag measures its heading change from the heading at the execute).
    """

    def __init__(self, execute: float, manoeuvre: RudderCommand, seed: int,
                 helmsman: dict | None = None):
        self.execute = float(execute)
        self.manoeuvre = manoeuvre
        self.seed = int(seed)
        self.helmsman = {**HELMSMAN, **(helmsman or {})}
        self._started = False
        self._next = 0.0
        self._held = 0.0
        self._psi_ref = 0.0
        self._rng = np.random.default_rng(self.seed)

    def reset(self, state0):
        self._started = False
        self._next = 0.0
        self._held = 0.0
        self._psi_ref = float(state0[5])
        self._rng = np.random.default_rng(self.seed)

    def value(self, t, state):
        if t >= self.execute - 1e-9:
            if not self._started:
                self.manoeuvre.reset(state)
                self._started = True
            return self.manoeuvre.value(t, state)
        if t >= self._next - 1e-9:
            h = self.helmsman
            error = float(state[5]) - self._psi_ref + h["lead_s"] * float(state[2])
            wheel = -h["gain"] * error
            limit = math.radians(h["limit"])
            hand = math.radians(h["hand"]) * float(self._rng.standard_normal())
            self._held = min(max(wheel + hand, -limit), limit)
            self._next = t + h["period"]
        return self._held

    def next_change(self, t):
        if t < self.execute - 1e-9:
            return min(self._next if self._next > t + 1e-9 else t + self.helmsman["period"],
                       self.execute)
        return self.manoeuvre.next_change(t)

    def event(self, state):
        return self.manoeuvre.event(state) if self._started else None

    def on_event(self):
        self.manoeuvre.on_event()


@dataclass(frozen=True)
class Manoeuvre:
    """A standard manoeuvre.

    Parameters
    ----------
    kind : str
        One of ``MANOEUVRE_KINDS``.
    rudder : float
        Rudder angle [deg]: the turning-circle or pull-out angle (sign gives the side), the
        zig-zag amplitude, the largest spiral angle, the random sequence's largest angle.
    check : float
        Zig-zag heading check angle [deg].
    first_sign : int
        Zig-zag first rudder side: +1 starboard, -1 port.  For a spiral: +1 an inward spiral to
        starboard (5, 10, ..., rudder deg), -1 an outward spiral to port (-rudder, ..., -5 deg).
    duration : float
        Length of the record [s]; samples at t = 0, dt, ..., duration - dt.
    dt : float
        Sample interval [s].
    steps : int
        Spiral: number of rudder steps; pull-out: ignored.
    pull_out_time : float
        Pull-out: time at which the rudder returns to zero [s].
    hold : tuple of float
        Random rudder: range of hold times [s].
    seed : int
        Random rudder: seed of ``numpy.random.default_rng``; the helmsman's hand in an
        approach.
    name : str
        Name of the record (default: made from kind and angles).
    approach : float
        Seconds of course keeping by hand before the programme starts (its rudder execute),
        as a trial is run (:class:`HelmsmanThen`); 0 starts it at once.

    Examples
    --------
    >>> Manoeuvre("zigzag", rudder=20, check=20).label
    'zz20_20'
    """

    kind: str
    rudder: float = 0.0
    check: float = 0.0
    first_sign: int = 1
    duration: float = 3200.0
    dt: float = 1.0
    steps: int = 7
    pull_out_time: float = 1000.0
    hold: tuple[float, float] = (30.0, 120.0)
    seed: int = 0
    name: str = ""
    meta: dict = field(default_factory=dict, compare=False)
    approach: float = 0.0

    def __post_init__(self):
        if self.kind not in MANOEUVRE_KINDS:
            raise SindyshipInputError(
                f"unknown manoeuvre {self.kind!r}; choose one of {', '.join(MANOEUVRE_KINDS)}."
            )
        if not (self.duration > 0 and self.dt > 0 and self.duration >= 2 * self.dt):
            raise SindyshipInputError(
                f"duration {self.duration} s and dt {self.dt} s must be positive with at least "
                "two samples."
            )
        if self.kind == "pull-out" and not 0 < self.pull_out_time < self.duration:
            raise SindyshipInputError(
                f"a pull-out returns its rudder to zero before the record ends: pull_out_time "
                f"{self.pull_out_time:g} s is not within (0, {self.duration:g}) s."
            )
        if self.kind == "zigzag" and (self.rudder <= 0 or self.check <= 0):
            raise SindyshipInputError(
                "a zig-zag needs a positive rudder amplitude and check angle (e.g. --rudder 20 "
                "--check 20)."
            )
        if self.first_sign not in (1, -1):
            raise SindyshipInputError(
                f"first_sign is {self.first_sign!r}; give +1 (starboard first) or -1 (port).")
        if not math.isfinite(self.rudder) or abs(self.rudder) >= 90.0:
            raise SindyshipInputError(
                f"rudder {self.rudder!r} deg is no rudder angle; Manoeuvre takes degrees, up to "
                "the ship's rudder limit.")

    @property
    def label(self) -> str:
        """A short name such as ``tc35_stbd``, ``zz10_10``, ``spiral_stbd``."""
        if self.name:
            return self.name
        side = "stbd" if (self.rudder if self.kind in ("turning-circle", "pull-out")
                          else self.first_sign) >= 0 else "port"
        a = f"{abs(self.rudder):g}"
        if self.kind == "turning-circle":
            return f"tc{a}_{side}"
        if self.kind == "zigzag":
            suffix = "" if self.first_sign >= 0 else "_port"
            return f"zz{a}_{self.check:g}{suffix}"
        if self.kind == "spiral":
            return f"spiral_{side}"
        if self.kind == "pull-out":
            return f"pullout{a}_{side}"
        if self.kind == "random":
            return f"random{a}_seed{self.seed}"
        return "straight"

    @property
    def times(self) -> np.ndarray:
        """Sample times [s]."""
        return np.arange(int(round(self.duration / self.dt))) * self.dt

    def command(self) -> RudderCommand:
        """The commanded rudder programme (paper section 3.1 for the protocol's manoeuvres),
        after course keeping by hand for ``approach`` seconds when there is one."""
        if self.approach > 0:
            return HelmsmanThen(self.approach, self._programme(), self.seed)
        return self._programme()

    def _programme(self) -> RudderCommand:
        rad = math.radians
        if self.kind == "straight":
            return ConstantCommand(0.0)
        if self.kind == "turning-circle":
            return ConstantCommand(rad(self.rudder))
        if self.kind == "zigzag":
            return ZigZagCommand(rad(self.rudder), rad(self.check), self.first_sign)
        if self.kind == "pull-out":
            return StepCommand([0.0, self.pull_out_time], [rad(self.rudder), 0.0])
        if self.kind == "spiral":
            n = self.steps
            angles = np.linspace(abs(self.rudder) / n, abs(self.rudder), n)
            if self.first_sign < 0:
                angles = -angles[::-1]
            times = np.arange(n) * self.duration / n
            return StepCommand(times, np.radians(angles))
        rng = np.random.default_rng(self.seed)
        times = [0.0]
        while times[-1] < self.duration:
            times.append(times[-1] + rng.uniform(*self.hold))
        angles = rng.uniform(-abs(self.rudder), abs(self.rudder), len(times))
        return StepCommand(times, np.radians(angles))


def protocol_manoeuvres(duration: float = 3200.0, *, ship=None) -> dict[str, list[Manoeuvre]]:
    """The reproduction protocol's training and held-out manoeuvres (paper section 3.1).

    Parameters
    ----------
    duration : float
        Record length [s] of the KCS's plan; the protocol's is 3200 s at 1 Hz (shorter runs
        make quick examples).
    ship : Ship, optional
        Another ship flies the same plan in its own time scale L/U0: the length and the
        sampling step scaled by its L/U0 over the KCS's (18.63 s), the step rounded to three
        significant digits, the same number of samples.  The KVLCC2 model (5.94 s) records
        3200 samples every 0.319 s: flown at 1 Hz, as the KCS is, its records are too coarse
        for finite differences to resolve its accelerations.

    Returns
    -------
    dict
        ``{"train": [8 manoeuvres], "test": [tc15_port, tc15_stbd, zz10_10]}``.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> plan = protocol_manoeuvres(ship=load_ship("kvlcc2"))
    >>> plan["train"][0].dt, plan["train"][0].duration
    (0.319, 1020.8)
    >>> protocol_manoeuvres(ship=load_ship("kcs"))["train"][0].dt
    1.0
    """
    dt = PROTOCOL_STEP
    if ship is not None:
        from .ships import load_ship

        factor = ship.time_scale / load_ship("kcs").time_scale
        if not math.isclose(factor, 1.0, rel_tol=1e-9):
            dt = float(f"{PROTOCOL_STEP * factor:.3g}")
            duration = round(duration / PROTOCOL_STEP * dt, 9)
    train = [
        Manoeuvre("straight", duration=duration, dt=dt),
        Manoeuvre("turning-circle", rudder=35, duration=duration, dt=dt),
        Manoeuvre("turning-circle", rudder=-35, duration=duration, dt=dt),
        Manoeuvre("zigzag", rudder=35, check=10, duration=duration, dt=dt),
        Manoeuvre("zigzag", rudder=20, check=20, duration=duration, dt=dt),
        Manoeuvre("zigzag", rudder=15, check=15, duration=duration, dt=dt),
        Manoeuvre("spiral", rudder=35, first_sign=1, duration=duration, dt=dt),
        Manoeuvre("spiral", rudder=35, first_sign=-1, duration=duration, dt=dt),
    ]
    test = [
        Manoeuvre("turning-circle", rudder=-15, duration=duration, dt=dt),
        Manoeuvre("turning-circle", rudder=15, duration=duration, dt=dt),
        Manoeuvre("zigzag", rudder=10, check=10, duration=duration, dt=dt),
    ]
    return {"train": train, "test": test}


#: The sampling step [s] of the reproduction protocol's KCS records (paper section 3.1).
PROTOCOL_STEP = 1.0


def initial_state(ship, u0: float | None = None) -> np.ndarray:
    """The protocol's initial state: u = U0 (or ``u0``), everything else zero."""
    return np.array([ship.U0 if u0 is None else u0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


def result_to_trajectory(result: SimulationResult, name: str, meta: dict | None = None
                         ) -> Trajectory:
    """A simulation result in the measurement-CSV layout (``delta`` and ``delta_c``)."""
    s = result.states
    frame = pd.DataFrame({
        "t": result.t, "u": s[0], "v": s[1], "r": s[2], "x": s[3], "y": s[4], "psi": s[5],
        "delta": s[6], "delta_c": result.delta_c,
    })
    info = dict(meta or {})
    info["diverged_at"] = result.diverged_at
    return Trajectory(frame, name=name, meta=info)


def check_rudder_limit(angle: float | None, ship, what: str) -> None:
    """Refuse a rudder (or check) angle [deg] beyond the ship's rudder limit (``[servo]
    delta_max``); ``what`` names it in the message (``"--rudder"``)."""
    limit = ship.servo.delta_max
    if angle is not None and abs(angle) > limit:
        raise SindyshipInputError(
            f"{what} {angle:g} deg is beyond the rudder limit of {ship.name} ({limit:g} deg); "
            f"give an angle of magnitude up to {limit:g} deg."
        )


def fly(dynamics, manoeuvres: Sequence[Manoeuvre], *, state0: np.ndarray | None = None,
        step: float | None = None, check_divergence: bool = True) -> list[Trajectory]:
    """Fly manoeuvres with a model (MMG or identified) and return their records.

    Manoeuvres with equal sample times are integrated together as one batch.

    Parameters
    ----------
    dynamics : object
        Simulator dynamics (see :func:`sindyship.simulation.simulate_batch`), such as
        :class:`sindyship.mmg.MMGModel`, or a fitted model (its ``dynamics()`` flies).
    manoeuvres : sequence of Manoeuvre
    state0 : ndarray, optional
        Initial state; default :func:`initial_state`.
    step : float, optional
        Runge-Kutta step [s].
    check_divergence : bool
        Stop and flag a diverging member (``meta["diverged_at"]``).

    Returns
    -------
    list of Trajectory
        In the order of ``manoeuvres``; a record whose simulation diverged holds NaN after
        ``meta["diverged_at"]``.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> from sindyship.mmg import MMGModel
    >>> (run,) = fly(MMGModel(load_ship("kcs")), [Manoeuvre("straight", duration=100)])
    >>> round(float(run["u"][-1] / 12.348), 4)  # the straight-run equilibrium u' = 1.0001
    1.0001
    """
    if isinstance(manoeuvres, Trajectory):
        raise TypeError("manoeuvres must be a list of Manoeuvre, not a record; to fly a "
                        "model the way a record was flown use sindyship.evaluate(model, "
                        "[record]) or sindyship.flights.fly_like(model, [record]).")
    if isinstance(manoeuvres, Manoeuvre | str) or not all(
            isinstance(m, Manoeuvre) for m in manoeuvres):
        raise TypeError("manoeuvres must be a list of Manoeuvre, such as "
                        "[Manoeuvre('zigzag', rudder=20, check=20)].")
    if not hasattr(dynamics, "accelerations") and hasattr(dynamics, "dynamics"):
        dynamics = dynamics.dynamics()  # a fitted model flies through its dynamics
    if not hasattr(dynamics, "accelerations"):
        raise TypeError(f"dynamics must be a model (MMGModel, an identified model or its "
                        f"dynamics), not {type(dynamics).__name__}.")
    ship = dynamics.ship
    for m in manoeuvres:
        check_rudder_limit(m.rudder, ship, f"{m.label}: rudder")
    s0 = initial_state(ship) if state0 is None else np.asarray(state0, dtype=float)
    if s0.shape != (7,) or not np.all(np.isfinite(s0)):
        raise SindyshipInputError(
            f"state0 has shape {s0.shape}; give 7 finite values [u, v, r, x, y, psi, delta] "
            "(SI, rad).")
    groups: dict[tuple, list[int]] = {}
    for i, m in enumerate(manoeuvres):
        groups.setdefault((m.duration, m.dt), []).append(i)
    records: list[Trajectory | None] = [None] * len(manoeuvres)
    for idx in groups.values():
        t = manoeuvres[idx[0]].times
        results = simulate_batch(dynamics, [manoeuvres[i].command() for i in idx], t, s0,
                                 step=step, check_divergence=check_divergence)
        for i, res in zip(idx, results, strict=True):
            m = manoeuvres[i]
            meta = {"manoeuvre": m.kind, "rudder_deg": m.rudder, "check_deg": m.check,
                    "first_sign": m.first_sign, **m.meta,
                    "checks": checks_done(ship)}
            records[i] = result_to_trajectory(res, m.label, meta)
    return records  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------
# Standard figures
# ---------------------------------------------------------------------------------------------
def _execute_index(traj: Trajectory) -> int:
    delta = traj.rudder
    moved = np.flatnonzero(np.abs(delta - delta[0]) > math.radians(1.0))
    cmd = traj["delta_c"] if traj.has("delta_c") else None
    if cmd is not None:
        moved_c = np.flatnonzero(np.abs(cmd - cmd[0]) > math.radians(1.0))
        if moved_c.size and (not moved.size or moved_c[0] < moved[0]):
            return int(moved_c[0])
        if cmd[0] != 0.0 and abs(cmd[0]) > math.radians(1.0):
            return 0
    return int(moved[0]) if moved.size else 0


def turning_figures(traj: Trajectory, L: float, *, execute: int | None = None) -> dict:
    """Advance, transfer, tactical diameter, steady diameter, speed loss, time to 90 deg.

    All measured from the rudder execute point (the first sample where the commanded, else
    the actual, rudder differs from its initial value by more than 1 deg; sample 0 when the
    command is already applied there), in ship lengths, for a turn to either side.

    Returns
    -------
    dict
        ``advance_L``, ``transfer_L``, ``tactical_diameter_L``, ``steady_diameter_L``,
        ``speed_loss`` (1 - steady U / approach U), ``time_to_90_s``; NaN where the turn
        never reached the heading change that defines a figure.
    """
    k0 = _execute_index(traj) if execute is None else execute
    x, y, psi = traj["x"][k0:], traj["y"][k0:], traj["psi"][k0:]
    t = traj.t[k0:]
    psi0 = psi[0]
    turn = np.sign(psi[-1] - psi0) or 1.0
    dpsi = turn * (psi - psi0)
    c, s = math.cos(psi0), math.sin(psi0)
    along = (x - x[0]) * c + (y - y[0]) * s
    across = turn * (-(x - x[0]) * s + (y - y[0]) * c)

    def at(angle_deg: float, values: np.ndarray) -> float:
        target = math.radians(angle_deg)
        k = np.flatnonzero(dpsi >= target)
        if not k.size:
            return math.nan
        k = int(k[0])
        if k == 0:
            return float(values[0])
        w = (target - dpsi[k - 1]) / (dpsi[k] - dpsi[k - 1])
        return float(values[k - 1] + w * (values[k] - values[k - 1]))

    U = np.hypot(traj["u"][k0:], traj["v"][k0:])
    # the steady turn: the last full circle flown with the rudder still at its turning angle
    rudder = traj.rudder[k0:]
    held = np.abs(rudder - np.median(rudder[: max(len(rudder) // 2, 1)])) < math.radians(1.0)
    end = int(np.flatnonzero(held)[-1]) if held.any() else len(dpsi) - 1
    steady = np.zeros_like(dpsi, dtype=bool)
    if dpsi[end] > 3 * math.pi:
        steady[:end + 1] = dpsi[:end + 1] >= dpsi[end] - 2 * math.pi
    if steady.any():
        xs, ys = x[steady], y[steady]
        diameter = float(0.5 * ((xs.max() - xs.min()) + (ys.max() - ys.min())))
        speed_loss = float(1.0 - U[steady].mean() / U[0])
    else:
        diameter = math.nan
        speed_loss = math.nan
    return {
        "advance_L": at(90.0, along) / L,
        "transfer_L": at(90.0, across) / L,
        "tactical_diameter_L": at(180.0, across) / L,
        "steady_diameter_L": diameter / L,
        "speed_loss": speed_loss,
        "time_to_90_s": at(90.0, t - t[0]),
    }


#: How far [deg] the heading must have turned back from its peak after a zig-zag's last
#: rudder reversal for that overshoot to count (:func:`zigzag_events`): well above a gyro's
#: noise.
OVERSHOOT_TURN_BACK_DEG = 0.5


def zigzag_events(traj: Trajectory) -> dict:
    """Rudder reversals, heading peaks and overshoots of a zig-zag record.

    The overshoot is the heading excursion beyond the heading at each rudder reversal (the
    check angle), up to the next reversal; after the last reversal to the other side, up to
    the end of the record once the heading has gone on past the reversal's heading and turned
    back from its peak (each by more than :data:`OVERSHOOT_TURN_BACK_DEG`, the turn back also
    by a tenth of the excursion): a record that ends before the next reversal, as the MARIN
    10/10 zig-zags do, keeps its second overshoot, and one whose rudder goes back amidships
    gets none there.

    Returns
    -------
    dict
        ``reversals`` and ``peaks`` (sample indices), ``overshoots_deg`` (one per leg whose
        peak is passed) and ``heading_deg`` (heading change from the first sample).
    """
    from .trials import zigzag_command

    psi = np.degrees(traj["psi"] - traj["psi"][0])
    implied = zigzag_command(traj)  # an actual rudder crosses zero seconds after its command
    cmd = traj.rudder if implied is None else implied
    sign = np.sign(cmd)
    reversals = np.flatnonzero(np.diff(sign) != 0) + 1
    reversals = reversals[sign[reversals - 1] != 0]
    overshoots, peaks = [], []
    ends = [*reversals[1:], len(psi)] if len(reversals) else []
    for a, b in zip(reversals, ends, strict=True):
        turning = psi[a:b] if sign[a - 1] > 0 else -psi[a:b]  # the overshoot's way up
        peak = int(np.argmax(turning))
        excursion = float(turning[peak] - turning[0])
        if b == len(psi) and (not np.any(sign[a:b] == -sign[a - 1])  # never to the other side
                              or excursion <= OVERSHOOT_TURN_BACK_DEG
                              or turning[peak] - turning[-1] < max(OVERSHOOT_TURN_BACK_DEG,
                                                                   0.1 * excursion)):
            break  # the rudder back amidships, or the record ends before the heading turns
        peaks.append(a + peak)
        overshoots.append(excursion)
    return {"reversals": reversals, "peaks": np.array(peaks, dtype=int),
            "overshoots_deg": overshoots, "heading_deg": psi}


def zigzag_figures(traj: Trajectory) -> dict:
    """First and second overshoot angles [deg] and the period of a zig-zag [s].

    The overshoot is the heading excursion beyond the check angle after each rudder
    reversal (:func:`zigzag_events`); the period is the time between the first and third
    reversals.
    """
    events = zigzag_events(traj)
    reversals, overshoots = events["reversals"], events["overshoots_deg"]
    t = traj.t
    period = float(t[reversals[2]] - t[reversals[0]]) if len(reversals) >= 3 else math.nan
    return {
        "first_overshoot_deg": overshoots[0] if overshoots else math.nan,
        "second_overshoot_deg": overshoots[1] if len(overshoots) > 1 else math.nan,
        "period_s": period,
    }


def imo_criteria(kind: str, L_over_V: float, *, rudder: float = 35.0, check: float = 0.0
                 ) -> dict[str, float]:
    """The IMO manoeuvrability criteria that apply (Resolution MSC.137(76), Standards for ship
    manoeuvrability, 2002, section 5.2).

    Turning ability (35 deg rudder): advance at most 4.5 L, tactical diameter at most 5 L.
    10/10 zig-zag: first overshoot at most 10 deg if L/V < 10 s, 20 deg if L/V >= 30 s and
    5 + 0.5 L/V deg in between; second overshoot at most 25 deg, 40 deg and 17.5 + 0.75 L/V.
    20/20 zig-zag: first overshoot at most 25 deg.

    Parameters
    ----------
    kind : {"turning-circle", "zigzag"}
    L_over_V : float
        Ship length over approach speed [s].
    rudder, check : float
        Rudder and check angle [deg] of the manoeuvre.

    Returns
    -------
    dict
        Criterion name -> limit (``advance_L``, ``tactical_diameter_L``,
        ``first_overshoot_deg``, ``second_overshoot_deg``); empty where none applies.

    Examples
    --------
    >>> imo_criteria("zigzag", 18.63, rudder=10, check=10)["first_overshoot_deg"]
    14.315
    """
    if kind == "turning-circle":
        return {"advance_L": 4.5, "tactical_diameter_L": 5.0} if abs(rudder) == 35 else {}
    if kind != "zigzag":
        return {}
    if (abs(rudder), check) == (10, 10):
        first = 10.0 if L_over_V < 10 else 20.0 if L_over_V >= 30 else 5 + 0.5 * L_over_V
        second = 25.0 if L_over_V < 10 else 40.0 if L_over_V >= 30 else 17.5 + 0.75 * L_over_V
        return {"first_overshoot_deg": first, "second_overshoot_deg": second}
    if (abs(rudder), check) == (20, 20):
        return {"first_overshoot_deg": 25.0}
    return {}

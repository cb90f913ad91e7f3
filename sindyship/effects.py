"""Physical effects the simulator can add, to make data with a hidden effect.

Each effect stands for something real that a 3-DOF Abkowitz model fitted on calm-water data
does not contain.  Names, units and direction conventions are those of the ``simulate``
command's ``--effect NAME=VALUE`` option:

``load``, ``load_dir``, ``load_arm``
    A steady earth-fixed force (wind on the superstructure, a towline, a mooring) of magnitude
    ``load`` (Prime II: force / (0.5 rho L d U0^2)) coming FROM the direction ``load_dir`` [deg,
    clockwise from north], acting at ``load_arm`` x/L from midship.  In the body frame it
    rotates with the heading, so the forces it causes vary with psi.
``current``, ``current_dir``
    A uniform steady current of ``current`` [m/s] flowing TOWARD ``current_dir`` [deg].  The hull
    sees the velocity relative to the water, the record is over ground (as a GPS logs it): the
    recorded u, v, x and y include the drift.
``crossflow``
    Quadratic cross-flow drag with drag coefficient C_D along the hull (strip theory):
    Y' = -C_D int (v' + x' r') |v' + x' r'| dx', N' = -C_D int x' (v' + x' r') |...| dx' over
    x' in [-1/2, 1/2].
``prop_side_force``
    A constant side force Y' (Prime II) at the propeller position x'_P, as a single-screw
    propeller makes; it gives a yaw moment x'_P Y'.
``rudder_offset``
    A rudder-angle indicator offset [deg]: recorded angle = true angle + offset.  The rudder
    programme is flown on the indicator (an autopilot commanding 10 deg gets 10 - offset deg).
``wind``, ``wind_dir``, ``gust``, ``wind_wander``
    A true wind of mean speed ``wind`` [m/s] coming FROM ``wind_dir`` [deg, clockwise from
    north], with gusts of standard deviation ``gust`` times the mean speed (correlation time
    L/U0) and a direction that wanders with a standard deviation of ``wind_wander`` [deg]
    (correlation time 20 L/U0); the force follows the apparent wind on a container ship's
    windage (:func:`sindyship.conditions.wind_force`).  Recorded as the channels
    ``wind_speed`` [m/s] and ``wind_dir`` [rad, from].
``rps``, ``rps_step``, ``rps_step_at``, ``rps_vary``
    Propeller revolutions ``rps`` times the ship's design ``n_P`` (default 1), changed by
    ``rps_step`` times ``n_P`` at the fraction ``rps_step_at`` of the record (default 0.5, the
    middle), plus a slow random variation of standard deviation ``rps_vary`` times ``n_P``
    (correlation time 5 L/U0).  Recorded as the channel ``n`` [rps].  The run starts at the
    design speed, so a record at other revolutions begins by speeding up or slowing down.
``rudder_lag``
    A rudder-angle sensor late by ``rudder_lag`` [s]: the recorded ``delta`` is the angle the
    water saw that long before (held at its first value at the start); the commanded
    ``delta_c`` is exact.
``rudder_stall``
    The rudder stalls at ``rudder_stall`` [deg] of effective angle of attack: its normal force
    stops growing beyond it (:func:`sindyship.mmg.force_components`).
``bank``, ``bank_distance``
    A straight bank along north, ``bank_distance`` ship lengths east of the start (negative:
    west), that pulls the ship toward it with an earth-fixed force of ``bank`` (Prime II) times
    (L / distance)^2, acting a quarter length aft of midship.
``shallow_patch``, ``patch_distance``, ``patch_dir``
    Shallow water beyond a straight edge ``patch_distance`` ship lengths from the start toward
    ``patch_dir`` [deg, clockwise from north]: the linear hull derivatives are
    ``1 + shallow_patch`` times their deep-water values there (a smooth step half a ship
    length wide; :class:`sindyship.mmg.MMGModel`), and no depth is recorded.  A negative
    ``patch_distance`` puts the edge behind the start, which is then on the patch.
``noise``
    Gaussian measurement noise with a standard deviation of ``noise`` times each channel's RMS
    for u, v, r and delta (positions and heading get their own levels through
    :func:`add_noise`), from ``numpy.random.default_rng(seed)``.
``quantise``
    Every recorded channel but time rounded to ``quantise`` significant figures (the MARIN
    files carry three).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields

import numpy as np

from .errors import SindyshipInputError
from .mmg import MMGModel
from .ships import Ship
from .simulation.kernels import ChannelSeries
from .trajectory import Trajectory

# Gauss-Legendre nodes for the cross-flow integral over x' in [-1/2, 1/2].
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(12)
_NODES = 0.5 * _NODES
_WEIGHTS = 0.5 * _WEIGHTS


@dataclass(frozen=True)
class Effects:
    """Settings of the optional physical effects (all off by default).

    Examples
    --------
    >>> effects = parse_effects(["load=0.002", "load_dir=90"])
    >>> effects.load, effects.load_dir
    (0.002, 90.0)
    """

    load: float = 0.0
    load_dir: float = 0.0
    load_arm: float = 0.0
    current: float = 0.0
    current_dir: float = 0.0
    crossflow: float = 0.0
    prop_side_force: float = 0.0
    rudder_offset: float = 0.0
    noise: float = 0.0
    quantise: int = 0
    wind: float = 0.0
    wind_dir: float = 0.0
    gust: float = 0.0
    wind_wander: float = 0.0
    rps: float = 1.0
    rps_step: float = 0.0
    rps_step_at: float = 0.5
    rps_vary: float = 0.0
    rudder_lag: float = 0.0
    rudder_stall: float = 0.0
    bank: float = 0.0
    bank_distance: float = 5.0
    shallow_patch: float = 0.0
    patch_distance: float = 5.0
    patch_dir: float = 0.0
    seed: int = 0

    def active(self) -> list[str]:
        """Names of the effects switched on."""
        main = ("load", "current", "crossflow", "prop_side_force", "rudder_offset", "noise",
                "quantise", "wind", "rps_step", "rps_vary", "rudder_lag", "rudder_stall", "bank",
                "shallow_patch")
        return [name for name in main if getattr(self, name)] + (
            ["rps"] if self.rps != 1.0 else [])

    @property
    def varies_in_time(self) -> bool:
        """Whether the effects change during a run (wind, revolutions): each run then has its
        own series of conditions."""
        return bool(self.wind or self.rps != 1.0 or self.rps_step or self.rps_vary)

    def conditions(self, ship: Ship, times: np.ndarray, index: int) -> dict[str, np.ndarray]:
        """The wind and revolutions of the run ``index`` of a batch at ``times`` (SI, named as
        the measurement CSV names them), from ``numpy.random.default_rng([seed, index])``."""
        from .conditions import revolution_series, wind_series

        rng = np.random.default_rng([self.seed, index])
        out: dict[str, np.ndarray] = {}
        if self.wind:
            out.update(wind_series(times, self.wind, self.wind_dir, self.gust, self.wind_wander,
                                   ship.time_scale, rng))
        if self.rps != 1.0 or self.rps_step or self.rps_vary:
            out["n"] = revolution_series(times, ship.propeller.n_P, self.rps, self.rps_step,
                                         self.rps_step_at, self.rps_vary, ship.time_scale, rng)
        return out

    def dynamics(self, ship: Ship, conditions: ChannelSeries | None = None) -> MMGModel:
        """The MMG model of ``ship`` with the physical effects in its right-hand side, and the
        conditions of the runs it flies (:meth:`conditions`) as time series."""
        extra = []
        if self.load:
            extra.append(_steady_load(self.load, self.load_dir, self.load_arm))
        if self.crossflow:
            extra.append(_crossflow(self.crossflow))
        if self.prop_side_force:
            extra.append(_side_force(self.prop_side_force, ship.propeller.x_P))
        current = (0.0, 0.0)
        if self.current:
            to = math.radians(self.current_dir)
            current = (self.current * math.cos(to), self.current * math.sin(to))
        stall = math.radians(self.rudder_stall) if self.rudder_stall else None
        bank = (self.bank_distance * ship.L, self.bank) if self.bank else None
        patch = ((self.patch_distance * ship.L, math.radians(self.patch_dir),
                  self.shallow_patch) if self.shallow_patch else None)
        return MMGModel(ship, extra_forces=tuple(extra),
                        rudder_offset=math.radians(self.rudder_offset), current=current,
                        conditions=conditions, stall=stall, bank=bank, patch=patch)

    def record(self, trajectory: Trajectory, ship: Ship,
               conditions: Mapping[str, np.ndarray] | None = None) -> Trajectory:
        """What an instrument records of a simulated run: over-ground velocities, the
        conditions' channels, noise, quantisation."""
        data = trajectory.data.copy()
        for name, values in (conditions or {}).items():
            data[name] = values
        if self.rudder_lag:
            t = data["t"].to_numpy(dtype=float)
            data["delta"] = np.interp(t - self.rudder_lag, t, data["delta"].to_numpy(dtype=float))
        if self.current:
            to = math.radians(self.current_dir)
            north, east = self.current * math.cos(to), self.current * math.sin(to)
            psi = data["psi"].to_numpy()
            data["u"] = data["u"] + north * np.cos(psi) + east * np.sin(psi)
            data["v"] = data["v"] - north * np.sin(psi) + east * np.cos(psi)
        out = Trajectory(data, name=trajectory.name,
                         meta={**trajectory.meta, "effects": self.as_dict()})
        if self.noise:
            levels = {c: self.noise * float(np.sqrt(np.nanmean(data[c] ** 2)))
                      for c in ("u", "v", "r", "delta")}
            out = add_noise(out, levels, seed=self.seed)
        if self.quantise:
            out = quantise(out, self.quantise)
        return out

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) != f.default}


#: Physical range of each effect's value: (lowest, highest, unit and meaning).  Beyond them
#: the effect is not a correction a calm-water model misses but a different ship or sea.
EFFECT_RANGES = {
    "load": (-0.1, 0.1, "Prime II force, the ship's own hull forces are about 0.01-0.2"),
    "load_dir": (-360.0, 360.0, "deg"),
    "load_arm": (-1.0, 1.0, "x/L from midship"),
    "current": (-10.0, 10.0, "m/s, the strongest tidal races run at 5"),
    "current_dir": (-360.0, 360.0, "deg"),
    "crossflow": (0.0, 10.0, "drag coefficient, about 0.5-1.5 for a hull"),
    "prop_side_force": (-0.05, 0.05, "Prime II force"),
    "rudder_offset": (-10.0, 10.0, "deg"),
    "noise": (0.0, 1.0, "fraction of each channel's RMS"),
    "quantise": (0, 17, "significant figures, 0 for none"),
    "wind": (0.0, 40.0, "m/s, a storm blows at 25"),
    "wind_dir": (-360.0, 360.0, "deg"),
    "gust": (0.0, 1.0, "fraction of the mean wind speed"),
    "wind_wander": (0.0, 180.0, "deg"),
    "rps": (0.2, 1.5, "fraction of the ship's design revolutions"),
    "rps_step": (-0.8, 0.5, "fraction of the ship's design revolutions"),
    "rps_step_at": (0.0, 1.0, "fraction of the record"),
    "rps_vary": (0.0, 0.3, "fraction of the ship's design revolutions"),
    "rudder_lag": (0.0, 60.0, "s"),
    "rudder_stall": (0.0, 45.0, "deg of effective angle of attack, 0 for none"),
    "bank": (0.0, 0.05, "Prime II force at one ship length from the bank"),
    "bank_distance": (-100.0, 100.0, "ship lengths east of the start, not 0"),
    "shallow_patch": (0.0, 2.0, "relative increase of the linear hull derivatives on the "
                      "patch, 0.5-1 where the depth is a little more than the draught"),
    "patch_distance": (-100.0, 100.0, "ship lengths from the start to the patch's edge"),
    "patch_dir": (-360.0, 360.0, "deg, clockwise from north, from the start across the edge"),
    "seed": (0, 2**63 - 1, "a whole number"),
}


def parse_effects(items: Iterable[str] | Mapping[str, float]) -> Effects:
    """Effects from ``NAME=VALUE`` strings (the command line) or a mapping.

    Raises
    ------
    SindyshipInputError
        For an unknown name, a value that is not a finite number, or one outside its physical
        range (:data:`EFFECT_RANGES`, the message gives it).
    """
    valid = {f.name: f.type for f in fields(Effects)}
    pairs = items.items() if isinstance(items, Mapping) else (
        _split(item) for item in items)
    values: dict[str, float] = {}
    for name, raw in pairs:
        if name not in valid:
            raise SindyshipInputError(
                f"unknown effect {name!r}; choose from {', '.join(valid)} "
                "(e.g. --effect load=0.002)."
            )
        try:
            value = float(raw)
        except (TypeError, ValueError):
            raise SindyshipInputError(
                f"effect {name} needs a number, not {raw!r} (e.g. --effect {name}=0.5)."
            ) from None
        values[name] = _bounded(name, value, raw)
    effects = Effects(**values)
    if effects.bank and abs(effects.bank_distance) < 1.0:
        raise SindyshipInputError(
            f"effect bank_distance = {effects.bank_distance:g} puts the bank within one ship "
            "length of the start; give at least 1 (ship lengths east, negative for west)."
        )
    for needs_wind in ("gust", "wind_wander"):
        if getattr(effects, needs_wind) and not effects.wind:
            raise SindyshipInputError(
                f"effect {needs_wind} varies the wind, but there is none; add --effect wind=SPEED "
                "(m/s)."
            )
    highest = effects.rps + max(effects.rps_step, 0.0) + 3.0 * effects.rps_vary
    if highest > 1.5:
        raise SindyshipInputError(
            f"effects rps={effects.rps:g}, rps_step={effects.rps_step:g} and "
            f"rps_vary={effects.rps_vary:g} take the revolutions up to {highest:.2g} of the "
            "design value (rps + rps_step + 3 rps_vary); keep that at 1.5 or below."
        )
    lowest = effects.rps + min(effects.rps_step, 0.0) - 3.0 * effects.rps_vary
    if lowest < 0.2:
        raise SindyshipInputError(
            f"effects rps={effects.rps:g}, rps_step={effects.rps_step:g} and "
            f"rps_vary={effects.rps_vary:g} take the revolutions down to {lowest:.2g} of the "
            "design value (rps + rps_step - 3 rps_vary); keep that at 0.2 or above."
        )
    return effects


def _bounded(name: str, value: float, raw) -> float:
    """``value`` when it is finite and inside the effect's physical range."""
    low, high, unit = EFFECT_RANGES[name]
    if not math.isfinite(value):
        raise SindyshipInputError(
            f"effect {name} must be finite, not {raw!r}; give a value from {low:g} to {high:g} "
            f"({unit})."
        )
    if name in ("quantise", "seed"):
        if value != int(value) or not low <= value <= high:
            raise SindyshipInputError(
                f"effect {name} must be a whole number from {low} to {high} ({unit}), not "
                f"{raw!r}."
            )
        return int(value)
    if not low <= value <= high:
        raise SindyshipInputError(
            f"effect {name} = {raw} is outside its physical range {low:g} to {high:g} ({unit})."
        )
    return value


def _split(item: str) -> tuple[str, str]:
    if "=" not in item:
        raise SindyshipInputError(
            f"effect {item!r} must be written NAME=VALUE (e.g. --effect current=0.5)."
        )
    name, raw = item.split("=", 1)
    return name.strip(), raw.strip()


def _steady_load(magnitude: float, from_deg: float, arm: float):
    come_from = math.radians(from_deg)
    north = -magnitude * math.cos(come_from)  # the force pushes away from where it comes from
    east = -magnitude * math.sin(come_from)

    def force(u, v, r, delta, psi):
        c, s = np.cos(psi), np.sin(psi)
        X = north * c + east * s
        Y = -north * s + east * c
        return X, Y, arm * Y

    return force


def _crossflow(c_d: float):
    def force(u, v, r, delta, psi):
        local = np.multiply.outer(_NODES, r) + v  # (nodes, ...) local sway velocity
        drag = -c_d * local * np.abs(local)
        Y = np.tensordot(_WEIGHTS, drag, axes=1)
        N = np.tensordot(_WEIGHTS * _NODES, drag, axes=1)
        return 0.0 * u, Y, N

    return force


def _side_force(Y_prop: float, x_P: float):
    def force(u, v, r, delta, psi):
        zero = 0.0 * u
        return zero, zero + Y_prop, zero + Y_prop * x_P

    return force


def add_noise(trajectory: Trajectory, std: Mapping[str, float], *, seed: int) -> Trajectory:
    """Gaussian noise with the given standard deviation per channel (SI), reproducible by seed.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0, 2.0], "u": [1.0, 1.0, 1.0]})
    >>> a = add_noise(Trajectory(frame), {"u": 0.1}, seed=3)["u"]
    >>> b = add_noise(Trajectory(frame), {"u": 0.1}, seed=3)["u"]
    >>> bool((a == b).all()) and bool((a != 1.0).any())
    True
    """
    rng = np.random.default_rng(seed)
    data = trajectory.data.copy()
    for column in sorted(std):
        if column in data.columns and std[column] > 0:
            data[column] = data[column] + rng.normal(0.0, std[column], len(data))
    return Trajectory(data, name=trajectory.name, meta=dict(trajectory.meta))


def sensor_noise(records, level: float, seed: int) -> list[Trajectory]:
    """Records with the measurement noise of the benchmarks: ``level`` times each record's RMS
    on u, v and r, 0.1 deg on heading and rudder and 0.5 m on positions (none when ``level``
    is 0); record k draws from ``1000 seed + k``.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({c: [1.0, 1.0, 1.0] for c in ("t", "u", "v", "r", "x", "y")})
    >>> noisy = sensor_noise([Trajectory(frame, name="run")], 0.01, seed=1)[0]
    >>> bool(abs(noisy["u"] - 1.0).max() < 0.05), bool((noisy["x"] != 1.0).any())
    (True, True)
    """
    if level == 0.0:
        return list(records)
    out = []
    for k, record in enumerate(records):
        std = {c: level * float(np.sqrt(np.mean(record[c] ** 2))) for c in ("u", "v", "r")}
        std.update({"psi": math.radians(0.1), "delta": math.radians(0.1), "x": 0.5, "y": 0.5})
        out.append(add_noise(record, std, seed=1000 * seed + k))
    return out


def quantise(trajectory: Trajectory, digits: int) -> Trajectory:
    """Round every channel except time to ``digits`` significant figures."""
    data = trajectory.data.copy()
    for column in data.columns:
        if column == "t":
            continue
        values = data[column].to_numpy(dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            mag = np.where(values == 0, 0, np.floor(np.log10(np.abs(values))))
        factor = 10.0 ** (digits - 1 - mag)
        data[column] = np.round(values * factor) / factor
    return Trajectory(data, name=trajectory.name, meta=dict(trajectory.meta))


def simulate_with_effects(ship: Ship, manoeuvres, effects: Effects | None = None, *,
                          step: float | None = None,
                          state0: np.ndarray | None = None) -> list[Trajectory]:
    """Fly manoeuvres with the MMG model of ``ship`` and the given effects; return the records.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> from sindyship.manoeuvres import Manoeuvre
    >>> (run,) = simulate_with_effects(load_ship("kcs"), [Manoeuvre("straight", duration=60)],
    ...                                parse_effects(["current=1", "current_dir=90"]))
    >>> round(float(run["y"][-1]), 3)  # 59 s drifting east at 1 m/s
    59.0
    """
    from .manoeuvres import fly

    effects = effects or Effects()
    if not effects.varies_in_time:
        runs = fly(effects.dynamics(ship), manoeuvres, step=step, state0=state0)
        return [effects.record(run, ship) for run in runs]
    records: list[Trajectory | None] = [None] * len(manoeuvres)
    batches: dict[tuple, list[int]] = {}
    for index, manoeuvre in enumerate(manoeuvres):
        batches.setdefault((manoeuvre.duration, manoeuvre.dt), []).append(index)
    for batch in batches.values():  # runs of one length fly together, each in its conditions
        times = manoeuvres[batch[0]].times
        conditions = [effects.conditions(ship, times, index) for index in batch]
        series = ChannelSeries(times, {name: np.vstack([c[name] for c in conditions])
                                       for name in conditions[0]})
        runs = fly(effects.dynamics(ship, series), [manoeuvres[i] for i in batch], step=step,
                   state0=state0)
        for index, run, own in zip(batch, runs, conditions, strict=True):
            records[index] = effects.record(run, ship, own)
    return records

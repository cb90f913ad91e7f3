"""Fly a model the way a record was flown.

A record is recognised as a zig-zag when its commanded rudder (else its rudder) takes values
+-A (|A| >= 1 deg, spread <= 0.5 deg) with at least two reversals, each at a sample where
|psi - psi(0)| is within 1 deg of a common check angle C; it is then flown closed loop with A
and C rounded to 0.1 deg and the recorded first rudder sign.  A logged zig-zag (a manual
lead-in, plateaus a degree or two off nominal: :func:`sindyship.trials.recognise_zigzag`) is
flown from its execute, as a zig-zag test is defined (:func:`from_execute`; replaying a
zig-zag's rudder open loop is not a zig-zag test: small heading errors grow without bound).
Any other record replays its commanded rudder through the servo, or its actual rudder
directly if that is all it has.  A zig-zag or a turn starts from its rudder execute, with the
measured state there, any other record from its first row (:func:`flight_start`): a manual
approach before an execute is neither flown nor scored.

Many records fly together: :func:`fly_like_batch` in one integration of the kernel where they
share a sampling grid, :func:`fly_jobs_like` several models of one ship side by side
(stacked).  :mod:`sindyship.evaluation` measures how far a
flight ends from its record.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from .manoeuvres import result_to_trajectory
from .simulation import (
    PrescribedRudder,
    RecordedZigZag,
    SimulationResult,
    StepCommand,
    ZigZagCommand,
    simulate_batch,
)
from .trajectory import Trajectory
from .trials import (  # noqa: F401  (detect_zigzag and recognised_zigzag are re-exported)
    FlightStart,
    detect_zigzag,
    flight_start,
    recognised_zigzag,
    trim,
    zigzag_to_fly,
)


def command_for(record: Trajectory):
    """The rudder command that re-flies a record (see the module docstring): a zig-zag as its
    flight start recognised it on the whole record (:func:`flight_start`), else as the record
    itself is recognised (:func:`zigzag_to_fly`)."""
    saved = record.meta.get("flight_start") or {}
    zigzag = saved.get("zigzag")
    if zigzag is None or abs(saved["time"] - float(record.t[0])) > 1e-9:
        found = zigzag_to_fly(record)
        zigzag = None if found is None else found[1]
    if zigzag is not None:
        angles = (math.radians(zigzag["amplitude_deg"]), math.radians(zigzag["check_deg"]),
                  int(zigzag["first_sign"]))
        if zigzag["levels_deg"] is None:
            return ZigZagCommand(*angles)
        return RecordedZigZag(*angles, levels=tuple(math.radians(level)
                                                    for level in zigzag["levels_deg"]))
    if record.has("delta_c"):
        return StepCommand(record.t, record["delta_c"])
    return PrescribedRudder(record.t, record["delta"])


def _aligned(flier, records: Sequence[Trajectory]) -> list[Trajectory]:
    """The parts of the records a flight covers (:func:`flown_part`), as a fitted model reads
    them: the channels its library delays moved to the physics' time
    (:meth:`sindyship.library.TermLibrary.aligned`), so that a replayed rudder is the one the
    water saw."""
    library = getattr(flier, "library", None)
    parts = [flown_part(r) for r in records]
    return [library.aligned(r) for r in parts] if library is not None else parts


def _dynamics_for(flier, records: Sequence[Trajectory]):
    """Dynamics that fly ``records``: a dynamics object as given, or a fitted model's dynamics
    with the channels its library uses taken from the records as time series."""
    if hasattr(flier, "accelerations") or not hasattr(flier, "dynamics"):
        return flier
    return flier.dynamics(records=records)


def fly_like(dynamics, records: Sequence[Trajectory], *, step: float | None = None
             ) -> list[Trajectory]:
    """Fly ``dynamics`` (or a fitted model, with its records' channels) the way each record
    was flown, from each record's flight start (:func:`flight_start`)."""
    out = []
    for record in _aligned(dynamics, records):
        state0 = record.state()[:, 0]
        (result,) = simulate_batch(_dynamics_for(dynamics, [record]), [command_for(record)],
                                   record.t, state0, step=step)
        out.append(result_to_trajectory(result, record.name))
    return out


def fly_like_batch(dynamics, records: Sequence[Trajectory], *, step: float | None = None
                   ) -> list[Trajectory]:
    """As :func:`fly_like`, integrating records together whose sample times are one grid or
    the start of it (records of one logger, of different lengths).

    A shorter record's member flies on to the end of the longest with its last rudder and
    channels held; its flight is cut at its own last sample, and a divergence after that
    sample is not its own.  The states at the record's samples are those of a flight of the
    record alone (``tests/test_channels.py``).
    """
    return fly_jobs_like([(dynamics, records)], step=step)[0]


def fly_jobs_like(jobs: Sequence[tuple[object, Sequence[Trajectory]]], *,
                  step: float | None = None, bar=None) -> list[list[Trajectory]]:
    """Fly several ``(dynamics or fitted model, records)`` jobs as :func:`fly_like_batch`
    flies one, in as few integrations as possible.

    Records of one job that share a grid fly in one batch; fitted models of one ship and
    rudder signal fly side by side in that batch too (their accelerations evaluated each on
    its own members, :class:`_Stacked`), so the integrator's work per step is shared by
    every model a diagnosis compares.  Each flight is that of its model alone.  ``bar``, a
    tqdm progress bar (optional), gets the seconds the integrations fly as its total and
    advances with every step.

    Returns
    -------
    list of list of Trajectory
        Per job, in the order of its records.
    """
    out: list[list] = [[None] * len(records) for _, records in jobs]
    groups: dict[tuple, list] = {}
    for i, (flier, records) in enumerate(jobs):
        key = (("model", id(flier.ship), flier.rudder_signal) if _stackable(flier)
               else ("own", i))
        for k, record in enumerate(_aligned(flier, records)):
            groups.setdefault(key, []).append((i, k, flier, record))
    batches = [(members, grid, idx) for members in groups.values()
               for grid, idx in _common_grids([m[3] for m in members])]
    if bar is not None:
        bar.reset(total=sum(float(grid[-1] - grid[0]) for _, grid, _ in batches))
    for members, grid, idx in batches:
        batch = [members[j] for j in idx]
        state0 = np.column_stack([m[3].state()[:, 0] for m in batch])
        results = simulate_batch(_batch_dynamics(batch, grid),
                                 [_command_on(m[3], grid) for m in batch], grid, state0,
                                 step=step, on_step=None if bar is None else bar.update)
        for (i, k, _, record), res in zip(batch, results, strict=True):
            out[i][k] = result_to_trajectory(_cut(res, len(record.t)), record.name)
    return out


def _command_on(record: Trajectory, grid: np.ndarray):
    """The record's command (:func:`command_for`); a replayed rudder is held on to the end of
    the batch's grid, changing at its samples as the longer records' do, so that the batch
    keeps stepping from sample to sample together (see :func:`_held_to`)."""
    command = command_for(record)
    n = len(record.t)
    if command.prescribed and len(grid) > n:
        # every Runge-Kutta stage up to the record's last sample takes the rate of its own
        # interval, so the held tail does not change the flight up to there
        return PrescribedRudder(grid, np.asarray(_held_to(record, grid)["delta"], dtype=float))
    return command


def _stackable(flier) -> bool:
    """Whether ``flier`` is a fitted model (it makes dynamics that fly beside others')."""
    return all(hasattr(flier, name) for name in ("dynamics", "library", "rudder_signal"))


def _batch_dynamics(batch, grid: np.ndarray):
    """The dynamics of a batch of ``(job, index, flier, record)`` members ordered by job: the
    flier's own with one flier, else its models' side by side."""
    parts, start = [], 0
    for stop in range(1, len(batch) + 1):
        if stop == len(batch) or batch[stop][0] != batch[start][0]:
            held = [_held_to(m[3], grid) for m in batch[start:stop]]
            parts.append((_dynamics_for(batch[start][2], held), start, stop))
            start = stop
    return parts[0][0] if len(parts) == 1 else _Stacked(tuple(parts))


class _Stacked:
    """Several fitted models' dynamics flown in one batch, each on a contiguous range of its
    members (same ship and rudder signal; simulator dynamics, see
    :func:`sindyship.simulation.simulate_batch`)."""

    time_varying = True  # the integrator then passes the members, which select the models

    def __init__(self, parts: tuple):
        self.parts = parts
        first = parts[0][0]
        self.ship = first.ship
        self.rudder_input = first.rudder_input
        self.uses_position = any(d.uses_position for d, _, _ in parts)
        self.uses_rudder_rate = any(d.uses_rudder_rate for d, _, _ in parts)

    def fly_compiled(self, integ, commands, t, state0, step, check_divergence, on_step):
        """The models' flights through the compiled loop (each on its members), or None
        where it has no form for one (:meth:`sindyship.model.AbkowitzDynamics.fly_compiled`)."""
        from ._flights_compiled import fly

        return fly(self.parts, integ, commands, t, state0, step, check_divergence, on_step)

    def accelerations(self, u, v, r, delta, psi, branch=None, t=None, members=None,
                      position=None, rudder_rate=None):
        """Each model's accelerations on its members (``members`` ascending, as the
        integrator passes them)."""
        out = (np.empty_like(u), np.empty_like(u), np.empty_like(u))
        for dynamics, start, stop in self.parts:
            lo, hi = members.searchsorted((start, stop))  # the method: called every stage
            if lo == hi:
                continue
            part = slice(lo, hi)
            extra = {}
            if dynamics.time_varying:
                extra = {"t": t, "members": members[part] - start}
            if position is not None:
                extra["position"] = (position[0][part], position[1][part])
            if rudder_rate is not None:
                extra["rudder_rate"] = rudder_rate[part]
            accelerations = dynamics.accelerations(u[part], v[part], r[part], delta[part],
                                                   psi[part], **extra)
            for whole, piece in zip(out, accelerations, strict=True):
                whole[part] = piece
        return out


def _common_grids(records: Sequence[Trajectory]) -> list[tuple[np.ndarray, list[int]]]:
    """Records grouped by sample times: each group's times are the first samples of the
    longest member's (to a millionth of the sample interval)."""
    groups: list[tuple[np.ndarray, list[int]]] = []
    for i in sorted(range(len(records)), key=lambda k: -len(records[k].t)):
        t = np.asarray(records[i].t, dtype=float)
        tol = 1e-6 * (float(np.min(np.diff(t))) if len(t) > 1 else 1.0)
        for grid, idx in groups:
            if len(t) <= len(grid) and np.allclose(grid[: len(t)], t, rtol=0.0, atol=tol):
                idx.append(i)
                break
        else:
            groups.append((t, [i]))
    return [(grid, sorted(idx)) for grid, idx in groups]


def _held_to(record: Trajectory, grid: np.ndarray) -> Trajectory:
    """The record on a longer grid that starts with its samples, its last row held."""
    n = len(record.t)
    if n == len(grid):
        return record
    data = record.data
    tail = data.iloc[np.full(len(grid) - n, n - 1)].copy()
    tail["t"] = grid[n:]
    held = pd.concat([data, tail], ignore_index=True)
    return Trajectory(held, name=record.name, meta=record.meta)


def _cut(result: SimulationResult, n: int) -> SimulationResult:
    """A batch member's flight cut to its record's ``n`` samples."""
    diverged_at = result.diverged_at
    if diverged_at is not None and diverged_at > result.t[n - 1]:
        diverged_at = None
    return SimulationResult(t=result.t[:n], states=result.states[:, :n],
                            delta_c=result.delta_c[:n], diverged_at=diverged_at)


def flown_part(record: Trajectory) -> Trajectory:
    """The record from its flight start on (:func:`flight_start`), the part a flight covers
    and is scored on (all of it when it starts at its first row); the part keeps its start
    in ``meta``, so that :func:`flight_start` reads it there instead of recognising the
    manoeuvre again."""
    return _part_from(record, flight_start(record))


def _part_from(record: Trajectory, start) -> Trajectory:
    part = record if start.time <= record.t[0] + 1e-9 else \
        trim(record, (start.time, float(record.t[-1])))
    meta = {**part.meta, "flight_start": start.as_meta()}
    return Trajectory(part.data, name=part.name, meta=meta)


def flown_as(record: Trajectory) -> dict:
    """How :func:`fly_like` flies a record, for reports.

    Returns
    -------
    dict
        ``{"flown_as": "zigzag", "amplitude_deg": A, "check_deg": C}`` for a recognised
        zig-zag (closed loop), else ``{"flown_as": "replay-commanded"}`` (the commanded rudder
        through the servo) or ``{"flown_as": "replay-actual"}`` (the recorded actual rudder);
        with ``start_s`` (the first flown and scored sample, :func:`flight_start`) and
        ``start_reason``.
    """
    start = flight_start(record)
    zigzag, reason = start.zigzag, start.reason
    if zigzag is None and start.kind != "zigzag":  # as command_for flies the part
        found = zigzag_to_fly(_part_from(record, start))
        zigzag = None if found is None else found[1]
        if zigzag is not None:  # the part alone holds a zig-zag the whole record did not
            reason += (f"; from there the record is a {zigzag['amplitude_deg']:g}/"
                       f"{zigzag['check_deg']:g} zig-zag, flown closed loop")
    if zigzag is not None:
        out = {"flown_as": "zigzag", "amplitude_deg": zigzag["amplitude_deg"],
               "check_deg": zigzag["check_deg"]}
    else:
        out = {"flown_as": "replay-commanded" if record.has("delta_c") else "replay-actual"}
    out.update(start_s=start.time, start_reason=reason)
    return out

"""What a refinement must keep before it is accepted (:func:`sindyship.refine.refine`).

A refinement by the records' flights moves every active coefficient; where the records do
not pin a combination down, disturbances the library lacks (gusts, noise, roll) can pull it
far.  Two checks catch that: the hard-over turning circles the fitted model flies must still
fly (:func:`turns_kept`), and refining on half of the records must fly the other half closer
than fitting on that half alone does (:func:`carries_over`).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd

from . import hybrid
from ._shooting_compiled import loop_flies
from .evaluation import compare_flights
from .flights import flown_part, fly_jobs_like
from .library import nondimensional_variables
from .manoeuvres import Manoeuvre, fly, turning_figures
from .model import AbkowitzModel
from .shooting import SHOOTING_STATES, fly_segments, make_segments
from .trajectory import Trajectory

__all__ = ["TURN_CHECK_FACTOR", "TURN_CHECK_TIMES", "VALIDATION_RATIO", "carries_over",
           "fitted_again", "flown_whole", "hard_over_turns", "turns_kept"]

#: A refinement is kept when, refined on half the records, it flies the others at most this
#: share of the distance of the fit on that half alone (geometric mean).
VALIDATION_RATIO = 1.0


#: The hard-over turns a refinement must keep flying: their length in L/U0, and how far their
#: tactical diameter may move from the fitted model's (a factor).
TURN_CHECK_TIMES = 30.0
TURN_CHECK_FACTOR = 2.0


def turns_kept(fitted: AbkowitzModel, refined: AbkowitzModel, records) -> str | None:
    """Why the refined model fails the hard-over turns the fitted one flies (None when it
    does not): records rarely span them (zig-zags stay within their check angles), and a
    refinement that absorbs the records' own disturbances into terms they do not pin down can
    lose them.  Turning circles to both sides at the rudder limit, from a straight run at
    U0, with the records' mean channels: each must not diverge, and must keep its tactical
    diameter and its speed at the end within a factor :data:`TURN_CHECK_FACTOR` of the fitted
    model's (a displacement ship turning hard over slows to a steady speed; one that keeps
    slowing towards rest has lost its forces)."""
    before, after = hard_over_turns(fitted, records), hard_over_turns(refined, records)
    for side in before:
        if before[side] is None:
            continue  # the fit promised nothing there
        if after[side] is None:
            return f"diverges in a hard-over turn to {side}, which the fit it started from flies"
        ratio = after[side]["tactical_diameter_L"] / before[side]["tactical_diameter_L"]
        if not 1.0 / TURN_CHECK_FACTOR <= ratio <= TURN_CHECK_FACTOR:
            return (f"turns to {side} at the rudder limit in a tactical diameter {ratio:.2g} "
                    "times the fitted model's")
        speeds = after[side]["final_speed"], before[side]["final_speed"]
        if speeds[0] < speeds[1] / TURN_CHECK_FACTOR:
            return (f"slows to {speeds[0]:.2g} U0 in a hard-over turn to {side}, where the "
                    f"fit it started from keeps {speeds[1]:.2g} U0")
    return None


def hard_over_turns(model: AbkowitzModel, records) -> dict:
    """Turning circles to starboard and port at the rudder limit, :data:`TURN_CHECK_TIMES`
    L/U0 long: their tactical diameter [L] and their speed at the end [U0]; None where the
    flight diverged or never turned 180 deg."""
    names = model.recorded_channels
    channels = {}
    if names:
        values = [nondimensional_variables(r, model.ship.L, model.ship.U0, needed=names)
                  for r in records]
        channels = {n: float(np.mean(np.concatenate([v[n] for v in values]))) for n in names}
    ship = model.ship
    duration = TURN_CHECK_TIMES * ship.time_scale
    dt = ship.time_scale / 20.0
    plan = [Manoeuvre("turning-circle", rudder=sign * ship.servo.delta_max, duration=duration,
                      dt=dt) for sign in (1, -1)]
    flights = fly(model.dynamics(channels=channels), plan)
    out = {}
    for side, flown in zip(("starboard", "port"), flights, strict=True):
        figures = None if flown.meta.get("diverged_at") is not None else \
            turning_figures(flown, ship.L)
        diameter = None if figures is None else figures.get("tactical_diameter_L")
        out[side] = None if diameter is None or not math.isfinite(diameter) else {
            "tactical_diameter_L": diameter,
            "final_speed": float(np.hypot(flown["u"][-1], flown["v"][-1]) / ship.U0)}
    return out


def carries_over(model: AbkowitzModel, records, refined_on) -> dict:
    """Whether refining carries over to flights it was not refined on (a two-way split of the
    records taken in the order of their names, so that the verdict does not depend on the
    order they were given in; records that share a name keep theirs): fitted again on every
    other record, as the model was, and refined on those
    (``refined_on(fitted, records)``), the model flies the rest (whole, as
    :func:`sindyship.evaluation.evaluate` flies them, on the refinement's grid:
    :func:`flown_whole`) closer than its fit on them alone does (geometric mean of the mean
    distances over the windows both cover below :data:`VALIDATION_RATIO`, and no new
    divergence).  Where the refinement on every other record keeps the fitted coefficients
    (refused there, or no step lowered the cost: ``half_refused`` says why), it cannot be
    shown to carry over: not accepted."""
    ordered = sorted(records, key=lambda record: record.name)
    fitted_on, flown = ordered[0::2], ordered[1::2]
    half_fit = fitted_again(model, fitted_on)
    half = refined_on(half_fit, fitted_on)
    names = {"refined_on": [r.name for r in fitted_on], "flown": [r.name for r in flown]}
    done = half.info.get("refined", {})
    if done.get("largest_change", True) is None:  # it kept the fitted coefficients
        reason = str(done.get("stopped", "")).removesuffix("; the fitted coefficients are kept")
        return {**names, "ratio": None, "accepted": False, "why": "not refined there",
                "diverged": [], "half_refused": reason}
    ratios, worse = [], []
    for (b, record), (a, _) in zip(*flown_whole([half_fit, half], flown), strict=True):
        if b is None:  # fewer than two samples from its flight start: nothing to compare
            continue
        common = compare_flights(b, a, record, model.ship.L)
        if common["worse"] == "after" and a.meta.get("diverged_at") is not None:
            worse.append(record.name)
        if common["before_mean_L"] > 0 and math.isfinite(common["after_mean_L"]):
            ratios.append(common["after_mean_L"] / common["before_mean_L"])
    ratio = float(np.exp(np.mean(np.log(ratios)))) if ratios else math.inf
    accepted = not worse and ratio < VALIDATION_RATIO
    why = (f"{', '.join(worse)} diverged" if worse else
           "no closer" if not accepted else "closer")
    return {**names, "ratio": ratio, "accepted": accepted, "why": why, "diverged": worse,
            "half_refused": None}


def flown_whole(models: Sequence[AbkowitzModel], records) -> list[list[tuple]]:
    """Each record flown whole by each model, from its flight start, on the refinement's
    grid: as :func:`sindyship.evaluation.evaluate` flies it (a zig-zag closed loop, any other
    record replaying its rudder), by the compiled loop of the refinement
    (:func:`sindyship.shooting.make_segments` without segments).

    Parameters
    ----------
    models : sequence of AbkowitzModel
        Models of one library, ship and rudder signal (a fit and its refinement): the
        records' segments are made once and flown with each model's coefficients.
    records : sequence of Trajectory

    Returns
    -------
    list of list of (Trajectory, Trajectory)
        Per model, per record: the flight and the record at the compared samples (the first,
        and every sample the RK4 steps of about 0.1 L/U0 reach; one sample for a record too
        short for a step; ``(None, None)`` for one of fewer than two samples from its
        start).  The flight holds the states (no rudder) and ``diverged_at``, its first
        compared sample out of range, with NaN from there on, as
        :func:`sindyship.simulation.simulate_batch` gives it; its divergence can come some
        seconds apart from the integrator's, whose steps differ.  Where the loop cannot fly
        the library (:func:`sindyship._shooting_compiled.loop_flies`), the flights of
        :func:`sindyship.flights.fly_jobs_like` and the records themselves.
    """
    if not loop_flies(models[0]):
        flights = fly_jobs_like([(model, records) for model in models])
        return [list(zip(flown, records, strict=True)) for flown in flights]
    out = [[(None, None)] * len(records) for _ in models]
    for batch in make_segments(models[0], records, None):
        parts = {index: flown_part(records[index]) for index in batch.record}
        for m, model in enumerate(models):
            stopped = np.empty(batch.n_segments, dtype=np.int64)
            states, _ = fly_segments(model, batch, stopped=stopped)
            for k, index in enumerate(batch.record):
                out[m][index] = _pair(batch, k, states[k], stopped[k], parts[index])
    return out


def _pair(batch, k: int, states: np.ndarray, stopped: int, record) -> tuple:
    """The flight of segment ``k`` of a batch of whole records and its record, at the
    compared samples (the record's own times)."""
    valid = np.concatenate([[True], batch.valid[k]])
    rows = np.rint(batch.step * batch.every * np.arange(len(valid)) / record.dt).astype(int)
    t = record.t[rows[valid]]
    measured = np.vstack([batch.state0[k], batch.measured[k]])[valid]
    flight = np.vstack([batch.state0[k], states])[valid]
    meta = {"diverged_at": None}
    if stopped >= 0:
        first = stopped // batch.every + 1  # the initial state is row 0
        flight[first:] = np.nan
        meta["diverged_at"] = float(t[first]) if first < len(t) else None
    frames = [pd.DataFrame({"t": t, **dict(zip(SHOOTING_STATES, values.T, strict=True))})
              for values in (flight, measured)]
    return (Trajectory(frames[0], name=record.name, meta=meta),
            Trajectory(frames[1], name=record.name))


def fitted_again(model: AbkowitzModel, records) -> AbkowitzModel:
    """The model's fit (its library, optimizer and parameters, rudder signal, acceleration
    estimate and captive rows: :func:`sindyship.hybrid.fitted_again`) on other records."""
    with warnings.catch_warnings():  # the fit warned once already
        warnings.simplefilter("ignore")
        return hybrid.fitted_again(model, records)

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

import numpy as np
import pandas as pd

from .evaluation import compare_flights
from .identify import fit
from .library import nondimensional_variables
from .manoeuvres import Manoeuvre, fly, turning_figures
from .model import AbkowitzModel
from .shooting import fly_segments, make_segments
from .trajectory import Trajectory

__all__ = ["TURN_CHECK_FACTOR", "TURN_CHECK_TIMES", "VALIDATION_RATIO", "carries_over",
           "fitted_again", "flown_whole", "hard_over_diameters", "turns_kept"]

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
    U0, with the records' mean channels."""
    before, after = hard_over_diameters(fitted, records), hard_over_diameters(refined, records)
    for side in before:
        if before[side] is None:
            continue  # the fit promised nothing there
        if after[side] is None:
            return f"diverges in a hard-over turn to {side}"
        ratio = after[side] / before[side]
        if not 1.0 / TURN_CHECK_FACTOR <= ratio <= TURN_CHECK_FACTOR:
            return (f"turns to {side} at the rudder limit in a tactical diameter {ratio:.2g} "
                    "times the fitted model's")
    return None


def hard_over_diameters(model: AbkowitzModel, records) -> dict:
    """Tactical diameters [L] of hard-over turning circles to starboard and port (None where
    the flight diverged or never turned 180 deg)."""
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
        out[side] = diameter if diameter is not None and math.isfinite(diameter) else None
    return out


def carries_over(model: AbkowitzModel, records, refined_on) -> dict:
    """Whether refining carries over to flights it was not refined on (a two-way split of the
    records): fitted again on every other record, as the model was, and refined on those
    (``refined_on(fitted, records)``), the model flies the rest (whole, as
    :func:`sindyship.evaluation.evaluate` flies them, on the refinement's grid:
    :func:`flown_whole`) closer than its fit on them alone does (geometric mean of the mean
    distances over the windows both cover below :data:`VALIDATION_RATIO`, and no new
    divergence)."""
    fitted_on, flown = list(records[0::2]), list(records[1::2])
    half_fit = fitted_again(model, fitted_on)
    half = refined_on(half_fit, fitted_on)
    ratios, worse = [], []
    for (b, record), (a, _) in zip(flown_whole(half_fit, flown), flown_whole(half, flown),
                                   strict=True):
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
    return {"refined_on": [r.name for r in fitted_on], "flown": [r.name for r in flown],
            "ratio": ratio, "accepted": accepted, "why": why}


def flown_whole(model: AbkowitzModel, records) -> list[tuple]:
    """Each record flown whole from its flight start by the refinement's compiled loop
    (:func:`sindyship.shooting.make_segments` without segments: a zig-zag closed loop, any
    other record replaying its rudder, as :func:`sindyship.evaluation.evaluate` flies them,
    with RK4 steps of whole samples): per record the flight and the record at the compared
    samples (its first and every ``every``-th step's), or (None, None) for a record of fewer
    than two samples from its start.  A diverged flight holds ``diverged_at`` (its first
    compared sample out of range) and NaN from there on, as
    :func:`sindyship.simulation.simulate_batch` gives it; the flights hold the states only.
    """
    out: list[tuple] = [(None, None)] * len(records)
    names = ("u", "v", "r", "x", "y", "psi")
    for batch in make_segments(model, records, None):
        stopped = np.empty(batch.n_segments, dtype=np.int64)
        states, _ = fly_segments(model, batch, stopped=stopped)
        n_out = states.shape[1]
        for k, index in enumerate(batch.record):
            valid = np.concatenate([[True], batch.valid[k]])
            t = (batch.start[k] + batch.step * batch.every * np.arange(n_out + 1))[valid]
            measured = np.vstack([batch.state0[k], batch.measured[k]])[valid]
            flight = np.vstack([batch.state0[k], states[k]])[valid]
            meta = {"diverged_at": None}
            if stopped[k] >= 0:
                first = stopped[k] // batch.every + 1  # the initial state is row 0
                flight[first:] = np.nan
                meta["diverged_at"] = float(t[first]) if first < len(t) else None
            frames = [pd.DataFrame({"t": t, **dict(zip(names, rows.T, strict=True))})
                      for rows in (flight, measured)]
            name = records[index].name
            out[index] = (Trajectory(frames[0], name=name, meta=meta),
                          Trajectory(frames[1], name=name))
    return out


def fitted_again(model: AbkowitzModel, records) -> AbkowitzModel:
    """The model's fit (its library, optimizer and parameters, rudder signal and acceleration
    estimate) on other records."""
    window = model.info.get("window_s")
    with warnings.catch_warnings():  # the fit warned once already
        warnings.simplefilter("ignore")
        return fit(records, model.ship, library=model.library,
                   optimizer=model.optimizer["name"], params=dict(model.optimizer["params"]),
                   rudder_signal=model.rudder_signal,
                   derivative=model.info.get("derivative", "five-point"),
                   window=21.0 if window is None else window)

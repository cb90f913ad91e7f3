"""Flights of identified models like the records, in parallel processes when asked."""

from __future__ import annotations

import sys
from collections.abc import Sequence

from ..flights import fly_jobs_like, fly_like_batch
from ..library import (
    DOFS,
    TermLibrary,
)
from ..model import AbkowitzModel
from ..trajectory import Trajectory

#: The flights' progress bar: seconds of flight integrated, of all the integrations' total.
_SECONDS_BAR = ("{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} s flown "
                "[{elapsed}<{remaining}]")


# =============================================================================== flights
def fly_model(model: AbkowitzModel, records: Sequence[Trajectory]) -> list[Trajectory]:
    """Fly an identified model the way each record was flown.

    The flights of ``fly_like_batch(model, records)`` (:mod:`sindyship.evaluation`): zig-zags
    closed loop, other records replaying their rudder, from each record's first row.  Channels
    the library uses beyond the heading (``n``, ``wind_speed``, ...) come from each record as
    time series, interpolated at the integrator's stage times.

    Parameters
    ----------
    model : AbkowitzModel
    records : sequence of Trajectory

    Returns
    -------
    list of Trajectory
        In the order of ``records``; ``meta["diverged_at"]`` is the divergence time or None.
    """
    return fly_like_batch(model, records)


def _model_payload(model: AbkowitzModel) -> dict:
    """What a worker process needs to rebuild a model (a TermLibrary does not pickle)."""
    return {
        "ship": model.ship,
        "library": model.library.to_dict(),
        "coefficients": {dof: dict(model.coefficients[dof]) for dof in DOFS},
        "rudder_signal": model.rudder_signal,
    }


def _fly_payload(payload: dict, records: Sequence[Trajectory]) -> list[Trajectory]:
    model = AbkowitzModel(
        ship=payload["ship"],
        library=TermLibrary.from_dict(payload["library"]),
        coefficients=payload["coefficients"],
        rudder_signal=payload["rudder_signal"],
    )
    return fly_model(model, records)


def _fly_many(
    jobs: Sequence[tuple[AbkowitzModel, Sequence[Trajectory]]],
    *,
    n_jobs: int,
    progress: bool,
    what: str,
) -> list[list[Trajectory]]:
    """Fly several (model, records) jobs: in one process side by side
    (:func:`sindyship.flights.fly_jobs_like`), or in parallel processes when ``n_jobs`` != 1."""
    from tqdm.auto import tqdm

    jobs = [(model, list(records)) for model, records in jobs if records]
    if not jobs:
        return []
    if n_jobs == 1 or len(jobs) == 1:
        # every model side by side in one integration per grid: progress in seconds flown
        bar = tqdm(total=1, desc=what, file=sys.stderr, disable=not progress, leave=False,
                   bar_format=_SECONDS_BAR, delay=0.5)  # fly_jobs_like sets the total
        out = fly_jobs_like(jobs, bar=bar)
    else:
        bar = tqdm(total=len(jobs), desc=what, file=sys.stderr, disable=not progress,
                   leave=False)
        from joblib import Parallel, delayed

        calls = [delayed(_fly_payload)(_model_payload(model), records)
                 for model, records in jobs]
        try:  # each flight counted as it lands
            results = Parallel(n_jobs=n_jobs, return_as="generator")(calls)
        except ValueError as exc:  # a backend that cannot hand results on one by one
            if "return_as" not in str(exc):  # (Dask under joblib < 1.4): all at the end
                raise
            results = Parallel(n_jobs=n_jobs)(calls)
        out = []
        for flown in results:
            out.append(flown)
            bar.update()
    bar.close()
    return out

"""Choosing the smoothing by leave-one-manoeuvre-out flights of the training records."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd

from ..errors import SindyshipInputError
from ..ships import Ship
from ..targets import savgol_points
from ..trajectory import Trajectory
from ._apply import smooth_records
from ._settings import SmoothingSetting, default_candidates


# ---------------------------------------------------------------------------------------------
# Choosing the setting by leave-one-manoeuvre-out cross-validation
# ---------------------------------------------------------------------------------------------
def _as_setting(candidate: SmoothingSetting | str | Mapping | tuple) -> SmoothingSetting:
    if isinstance(candidate, SmoothingSetting):
        return candidate
    if isinstance(candidate, str):
        return SmoothingSetting.parse(candidate)
    if isinstance(candidate, Mapping):
        return SmoothingSetting(candidate.get("method", "none"),
                                float(candidate.get("window", candidate.get("window_s", 21.0))),
                                int(candidate.get("order", 3)))
    return SmoothingSetting(*candidate)


def _fold_task(smoothed: Sequence[Trajectory], raw: Trajectory, held_out: int, ship: Ship,
               library, optimizer: str, params: dict | None, fit_settings: Mapping,
               step: float | None) -> dict:
    """Fit on all smoothed records but one, fly like the raw held-out one, measure."""
    from threadpoolctl import threadpool_limits

    from ..evaluation import distance_errors
    from ..flights import fly_like
    from ..identify import fit

    train = [r for k, r in enumerate(smoothed) if k != held_out]
    start = _with_initial_state(raw, smoothed[held_out])
    with threadpool_limits(limits=1, user_api="blas"):
        model = fit(train, ship, library=library, optimizer=optimizer, params=params,
                    part_of_set=True, **fit_settings)
        (flown,) = fly_like(model, [start], step=step)
    return distance_errors(flown, raw, ship.L)


def _fits_every(setting: SmoothingSetting, records: Sequence[Trajectory]) -> bool:
    """Whether a Savitzky-Golay setting's window holds enough samples of every record for its
    polynomial and is no longer than any record (:func:`sindyship.targets.savgol_points`)."""
    if setting.method != "savgol":
        return True
    try:
        for record in records:
            savgol_points(setting.window, record.dt, setting.order, record.n_samples, "")
    except SindyshipInputError:
        return False
    return True


def _with_initial_state(raw: Trajectory, smoothed: Trajectory) -> Trajectory:
    """The raw record with its first row's motion state taken from the smoothed record.

    A flight starts from the first row; the smoother's estimate of the initial velocities is
    better than one noisy sample (a single sample's yaw-rate noise can turn a course-unstable
    model away from a straight run).  Everything else, and so the rudder programme and the
    zig-zag detection, stays as recorded.
    """
    data = raw.data.copy()
    for column in ("u", "v", "r", "x", "y", "psi"):
        data.loc[data.index[0], column] = float(smoothed[column][0])
    return Trajectory(data, name=raw.name, meta=dict(raw.meta))


def _cv_scores(means: np.ndarray, failed: np.ndarray) -> np.ndarray:
    """Geometric mean over folds of the held-out flight distance, per candidate.

    ``means[i, k]`` is candidate i's mean distance on held-out record k.  A flight that
    diverged counts as the worst complete flight of any candidate on that record (at least
    its own distance before diverging); where every candidate diverged, the largest distance
    before divergence.  The geometric mean weighs every held-out manoeuvre alike, whatever
    its scale: a record whose flights all miss by tens of ship lengths (a straight run of a
    course-unstable ship, where any model drifts) neither dominates nor decides the choice.
    """
    filled = np.where(failed | ~np.isfinite(means), np.nan, means)
    worst = np.nanmax(np.where(np.isfinite(means), means, np.nan), axis=0, initial=0.0)
    complete_worst = np.nanmax(filled, axis=0, initial=-np.inf)
    penalty = np.where(np.isfinite(complete_worst), complete_worst, worst)
    own = np.where(np.isfinite(means), means, 0.0)
    values = np.where(failed | ~np.isfinite(means), np.maximum(penalty[None, :], own), means)
    values = np.maximum(values, 1e-12)
    return np.exp(np.mean(np.log(values), axis=1))


def choose_smoothing(records: Sequence[Trajectory], ship: Ship,
                     candidates: Iterable[SmoothingSetting | str] | None = None,
                     optimizer: str = "ls", *, library="abkowitz", effects: Sequence[str] = (),
                     params: dict | None = None, rudder_signal: str = "actual",
                     derivative: str = "five-point", window: float = 21.0,
                     n_jobs: int | None = None, step: float | None = None
                     ) -> tuple[SmoothingSetting, pd.DataFrame]:
    """The smoothing setting with the smallest leave-one-manoeuvre-out flight error.

    Uses the training records only (module docstring): for every candidate and record, the
    model is fitted on the other records smoothed with the candidate, then flown the way the
    held-out record was flown (zig-zags closed loop) from its first row, and compared with
    the held-out record's measured track.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records (at least two); nothing else is used.
    ship : Ship
        The ship (L, U0, inertia, rudder servo).
    candidates : iterable of SmoothingSetting or str, optional
        Settings to compare (``"savgol:21"`` style text is accepted); default
        :func:`default_candidates` of the ship (windows in ship time), those a record is too
        short or too coarsely sampled for left out.
    optimizer : str
        Regression method of the folds (:func:`sindyship.optimizers.make_optimizer`).
    library, effects, params, rudder_signal, derivative, window
        As for :func:`sindyship.identify.fit`.
    n_jobs : int, optional
        joblib workers for the smoothing and the folds (``None``: joblib's default, one
        unless inside a ``joblib.parallel_config`` block; ``-1``: every core).  The result does
        not depend on it.
    step : float, optional
        Runge-Kutta step of the flights [s].

    Returns
    -------
    best : SmoothingSetting
        The candidate with the smallest score.
    table : pandas.DataFrame
        One row per candidate: ``setting``, ``method``, ``window_s``, ``order``, ``score_L``
        (the geometric mean over held-out records of the flight's mean distance in ship
        lengths, a diverged flight counting as the worst complete one on its record),
        ``n_diverged``, one column per held-out record (its mean distance, over the samples
        before any divergence) and ``chosen``.

    Raises
    ------
    SindyshipInputError
        For fewer than two records, no candidates, or a bad candidate.
    """
    from joblib import Parallel, delayed

    from ..arguments import as_ship
    from ..identify import resolve_library

    ship = as_ship(ship)
    records = list(records)
    if len(records) < 2:
        raise SindyshipInputError(
            "choosing the smoothing by leave-one-manoeuvre-out cross-validation needs at "
            f"least two training records, not {len(records)}."
        )
    settings = ([s for s in default_candidates(ship) if _fits_every(s, records)]
                if candidates is None else [_as_setting(c) for c in candidates])
    if not settings:
        raise SindyshipInputError("give at least one smoothing candidate.")
    names = [r.name or f"record {k}" for k, r in enumerate(records)]
    lib = resolve_library(library, effects)

    fit_settings = {"rudder_signal": rudder_signal, "derivative": derivative, "window": window}
    parallel = Parallel(n_jobs=n_jobs)
    smoothed = parallel(delayed(smooth_records)(records, setting) for setting in settings)
    folds = parallel(
        delayed(_fold_task)(smoothed[i], records[k], k, ship, lib, optimizer, params,
                            fit_settings, step)
        for i in range(len(settings)) for k in range(len(records))
    )
    n_rec = len(records)
    means = np.array([[e["mean_distance_L"] for e in folds[i * n_rec:(i + 1) * n_rec]]
                      for i in range(len(settings))])
    failed = np.array([[e["diverged_at_s"] is not None or not math.isfinite(e["mean_distance_L"])
                        for e in folds[i * n_rec:(i + 1) * n_rec]]
                       for i in range(len(settings))])
    score = _cv_scores(means, failed)
    rows = []
    for i, setting in enumerate(settings):
        row = {"setting": setting.label, "method": setting.method,
               "window_s": setting.window if setting.method != "none" else math.nan,
               "order": setting.order if setting.method == "savgol" else math.nan,
               "score_L": float(score[i]),
               "n_diverged": int(failed[i].sum())}
        row.update({name: float(means[i, k]) for k, name in enumerate(names)})
        rows.append(row)
    table = pd.DataFrame(rows)
    best = int(np.argmin(np.where(np.isfinite(score), score, np.inf)))
    table["chosen"] = False
    table.loc[best, "chosen"] = True
    return settings[best], table


def resolve_smoothing(smoothing, records: Sequence[Trajectory], ship: Ship, *, library="abkowitz",
                      optimizer: str = "ls", rudder_signal: str = "actual",
                      derivative: str = "five-point", window: float = 21.0,
                      n_jobs: int | None = None) -> SmoothingSetting | None:
    """The smoothing to apply: None (for None or ``"none"``), the given setting (a
    :class:`SmoothingSetting` or its text, ``"savgol:W"``, ``"rts:W"``), or the one
    ``"auto"`` chooses with :func:`choose_smoothing` on ``records``.

    Examples
    --------
    >>> resolve_smoothing("savgol:21", [], None).as_dict()["window_s"]
    21.0
    >>> resolve_smoothing("none", [], None) is None
    True
    """
    if smoothing is None or smoothing == "none":
        return None
    if smoothing == "auto":
        setting, _ = choose_smoothing(records, ship, optimizer=optimizer, library=library,
                                      rudder_signal=rudder_signal, derivative=derivative,
                                      window=window, n_jobs=n_jobs)
    elif isinstance(smoothing, SmoothingSetting):
        setting = smoothing
    else:
        setting = SmoothingSetting.parse(smoothing)
    return None if setting.method == "none" else setting

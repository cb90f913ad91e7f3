"""How far a flight ends from its record: the Table-10 metric and its summaries.

:mod:`sindyship.flights` flies a model the way a record was flown; :func:`evaluate` does both
for a model and its records.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np

from .flights import flight_start, flown_as, flown_part, fly_like_batch
from .trajectory import Trajectory


def _before_divergence(flown: Trajectory) -> np.ndarray:
    """Samples a flight covers: finite, and before its divergence (docs/protocol.md, Divergence)."""
    ok = np.isfinite(flown["x"]) & np.isfinite(flown["y"])
    diverged_at = flown.meta.get("diverged_at")
    if diverged_at is not None:
        ok &= flown.t < diverged_at
    return ok


def matching_part(reference: Trajectory, flown: Trajectory) -> Trajectory:
    """The samples of ``reference`` a flight covers: the flight starts at the record's flight
    start (:func:`sindyship.flights.flight_start`), so a record with an approach before its
    execute is longer than its flight; the record as it is when the two have equal length."""
    if reference.n_samples == flown.n_samples:
        return reference
    t0 = float(flown.t[0]) if flown.n_samples else float(reference.t[0])
    first = int(np.searchsorted(reference.t, t0 - 1e-9 * max(1.0, abs(t0))))
    part = reference.data.iloc[first:first + flown.n_samples].reset_index(drop=True)
    if len(part) != flown.n_samples:
        raise ValueError(f"the flight of {reference.name!r} ({flown.n_samples} samples from "
                         f"t = {t0:g} s) is not a part of its record")
    return Trajectory(part, name=reference.name, meta=reference.meta)


def flown_seconds(flown: Trajectory) -> float:
    """How long a flight flew [s]: its samples before any divergence times the sample
    interval (a complete 3200-sample record at 1 Hz flew 3200 s)."""
    if flown.n_samples < 2:
        return 0.0
    return float(np.count_nonzero(_before_divergence(flown))) * flown.dt


def distance_errors(flown: Trajectory, reference: Trajectory, L: float) -> dict:
    """Table-10 metric: mean and maximum Euclidean distance [ship lengths] between tracks.

    A diverged flight has failed (``completed`` is False): its mean is over the samples
    before the divergence, reported with that time and never alone; a flight that diverges
    at its first sample has no mean (NaN, ``null`` in JSON), never 0.

    Returns
    -------
    dict
        ``mean_distance_L``, ``max_distance_L``, ``diverged_at_s`` (None if it did not),
        ``completed`` (bool) and ``flown_s`` [s].
    """
    reference = matching_part(reference, flown)
    dist = np.hypot(flown["x"] - reference["x"], flown["y"] - reference["y"]) / L
    diverged_at = flown.meta.get("diverged_at")
    valid = _before_divergence(flown) & np.isfinite(dist)
    out = {"mean_distance_L": math.nan, "max_distance_L": math.nan,
           "diverged_at_s": diverged_at, "completed": diverged_at is None and bool(valid.all()),
           "flown_s": flown_seconds(flown)}
    if valid.any():
        out["mean_distance_L"] = float(dist[valid].mean())
        out["max_distance_L"] = float(dist[valid].max())
    return out


def compare_flights(before: Trajectory, after: Trajectory, reference: Trajectory, L: float
                    ) -> dict:
    """Two flights of one record compared over the samples both cover (docs/protocol.md).

    A flight that diverges where the other does not (or earlier) is the worse one, whatever
    the means; otherwise the smaller mean distance over the common window is the better.

    Returns
    -------
    dict
        ``window_s`` (length of the common window [s]), ``before_mean_L`` and
        ``after_mean_L`` over it, and ``worse``: ``"before"``, ``"after"`` or None (equal).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> (run,) = fly(MMGModel(load_ship("kcs")), [Manoeuvre("turning-circle", duration=100)])
    >>> from dataclasses import replace
    >>> cut = replace(run, meta={**run.meta, "diverged_at": 50.0})
    >>> result = compare_flights(run, cut, run, 230.0)
    >>> result["worse"], result["window_s"]
    ('after', 50.0)
    """
    reference = matching_part(reference, before)
    common = _before_divergence(before) & _before_divergence(after)
    means = {}
    for when, flown in (("before", before), ("after", after)):
        dist = np.hypot(flown["x"] - reference["x"], flown["y"] - reference["y"]) / L
        means[when] = float(dist[common].mean()) if common.any() else math.nan
    ends = {when: flown.meta.get("diverged_at") for when, flown in (("before", before),
                                                                   ("after", after))}
    window = float(common.sum()) * reference.dt if len(reference.t) > 1 else 0.0
    if ends["before"] != ends["after"]:
        if ends["before"] is None:
            worse = "after"
        elif ends["after"] is None:
            worse = "before"
        else:
            worse = "before" if ends["before"] < ends["after"] else "after"
    elif means["before"] == means["after"] or not common.any():
        worse = None
    else:
        worse = "after" if means["after"] > means["before"] else "before"
    return {"window_s": window, "before_mean_L": means["before"],
            "after_mean_L": means["after"], "worse": worse}


def error_summary(flown: Trajectory, reference: Trajectory, L: float) -> dict:
    """Distance errors plus RMS heading [deg] and speed [m/s] errors."""
    out = distance_errors(flown, reference, L)
    reference = matching_part(reference, flown)
    dpsi = np.degrees(flown["psi"] - reference["psi"])
    du = np.hypot(flown["u"], flown["v"]) - np.hypot(reference["u"], reference["v"])
    ok = np.isfinite(dpsi)
    out["rms_heading_deg"] = float(np.sqrt(np.mean(dpsi[ok] ** 2))) if ok.any() else math.nan
    out["rms_speed_m_s"] = float(np.sqrt(np.mean(du[ok] ** 2))) if ok.any() else math.nan
    return out


def evaluate(model, records: Sequence[Trajectory], *, step: float | None = None) -> dict:
    """Fly a model like each record and report the Table-10 distances per record name.

    A zig-zag or a turn is flown and scored from its rudder execute
    (:func:`sindyship.flights.flight_start`).  Each entry is :func:`distance_errors` plus
    :func:`flown_as` (``start_s`` and ``start_reason`` say where the flight started and why),
    and for a turn ``turn``: its figures flown and recorded (:func:`turn_figures`); for a
    zig-zag flown closed loop ``zigzag``: its overshoots and period flown and recorded
    (:func:`zigzag_overshoots`).
    """
    return evaluate_with_flights(model, records, step=step)[0]


def evaluate_with_flights(model, records: Sequence[Trajectory], *, step: float | None = None
                          ) -> tuple[dict, dict[str, tuple[Trajectory, Trajectory]]]:
    """:func:`evaluate`'s report, and the flights it scored by record name, each beside the
    part of its record it was flown like and scored on (from its flight start):
    ``{name: (part, flown)}``, as :func:`sindyship.plotting.plot_comparison` draws them."""
    from .arguments import as_records, check_distinct_names, check_records
    from .model import AbkowitzModel

    if isinstance(model, str | os.PathLike):
        model = AbkowitzModel.load(model)
    if not hasattr(model, "ship"):
        raise TypeError(f"model must be an AbkowitzModel or a saved model's path, not "
                        f"{type(model).__name__}.")
    records = check_records(as_records(records), model.ship)
    check_distinct_names(records)  # the errors are keyed by name
    check_recorded_channels(model, records)
    cut = [flown_part(record) for record in records]
    flown = fly_like_batch(model, cut, step=step)
    out, flights = {}, {}
    for rec, short, f in zip(records, cut, flown, strict=True):
        out[rec.name] = {**distance_errors(f, short, model.ship.L), **flown_as(rec)}
        if flight_start(short).kind == "turn":  # read from the part's meta
            out[rec.name]["turn"] = turn_figures(f, short, model.ship.L)
        elif out[rec.name]["flown_as"] == "zigzag":
            out[rec.name]["zigzag"] = zigzag_overshoots(f, short)
        flights[rec.name] = (short, f)
    return out, flights


def check_recorded_channels(model, records: Sequence[Trajectory]) -> None:
    """Every record must hold every channel a flight of ``model`` reads from it
    (:attr:`sindyship.model.AbkowitzModel.recorded_channels`).

    Raises
    ------
    SindyshipInputError
        Naming every record that lacks one and the channels it lacks (up to
        :data:`LISTED_RECORDS` records), before anything is flown.
    """
    from .errors import SindyshipInputError

    lacking = [(f'"{record.name}"' if record.name else f"record {k + 1}",
                [c for c in model.recorded_channels if not record.has(c)])
               for k, record in enumerate(records)]
    lacking = [(label, columns) for label, columns in lacking if columns]
    if not lacking:
        return
    listed = "; ".join(f"{label} has no {', '.join(repr(c) for c in columns)}"
                       for label, columns in lacking[:LISTED_RECORDS])
    more = len(lacking) - LISTED_RECORDS
    used = ", ".join(repr(c) for c in model.recorded_channels)
    raise SindyshipInputError(
        f"the model's library reads {used} from every record it flies, and {len(lacking)} of "
        f"{len(records)} records {'lacks' if len(lacking) == 1 else 'lack'} some ({listed}"
        f"{f'; and {more} more' if more > 0 else ''}); add the columns to the records, or fly "
        "them with a model fitted without the terms that use them."
    )


#: Most records a refusal of :func:`check_recorded_channels` names.
LISTED_RECORDS = 5


#: The figures of a turning circle :func:`evaluate` reports (IMO MSC.137(76), the steady
#: diameter, which shows the steady yaw rate, and the speed loss).
TURN_FIGURES = ("advance_L", "tactical_diameter_L", "steady_diameter_L", "speed_loss")


def turn_figures(flown: Trajectory, recorded: Trajectory, L: float) -> dict:
    """A turn's side, advance, tactical and steady diameter [L] (the steady one needs a turn
    and a half with the rudder held) and speed loss (1 - steady U / approach U), flown and
    recorded, both from the flight's first sample, the rudder execute
    (:func:`sindyship.manoeuvres.turning_figures`); None where the flight diverged or the
    turn never reached the heading change a figure needs.  A flight that turns to the other
    side than the record has no figures to compare (``"flown"`` holds its side alone).

    Examples
    --------
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.ships import load_ship
    >>> ship = load_ship("kcs")
    >>> (run,) = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=35, duration=900)])
    >>> figures = turn_figures(run, run, ship.L)
    >>> figures["flown"] == figures["recorded"], round(figures["recorded"]["advance_L"], 2)
    (True, 3.56)
    """
    from .manoeuvres import turning_figures

    def figures(run: Trajectory) -> dict | None:
        values = _finite(run, lambda: turning_figures(run, L, execute=0), TURN_FIGURES)
        side = "starboard" if run["psi"][-1] >= run["psi"][0] else "port"
        return None if values is None else {"side": side, **values}

    out = {"flown": figures(flown), "recorded": figures(recorded)}
    if out["flown"] and out["recorded"] and out["flown"]["side"] != out["recorded"]["side"]:
        out["flown"] = {"side": out["flown"]["side"], **dict.fromkeys(TURN_FIGURES)}
    return out


#: The figures of a zig-zag :func:`evaluate` reports (IMO MSC.137(76): the overshoots).
ZIGZAG_FIGURES = ("first_overshoot_deg", "second_overshoot_deg", "period_s")


def zigzag_overshoots(flown: Trajectory, recorded: Trajectory) -> dict:
    """A zig-zag's first and second overshoot angles [deg] and its period [s], flown and
    recorded, both from the flight's first sample, the rudder execute
    (:func:`sindyship.manoeuvres.zigzag_figures`); None where the flight diverged or the
    zig-zag never reached the reversal a figure needs.

    Examples
    --------
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.ships import load_ship
    >>> (run,) = fly(MMGModel(load_ship("kcs")), [Manoeuvre("zigzag", rudder=10, check=10,
    ...                                                      duration=900)])
    >>> figures = zigzag_overshoots(run, run)
    >>> figures["flown"] == figures["recorded"], round(figures["recorded"]["first_overshoot_deg"])
    (True, 12)
    """
    from .manoeuvres import zigzag_figures

    return {name: _finite(run, lambda run=run: zigzag_figures(run), ZIGZAG_FIGURES)
            for name, run in (("flown", flown), ("recorded", recorded))}


def _finite(run: Trajectory, measured, keys) -> dict | None:
    """The figures ``measured()`` gives for ``run`` under ``keys``, None where one is not
    finite; None for a flight that diverged."""
    if run.meta.get("diverged_at") is not None:
        return None
    values = measured()
    return {k: float(values[k]) if math.isfinite(values[k]) else None for k in keys}

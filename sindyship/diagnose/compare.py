"""Compare: the identified model flown like each record, and the error per manoeuvre."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from ..evaluation import error_summary
from ..model import AbkowitzModel
from ..reports import SETS
from ..trajectory import Trajectory
from ._flights import fly_model


# =============================================================================== compare
@dataclass(frozen=True)
class ManoeuvreComparison:
    """A record beside the model flown the same way, and the error summary.

    Attributes
    ----------
    name : str
        The record.
    set : {"training", "held-out"}
    record, flown : Trajectory
        The measurement and the flight.
    errors : dict
        ``mean_distance_L``, ``max_distance_L`` [ship lengths], ``diverged_at_s`` [s or
        None], ``rms_heading_deg``, ``rms_speed_m_s`` (:func:`sindyship.evaluation.error_summary`).
    """

    name: str
    set: str
    record: Trajectory = field(repr=False)
    flown: Trajectory = field(repr=False)
    errors: dict


def compare(
    model: AbkowitzModel,
    records: Sequence[Trajectory],
    *,
    kind: str = "training",
    flights: Sequence[Trajectory] | None = None,
) -> list[ManoeuvreComparison]:
    """Fly the model like each record and summarise the error per manoeuvre.

    Parameters
    ----------
    model : AbkowitzModel
    records : sequence of Trajectory
    kind : {"training", "held-out"}
        Which set the records belong to (for reports).
    flights : sequence of Trajectory, optional
        The flights, if already flown (:func:`fly_model`).

    Returns
    -------
    list of ManoeuvreComparison

    Examples
    --------
    >>> from sindyship import load_ship, paper_model, Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> model = paper_model(ship)
    >>> (run,) = fly(model.dynamics(), [Manoeuvre("turning-circle", rudder=20, duration=300)])
    >>> (row,) = compare(model, [run])
    >>> row.errors["mean_distance_L"] < 1e-6, row.errors["diverged_at_s"]
    (True, None)
    """
    from ..arguments import as_records, check_records

    if kind not in SETS:
        raise ValueError(f"kind must be one of {SETS}, not {kind!r}")
    records = check_records(as_records(records), model.ship)
    flown = list(flights) if flights is not None else fly_model(model, records)
    return [
        ManoeuvreComparison(rec.name, kind, rec, f, error_summary(f, rec, model.ship.L))
        for rec, f in zip(records, flown, strict=True)
    ]

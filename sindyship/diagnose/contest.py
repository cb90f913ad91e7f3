"""Flights decide between a discovered family and a catalogued effect that stands in for it.

Shares of the force residual say how much of the equation error an extension removes, not what
it does to a flight: a catalogued effect can take a share of the residual that a spatial or
delayed effect leaves behind, and fly worse.  :func:`flight_contest` fits the library with each
extension leaving one manoeuvre out, flies the manoeuvre left out with both fits (as
:func:`sindyship.evaluation.evaluate` flies it) and compares them over the samples both flights
cover (:func:`sindyship.evaluation.compare_flights`): fewer divergences win, then the smaller
geometric mean of the mean distances.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .._io import clean_json
from ..evaluation import compare_flights
from ..flights import fly_jobs_like
from ..identify import Design, design, fit
from ..library import DOFS, Effect, TermLibrary
from ..ships import Ship
from ..trajectory import Trajectory

__all__ = ["FlightContest", "flight_contest"]


@dataclass
class FlightContest:
    """A discovered family against a catalogued effect, judged by left-out flights.

    Attributes
    ----------
    finding, catalogued : str
        The finding's family and the catalogued effect's name.
    finding_L, catalogued_L : float
        Geometric means over the left-out manoeuvres of the mean distance [L] of each fit's
        flight, over the samples both flights of a manoeuvre cover.
    finding_diverged, catalogued_diverged : list of str
        Manoeuvres whose flight diverged where the other's did not (or earlier).
    winner : {"finding", "catalogued"}
        The one with fewer such divergences, then the smaller geometric mean (a tie keeps the
        catalogued effect).
    per_record : dict
        Manoeuvre -> ``{"finding_L", "catalogued_L", "window_s", "worse"}``.
    """

    finding: str
    catalogued: str
    finding_L: float
    catalogued_L: float
    finding_diverged: list[str]
    catalogued_diverged: list[str]
    winner: str
    per_record: dict

    def sentence(self) -> str:
        """One sentence: which flew better, with both numbers."""
        def side(label, value, diverged):
            text = f"{label} {value:.3g} L"
            return text + (f" ({', '.join(diverged)} diverged)" if diverged else "")

        ours = side(f"the finding {self.finding}", self.finding_L, self.finding_diverged)
        theirs = side(f"the catalogued {self.catalogued}", self.catalogued_L,
                      self.catalogued_diverged)
        won = self.finding if self.winner == "finding" else self.catalogued
        return (f"Left-out flights (geometric mean distance): {ours}, {theirs}; "
                f"{won} flies better and wins.")

    def to_json(self) -> dict:
        return clean_json({
            "finding": self.finding, "catalogued": self.catalogued,
            "finding_L": self.finding_L, "catalogued_L": self.catalogued_L,
            "finding_diverged": self.finding_diverged,
            "catalogued_diverged": self.catalogued_diverged, "winner": self.winner,
            "per_record": self.per_record,
        })


def _subset(problems: Mapping[str, Design], keep: np.ndarray) -> dict[str, Design]:
    """The designs of the samples ``keep`` marks (the groups renumbered from 0)."""
    groups = problems["X"].groups[keep]
    _, renumbered = np.unique(groups, return_inverse=True)
    return {dof: Design(features=problems[dof].features[keep],
                        target=problems[dof].target[keep], groups=renumbered,
                        terms=problems[dof].terms) for dof in DOFS}


def _geometric_mean(values: Sequence[float]) -> float:
    finite = [v for v in values if math.isfinite(v) and v > 0]
    return float(np.exp(np.mean(np.log(finite)))) if finite else math.nan


def flight_contest(fitted: Sequence[Trajectory], measured: Sequence[Trajectory], ship: Ship,
                   library: TermLibrary, finding: tuple[str, Effect],
                   catalogued: Effect, settings: Mapping) -> FlightContest:
    """Fit ``library`` with the finding's and with the catalogued effect's terms leaving one
    manoeuvre out (least squares), fly each left-out manoeuvre with both, and say which flies
    better.

    Parameters
    ----------
    fitted : sequence of Trajectory
        The records the fits see (smoothed, if the search smoothed them).
    measured : sequence of Trajectory
        The same records as measured: the flights are compared with them.
    ship : Ship
    library : TermLibrary
        The library both extend.
    finding : (str, Effect)
        The finding's family and the finding as an effect.
    catalogued : Effect
        The catalogued effect that stands in for it.
    settings : mapping
        ``rudder_signal``, ``derivative`` and ``window`` of :func:`sindyship.identify.fit`.

    Returns
    -------
    FlightContest

    Examples
    --------
    The default KCS is asymmetric (its propeller's side force); the asymmetry effect flies
    its turns better than the earth-fixed ``environment`` that could stand in for it:

    >>> from sindyship.library import load_effect, load_library
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> runs = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=35, duration=400),
    ...                            Manoeuvre("turning-circle", rudder=-35, duration=400),
    ...                            Manoeuvre("zigzag", rudder=20, check=20, duration=400)])
    >>> settings = {"rudder_signal": "actual", "derivative": "five-point", "window": 21.0}
    >>> contest = flight_contest(runs, runs, kcs, load_library("abkowitz"),
    ...                          ("asymmetry", load_effect("asymmetry")),
    ...                          load_effect("environment"), settings)
    >>> contest.winner, contest.finding_L < contest.catalogued_L
    ('finding', True)
    """
    family, effect = finding
    libraries = {"finding": library.extended(effect),
                 "catalogued": library.extended(catalogued)}
    jobs, names = [], []
    for key, extended in libraries.items():
        problems = design(fitted, ship, extended, **settings)
        for k, record in enumerate(measured):
            keep = problems["X"].groups != k
            others = [r for j, r in enumerate(fitted) if j != k]
            model = fit(others, ship, library=extended, problems=_subset(problems, keep),
                        **settings)
            jobs.append((model, [record]))
            names.append((key, record))
    flown = dict(zip([(key, record.name) for key, record in names],
                     (out[0] for out in fly_jobs_like(jobs)), strict=True))
    per_record, diverged = {}, {"finding": [], "catalogued": []}
    means = {"finding": [], "catalogued": []}
    for record in measured:
        common = compare_flights(flown[("catalogued", record.name)],
                                 flown[("finding", record.name)], record, ship.L)
        worse = {"before": "catalogued", "after": "finding"}.get(common["worse"])
        ends = {key: flown[(key, record.name)].meta.get("diverged_at") for key in means}
        if worse is not None and ends["finding"] != ends["catalogued"]:
            diverged[worse].append(record.name)
        means["finding"].append(common["after_mean_L"])
        means["catalogued"].append(common["before_mean_L"])
        per_record[record.name] = {"finding_L": common["after_mean_L"],
                                   "catalogued_L": common["before_mean_L"],
                                   "window_s": common["window_s"], "worse": worse}
    scores = {key: _geometric_mean(values) for key, values in means.items()}
    if len(diverged["finding"]) != len(diverged["catalogued"]):
        winner = ("finding" if len(diverged["finding"]) < len(diverged["catalogued"])
                  else "catalogued")
    else:
        winner = ("finding" if scores["finding"] < scores["catalogued"] else "catalogued")
    return FlightContest(family, catalogued.name, scores["finding"], scores["catalogued"],
                         diverged["finding"], diverged["catalogued"], winner, per_record)

"""Flights decide between a discovered family and a catalogued effect that stands in for it.

Shares of the force residual say how much of the equation error an extension removes, not what
it does to a flight: a catalogued effect can take a share of the residual that a spatial or
delayed effect leaves behind, and fly worse.  :func:`flight_contest` fits the library with each
extension leaving one manoeuvre out, flies the manoeuvre left out with both fits (as
:func:`sindyship.evaluation.evaluate` flies it) and compares them manoeuvre by manoeuvre
(:func:`sindyship.evaluation.compare_flights`: a flight that diverges where the other does
not, or earlier, is the worse; else the one farther off over the samples both cover).  The
one that flies better on more manoeuvres wins; as many each is undecided.
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

__all__ = ["LIBRARY_ALONE", "FlightContest", "flight_contest"]

#: The name of the contest's other side when it is the library without any effect.
LIBRARY_ALONE = "none"


@dataclass
class FlightContest:
    """A discovered family against a catalogued effect, judged by left-out flights.

    Attributes
    ----------
    finding, catalogued : str
        The finding's family and the catalogued effect's name.
    finding_L, catalogued_L : float
        Geometric means over the left-out manoeuvres of the mean distance [L] of each fit's
        flight, over the samples both flights of a manoeuvre cover (manoeuvres where that
        window is empty left out).
    finding_diverged, catalogued_diverged : list of str
        Manoeuvres whose flight diverged where the other's did not (or earlier).
    finding_better, catalogued_better : list of str
        Manoeuvres each flies better (:func:`sindyship.evaluation.compare_flights`).
    winner : {"finding", "catalogued", "undecided"}
        The one that flies better on more manoeuvres; "undecided" when each does on as many.
    per_record : dict
        Manoeuvre -> ``{"finding_L", "catalogued_L", "window_s", "worse"}``.
    """

    finding: str
    catalogued: str
    finding_L: float
    catalogued_L: float
    finding_diverged: list[str]
    catalogued_diverged: list[str]
    finding_better: list[str]
    catalogued_better: list[str]
    winner: str
    per_record: dict

    def sentence(self) -> str:
        """One sentence: how each flew, and which won."""
        def side(label, value, better, diverged):
            text = f"{label} {value:.3g} L, better on {len(better)}"
            return text + (f" ({', '.join(diverged)} diverged)" if diverged else "")

        ours = side(f"the finding {self.finding}", self.finding_L, self.finding_better,
                    self.finding_diverged)
        alone = self.catalogued == LIBRARY_ALONE
        theirs = side("the library alone" if alone else f"the catalogued {self.catalogued}",
                      self.catalogued_L, self.catalogued_better, self.catalogued_diverged)
        if self.winner == "undecided":
            verdict = ("neither flies better, and the library stays as it is" if alone else
                       "neither flies better, and the catalogued effect comes first")
        else:
            won = (self.finding if self.winner == "finding" else
                   "the library alone" if alone else self.catalogued)
            means = (self.finding_L, self.catalogued_L)
            larger = means[self.winner != "finding"] > means[self.winner == "finding"]
            verdict = (f"{won} flies better on more manoeuvres and wins, though its geometric "
                       "mean distance is the larger" if larger else f"{won} flies better and wins")
        return (f"Left-out flights (geometric mean distance; manoeuvres flown better): {ours}; "
                f"{theirs}; {verdict}.")

    def to_json(self) -> dict:
        """The contest as a JSON-ready dict (``contests`` of ``discover --json``)."""
        return clean_json({
            "finding": self.finding, "catalogued": self.catalogued,
            "finding_L": self.finding_L, "catalogued_L": self.catalogued_L,
            "finding_diverged": self.finding_diverged,
            "catalogued_diverged": self.catalogued_diverged,
            "finding_better": self.finding_better, "catalogued_better": self.catalogued_better,
            "winner": self.winner, "per_record": self.per_record,
        })


def _subset(problems: Mapping[str, Design], keep: np.ndarray) -> dict[str, Design]:
    """The designs of the samples ``keep`` marks (the groups renumbered from 0)."""
    groups = problems["X"].groups[keep]
    _, renumbered = np.unique(groups, return_inverse=True)
    return {dof: Design(features=problems[dof].features[keep],
                        target=problems[dof].target[keep], groups=renumbered,
                        terms=problems[dof].terms) for dof in DOFS}


def _geometric_mean(values: Sequence[float]) -> float:
    """Geometric mean of the positive finite values (NaN when there is none)."""
    finite = [v for v in values if math.isfinite(v) and v > 0]
    return float(np.exp(np.mean(np.log(finite)))) if finite else math.nan


def flight_contest(fitted: Sequence[Trajectory], measured: Sequence[Trajectory], ship: Ship,
                   library: TermLibrary, finding: tuple[str, Effect],
                   catalogued: Effect | None, settings: Mapping) -> FlightContest:
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
    catalogued : Effect or None
        The catalogued effect that stands in for it; None: the library alone (named
        :data:`LIBRARY_ALONE` in the result).
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
                 "catalogued": library if catalogued is None else library.extended(catalogued)}
    jobs = []
    for extended in libraries.values():
        problems = design(fitted, ship, extended, **settings)
        for k, record in enumerate(measured):
            keep = problems["X"].groups != k
            others = [r for j, r in enumerate(fitted) if j != k]
            model = fit(others, ship, library=extended, problems=_subset(problems, keep),
                        part_of_set=True, **settings)
            jobs.append((model, [record]))
    flights = [out[0] for out in fly_jobs_like(jobs)]
    flown = {"finding": flights[:len(measured)], "catalogued": flights[len(measured):]}
    per_record, means = {}, {"finding": [], "catalogued": []}
    diverged = {"finding": [], "catalogued": []}
    better = {"finding": [], "catalogued": []}
    for k, record in enumerate(measured):
        common = compare_flights(flown["catalogued"][k], flown["finding"][k], record, ship.L)
        worse = {"before": "catalogued", "after": "finding"}.get(common["worse"])
        ends = {key: flown[key][k].meta.get("diverged_at") for key in flown}
        if worse is not None:
            better["catalogued" if worse == "finding" else "finding"].append(record.name)
            if ends["finding"] != ends["catalogued"]:
                diverged[worse].append(record.name)
        means["finding"].append(common["after_mean_L"])
        means["catalogued"].append(common["before_mean_L"])
        per_record[record.name] = {"finding_L": common["after_mean_L"],
                                   "catalogued_L": common["before_mean_L"],
                                   "window_s": common["window_s"], "worse": worse}
    wins = {key: len(names) for key, names in better.items()}
    winner = ("undecided" if wins["finding"] == wins["catalogued"] else
              max(wins, key=wins.get))
    return FlightContest(family, LIBRARY_ALONE if catalogued is None else catalogued.name,
                         _geometric_mean(means["finding"]),
                         _geometric_mean(means["catalogued"]), diverged["finding"],
                         diverged["catalogued"], better["finding"], better["catalogued"],
                         winner, per_record)

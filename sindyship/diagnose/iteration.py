"""Rounds of diagnosis and addition until no effect explains a meaningful share."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import pandas as pd

from .._io import clean_json
from ..identify import resolve_library
from ..library import (
    TermLibrary,
)
from ..ships import Ship
from ..trajectory import Trajectory
from .before_after import BeforeAfter, before_after
from .diagnosis import Diagnosis, diagnose


@dataclass
class Round:
    """One round of :func:`diagnose_iteratively`.

    Attributes
    ----------
    diagnosis : Diagnosis
        Of the library at the start of the round.
    added : str or None
        The effect added in this round (None in the last round).
    change : BeforeAfter or None
        The errors before and after adding it.
    """

    diagnosis: Diagnosis
    added: str | None
    change: BeforeAfter | None


@dataclass
class IterativeDiagnosis:
    """Rounds of diagnosis and addition, until no effect explains a meaningful share.

    Attributes
    ----------
    rounds : list of Round
    stopped : str
        Why the iteration ended.
    """

    rounds: list[Round]
    stopped: str

    @property
    def final_library(self) -> TermLibrary:
        """The library of the last round (every added effect)."""
        last = self.rounds[-1]
        if last.change is not None and last.change.model_after is not None:
            return last.change.model_after.library
        return last.diagnosis.library

    @property
    def added(self) -> list[str]:
        return [r.added for r in self.rounds if r.added]

    @property
    def table(self) -> pd.DataFrame:
        """Mean distance of every flown manoeuvre with the library of each round."""
        rows = []
        for k, rnd in enumerate(self.rounds):
            for c in rnd.diagnosis.comparisons:
                rows.append(
                    {
                        "round": k + 1,
                        "library": rnd.diagnosis.library.name,
                        "manoeuvre": c.name,
                        "set": c.set,
                        **c.errors,
                    }
                )
            if k == len(self.rounds) - 1 and rnd.change is not None:
                for row in rnd.change.rows:
                    rows.append(
                        {
                            "round": k + 2,
                            "library": rnd.change.after,
                            "manoeuvre": row["manoeuvre"],
                            "set": row["set"],
                            **row["after"],
                        }
                    )
        return pd.DataFrame(rows)


    def report(self, ship_argument: str | None = None,
               effect_arguments: list[str] | None = None) -> str:
        """One paragraph per round, the errors of every library and the ``fit`` command of the
        library the rounds end with (:func:`sindyship.reports.iteration_report`; the arguments
        as :meth:`Diagnosis.report`'s)."""
        from ..reports import iteration_report

        return iteration_report(self, ship_argument, effect_arguments)

    def to_json(self) -> dict:
        return clean_json(
            {
                "rounds": [
                    {
                        "round": k + 1,
                        "library": r.diagnosis.library.name,
                        "ranking": [
                            {"effect": s.effect.name, "explained": s.explained}
                            for s in r.diagnosis.ranking
                        ],
                        "complete": r.diagnosis.complete,
                        "added": r.added,
                        "errors": r.diagnosis.errors(),
                        "change": None if r.change is None else r.change.to_json(),
                    }
                    for k, r in enumerate(self.rounds)
                ],
                "final_library": self.final_library.name,
                "added": self.added,
                "stopped": self.stopped,
            }
        )

    def figure(self, ax=None):
        """Mean distance per manoeuvre after each round."""
        from ..plotting.diagnosis import plot_rounds

        return plot_rounds(self, ax=ax)


def diagnose_iteratively(
    records: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    test: Sequence[Trajectory] = (),
    max_rounds: int = 4,
    progress: bool = False,
    on_round: Callable[[int, Round], None] | None = None,
    **options,
) -> IterativeDiagnosis:
    """Diagnose, add the best effect, diagnose again, until the library is complete.

    Each round adds the effect the round's diagnosis names (:attr:`Diagnosis.top`: the best
    meaningful effect that re-flying the training records does not refute, else one that
    brings them clearly closer); the iteration stops when there is none, or after
    ``max_rounds`` additions.  Held-out records are flown every round
    and never used to choose.

    Parameters
    ----------
    records, ship, library, test
        As :func:`diagnose`.
    max_rounds : int
        Most effects to add.
    progress : bool
        Progress bar over the rounds on stderr.
    on_round : callable, optional
        Called as ``on_round(k, round)`` as each round ``k`` (from 1) ends: a log line for a
        run whose stderr is no terminal, where the bar is not drawn.
    **options
        Passed to :func:`diagnose` (``effects``, ``threshold``, ``confirm``, ``fly_training``,
        ``optimizer``, ``n_jobs``, ...).

    Returns
    -------
    IterativeDiagnosis
    """
    from tqdm.auto import tqdm

    from ..arguments import as_records, as_ship, check_records

    ship = as_ship(ship)
    records = check_records(as_records(records), ship)  # once, not in every round
    test = check_records(as_records(test, "test", allow_empty=True), ship, "test")
    lib = resolve_library(library)
    if options.get("smoothing") == "auto":  # choose once, on the plain library
        from ..smoothing import choose_smoothing

        chosen_with = {key: options[key] for key in ("rudder_signal", "derivative", "window")
                       if key in options}
        setting, _ = choose_smoothing(records, ship, optimizer=options.get("optimizer", "ls"),
                                      library=lib, n_jobs=options.get("n_jobs", 1),
                                      **chosen_with)
        options["smoothing"] = setting
    rounds: list[Round] = []

    def ended(rnd: Round) -> None:
        rounds.append(rnd)
        if on_round is not None:
            on_round(len(rounds), rnd)

    stopped = f"after {max_rounds} rounds"
    bar = tqdm(total=max_rounds, desc="rounds", file=sys.stderr, disable=not progress)
    command_before = None  # the last round's command model with its effect: this one's without
    for _ in range(max_rounds):
        result = diagnose(records, ship, library=lib, test=test, progress=progress,
                          command_before=command_before, **options)
        command_before = None if result.command is None else result.command.model_after
        pick = result.top  # the diagnosis's own verdict: never one the flights refute
        if result.verdict == "contested":
            ended(Round(result, None, None))
            stopped = ((f"the held-out flights refute {pick.effect.name}"
                        if pick.refuted_by_held_out else
                        f"the flights of the model the command to add {pick.effect.name} fits "
                        "refute it") + ", the effect re-flying the training records favours")
            break
        if pick is None:
            ended(Round(result, None, None))
            meaningful = any(s.meaningful for s in result.ranking)
            stopped = ("an effect beyond the catalogue was discovered (the verdict says how to "
                       "add it)" if result.verdict == "add-discovered" else
                       "no meaningful effect was confirmed by re-flying the training records"
                       if meaningful else "no effect explains a meaningful share, and none "
                       "brings the training flights clearly closer")
            break
        change = pick.confirmation
        if change is None:
            change = before_after(
                records,
                ship,
                library=lib,
                effects=[pick.effect],
                test=test,
                fly_training=options.get("fly_training", True),
                optimizer=options.get("optimizer", "ls"),
                n_jobs=options.get("n_jobs", 1),
                **{
                    k: options[k]
                    for k in ("rudder_signal", "derivative", "window", "smoothing")
                    if k in options
                },
            )
        ended(Round(result, pick.effect.name, change))
        lib = lib.extended(pick.effect)
        bar.update()
    bar.close()
    return IterativeDiagnosis(rounds, stopped)


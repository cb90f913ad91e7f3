"""Before and after: refit with effects added and compare the error on every manoeuvre."""

from __future__ import annotations

import math
import sys
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import pandas as pd

from .._diagnosis_thresholds import CONFIRMING_RATIO
from .._io import clean_json
from ..errors import PriorCoverageNote
from ..evaluation import compare_flights, error_summary
from ..identify import (
    Design,
    design,
    fit,
    recommended_library,
    resolve_library,
    resolve_rudder_signal,
)
from ..library import (
    PAPER_LIBRARY,
    Effect,
    TermLibrary,
    load_effect,
    load_library,
    read_from_builtin,
)
from ..model import AbkowitzModel
from ..optimizers import one_blas_thread
from ..reports import SETS
from ..ships import Ship
from ..trajectory import Trajectory
from ._flights import _fly_many

if TYPE_CHECKING:
    from .scoring import EffectScore


# =============================================================================== before/after
def _geometric_mean_ratio(rows: Iterable[dict]) -> float:
    """Geometric mean of after/before mean distance over the window both flights cover."""
    logs = []
    for row in rows:
        common = row["common"]
        b, a = common["before_mean_L"], common["after_mean_L"]
        if math.isfinite(a) and math.isfinite(b):
            logs.append(math.log(max(a, 1e-9) / max(b, 1e-9)))
    return math.exp(sum(logs) / len(logs)) if logs else math.nan


def _worse_by_divergence(row: dict) -> str | None:
    """Which flight of a row diverges where the other does not (or earlier), if one does."""
    b, a = row["before"]["diverged_at_s"], row["after"]["diverged_at_s"]
    if b == a:
        return None
    if b is None or (a is not None and a < b):
        return "after"
    return "before"


@dataclass
class BeforeAfter:
    """The error on every manoeuvre before and after adding effects to a library.

    Attributes
    ----------
    before, after : str
        Library names.
    added : tuple of str
        The effects added.
    rows : list of dict
        Per manoeuvre: ``manoeuvre``, ``set`` (training or held-out), the error summaries
        ``before`` and ``after`` (:func:`sindyship.evaluation.error_summary`) and their
        comparison over the window both flights cover, ``common``
        (:func:`sindyship.evaluation.compare_flights`).
    model_before, model_after : AbkowitzModel
    """

    before: str
    after: str
    added: tuple[str, ...]
    rows: list[dict]
    model_before: AbkowitzModel | None = field(default=None, repr=False)
    model_after: AbkowitzModel | None = field(default=None, repr=False)

    @property
    def table(self) -> pd.DataFrame:
        """One row per manoeuvre: mean and max distance and divergence, before and after, and
        the ratio of the means over the window both flights cover."""
        records = []
        for row in self.rows:
            entry = {"manoeuvre": row["manoeuvre"], "set": row["set"]}
            for when in ("before", "after"):
                err = row[when]
                entry[f"{when}_mean_L"] = err["mean_distance_L"]
                entry[f"{when}_max_L"] = err["max_distance_L"]
                entry[f"{when}_diverged_at_s"] = err["diverged_at_s"]
            common = row["common"]
            entry["common_window_s"] = common["window_s"]
            entry["ratio"] = (
                common["after_mean_L"] / common["before_mean_L"]
                if common["before_mean_L"] > 0
                else math.nan
            )
            entry["worse"] = common["worse"]
            records.append(entry)
        return pd.DataFrame(records)

    def ratio(self, kind: str = "training") -> float:
        """Geometric mean of after/before mean distance over the set's flights, each pair
        compared over the window both flights cover (docs/protocol.md, "Comparing two flights")."""
        return _geometric_mean_ratio(row for row in self.rows if row["set"] == kind)

    def divergences(self, kind: str = "training") -> tuple[int, int]:
        """Number of flights of the set (training or held-out) that diverged, before and after."""
        rows = [row for row in self.rows if row["set"] == kind]
        return (
            sum(row["before"]["diverged_at_s"] is not None for row in rows),
            sum(row["after"]["diverged_at_s"] is not None for row in rows),
        )

    @property
    def confirmed(self) -> bool | None:
        """Whether re-flying the training manoeuvres confirms the effect.

        A flight that diverges where the other does not, or earlier, is the worse one
        whatever the means (docs/protocol.md): False when some training flight diverges after
        adding the effect where it did not before (or earlier); when only divergences before
        are cured, True unless the geometric-mean distance over the common windows grows by
        more than the confirming margin (above 1 / :data:`CONFIRMING_RATIO` times its value
        before: a divergence cured near a record's end does not confirm an effect that flies
        every other manoeuvre farther off); else True when that distance falls below
        :data:`CONFIRMING_RATIO` times its value before.  None without training flights.
        Held-out flights never enter it (they would select the model on the test set).
        """
        return self._judged("training", CONFIRMING_RATIO, no_distance=False,
                            cured_limit=1.0 / CONFIRMING_RATIO)

    @property
    def held_out_supports(self) -> bool | None:
        """Whether the held-out flights agree with adding the effects: False when one of them
        diverges with the effects where it did not without (or earlier), or when, with no
        divergence cured, their geometric-mean distance over the common windows grows; None
        without held-out flights or a distance to compare.  It never enters :attr:`confirmed`
        (that would select the model on the test set); the report and the verdict say when
        the two disagree.
        """
        return self._judged("held-out", 1.0, no_distance=None)

    @property
    def training_refutes(self) -> bool:
        """Whether the training flights refute the effects: one diverges with them where it
        did not without (or earlier), or, with no divergence cured, their geometric-mean
        distance over the common windows grows by more than the confirming margin (above
        1 / :data:`CONFIRMING_RATIO` times its value without them).  A model that flies them
        no farther off does not refute them; it need not confirm them (:attr:`confirmed`)."""
        margin = 1.0 / CONFIRMING_RATIO
        return self._judged("training", margin, no_distance=True, cured_limit=margin) is False

    def _judged(self, kind: str, threshold: float, *, no_distance: bool | None,
                cured_limit: float = math.inf) -> bool | None:
        """Whether the set's flights favour the effects: False when one diverges with them
        where it did not without (or earlier); when only divergences without them are cured,
        True unless the geometric-mean ratio exceeds ``cured_limit``; else whether it is at
        most ``threshold`` (``no_distance`` without a distance to compare; None without
        flights of the set)."""
        rows = [row for row in self.rows if row["set"] == kind]
        if not rows:
            return None
        worse = {_worse_by_divergence(row) for row in rows}
        if "after" in worse:
            return False
        ratio = self.ratio(kind)
        if "before" in worse:
            return bool(not math.isfinite(ratio) or ratio <= cured_limit)
        return bool(ratio <= threshold) if math.isfinite(ratio) else no_distance

    def report(self) -> str:
        """A plain-text table of the errors before and after
        (:func:`sindyship.reports.before_after_report`)."""
        from ..reports import before_after_report

        return before_after_report(self)

    def to_json(self) -> dict:
        return clean_json(
            {
                "before": self.before,
                "after": self.after,
                "added": list(self.added),
                "confirmed": self.confirmed,
                "held_out_supports": self.held_out_supports,
                "ratio": {kind: self.ratio(kind) for kind in SETS},
                "errors": {
                    row["manoeuvre"]: {
                        "set": row["set"],
                        "before": row["before"],
                        "after": row["after"],
                        "common_window": row["common"],
                    }
                    for row in self.rows
                },
            }
        )

    def figure(self, ax=None):
        """Bar chart of the mean distance per manoeuvre, before and after."""
        from ..plotting.diagnosis import plot_before_after

        return plot_before_after(self, ax=ax)


def _fit(
    records: Sequence[Trajectory],
    ship: Ship,
    library: TermLibrary,
    problems: Mapping[str, Design],
    *,
    optimizer: str,
    rudder_signal: str,
    derivative: str,
    window: float,
) -> AbkowitzModel:
    """:func:`sindyship.identify.fit` on a design already built for ``records``."""
    return fit(
        records,
        ship,
        library=library,
        optimizer=optimizer,
        rudder_signal=rudder_signal,
        derivative=derivative,
        window=window,
        problems=dict(problems),
    )


def _change_rows(
    sets: Sequence[tuple[str, Sequence[Trajectory]]],
    before: Sequence[Sequence[Trajectory]],
    after: Sequence[Sequence[Trajectory]],
    L: float,
) -> list[dict]:
    """Rows of a :class:`BeforeAfter`: per record of each set, the two error summaries."""
    rows = []
    for (kind, records), flown_before, flown_after in zip(sets, before, after, strict=True):
        for rec, b, a in zip(records, flown_before, flown_after, strict=True):
            rows.append(
                {
                    "manoeuvre": rec.name,
                    "set": kind,
                    "before": error_summary(b, rec, L),
                    "after": error_summary(a, rec, L),
                    "common": compare_flights(b, a, rec, L),
                }
            )
    return rows


@one_blas_thread
def confirm_by_flights(scores: Sequence[EffectScore], model: AbkowitzModel,
                       fitted: Sequence[Trajectory], sets: list, flown: list, settings: Mapping,
                       *, optimizer: str, n_jobs: int | None, progress: bool) -> None:
    """Refit with each effect and fly the ``sets`` again: each score's ``confirmation``, its
    flights against the ``model``'s (``flown``, one list per set), as :func:`diagnose
    <sindyship.diagnose.diagnose>` confirms an effect."""
    if not scores:
        return
    models = []
    for score in scores:
        lib = model.library.extended(score.effect)
        models.append(_fit(fitted, model.ship, lib, design(fitted, model.ship, lib, **settings),
                           optimizer=optimizer, **settings))
    after = _fly_many([(m, recs) for m in models for _, recs in sets], n_jobs=n_jobs,
                      progress=progress, what="flights")
    n_sets = len(sets)
    for j, (score, refit) in enumerate(zip(scores, models, strict=True)):
        rows = _change_rows(sets, flown, after[j * n_sets:(j + 1) * n_sets], model.ship.L)
        score.confirmation = BeforeAfter(model.library.name, refit.library.name,
                                         (score.effect.name,), rows, model_before=model,
                                         model_after=refit)


#: The optimizers of a diagnosis whose verdict names a ``fit`` command that fits another model
#: than the one re-flown: ``ls`` (``fit`` without ``--optimizer`` gives its recommended
#: ``prior`` fit) and ``prior`` (which ``fit`` refines by its flights).
COMMAND_REFITS = ("ls", "prior")


def command_library(library: TermLibrary) -> TermLibrary:
    """The library of the ``fit`` command a diagnosis of ``library`` names: where that is the
    diagnosis's default (:data:`sindyship.library.PAPER_LIBRARY`, extended or not: its
    ``fit`` command leaves ``--library`` out), ``fit``'s recommended
    library for its ``prior`` fit (:func:`sindyship.identify.recommended_library`) with the
    terms ``library``'s effects add; else ``library`` itself."""
    if not read_from_builtin(library, PAPER_LIBRARY):
        return library
    recommended = load_library(recommended_library(library.speed))
    return library.rebased(load_library(PAPER_LIBRARY), recommended)


@one_blas_thread
def judge_command(fitted: Sequence[Trajectory], library: TermLibrary, effect: Effect,
                  sets: list, settings: Mapping, *, ship: Ship, n_jobs: int | None,
                  progress: bool, before: AbkowitzModel | None = None) -> BeforeAfter:
    """The models the verdict's ``fit`` command gives without and with ``effect``, flown like
    the ``sets``' records: ``fit``'s recommended fit, the ``prior`` on
    :func:`command_library`, refined by its flights with the defaults of ``fit``
    (:func:`sindyship.refine.refine`: a refinement that does not carry over to records it was
    not refined on is refused there, as ``fit`` refuses it).  ``fitted`` are the training
    records as fitted (smoothed, when the diagnosis smooths them), as ``fit`` fits and
    refines them.  ``before``, the command's model without the effect when it is already
    fitted (the last round's with it, in :func:`sindyship.diagnose.diagnose_iteratively`), is
    taken when its library has the terms and speed form of :func:`command_library`'s."""
    from ..refine import refine

    base = command_library(library)
    if progress:
        print(f"the command's fit: the prior on {base.name}, refined by its flights, without "
              f"and with {effect.name}", file=sys.stderr)
    kept = before is not None and before.library.terms == base.terms \
        and before.library.speed == base.speed
    with warnings.catch_warnings():  # the note is the command's, and fit gives it there
        warnings.simplefilter("ignore", PriorCoverageNote)
        models = [before if kept and lib is base else
                  refine(fit(fitted, ship, library=lib, optimizer="prior", **settings), fitted)
                  for lib in (base, base.extended(effect))]
    flown = _fly_many([(m, recs) for m in models for _, recs in sets], n_jobs=n_jobs,
                      progress=progress, what="flights of the command's fit")
    rows = _change_rows(sets, flown[:len(sets)], flown[len(sets):], ship.L)
    return BeforeAfter(base.name, models[1].library.name, (effect.name,), rows,
                       model_before=models[0], model_after=models[1])


def before_after(
    train: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    effects: Sequence[str | Effect],
    test: Sequence[Trajectory] = (),
    optimizer: str = "ls",
    rudder_signal: str = "actual",
    derivative: str = "five-point",
    window: float = 21.0,
    fly_training: bool = True,
    smoothing=None,
    n_jobs: int = 1,
    progress: bool = False,
) -> BeforeAfter:
    """Refit with effects added and compare the error on every manoeuvre, before and after.

    Parameters
    ----------
    train : sequence of Trajectory
        Training records: both models are fitted on them.
    ship : Ship
    library : str or TermLibrary
        The library before.
    effects : sequence of str or Effect
        The catalogued effects (names or files) to add.
    test : sequence of Trajectory
        Held-out records, flown but never fitted on.
    optimizer, rudder_signal, derivative, window
        As :func:`sindyship.identify.fit`.
    fly_training : bool
        Also fly the training records.
    smoothing : SmoothingSetting or str, optional
        Smoothing of the training records before the fits (``"savgol:W"``, ``"rts:W"``); the
        flights are compared with the records as measured.
    n_jobs : int
        Processes for the flights (joblib).
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    BeforeAfter
        ``.table``, ``.report()``, ``.figure()``, ``.to_json()``.

    Examples
    --------
    >>> from sindyship import load_ship, parse_effects, simulate_with_effects, Manoeuvre
    >>> ship = load_ship("kcs")
    >>> plan = [Manoeuvre("turning-circle", rudder=35, duration=800),
    ...         Manoeuvre("turning-circle", rudder=-35, duration=800),
    ...         Manoeuvre("zigzag", rudder=20, check=20, duration=800),
    ...         Manoeuvre("zigzag", rudder=10, check=10, duration=800),
    ...         Manoeuvre("turning-circle", rudder=-20, duration=800)]
    >>> runs = simulate_with_effects(ship, plan, parse_effects(["current=0.5", "current_dir=90"]))
    >>> change = before_after(runs[:4], ship, effects=["environment"], test=runs[4:])
    >>> change.table[["manoeuvre", "set"]].values.tolist()[-1]
    ['tc20_port', 'held-out']
    >>> bool(change.ratio("held-out") < 0.5)
    True
    """
    from ..arguments import as_records, as_ship, check_records

    ship = as_ship(ship)
    train = check_records(as_records(train, "train"), ship, "train")
    test = check_records(as_records(test, "test", allow_empty=True), ship, "test")
    base = resolve_library(library)
    added = [e if isinstance(e, Effect) else load_effect(e) for e in effects]
    extended = base.extended(*added)
    rudder_signal = resolve_rudder_signal(train, rudder_signal)
    settings = {"rudder_signal": rudder_signal, "derivative": derivative, "window": window}
    fitted = list(train)
    if smoothing is not None and smoothing != "none":
        from ..smoothing import smooth_records

        fitted = smooth_records(fitted, smoothing)
    models = []
    for lib in (base, extended):
        problems = design(fitted, ship, lib, **settings)
        models.append(_fit(fitted, ship, lib, problems, optimizer=optimizer, **settings))
    sets = ([("training", list(train))] if fly_training else []) + [("held-out", list(test))]
    sets = [(kind, records) for kind, records in sets if records]
    jobs = [(model, records) for model in models for _, records in sets]
    flown = _fly_many(jobs, n_jobs=n_jobs, progress=progress, what="before/after flights")
    rows = _change_rows(sets, flown[: len(sets)], flown[len(sets) :], ship.L)
    return BeforeAfter(
        base.name,
        extended.name,
        tuple(e.name for e in added),
        rows,
        model_before=models[0],
        model_after=models[1],
    )



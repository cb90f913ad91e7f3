"""The diagnosis: compare, residuals and the ranked missing effects."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .._diagnosis_thresholds import (
    COLLINEAR_VIF,
    FLIGHT_OVERRIDE_RATIO,
    FLIGHTS_PREFER_RATIO,
    MEANINGFUL_SHARE,
    NOISE_CAP,
    UNEXPLAINED_SHARE,
)
from .._io import clean_json
from ..errors import SindyshipInputError
from ..identify import Design, resolve_library, resolve_rudder_signal
from ..library import (
    DOFS,
    Effect,
    TermLibrary,
)
from ..model import AbkowitzModel
from ..optimizers import one_blas_thread
from ..reports import DOF_NAMES
from ..rudder_holds import rudder_side
from ..ships import Ship
from ..smoothing import SmoothingSetting, resolve_smoothing, smooth_records
from ..stability import Stability, straight_run_stability
from ..targets import RESOLVED_STEP, sampling_steps, under_resolved
from ..trajectory import Trajectory
from ..uncertainty import library_conditioning
from ._flights import _fly_many
from .before_after import COMMAND_REFITS, BeforeAfter, confirm_by_flights, judge_command
from .compare import ManoeuvreComparison, compare
from .discovery import Discovery, search_beyond_catalogue
from .noise import channel_noise
from .ranking import rank_effects
from .residuals import Residuals
from .scoring import EffectScore, NotTestable
from .speed import SpeedForms, speed_forms


@dataclass
class Diagnosis:
    """The answer of :func:`diagnose`: comparison, residuals and the ranked missing effects.

    Attributes
    ----------
    ship : Ship
    library : TermLibrary
        The library diagnosed.
    model : AbkowitzModel
        The library fitted on the training records.
    threshold : float
        The share an effect must explain to be meaningful.
    ranking : list of EffectScore
        Testable effects, best first.
    not_testable : list of NotTestable
    in_library : list of str
        Catalogued effects whose terms the library already has.
    comparisons : list of ManoeuvreComparison
        The model flown like every training (if flown) and held-out record.
    residuals : Residuals
        On the training records.
    force_error : dict
        Per degree of freedom: the leave-one-manoeuvre-out error of the library relative to
        the measured force (RMS over RMS).
    settings : dict
    seconds : float
    discovery : Discovery or None
        The search beyond the catalogue (:func:`sindyship.diagnose.discover`), run when no
        catalogued effect is meaningful and the model is visibly wrong (a training flight
        diverged, or a force's cross-validated error stands above its noise floor).
    speed : SpeedForms or None
        The records' speed range and which speed form they need
        (:func:`sindyship.diagnose.speed.speed_forms`).
    sides : dict
        Per training record, the side its rudder is put to
        (:func:`sindyship.rudder_holds.rudder_side`).
    command : BeforeAfter or None
        The model the verdict's ``fit`` command gives, without and with the effect named
        (:func:`sindyship.diagnose.before_after.judge_command`), when it is another than the
        one re-flown (a diagnosis by ``ls`` or ``prior``); its flights can contest the effect.
    sampling : dict
        Per training record, its sampling interval in ship-length times L/U0
        (:func:`sindyship.targets.sampling_steps`); above
        :data:`~sindyship.targets.RESOLVED_STEP` a caution says the accelerations are
        under-resolved.
    """

    ship: Ship
    library: TermLibrary
    model: AbkowitzModel
    threshold: float
    ranking: list[EffectScore]
    not_testable: list[NotTestable]
    in_library: list[str]
    comparisons: list[ManoeuvreComparison]
    residuals: Residuals
    force_error: dict[str, float]
    settings: dict
    seconds: float = 0.0
    stability: Stability | None = None
    collinear: dict[str, dict[str, float]] = field(default_factory=dict)
    noise_floor: dict[str, float] = field(default_factory=dict)
    noise_level: dict[str, float] = field(default_factory=dict)
    discovery: Discovery | None = None
    speed: SpeedForms | None = None
    sides: dict[str, int] = field(default_factory=dict)
    sampling: dict[str, float] = field(default_factory=dict)
    command: BeforeAfter | None = None

    @property
    def diverged(self) -> dict[str, float]:
        """Training flights that diverged, by record: the time they diverged [s]."""
        return {c.name: c.errors["diverged_at_s"] for c in self.comparisons
                if c.set == "training" and c.errors["diverged_at_s"] is not None}

    @property
    def unexplained(self) -> list[str]:
        """Equations whose cross-validated force error leaves most of the measured force
        unexplained (:meth:`unexplained_share` above :data:`UNEXPLAINED_SHARE`)."""
        return [dof for dof in DOFS if self.unexplained_share(dof) > UNEXPLAINED_SHARE]

    def unexplained_share(self, dof: str) -> float:
        """Share of the measured force above the noise floor that the library leaves
        unexplained on held-out manoeuvres (squared relative RMS error, noise removed)."""
        error = self.force_error[dof] ** 2
        floor = min(self.noise_floor.get(dof, 0.0), NOISE_CAP) * error
        return float((error - floor) / max(1.0 - floor, 1e-12))

    @property
    def verdict(self) -> str:
        """``"add-effect"`` (a meaningful effect is missing), ``"contested"`` (the effect
        :attr:`top` names is refuted by the held-out flights given: one diverges only with it,
        or they come out farther off; they never choose an effect, which would select the
        model on its test, but they can stop one; or by the flights of the model the
        verdict's command fits, :attr:`command`), ``"add-discovered"`` (no catalogued effect
        is meaningful but the search beyond the catalogue discovered one), ``"unstable"``
        (training flights diverged and no catalogued effect is meaningful), ``"unexplained"``
        (most of a force is unexplained and no catalogued effect is meaningful) or
        ``"complete"``."""
        if self.top is not None:
            if self.top.refuted_by_held_out:
                return "contested"
            command = self.command
            if command is not None and (command.training_refutes
                                        or command.held_out_supports is False):
                return "contested"
            return "add-effect"
        if self.discovery is not None and self.discovery.accepted:
            return "add-discovered"
        if self.diverged:
            return "unstable"
        if self.unexplained:
            return "unexplained"
        return "complete"

    @property
    def complete(self) -> bool:
        """No testable effect explains a meaningful share of the force error, no training
        flight diverged and the library predicts most of every force (:attr:`verdict`)."""
        return self.verdict == "complete"

    @property
    def warnings(self) -> list[str]:
        """Cautions about the data behind the verdict (empty when there are none)."""
        coarse = under_resolved(self.sampling, self.ship)
        out = [coarse] if coarse else []
        poor = [dof for dof in DOFS if self.force_error[dof] > 0.5]
        noisy = [dof for dof in poor if self.noise_floor.get(dof, 0.0) > 0.5]
        if noisy:
            names = " and ".join(DOF_NAMES[dof] for dof in noisy)
            smoothed = self.settings.get("smoothing") or self.settings.get("derivative") == "savgol"
            out.append(
                f"most of the error in the {names} is measurement noise amplified by the "
                "differentiation (the noise floor above); effects are judged on the error above "
                "it" + ("" if smoothed else ", and smoothing the records (--smoothing auto) "
                        "lowers it")
            )
        other = [dof for dof in poor if dof not in noisy]
        if other:
            names = " and ".join(DOF_NAMES[dof] for dof in other)
            out.append(
                f"the library predicts less than half of the measured {names} on "
                "held-out manoeuvres although the records are not noisy there: manoeuvres too "
                "unlike each other for one to be predicted from the rest, or physics no "
                "catalogued effect describes"
            )
        one_sided = self.one_sided
        if one_sided:
            out.append(one_sided)
        diverged = [c.name for c in self.comparisons if c.errors["diverged_at_s"] is not None]
        if diverged:
            out.append(
                f"the flights of {', '.join(diverged)} diverged: their mean distances "
                "cover only the time before the divergence"
            )
        return out

    @property
    def one_sided(self) -> str:
        """Why a difference between the sides cannot be scored, or "": no training record puts
        the rudder to both sides, and one side has one record or none, so leaving it out no
        other record shows that side."""
        if not self.sides or any(side == 2 for side in self.sides.values()):
            return ""
        for side, name in ((1, "starboard"), (-1, "port")):
            on_it = [record for record, turned in self.sides.items() if turned == side]
            if len(on_it) <= 1:
                held = f"only {on_it[0]} puts" if on_it else "no record puts"
                return (f"{held} the rudder to {name} and none to both sides: left out "
                        "manoeuvre by manoeuvre, effects that differ between the sides "
                        "(asymmetry) cannot be scored by their share of the force error, only "
                        "by re-flying; add a manoeuvre to each side, or a zig-zag")
        return ""

    @property
    def top(self) -> EffectScore | None:
        """The effect to add, or None: the best meaningful effect that re-flying does not
        refute (its confirmation is not False); else, unless the search beyond the catalogue
        discovered one, the other effect whose confirmation brings the training flights
        closest, by a clear margin (:func:`flight_confirmed`): the verdict never disagrees
        with the flights.  An effect its forces do not single out yields to a discovered one,
        which they do and which flies the manoeuvres left out better than it does (the
        search beyond the catalogue contests them)."""
        meaningful = self.meaningful_top
        if meaningful is not None:
            return meaningful
        if self.discovery is not None and self.discovery.accepted:
            return None
        return next(iter(self.flight_favoured), None)

    @property
    def flight_favoured(self) -> list[EffectScore]:
        """The effects that are not meaningful by their share of the force error but whose
        re-flown training flights come clearly closer (:func:`flight_confirmed`), the
        closest first."""
        return sorted((score for score in self.ranking if not score.meaningful
                       and flight_confirmed(score)),
                      key=lambda score: _finite_or_inf(score.confirmation.ratio("training")))

    @property
    def no_catalogued_effect(self) -> str:
        """Why no catalogued effect is named, for the verdict: none is meaningful, or
        re-flying the training records refutes those that are; and the effects the flights
        alone favour, which a discovery out-flew on the manoeuvres left out."""
        refuted = [s.effect.name for s in self.refuted]
        text = ("no catalogued effect is meaningful" if not refuted else
                f"re-flying the training records refutes {', '.join(refuted)}, the catalogued "
                f"effect{'s' if len(refuted) > 1 else ''} the force error singles out")
        flown = [score.effect.name for score in self.flight_favoured]
        if flown:
            one = len(flown) == 1
            text += (f" ({', '.join(flown)} bring{'s' if one else ''} the training flights "
                     f"closer but explain{'s' if one else ''} little of the force error, and "
                     "the discovery flies the manoeuvres left out better)")
        return text

    @property
    def meaningful_top(self) -> EffectScore | None:
        """The meaningful effect to add, or None (:func:`_meaningful_top`)."""
        return _meaningful_top(self.ranking)

    @property
    def refuted(self) -> list[EffectScore]:
        """The meaningful effects that re-flying the training records refutes."""
        return [s for s in self.ranking if s.meaningful and s.confirmation is not None
                and s.confirmation.confirmed is False]

    @property
    def first_unrefuted(self) -> EffectScore | None:
        """The meaningful effect first by its share of the force error that re-flying does not
        refute, or None."""
        return next(iter(_unrefuted(self.ranking)), None)

    def score(self, name: str) -> EffectScore:
        """The score of one effect by name."""
        for score in self.ranking:
            if score.effect.name == name:
                return score
        raise KeyError(f"effect {name!r} was not scored (not testable or already in the library)")

    def rank(self, name: str) -> int | None:
        """1-based rank of an effect, None if it was not scored."""
        names = [s.effect.name for s in self.ranking]
        return names.index(name) + 1 if name in names else None

    def errors(self, kind: str | None = None) -> dict[str, dict]:
        """Error summaries of the flights by record name (optionally of one set)."""
        return {c.name: c.errors for c in self.comparisons if kind in (None, c.set)}

    # ------------------------------------------------------------------------------- text

    def report(self, ship_argument: str | None = None,
               effect_arguments: list[str] | None = None) -> str:
        """The diagnosis as text a person reads (:func:`sindyship.reports.diagnosis_report`;
        ``ship_argument`` and ``effect_arguments``: the ``--ship`` and the library's
        ``--effects`` its verdict's command names)."""
        from ..reports import diagnosis_report

        return diagnosis_report(self, ship_argument, effect_arguments)

    def save_figures(self, out_dir, *, progress: bool = False) -> list:
        """Write the figures and before/after tables to a folder
        (:func:`sindyship.plotting.save_diagnosis_figures`)."""
        from ..plotting.diagnosis import save_diagnosis_figures

        return save_diagnosis_figures(self, out_dir, progress=progress)

    def to_json(self) -> dict:
        """The JSON document of ``sindyship diagnose --json`` (docs/command-line.md)."""
        return clean_json(
            {
                "ship": self.ship.name,
                "library": self.library.name,
                "effects_in_library": list(self.library.effects),
                "threshold": self.threshold,
                "complete": self.complete,
                "verdict": self.verdict,
                "effect_to_add": self.top.effect.name if self.verdict == "add-effect" else None,
                "diverged": self.diverged,
                "stability": None if self.stability is None else self.stability.to_json(),
                "collinear_terms": self.collinear,
                "noise": {"floor_share_of_error": self.noise_floor, "level": self.noise_level},
                "sampling": {"step_L_U0": self.sampling, "resolved_step_L_U0": RESOLVED_STEP},
                "ranking": [score.to_json() for score in self.ranking],
                "discovery": None if self.discovery is None else self.discovery.to_json(),
                "command_check": None if self.command is None else self.command.to_json(),
                "speed": None if self.speed is None else self.speed.to_json(),
                "not_testable": [item.to_json() for item in self.not_testable],
                "in_library": list(self.in_library),
                "warnings": self.warnings,
                "errors": {c.name: {"set": c.set, **c.errors} for c in self.comparisons},
                "force_residual": {
                    dof: {**self.residuals.summary()[dof], "cross_validated": self.force_error[dof]}
                    for dof in DOFS
                },
                "settings": self.settings,
                "seconds": self.seconds,
            }
        )

    # ------------------------------------------------------------------------------- figures

def _finite_or_inf(value: float) -> float:
    """A ratio to rank by: one without a window to compare (NaN) ranks last."""
    return value if math.isfinite(value) else math.inf


def _unrefuted(ranking: Sequence[EffectScore]) -> list[EffectScore]:
    """The meaningful effects re-flying does not refute (not re-flown, or confirmed)."""
    return [s for s in ranking if s.meaningful
            and (s.confirmation is None or s.confirmation.confirmed is not False)]


def _meaningful_top(ranking: Sequence[EffectScore]) -> EffectScore | None:
    """The best meaningful effect re-flying does not refute; among those it confirms, one whose
    training flights come :data:`FLIGHTS_PREFER_RATIO` times as close or closer than the best's
    is named instead (the closest)."""
    kept = _unrefuted(ranking)
    if not kept or kept[0].confirmation is None or kept[0].confirmation.confirmed is not True:
        return kept[0] if kept else None
    confirmed = [s for s in kept if s.confirmation is not None and s.confirmation.confirmed]
    closest = min(confirmed, key=lambda s: _finite_or_inf(s.confirmation.ratio("training")))
    best = kept[0].confirmation.ratio("training")  # NaN: it cures a divergence, and stays
    return closest if closest.confirmation.ratio("training") <= FLIGHTS_PREFER_RATIO * best \
        else kept[0]


def flight_confirmed(score: EffectScore) -> bool:
    """Whether re-flying the training records with an effect brings them closer by a clear
    margin (geometric mean of after over before at most :data:`FLIGHT_OVERRIDE_RATIO`, no new
    divergence; or a divergence cured and the flights no farther off), whatever its share of
    the force error."""
    confirmation = score.confirmation
    if confirmation is None or confirmation.confirmed is not True:
        return False
    ratio = confirmation.ratio("training")
    before, after = confirmation.divergences("training")
    return bool(ratio <= FLIGHT_OVERRIDE_RATIO
                or (after < before and not ratio > 1.0))  # cured, the others no farther off


def _stability(model: AbkowitzModel) -> Stability | None:
    """Straight-run stability, or None when the model has no linear sway-yaw dynamics."""
    try:
        return straight_run_stability(model)
    except (SindyshipInputError, np.linalg.LinAlgError, ValueError):
        return None


def _collinear_terms(problems: Mapping[str, Design]) -> dict[str, dict[str, float]]:
    """The sway and yaw terms the data cannot separate: VIF above :data:`COLLINEAR_VIF`,
    largest first (at most four per equation)."""
    vifs = library_conditioning({dof: problems[dof] for dof in ("Y", "N")})
    out = {}
    for dof, report in vifs.items():
        ranked = sorted(((v, term) for term, v in report["vif"].items()
                         if math.isfinite(v) and v > COLLINEAR_VIF), reverse=True)
        out[dof] = {term: float(v) for v, term in ranked[:4]}
    return out


@one_blas_thread
def diagnose(
    records: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    effects: Sequence[str | Effect] | None = None,
    test: Sequence[Trajectory] = (),
    threshold: float = MEANINGFUL_SHARE,
    confirm: int = 2,
    fly_training: bool = True,
    optimizer: str = "ls",
    rudder_signal: str = "actual",
    derivative: str = "five-point",
    window: float = 21.0,
    smoothing: SmoothingSetting | str | None = None,
    n_jobs: int = 1,
    progress: bool = False,
    search_beyond: bool = True,
    check_command: bool = True,
    command_before: AbkowitzModel | None = None,
    on_stage: Callable[[str], None] | None = None,
) -> Diagnosis:
    """Fit a library, show where it fails and rank the catalogued effects that are missing.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records (at least two: effects are scored leave-one-manoeuvre-out).
    ship : Ship
    library : str or TermLibrary
        The library to diagnose (a name, a file, or an extended library).
    effects : sequence of str or Effect, optional
        Candidate effects; default the whole catalogue (:func:`available_effects`).
    test : sequence of Trajectory
        Held-out records: flown before and after, never fitted on, never used to choose.
    threshold : float
        Share of the cross-validated force error an effect must explain to be meaningful.
    confirm : int
        Number of best meaningful candidates to confirm by refitting and re-flying; while
        re-flying refutes those, the next meaningful one is re-flown too (an effect is named
        only once its flights do not refute it).  0 re-flies none.
    fly_training : bool
        Fly the training records (compare, confirmation).  Without it only the held-out
        records are flown, and a candidate's ``confirmation.confirmed`` is None.
    optimizer : str
        The optimizer of the fitted model and of the confirmation refits (scoring always
        uses least squares).
    rudder_signal, derivative, window
        As :func:`sindyship.identify.fit`.
    smoothing : SmoothingSetting, str or None
        Smooth the training records before differencing (``"savgol:W"``, ``"rts:W"`` with W in
        seconds, ``"auto"`` to choose by leave-one-manoeuvre-out flights,
        :func:`sindyship.smoothing.choose_smoothing`); the models are fitted and the effects
        scored on the smoothed records, the flights compared with the measured ones.
    n_jobs : int
        Parallel jobs: threads for scoring the effects, processes for the flights (joblib).
    progress : bool
        Progress bars on stderr.
    search_beyond : bool
        When no catalogued effect is meaningful and the model is visibly wrong, search beyond
        the catalogue (:func:`sindyship.diagnose.discover`, the report's "Not in the
        catalogue").
    check_command : bool
        Fly the model the verdict's ``fit`` command gives, without and with the effect named,
        when it is another than the one re-flown (``optimizer`` ``ls`` or ``prior``: ``fit``
        then fits the ``prior`` and refines it); its flights can contest the effect
        (:attr:`Diagnosis.command`); ``command_before``: that model without the effect,
        when already fitted (:func:`diagnose_iteratively` passes the last round's).
    on_stage : callable, optional
        Called with a line saying what ended as each long step ends (the fit and scoring,
        the flights, the re-flights, the command's flights, the search beyond the
        catalogue): a log for a run whose stderr is no terminal, where no bar is drawn.

    Returns
    -------
    Diagnosis
        ``.ranking``, ``.not_testable``, ``.report()``, ``.to_json()``, ``.save_figures()``.

    Raises
    ------
    SindyshipInputError
        Fewer than two training records, an unknown effect, or a record the library cannot
        be evaluated on.
    """
    start = time.perf_counter()
    from ..arguments import as_records, as_ship, check_records

    ship = as_ship(ship)
    records = check_records(as_records(records), ship)
    test = check_records(as_records(test, "test", allow_empty=True), ship, "test")
    _check_arguments(records, test, threshold)
    base = resolve_library(library)
    rudder_signal = resolve_rudder_signal(records, rudder_signal)
    settings = {"rudder_signal": rudder_signal, "derivative": derivative, "window": window}
    smoothing = resolve_smoothing(smoothing, records, ship, library=base, optimizer=optimizer,
                                  rudder_signal=rudder_signal, derivative=derivative,
                                  window=window, n_jobs=n_jobs)
    fitted = records if smoothing is None else smooth_records(records, smoothing)
    ranked = rank_effects(fitted, records, ship, base, effects, settings, optimizer=optimizer,
                          threshold=threshold, n_jobs=n_jobs)
    model, ranking = ranked.model, ranked.ranking
    stage = on_stage or (lambda line: None)
    stage(f"fitted {base.name} and scored {len(ranking)} candidate effects on the forces")

    sets = ([("training", records)] if fly_training else []) + [("held-out", test)]
    sets = [(kind, recs) for kind, recs in sets if recs]
    # the meaningful effects first; then the best of the others, so that a verdict of
    # "complete" rests on flights too (a force share can hide under the noise)
    candidates = [s for s in ranking if s.meaningful] + [
        s for s in ranking if not s.meaningful]
    chosen = candidates[: max(int(confirm), 0)] if sets else []
    flown = _fly_many([(model, recs) for _, recs in sets], n_jobs=n_jobs, progress=progress,
                      what="flights")
    comparisons = []
    for k, (kind, recs) in enumerate(sets):
        comparisons += compare(model, recs, kind=kind, flights=flown[k])
    if sets:
        stage(f"flew the model on {sum(len(recs) for _, recs in sets)} records")
    confirm_by_flights(chosen, model, fitted, sets, flown, settings, optimizer=optimizer,
                       n_jobs=n_jobs, progress=progress)
    while chosen and (top := _meaningful_top(ranking)) is not None and top.confirmation is None:
        # an effect is named only once re-flown: down the ranking while those are refuted
        confirm_by_flights([top], model, fitted, sets, flown, settings, optimizer=optimizer,
                           n_jobs=n_jobs, progress=progress)
    if refitted := [s.effect.name for s in ranking if s.confirmation is not None]:
        stage(f"re-flew the model with {', '.join(refitted)}")
    result = Diagnosis(
        ship=ship,
        library=base,
        model=model,
        threshold=threshold,
        ranking=ranking,
        not_testable=ranked.not_testable,
        in_library=ranked.in_library,
        comparisons=comparisons,
        residuals=ranked.residuals,
        force_error=ranked.force_error,
        stability=_stability(model),
        noise_floor={dof: ranked.noise[dof] / max(float(ranked.base_errors[dof]
                                                        @ ranked.base_errors[dof]), 1e-300)
                     for dof in DOFS},
        noise_level=channel_noise(records),
        sampling=sampling_steps(records, ship),
        collinear=_collinear_terms(ranked.base_problems),
        settings={
            **settings,
            "optimizer": optimizer,
            "confirm": confirm,
            "fly_training": fly_training,
            "smoothing": None if smoothing is None else smoothing.as_dict(),
            "scoring": "least squares, leave-one-manoeuvre-out",
        },
        seconds=time.perf_counter() - start,
    )
    result.speed = speed_forms(fitted, ship, base, settings, test)
    result.sides = {record.name: rudder_side(record.rudder) for record in records}
    top = result.top
    if check_command and top is not None and optimizer in COMMAND_REFITS and sets \
            and not top.refuted_by_held_out:
        result.command = judge_command(fitted, base, top.effect, sets, settings, ship=ship,
                                       n_jobs=n_jobs, progress=progress,
                                       before=command_before)
        stage(f"flew the model of the verdict's fit command without and with "
              f"{top.effect.name}")
    if search_beyond and search_beyond_catalogue(result, fitted, settings, n_jobs):
        stage("searched beyond the catalogue")
    result.seconds = time.perf_counter() - start
    return result


def _check_arguments(records: Sequence[Trajectory], test: Sequence[Trajectory],
                     threshold: float) -> None:
    """Refuse fewer than two training records, a threshold outside (0, 1) and records that
    share a name."""
    from ..arguments import check_distinct_names, check_two_records

    check_two_records(records, "diagnose")
    if not 0.0 < threshold < 1.0:
        raise SindyshipInputError(f"the threshold must lie between 0 and 1, not {threshold}.")
    check_distinct_names([*records, *test])


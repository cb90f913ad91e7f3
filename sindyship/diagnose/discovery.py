"""Discovering a missing effect that no catalogue lists.

:func:`discover` fits a library and searches for what its cross-validated force residual still
holds, in two ways:

Delays.
    A channel the terms read (the rudder angle above all) may lag or lead the force it causes:
    a slow or filtered angle sensor, a logging delay.  For every candidate delay tau on a grid
    (steps of 0.05 L/U0 or one sample, over +-1.5 L/U0 and at least ten samples) the library is
    refitted on the channel read at ``t + tau`` (:meth:`sindyship.library.TermLibrary.aligned`)
    and judged by its leave-one-manoeuvre-out force error; the best grid point is refined by a
    parabola through its neighbours.  A best delay at the edge of the grid doubles the grid's
    reach, up to 4 L/U0 (75 s for the KCS).  A best delay shorter than the sample interval is
    not one the records can resolve and is not reported.
Terms.
    The families of :mod:`sindyship.diagnose.candidates` (pysindy feature libraries over the
    heading, the position, the rudder, the motion and every recorded channel).  In every
    equation :class:`sindyship.optimizers.ForwardSelection` adds a family's terms to the
    library one at a time, each time the one whose joint least-squares refit has the least
    leave-one-manoeuvre-out error, while that error falls by at least 1 % of the library's
    (sparse: at most :data:`MAX_TERMS` terms).  Terms that duplicate the library's are left
    out, so a term that only re-spends a library term's work gains nothing.

Each finding is judged as a catalogued effect is (:mod:`sindyship.diagnose.scoring`): the share
of the leave-one-manoeuvre-out force error above the noise floor it explains, counting only the
equations where the gain holds when the manoeuvres are resampled; it is meaningful at 5 %, and
only when its gain is significant in at least two equations (:data:`MIN_EQUATIONS`). The best
meaningful finding becomes an effect file in the catalogue's format
(:meth:`Discovery.effect_toml`) that ``fit --effects`` and ``diagnose --effects`` take.

A catalogued effect that is meaningful on the same records competes with it: a family can stand
in for a missing catalogued effect (position terms for an asymmetry), and a catalogued effect
for a family.  Shares of the residual do not say which flies better, so flights decide
(:func:`sindyship.diagnose.contest.flight_contest`): both extensions are fitted leaving one
manoeuvre out and fly the manoeuvre left out; the finding is accepted only when it flies
better than each meaningful catalogued effect, and the report gives the numbers.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .._diagnosis_thresholds import MEANINGFUL_SHARE, NOISE_VISIBLE
from .._io import clean_json
from ..identify import design, resolve_library, resolve_rudder_signal
from ..library import DOFS, Effect, TermLibrary
from ..optimizers import ForwardSelection, GroupedProblem, one_blas_thread
from ..ships import Ship
from ..smoothing import resolve_smoothing, smooth_records
from ..terms import SHAPE_KINDS
from ..trajectory import Trajectory
from ._words import _hint, _physics, _title, _toml_string, shape_words
from .candidates import Family, families, family_columns, unnamed_channels
from .contest import FlightContest, flight_contest
from .delays import lomo_errors, search_delay
from .noise import noise_sse
from .ranking import rank_effects
from .scoring import _dof_shares
from .shapes import far_from_origin, search_shape

#: Most terms a family may add to one equation.
MAX_TERMS = 4
#: Equations in which a finding's gain must be significant: the search tries many more
#: candidates than the catalogue holds, and a force missing from a hull acts on at least two
#: of X, Y and N (a side force has a moment), while a chance fit of a slow drift in one
#: equation does not.
MIN_EQUATIONS = 2
#: Least fall of the leave-one-manoeuvre-out error (share of the library's) for which the
#: forward selection adds another term.
MIN_STEP_GAIN = 0.01


@dataclass
class Finding:
    """One candidate explanation of the residual: a delay of a channel, or a family's terms.

    Attributes
    ----------
    family : str
        ``delay:CHANNEL`` or a family of :mod:`sindyship.diagnose.candidates`.
    terms : dict of str to list of str
        Terms added per degree of freedom (empty for a delay).
    delays : dict of str to float
        Channel -> seconds by which the recorded channel lags the force (empty for terms).
    explained_by_dof, signal_by_dof : dict of str to float
        Share of the leave-one-manoeuvre-out error explained, and of its part above the noise
        floor, per equation.
    significant : dict of str to bool
        Whether the gain in each equation holds when the manoeuvres are resampled.
    explained, explained_signal : float
        Means over X, Y and N (the signal share counting only significant equations).
    meaningful : bool
        ``explained_signal`` reaches the threshold, significant in :data:`MIN_EQUATIONS`
        equations.
    variables : list of str
        The variables the finding involves.
    hint : str
        What such a finding usually means physically, from its variables.
    curve : list of [float, float]
        For a delay: (delay [s], leave-one-manoeuvre-out error relative to no delay).
    intervals : dict of str to [float, float]
        For a delay: channel -> the 95 % interval of the delay [s] when the records are
        resampled (:func:`delay_interval`).
    """

    family: str
    terms: dict[str, list[str]]
    delays: dict[str, float]
    explained_by_dof: dict[str, float]
    signal_by_dof: dict[str, float]
    significant: dict[str, bool]
    explained: float
    explained_signal: float
    meaningful: bool
    variables: list[str]
    hint: str
    curve: list[list[float]] = field(default_factory=list)
    intervals: dict[str, list[float]] = field(default_factory=dict)

    def to_json(self) -> dict:
        return clean_json({
            "family": self.family, "terms": self.terms, "delays": self.delays,
            "intervals": self.intervals,
            "explained": self.explained, "explained_signal": self.explained_signal,
            "explained_by_dof": self.explained_by_dof, "signal_by_dof": self.signal_by_dof,
            "significant": self.significant, "meaningful": self.meaningful,
            "variables": self.variables, "hint": self.hint, "curve": self.curve,
        })


@dataclass
class Discovery:
    """What :func:`discover` found.

    Attributes
    ----------
    library : TermLibrary
        The library that was fitted.
    records : list of str
        Training record names.
    rounds : list of list of Finding
        Every candidate of every round, the most explaining first; round k searched with the
        findings of the rounds before it added to the library.
    accepted : list of Finding
        The meaningful best finding of each round, in order (empty: nothing was discovered).
    noise_floor : dict of str to float
        Share of each equation's leave-one-manoeuvre-out error that is noise (first round).
    threshold : float
    seconds : float
    catalogue : dict of str to float
        Catalogued effects that are meaningful on these records, with the share they explain:
        each round's best finding competes with each of them in flights (``contests``), else
        a family could be standing in for a catalogued effect that is missing.
    smoothing : dict or None
        The smoothing applied to the records (:meth:`SmoothingSetting.as_dict`).
    unnamed_channels : list of str
        Recorded columns left out of the search because no term can name them.
    contests : list of FlightContest
        Each round's meaningful findings against the meaningful catalogued effects, most
        explaining first (and a shape also against the library alone), flown
        (:func:`sindyship.diagnose.contest.flight_contest`) until one does not lose; a finding
        is accepted only when it won every contest.  A shape that loses to the library alone
        was a chance fit, and the round's next meaningful finding is tried.
    notes : list of str
        What the search left out and why (shapes of the position on tracks far from the
        origin).
    """

    library: TermLibrary
    records: list[str]
    rounds: list[list[Finding]]
    accepted: list[Finding]
    noise_floor: dict[str, float]
    threshold: float
    seconds: float
    catalogue: dict[str, float] = field(default_factory=dict)
    smoothing: dict | None = None
    unnamed_channels: list[str] = field(default_factory=list)
    contests: list[FlightContest] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def findings(self) -> list[Finding]:
        """The first round's candidates, the most explaining first."""
        return self.rounds[0] if self.rounds else []

    @property
    def best(self) -> Finding | None:
        """The first accepted finding, or None."""
        return self.accepted[0] if self.accepted else None

    def effect(self, name: str | None = None) -> Effect:
        """The accepted findings as one effect (raises when nothing was discovered)."""
        from ..errors import SindyshipInputError

        if not self.accepted:
            raise SindyshipInputError(
                "nothing meaningful was discovered, so there is no effect to write; the "
                "report says what was tried (and which catalogued effects to add first)."
            )
        families = [f.family.replace(":", "_") for f in self.accepted]
        name = name or "discovered_" + "_".join(families)
        delays = {c: d for f in self.accepted for c, d in f.delays.items()}
        terms = {dof: [t for f in self.accepted for t in f.terms.get(dof, [])] for dof in DOFS}
        channels = _channels({v for f in self.accepted for v in f.variables}, delays)
        title = "; ".join(_title(f) for f in self.accepted)
        physics = " ".join(_physics(f, self.records) for f in self.accepted)
        return Effect(name, title, physics, channels, terms, delays=delays)

    def effect_toml(self, name: str | None = None) -> str:
        """The best finding as an effect file in the catalogue's format (docs/effects.md)."""
        effect = self.effect(name)
        lines = ["# Discovered by sindyship discover.  Format: see docs/effects.md.",
                 f"name = {_toml_string(effect.name)}", f"title = {_toml_string(effect.title)}",
                 f"physics = {_toml_string(effect.physics)}",
                 f"channels = {json.dumps(list(effect.channels))}"]
        if effect.delays:
            intervals = {c: i for f in self.accepted for c, i in f.intervals.items()}
            lines += ["", "[delays]  # seconds by which the recorded channel lags the force"]
            lines += [f"{c} = {d:.2f}" + (f"  # 95 % interval {intervals[c][0]:.2f} to "
                                          f"{intervals[c][1]:.2f} s" if c in intervals else "")
                      for c, d in effect.delays.items()]
        if any(effect.terms.values()):
            lines += [""]
            words = (shape_words(f.variables, f.intervals) for f in self.accepted)
            lines += [f"# {line}" for line in words if line]
            lines += ["[terms]"]
            lines += [f"{dof} = {json.dumps([t.text for t in effect.terms[dof]])}"
                      for dof in DOFS if effect.terms[dof]]
        return "\n".join(lines) + "\n"

    def report(self, effect_file: str | None = None) -> str:
        """The findings as text (:func:`sindyship.diagnose.discovery_report.discovery_report`)."""
        from .discovery_report import discovery_report

        return discovery_report(self, effect_file)

    def to_json(self) -> dict:
        """The JSON document of ``sindyship discover --json``: at the top, the discovery (the
        accepted findings together, else the best candidate, with ``meaningful`` false), then
        every finding of every round."""
        shown = self.accepted or self.findings[:1]
        return clean_json({
            "meaningful": bool(self.accepted),
            "terms": {dof: [t for f in shown for t in f.terms.get(dof, [])] for dof in DOFS},
            "delays": {c: d for f in shown for c, d in f.delays.items()},
            "explained": shown[0].explained if shown else 0.0,
            "explained_signal": shown[0].explained_signal if shown else 0.0,
            "explained_by_dof": shown[0].explained_by_dof if shown else dict.fromkeys(DOFS, 0.0),
            "variables": sorted({v for f in shown for v in f.variables}),
            "hints": [f.hint for f in shown],
            "library": self.library.name, "records": self.records,
            "noise_floor": self.noise_floor, "threshold": self.threshold,
            "accepted": [f.to_json() for f in self.accepted],
            "rounds": [[f.to_json() for f in found] for found in self.rounds],
            "catalogue_meaningful": self.catalogue, "smoothing": self.smoothing,
            "unnamed_channels": self.unnamed_channels,
            "notes": self.notes,
            "contests": [c.to_json() for c in self.contests], "seconds": self.seconds,
        })


# ------------------------------------------------------------------------------- search
def _finding(family, terms, delays, e0, e1, noise, groups, threshold, variables, curve=(),
             logged_wind=False, intervals=None):
    explained, signal, significant = {}, {}, {}
    for dof in DOFS:
        if e1.get(dof) is None or not float(e0[dof] @ e0[dof]) > 0:
            explained[dof], signal[dof], significant[dof] = 0.0, 0.0, False
            continue
        explained[dof], signal[dof], significant[dof] = _dof_shares(e0[dof], e1[dof],
                                                                    noise[dof], groups)
    share = float(np.mean([explained[d] for d in DOFS]))
    share_signal = float(np.mean([signal[d] if significant[d] else 0.0 for d in DOFS]))
    meaningful = share_signal >= threshold and sum(significant.values()) >= MIN_EQUATIONS
    return Finding(family, {d: list(terms.get(d, [])) for d in DOFS}, dict(delays), explained,
                   signal, significant, share, share_signal, meaningful,
                   sorted(variables), _hint(family, delays, terms, logged_wind),
                   [list(map(float, p)) for p in curve],
                   {c: [float(a), float(b)] for c, (a, b) in (intervals or {}).items()})


def _search_family(family: Family, records, ship, library, problems, rudder_signal):
    """The family's terms :class:`ForwardSelection` adds to the library in each equation,
    leaving one manoeuvre out, and the leave-one-manoeuvre-out errors of the joint refit."""
    columns = family_columns(family, records, library, ship, rudder_signal)
    groups = problems["X"].groups
    chosen, errors = {}, {}
    for dof in DOFS:
        block = columns[dof]
        usable = np.all(np.isfinite(block), axis=0) & (np.ptp(block, axis=0) > 0)
        if not usable.any():
            continue
        names = [t for t, ok in zip(family.terms[dof], usable, strict=True) if ok]
        base = problems[dof].features.shape[1]
        joint = np.column_stack([problems[dof].features, block[:, usable]])
        search = ForwardSelection(n_fixed=base, max_terms=MAX_TERMS, min_gain=MIN_STEP_GAIN)
        added = search.fit(joint, problems[dof].target, groups=groups).selected_[0]
        if added:
            chosen[dof] = [names[j - base] for j in added]
            grouped = GroupedProblem(joint, problems[dof].target, groups)
            errors[dof] = grouped.lomo_errors(np.r_[np.arange(base), added])
    return chosen, errors


@one_blas_thread
def discover(
    records: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    effects: Sequence[str | Effect] = (),
    rudder_signal: str = "actual",
    derivative: str = "five-point",
    window: float = 21.0,
    smoothing=None,
    threshold: float = MEANINGFUL_SHARE,
    max_rounds: int = 1,
    check_catalogue: bool = True,
    rivals: Sequence[str | Effect] = (),
    n_jobs: int | None = 1,
) -> Discovery:
    """Search the force residual of a fitted library for an effect no catalogue lists.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records (at least two manoeuvres: everything is judged leaving one out).
    ship : Ship
    library : str or TermLibrary
        The library to extend (a name, a file, or an extended library).
    effects : sequence of str or Effect
        Effects already added to it (catalogued names, files or objects).
    rudder_signal, derivative, window
        As :func:`sindyship.identify.fit`.
    smoothing : SmoothingSetting or str, optional
        Smooth the records before differencing: ``"savgol:W"``, ``"rts:W"`` or ``"auto"``
        (:func:`sindyship.smoothing.resolve_smoothing`).
    threshold : float
        Share of the error above the noise floor a finding must explain to be meaningful.
    max_rounds : int
        Search again with each meaningful finding added, up to this many rounds: an effect
        can need a delay and terms (every accepted finding goes into the effect file).
    check_catalogue : bool
        Score the catalogue first: when catalogued effects are meaningful on the records, the
        best finding is accepted only when, fitted leaving one manoeuvre out, it flies the
        manoeuvres left out better than each of them does
        (:func:`sindyship.diagnose.contest.flight_contest`; a family can stand in for a
        missing catalogued effect: position terms for an asymmetry, say).
        :func:`sindyship.diagnose.diagnose` searches only when none is meaningful.
    rivals : sequence of str or Effect
        Effects (catalogued names, or objects such as an effect file's) the best finding must
        also fly better than in that contest, after the meaningful ones
        (:func:`sindyship.diagnose.diagnose` passes those its re-flown training flights
        favour although their share of the force error is small).
    n_jobs : int or None
        joblib workers for the refits of the delay grid (``None``: from a
        ``joblib.parallel_config`` block, e.g. a Dask cluster's; the result is the same).

    Returns
    -------
    Discovery
        ``.best``, ``.findings``, ``.report()``, ``.to_json()``, ``.effect_toml()``.

    Examples
    --------
    >>> from sindyship import load_ship, parse_effects, simulate_with_effects, Manoeuvre
    >>> ship = load_ship("kcs").with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)
    >>> plan = [Manoeuvre("turning-circle", rudder=35, duration=600),
    ...         Manoeuvre("turning-circle", rudder=-35, duration=600),
    ...         Manoeuvre("zigzag", rudder=20, check=20, duration=600),
    ...         Manoeuvre("zigzag", rudder=10, check=10, duration=600)]
    >>> runs = simulate_with_effects(ship, plan, parse_effects(["rudder_lag=4"]))
    >>> found = discover(runs, ship)
    >>> found.best.family, round(found.best.delays["delta"])
    ('delay:delta', 4)
    """
    from ..arguments import (
        as_records,
        as_ship,
        check_distinct_names,
        check_records,
        check_two_records,
    )
    from ..library import load_effect

    start = time.perf_counter()
    ship = as_ship(ship)
    records = check_records(as_records(records), ship)
    check_two_records(records, "discover")
    check_distinct_names(records)
    base = resolve_library(library)
    added = [e if isinstance(e, Effect) else load_effect(e) for e in effects]
    base = base.extended(*added) if added else base
    rudder_signal = resolve_rudder_signal(records, rudder_signal)
    setting = resolve_smoothing(smoothing, records, ship, library=base,
                                rudder_signal=rudder_signal, derivative=derivative,
                                window=window)
    measured = records
    if setting is not None:
        records = smooth_records(records, setting)
    settings = {"rudder_signal": rudder_signal, "derivative": derivative, "window": window}
    catalogue = (_meaningful_catalogue(records, ship, base, threshold, settings)
                 if check_catalogue else {})
    stand_ins = [load_effect(name) for name in sorted(catalogue, key=lambda n: -catalogue[n])]
    stand_ins += [e if isinstance(e, Effect) else load_effect(e) for e in rivals
                  if (e.name if isinstance(e, Effect) else e) not in catalogue]
    rounds, accepted, contests, library_now = [], [], [], base
    for _ in range(max(int(max_rounds), 1)):
        findings, floor = _search(records, ship, library_now, settings, threshold, n_jobs)
        rounds.append(findings)
        if len(rounds) == 1:
            first_floor = floor
        best = None
        for candidate in (f for f in findings if f.meaningful):
            effect = _as_effect(candidate, len(accepted) + 1)
            contenders = list(stand_ins)  # most explaining first
            if candidate.family in SHAPE_KINDS:  # a line chosen among hundreds: flights decide
                contenders.append(None)
            lost = None  # the position of the first contender that flies as well or better
            for k, rival in enumerate(contenders):  # the finding must fly better than each
                contests.append(flight_contest(records, measured, ship, library_now,
                                               (candidate.family, effect), rival, settings))
                if contests[-1].winner != "finding":
                    lost = k
                    break
            if lost is None:
                best = candidate
                break
            if lost < len(stand_ins):
                break  # a catalogued effect flies as well or better: the user adds it first
            # a shape that flies no better than the library alone was a chance fit: go on
        if best is None:
            break
        accepted.append(best)
        library_now = library_now.extended(_as_effect(best, len(accepted)))
    far = far_from_origin(records, ship.L)
    notes = [] if far is None else [
        f"Shapes of the position were not searched: the tracks lie {far:.0f} ship lengths "
        "from the origin (projected coordinates?); subtract a point near the trials from x "
        "and y, the same for every record, to search them."]
    return Discovery(base, [r.name for r in records], rounds, accepted, first_floor, threshold,
                     time.perf_counter() - start, catalogue,
                     None if setting is None else setting.as_dict(), unnamed_channels(records),
                     contests, notes)


def _meaningful_catalogue(records, ship, library, threshold, settings) -> dict[str, float]:
    """The catalogued effects meaningful on ``records`` (scored as the diagnosis does)."""
    ranked = rank_effects(records, records, ship, library, None, settings, optimizer="ls",
                          threshold=threshold)
    return {s.effect.name: s.explained_signal for s in ranked.ranking if s.meaningful}


def _as_effect(finding: Finding, k: int) -> Effect:
    """A finding as an in-memory effect (to search again with it in the library)."""
    return Effect(f"found{k}", finding.family, "", _channels(finding.variables, finding.delays),
                  finding.terms,
                  delays=finding.delays)


def _search(records, ship, library, settings, threshold, n_jobs=1
            ) -> tuple[list[Finding], dict]:
    """One round: every delay and family scored against ``library``'s residual."""
    problems = design(records, ship, library, **settings)
    groups = problems["X"].groups
    e0 = {dof: lomo_errors(problems[dof]) for dof in DOFS}
    window_samples = max(1, int(round(ship.time_scale / float(np.median([r.dt for r in records])))))
    noise = {dof: noise_sse(e0[dof], groups, window_samples) for dof in DOFS}
    findings = []
    dt = float(np.median([r.dt for r in records]))
    rudder_channel = "delta_c" if settings["rudder_signal"] == "commanded" else "delta"
    delayable = [rudder_channel] + sorted(set(library.channels) - {"psi", "x", "y"})
    for channel in delayable:
        if channel in library.delays or not all(r.has(channel) for r in records):
            continue  # a channel already delayed keeps its delay
        tau, errors, curve, interval = search_delay(records, ship, library, channel, e0,
                                                     settings, problems, n_jobs)
        if abs(tau) < dt:  # shorter than a sample: not a delay the records can resolve
            continue
        findings.append(_finding(f"delay:{channel}", {}, {channel: tau}, e0, errors, noise,
                                 groups, threshold, [channel], curve,
                                 intervals={channel: interval}))
    searched = [(family, {}) for family in families(records, library, ship)]
    for kind in SHAPE_KINDS:  # a shape of the position, its line searched, times library terms
        line = search_shape(kind, records, ship, library, problems, settings["rudder_signal"])
        if line is not None:
            searched.append((line.family(library), line.intervals))
    logged_wind = all(r.has("wind_speed") and r.has("wind_dir") for r in records)
    for family, intervals in searched:
        chosen, errors = _search_family(family, records, ship, library, problems,
                                        settings["rudder_signal"])
        if not chosen:
            continue
        used = {v for ts in chosen.values() for t in ts for v in _variables_of(t)}
        findings.append(_finding(family.name, chosen, {}, e0, errors, noise, groups,
                                 threshold, used, logged_wind=logged_wind, intervals=intervals))
    findings.sort(key=lambda f: (-f.explained_signal, -f.explained, f.family))
    floor = {dof: min(noise[dof] / max(float(e0[dof] @ e0[dof]), 1e-300), 1.0) for dof in DOFS}
    return findings, floor


def search_beyond_catalogue(result, fitted: Sequence[Trajectory], settings: Mapping,
                            n_jobs: int | None) -> bool:
    """Search beyond the catalogue for a diagnosis (:func:`sindyship.diagnose.diagnose`),
    into ``result.discovery``, when no catalogued effect is meaningful and the model is
    visibly wrong (a training flight diverged, or an equation's error stands clearly above
    its noise floor); whether it searched.  The effects the flights alone favour do not stop
    the search, but a finding must fly the manoeuvres left out better than each of them to
    be discovered (:func:`sindyship.diagnose.contest.flight_contest`)."""
    floor = result.noise_floor
    visibly_wrong = bool(result.diverged) or any(floor[dof] < NOISE_VISIBLE for dof in DOFS)
    if result.meaningful_top is not None or not visibly_wrong:
        return False
    result.discovery = discover(fitted, result.ship, library=result.library,
                                threshold=result.threshold, check_catalogue=False,
                                rivals=[score.effect for score in result.flight_favoured],
                                n_jobs=n_jobs, **settings)
    return True


def _channels(variables, delays) -> tuple[str, ...]:
    """The recorded channels an effect's variables are made from, beyond du, v, r, delta and
    the delayed channels (a shape of the position is made from x and y)."""
    from ..terms import sources_of

    sources = {source for name in variables for source in sources_of(name)}
    return tuple(sorted(sources - {"du", "v", "r", "delta"} - set(delays)))


def _variables_of(text: str) -> frozenset[str]:
    from ..terms import Term

    return Term(text).variables


__all__ = ["Discovery", "Finding", "discover"]

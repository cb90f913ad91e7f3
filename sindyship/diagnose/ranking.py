"""The catalogued effects ranked by the share of a library's force error they explain, leaving
one manoeuvre out: the scoring both the diagnosis and the search beyond the catalogue use."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import SindyshipInputError
from ..identify import Design, design
from ..library import DOFS, Effect, TermLibrary, available_effects, load_effect
from ..model import AbkowitzModel
from ..optimizers import GroupedProblem
from ..ships import Ship
from ..terms import Term
from ..trajectory import Trajectory
from .before_after import _fit
from .noise import noise_sse
from .residuals import Residuals, _residuals
from .scoring import EffectScore, NotTestable, _score, _untestable


@dataclass
class Ranking:
    """What :func:`rank_effects` finds: the library's fit, its cross-validated errors and
    noise floor, and the catalogued effects ranked (best first)."""

    model: AbkowitzModel
    base_problems: dict[str, Design]
    residuals: Residuals
    base_errors: dict[str, np.ndarray]
    noise: dict[str, float]
    force_error: dict[str, float]
    ranking: list[EffectScore]
    not_testable: list[NotTestable]
    in_library: list[str]


def catalogue(effects: Sequence[str | Effect] | None) -> list[Effect]:
    """The candidate effects: the whole catalogue (None), or names, files and objects."""
    names = available_effects() if effects is None else effects
    out = [e if isinstance(e, Effect) else load_effect(e) for e in names]
    seen = set()
    for effect in out:
        if effect.name in seen:
            raise SindyshipInputError(f'the effect "{effect.name}" is given twice.')
        seen.add(effect.name)
    return out


def _candidates(base: TermLibrary, effects: Sequence[Effect], records: Sequence[Trajectory]):
    """The effects to score (with their terms the library lacks), those not testable on the
    records and those already in the library."""
    candidates, not_testable, in_library = [], [], []
    present = {dof: {t.canonical(scale=False) for t in base.terms[dof]} for dof in DOFS}
    for effect in effects:
        if effect.name in base.effects:
            in_library.append(effect.name)
            continue
        reason = _untestable(effect, records)
        if reason is not None:
            not_testable.append(reason)
            continue
        new = {dof: [t.text for t in effect.terms[dof]
                     if t.canonical(scale=False) not in present[dof]] for dof in DOFS}
        if not any(new.values()):
            in_library.append(effect.name)
            continue
        candidates.append((effect, new))
    return candidates, not_testable, in_library


def rank_effects(fitted: Sequence[Trajectory], records: Sequence[Trajectory], ship: Ship,
                 base: TermLibrary, effects: Sequence[str | Effect] | None, settings: Mapping,
                 *, optimizer: str, threshold: float, n_jobs: int | None = 1) -> Ranking:
    """Fit ``base`` and score every candidate effect by the share of its leave-one-manoeuvre-out
    force error the effect's terms explain (least squares), best first.

    Parameters
    ----------
    fitted : sequence of Trajectory
        The training records as fitted (smoothed, if the caller smooths).
    records : sequence of Trajectory
        The same records as measured (which channels they hold; the noise window).
    ship, base, effects
        The ship, the library and the candidates (:func:`catalogue`).
    settings : mapping
        ``rudder_signal``, ``derivative`` and ``window`` of :func:`sindyship.identify.fit`.
    optimizer : str
        The optimizer of the library's fit (the scoring itself is least squares).
    threshold : float
        Share of the error above the noise floor an effect must explain to be meaningful.
    n_jobs : int or None
        Threads for the scores.
    """
    from joblib import Parallel, delayed

    candidates, not_testable, in_library = _candidates(base, catalogue(effects), records)
    union = base.extended(*[effect for effect, _ in candidates])
    problems = design(fitted, ship, union, **settings)
    n_base = {dof: len(base.terms[dof]) for dof in DOFS}
    base_problems = {
        dof: Design(problems[dof].features[:, : n_base[dof]], problems[dof].target,
                    problems[dof].groups, problems[dof].terms[: n_base[dof]])
        for dof in DOFS
    }
    model = _fit(fitted, ship, base, base_problems, optimizer=optimizer, **settings)
    residuals = _residuals(base_problems, {dof: model.coefficient_vector(dof) for dof in DOFS},
                           fitted, ship, settings["rudder_signal"])
    grouped = {dof: GroupedProblem(problems[dof].features, problems[dof].target,
                                   problems[dof].groups) for dof in DOFS}
    base_columns = {dof: np.arange(n_base[dof]) for dof in DOFS}
    base_errors = {dof: grouped[dof].lomo_errors(base_columns[dof]) for dof in DOFS}
    window = max(1, int(round(ship.time_scale / float(np.median([r.dt for r in records])))))
    noise = {dof: noise_sse(base_errors[dof], problems[dof].groups, window) for dof in DOFS}
    force_error = {
        dof: float(np.sqrt(np.mean(base_errors[dof] ** 2))
                   / max(np.sqrt(np.mean(problems[dof].target ** 2)), 1e-300))
        for dof in DOFS
    }
    index = {dof: {t.canonical(scale=False): i for i, t in enumerate(union.terms[dof])}
             for dof in DOFS}
    jobs = []
    for effect, new in candidates:
        columns = {dof: np.array(sorted(set(base_columns[dof].tolist())
                                        | {index[dof][Term(t).canonical(scale=False)]
                                           for t in new[dof]}), dtype=int)
                   for dof in DOFS}
        jobs.append(delayed(_score)(effect, columns, grouped, base_errors, residuals, new,
                                    threshold, noise))
    ranking = list(Parallel(n_jobs=n_jobs, prefer="threads")(jobs)) if jobs else []
    ranking.sort(key=lambda s: (-s.explained_signal, -s.explained, s.effect.name))
    return Ranking(model, base_problems, residuals, base_errors, noise, force_error, ranking,
                   not_testable, in_library)

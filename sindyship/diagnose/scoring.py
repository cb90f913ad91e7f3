"""Scoring catalogued effects by the share of the cross-validated force error they explain."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from .._diagnosis_thresholds import BOOTSTRAP, NOISE_CAP, SIGNIFICANCE
from .._io import clean_json
from ..library import (
    DOFS,
    Effect,
    apparent_wind,
)
from ..optimizers import GroupedProblem
from ..reports import DOF_NAMES
from ..terms import DERIVED_SOURCES, describe_variable
from ..trajectory import Trajectory
from .before_after import BeforeAfter
from .residuals import STATE_BINS, Residuals, _bin_index, _bin_labels


# =============================================================================== scoring
@dataclass(frozen=True)
class NotTestable:
    """An effect the data cannot test, and the channels to record.

    Attributes
    ----------
    effect : Effect
    needs : tuple of str
        Channels absent from some record, or with one value throughout all of them.
    reason : str
    """

    effect: Effect
    needs: tuple[str, ...]
    reason: str

    def to_json(self) -> dict:
        return {
            "effect": self.effect.name,
            "title": self.effect.title,
            "needs": list(self.needs),
            "reason": self.reason,
        }


def _untestable(effect: Effect, records: Sequence[Trajectory]) -> NotTestable | None:
    """Why the data cannot test ``effect``, or None if they can.

    A channel is missing when some record lacks it, and carries no information when it has
    one value throughout all the records (a channel constant within each record but
    different between records, such as the depth of runs in two waters, is testable).  A
    channel the terms read only through a variable made from the motion (the true wind of the
    apparent wind) is judged by that variable: a steady wind from one direction still turns
    with the ship.
    """
    derived = {name for name in effect.variables if name in DERIVED_SOURCES}
    through_motion = ({source for name in derived for source in DERIVED_SOURCES[name]}
                      - set(effect.variables))
    needs, reasons = [], []
    for channel in effect.channels:
        variable = describe_variable(channel)
        if variable.column == "rudder_rate":
            continue  # made from the rudder angle
        what = "" if variable.description.startswith("channel ") else f" ({variable.description})"
        missing = [r.name for r in records if not r.has(variable.column)]
        if missing:
            needs.append(channel)
            where = "every record" if len(missing) == len(records) else ", ".join(missing)
            reasons.append(f"{channel}{what} is absent from {where}")
            continue
        if channel in through_motion:
            continue  # judged by the apparent wind below
        values = np.concatenate([r[variable.column] for r in records])
        finite = values[np.isfinite(values)]
        spread = float(np.ptp(finite)) if finite.size else 0.0
        if spread <= 1e-12 * max(1.0, float(np.max(np.abs(finite), initial=0.0))):
            needs.append(channel)
            value = f" ({finite[0]:g})" if finite.size else ""
            reasons.append(f"{channel}{what} has one value{value} throughout all the records")
    if derived and not needs and not _apparent_wind_changes(records):
        needs = sorted(through_motion)
        reasons.append("the apparent wind made from wind_speed and wind_dir does not change "
                       "(no wind was recorded)")
    if not needs:
        return None
    advice = f"record {', '.join(needs)} in every record, with values that change"
    return NotTestable(effect, tuple(needs), "; ".join(reasons) + f": {advice}.")


def _apparent_wind_changes(records: Sequence[Trajectory]) -> bool:
    """Whether the apparent wind (speed or angle) the records' true wind and motion make
    changes over the records."""
    speeds, angles = [], []
    for r in records:
        speed, angle = apparent_wind(r["u"], r["v"], r["psi"], r["wind_speed"], r["wind_dir"])
        speeds.append(speed)
        angles.append(np.sin(angle))
    return any(_varies(np.concatenate(values)) for values in (speeds, angles)) and any(
        float(np.nanmax(np.abs(r["wind_speed"]), initial=0.0)) > 0.0 for r in records)


def _varies(values: np.ndarray) -> bool:
    finite = values[np.isfinite(values)]
    return bool(finite.size) and float(np.ptp(finite)) > 1e-9 * max(
        1.0, float(np.max(np.abs(finite))))


@dataclass
class EffectScore:
    """How much of the remaining force error one catalogued effect explains.

    Attributes
    ----------
    effect : Effect
    explained : float
        Mean over X, Y and N of clip(1 - SSE_with / SSE_without, 0, 1) on
        leave-one-manoeuvre-out predictions (see the module docstring).
    explained_by_dof : dict of str to float
        The three terms of that mean.
    new_terms : dict of str to list of str
        The effect's terms the library did not have, per degree of freedom.
    regime : str
        Where the effect matters: the state bin and the manoeuvres that gain most.
    regime_detail : dict
        The numbers behind ``regime``.
    meaningful : bool
        ``explained_signal`` reaches the threshold of :func:`diagnose`.
    confirmation : BeforeAfter or None
        The refit with the effect and its flights, for the best candidates.
    explained_signal : float
        Mean over X, Y and N of the share of the error above the noise floor that the effect
        explains, counting only the equations where its gain is significant
        (:func:`significance`); equals ``explained`` on noise-free data with a consistent gain.
    significant : dict of str to bool
        Per equation: whether the gain holds against chance (bootstrap over manoeuvres).
    """

    effect: Effect
    explained: float
    explained_by_dof: dict[str, float]
    new_terms: dict[str, list[str]]
    regime: str
    regime_detail: dict
    meaningful: bool
    confirmation: BeforeAfter | None = None
    explained_signal: float = 0.0
    significant: dict[str, bool] = field(default_factory=dict)

    @property
    def refuted_by_held_out(self) -> bool:
        """Whether the held-out flights of :attr:`confirmation` refute the effect
        (:attr:`BeforeAfter.held_out_supports` is False)."""
        return self.confirmation is not None and self.confirmation.held_out_supports is False

    def to_json(self) -> dict:
        return clean_json(
            {
                "effect": self.effect.name,
                "title": self.effect.title,
                "explained": self.explained,
                "explained_by_dof": self.explained_by_dof,
                "explained_signal": self.explained_signal,
                "significant": self.significant,
                "meaningful": self.meaningful,
                "regime": self.regime,
                "regime_detail": self.regime_detail,
                "physics": self.effect.physics,
                "channels": list(self.effect.channels),
                "new_terms": self.new_terms,
                "confirmation": None if self.confirmation is None else self.confirmation.to_json(),
            }
        )


def _regime(
    gain: np.ndarray,
    gain_by_dof: Mapping[str, float],
    residuals: Residuals,
    *,
    uses_heading: bool = False,
) -> tuple[str, dict]:
    """Describe where an effect's gain (per-sample error reduction) is concentrated."""
    total = float(gain.sum())
    if not total > 0:
        return "nowhere: it explains nothing on held-out manoeuvres", {}
    best = None
    for variable, bins in STATE_BINS.items():
        index = _bin_index(residuals.state[variable], bins)
        labels = _bin_labels(bins, variable)
        for b, label in enumerate(labels):
            mask = index == b
            share = float(gain[mask].sum()) / total
            samples = float(mask.mean())
            if samples == 0 or share < 0.25:
                continue
            lift = share / samples
            if best is None or lift > best["lift"]:
                best = {
                    "variable": variable,
                    "bin": f"{label} {bins.unit}".strip(),
                    "description": bins.name,
                    "gain_share": share,
                    "sample_share": samples,
                    "lift": lift,
                }
    by_record = {
        name: float(gain[residuals.groups == g].sum()) / total
        for g, name in enumerate(residuals.names)
    }
    ranked = sorted(by_record.items(), key=lambda item: -item[1])
    dof = max(gain_by_dof, key=gain_by_dof.get)
    parts = [f"mostly in the {DOF_NAMES[dof]}"]
    if best is not None and best["lift"] >= 1.2:
        parts.append(
            f"at {best['description']} {best['bin']} ({best['gain_share']:.0%} of the "
            f"gain in {best['sample_share']:.0%} of the samples)"
        )
    else:
        parts.append("spread over all drift angles, yaw rates, rudder angles and headings")
    top = [f"{name} ({share:.0%})" for name, share in ranked[:2] if share > 0]
    if top:
        parts.append("largest on " + " and ".join(top))
    detail = {"dof": dof, "bin": best, "by_manoeuvre": by_record}
    if uses_heading:
        covered = _heading_coverage(residuals.state["heading"])
        detail["heading_coverage_deg"] = covered
        if covered < 180.0:
            parts.append(
                f"caution: the records visit only {covered / 10:.0f} ten-degree sectors of "
                "heading, over which sin and cos of psi can stand in for any slow drift"
            )
    return "; ".join(parts), detail


def _heading_coverage(heading_deg: np.ndarray) -> float:
    """Degrees of the compass the records visit (in 10-degree sectors)."""
    sectors = np.unique(np.floor(np.mod(heading_deg, 360.0) / 10.0))
    return 10.0 * len(sectors)


def significance(sse_without: np.ndarray, sse_with: np.ndarray, *, n_boot: int = BOOTSTRAP,
                 level: float = SIGNIFICANCE) -> bool:
    """Whether an effect's gain in one equation holds against chance.

    The leave-one-manoeuvre-out errors are resampled by manoeuvre (a block bootstrap: the
    manoeuvres are the independent units, the samples within one are not) and the gain
    ``1 - SSE_with / SSE_without`` recomputed; the gain is significant when its ``level``
    quantile stays above zero, i.e. when it does not hinge on one or two manoeuvres.  Terms
    of an absent effect fit noise and chance features of some manoeuvres and lose on others,
    so their resampled gain straddles zero.  Seeded (``numpy.random.default_rng(0)``).

    Parameters
    ----------
    sse_without, sse_with : ndarray, shape (n_records,)
        Per manoeuvre: summed squared leave-one-manoeuvre-out error without and with the
        effect's terms.
    n_boot : int
        Bootstrap resamples.
    level : float
        Quantile of the resampled gain that must stay above zero.

    Returns
    -------
    bool

    Examples
    --------
    >>> significance(np.array([4.0, 5.0, 6.0, 5.0]), np.array([2.0, 2.5, 3.0, 2.0]))
    True
    >>> significance(np.array([4.0, 5.0, 6.0, 5.0]), np.array([1.0, 6.0, 6.5, 5.5]))
    False
    """
    n = len(sse_without)
    rng = np.random.default_rng(0)
    weights = rng.multinomial(n, np.full(n, 1.0 / n), size=n_boot)
    with np.errstate(invalid="ignore", divide="ignore"):
        gains = 1.0 - (weights @ sse_with) / (weights @ sse_without)
    return bool(np.quantile(np.nan_to_num(gains, nan=0.0), level) > 0.0)


def _dof_shares(e0: np.ndarray, e1: np.ndarray, noise: float, groups: np.ndarray
                ) -> tuple[float, float, bool]:
    """Explained share, share above the noise floor, and significance of one equation."""
    sse0, sse1 = float(e0 @ e0), float(e1 @ e1)
    gain = sse0 - sse1
    explainable = sse0 - min(noise, NOISE_CAP * sse0)
    significant = significance(_sse_by_record(e0, groups), _sse_by_record(e1, groups))
    return (float(np.clip(gain / sse0, 0.0, 1.0)),
            float(np.clip(gain / explainable, 0.0, 1.0)),
            significant)


def _score(
    effect: Effect,
    columns: Mapping[str, np.ndarray],
    grouped: Mapping[str, GroupedProblem],
    base_errors: Mapping[str, np.ndarray],
    residuals: Residuals,
    new_terms: dict,
    threshold: float,
    noise: Mapping[str, float],
) -> EffectScore:
    explained, signal, significant = {}, {}, {}
    gain = np.zeros(len(residuals.t))
    for dof in DOFS:
        e0 = base_errors[dof]
        sse0 = float(e0 @ e0)
        if not new_terms[dof] or not sse0 > 0:
            explained[dof], signal[dof], significant[dof] = 0.0, 0.0, False
            continue
        e1 = grouped[dof].lomo_errors(columns[dof])
        explained[dof], signal[dof], significant[dof] = _dof_shares(
            e0, e1, noise[dof], residuals.groups)
        if explained[dof] > 0.0:  # the regime follows the equations the effect helps
            gain += (e0**2 - e1**2) / sse0 / len(DOFS)
    share = float(np.mean([explained[dof] for dof in DOFS]))
    share_signal = float(np.mean([signal[dof] if significant[dof] else 0.0 for dof in DOFS]))
    regime, detail = _regime(gain, explained, residuals, uses_heading="psi" in effect.variables)
    return EffectScore(
        effect, share, explained, new_terms, regime, detail,
        meaningful=share_signal >= threshold, explained_signal=share_signal,
        significant=significant,
    )


def _sse_by_record(errors: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Summed squared error of each record (groups are 0..n_records-1)."""
    return np.bincount(groups, weights=errors**2)


"""Which terms the records cannot separate, and which tests would separate them.

Least squares always returns a coefficient for every term, and a model fitted to zig-zags flies
well even when its cubic coefficients are far from the ship's derivatives: along the records
the collinear terms trade off against each other.  :func:`identifiability` reports

* the terms whose variance inflation factor (VIF, :func:`sindyship.uncertainty.
  library_conditioning`) exceeds ``vif_bound``;
* the coefficients whose sign changes between leave-one-manoeuvre-out least-squares fits
  (:func:`sindyship.uncertainty.ensemble` with ``scheme="lomo"``);
* groups of collinear terms (Belsley, Kuh & Welsch 1980, on the standardised library: each
  near-dependency with a condition index above ``condition_bound`` groups the terms that owe
  more than ``proportion_bound`` of their coefficient variance to it; groups that share terms
  are merged), and for each group which variables of the data move together and which
  additional test lowers the group's VIF most.

Why the VIF bound is 1e5
------------------------
sqrt(VIF) is the factor by which collinearity inflates a coefficient's standard error, and
1 / VIF = 1 - R^2 is the share of the term's spread that the other terms cannot reproduce.  At
VIF = 1e5 that independent part is sqrt(1e-5) = 0.3 % of the term's spread, three to six
times below the relative residual of an Abkowitz least-squares fit to noise-free KCS
manoeuvres (0.7 % in Y to 2 % in N, reported as ``relative_residual``): the data see less of
the term on its own than the model's own misfit, so its fitted value is set by the misfit, not
by the ship.  On the KCS the terms above the bound (v^3, r^2 v, v^2 r, r^3, ...) are those whose
least-squares values are far from the MMG's Taylor reference, while the linear terms (VIF below
about 6e4) come out within a few per cent.  The textbook bound of 10 (Marquardt 1970) is meant
for independent noisy samples; every term of a third-order library exceeds it on manoeuvre
records.  Measured (noisy) data have larger residuals and call for a lower bound.

How a remedy is found
---------------------
For each group the variables its terms use (du, v', r', delta) are compared pairwise: a pair
is *tied* when one is predicted by a quadratic in the other with R^2 >= ``tie_bound`` (a
quadratic also catches the speed loss du that grows with v'^2).  Then candidate additions are
tried, not looked up: standard manoeuvres flown with the ship's MMG model (pull-outs, turning
circles at other angles, spirals, zig-zags of other shapes, random rudder sequences) and the
virtual captive tests of :mod:`sindyship.captive`; each candidate's samples are appended to
the records and the group's largest VIF is recomputed.  The best free-running candidate and
the captive tests are reported with the factor by which they lower it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import combinations
from typing import Any

import numpy as np

from .errors import SindyshipInputError
from .identify import Design, design, fit, resolve_library, resolve_rudder_signal
from .model import AbkowitzModel
from .ships import Ship
from .targets import DOFS
from .trajectory import Trajectory
from .uncertainty import ensemble, library_conditioning

__all__ = [
    "CONDITION_BOUND",
    "PROPORTION_BOUND",
    "TIE_BOUND",
    "VIF_BOUND",
    "CollinearGroup",
    "Identifiability",
    "identifiability",
]

VIF_BOUND = 1e5
CONDITION_BOUND = 30.0
PROPORTION_BOUND = 0.5
TIE_BOUND = 0.8
_CORE = ("du", "v", "r", "delta")
_NAMES = {"du": "u'", "v": "v'", "r": "r'", "delta": "delta"}


@dataclass(frozen=True)
class CollinearGroup:
    """Terms of one equation that the records cannot separate.

    Attributes
    ----------
    dof : str
        The equation (X, Y or N).
    terms : tuple of str
        The terms.
    condition_index : float
        Largest condition index of the near-dependencies that make the group.
    max_vif : float
        Largest VIF among the terms.
    variables : tuple of str
        The variables the terms use.
    ties : list of dict
        Variable pairs that move together: ``{"pair": [a, b], "r2": x}``.
    remedies : list of dict
        Candidate additions, best first: ``{"test": ..., "captive": bool, "max_vif": x,
        "factor": old / new}``.
    """

    dof: str
    terms: tuple[str, ...]
    condition_index: float
    max_vif: float
    variables: tuple[str, ...]
    ties: list[dict]
    remedies: list[dict] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"dof": self.dof, "terms": list(self.terms),
                "condition_index": _finite(self.condition_index),
                "max_vif": _finite(self.max_vif), "variables": list(self.variables),
                "ties": self.ties, "remedies": self.remedies}

    def text(self) -> str:
        """One line in plain words."""
        line = (f"{self.dof}: {', '.join(self.terms)} cannot be separated "
                f"(VIF up to {self.max_vif:.2g})")
        if self.ties:
            tied = "; ".join(f"{_NAMES.get(t['pair'][0], t['pair'][0])} moves with "
                             f"{_NAMES.get(t['pair'][1], t['pair'][1])} (R^2 {t['r2']:.2f})"
                             for t in self.ties)
            line += f": {tied}"
        else:
            names = ", ".join(_NAMES.get(v, v) for v in self.variables)
            line += f": the records excite {names} too little on their own"
        free = next((r for r in self.remedies if not r["captive"]), None)
        captive = next((r for r in self.remedies if r["captive"]), None)
        advice = []
        if free is not None:
            amount = _amount(free)
            advice.append(f"adding {free['test']} " + ("leaves it infinite" if amount is None
                                                       else f"lowers it {amount}"))
        if captive is not None:  # a hybrid fit takes them beside the records
            amount = _amount(captive)
            advice.append(f"{captive['test']} would lower it {amount} (give them to fit "
                          "with --captive, or check the model's forces against them with "
                          "sindyship forces)" if amount is not None else
                          f"{captive['test']} would leave it infinite")
        return line + (f"; {', '.join(advice)}." if advice else ".")


def _amount(remedy: dict) -> str | None:
    """How far a remedy lowers the largest VIF ("40-fold", or "to a finite VIF" for terms that
    were exactly collinear before it); None when they stay exactly collinear."""
    if remedy["max_vif"] is None:
        return None
    return "to a finite VIF" if remedy["factor"] is None else f"{remedy['factor']:.2g}-fold"


@dataclass(frozen=True)
class Identifiability:
    """What the records can and cannot identify (numbers; :meth:`text` for words).

    Attributes
    ----------
    vif : dict
        ``{dof: {term: VIF}}``.
    high_vif : dict
        ``{dof: [terms with VIF > vif_bound]}``, largest first.
    sign_flips : dict
        ``{dof: {term: [min, max]}}`` over the leave-one-manoeuvre-out fits.
    groups : list of CollinearGroup
    relative_residual : dict
        ``{dof: RMS(residual) / std(target)}`` of the fit on all records.
    bounds : dict
        ``vif``, ``condition_index``, ``proportion``, ``tie``.
    records : list of str
    """

    vif: dict[str, dict[str, float]]
    high_vif: dict[str, list[str]]
    sign_flips: dict[str, dict[str, list[float]]]
    groups: list[CollinearGroup]
    relative_residual: dict[str, float]
    bounds: dict[str, float]
    records: list[str]

    def flagged(self, dof: str) -> list[str]:
        """Every term of one equation flagged by VIF or by a sign flip."""
        return sorted(set(self.high_vif[dof]) | set(self.sign_flips[dof]))

    def to_dict(self) -> dict[str, Any]:
        return {"vif": {d: {t: _finite(v) for t, v in terms.items()}
                        for d, terms in self.vif.items()},
                "high_vif": self.high_vif, "sign_flips": self.sign_flips,
                "groups": [g.to_dict() for g in self.groups],
                "relative_residual": self.relative_residual, "bounds": self.bounds,
                "records": self.records}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, allow_nan=False)

    def text(self) -> str:
        """Plain words: one line per collinear group, one per equation with sign flips."""
        merged: dict[str, list[str]] = {}  # sway and yaw share their terms, hence their groups
        for group in self.groups:
            body = group.text().split(": ", 1)[1]
            merged.setdefault(body, []).append(group.dof)
        lines = [f"{' and '.join(dofs)}: {body}" for body, dofs in merged.items()]
        for dof in DOFS:
            if self.sign_flips[dof]:
                lines.append(f"{dof}: {', '.join(self.sign_flips[dof])} change sign between "
                             "leave-one-manoeuvre-out fits.")
        if not lines:
            lines.append("Every term is identifiable from these records (no VIF above "
                         f"{self.bounds['vif']:.2g}, no sign flips).")
        return "\n".join(lines)


def _finite(value: float) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


def _belsley_groups(problem: Design, condition_bound: float, proportion_bound: float
                    ) -> list[tuple[set[int], float]]:
    """Groups of column indices from the variance decomposition of the standardised library."""
    X = np.asarray(problem.features, dtype=float)
    spread = np.std(X, axis=0)
    free = np.flatnonzero(spread > 1e-12 * np.maximum(np.max(np.abs(X), axis=0), 1e-300))
    if free.size < 2:
        return []
    Z = (X[:, free] - X[:, free].mean(axis=0)) / spread[free]
    w, V = np.linalg.eigh((Z.T @ Z) / len(Z))
    w = np.maximum(w, 1e-300)
    share = V**2 / w[None, :]
    share /= share.sum(axis=1, keepdims=True)
    index = np.sqrt(w.max() / w)
    groups = []
    for k in np.flatnonzero(index > condition_bound):
        members = {int(free[j]) for j in np.flatnonzero(share[:, k] > proportion_bound)}
        if len(members) >= 2:
            groups.append((members, float(index[k])))
    merged: list[tuple[set[int], float]] = []
    for members, ci in sorted(groups, key=lambda g: -g[1]):
        for other in [m for m in merged if m[0] & members]:
            merged.remove(other)
            members, ci = members | other[0], max(ci, other[1])
        merged.append((members, ci))
    return merged


def _ties(values: dict[str, np.ndarray], variables: Sequence[str], bound: float) -> list[dict]:
    """Variable pairs where one is a quadratic of the other with R^2 >= bound."""
    out = []
    for a, b in combinations(variables, 2):
        best = 0.0
        for x, y in ((values[a], values[b]), (values[b], values[a])):
            if np.std(y) == 0 or np.std(x) == 0:
                continue
            A = np.column_stack([np.ones_like(x), x, x * x])
            residual = y - A @ np.linalg.lstsq(A, y, rcond=None)[0]
            best = max(best, 1.0 - float(np.var(residual) / np.var(y)))
        if best >= bound:
            out.append({"pair": [a, b], "r2": round(best, 4)})
    return out


def _candidates(ship: Ship) -> list[tuple[str, bool, list]]:
    """Candidate additions: (description, captive, manoeuvres or a captive frame)."""
    from .captive import captive_tests
    from .manoeuvres import Manoeuvre

    return [
        ("pull-outs from 35 deg turns to both sides", False,
         [Manoeuvre("pull-out", rudder=a) for a in (35.0, -35.0)]),
        ("turning circles at 10 and 20 deg to both sides", False,
         [Manoeuvre("turning-circle", rudder=a) for a in (10.0, 20.0, -10.0, -20.0)]),
        ("spirals to both sides", False,
         [Manoeuvre("spiral", rudder=35.0, first_sign=s) for s in (1, -1)]),
        ("zig-zags 35/5 and 10/10", False,
         [Manoeuvre("zigzag", rudder=35.0, check=5.0), Manoeuvre("zigzag", rudder=10.0,
                                                                 check=10.0)]),
        ("random rudder sequences", False,
         [Manoeuvre("random", rudder=35.0, seed=s) for s in (1, 2)]),
        ("captive static-drift, pure-yaw, drift-yaw and rudder tests", True,
         captive_tests(ship, "all")),
    ]


def _features(shell: AbkowitzModel, records: Sequence[Trajectory]) -> dict[str, np.ndarray]:
    """Library columns of records (features only, no targets)."""
    blocks = {dof: [] for dof in DOFS}
    for record in records:
        values = shell.variables(record)
        for dof in DOFS:
            blocks[dof].append(np.column_stack([t.evaluate(values) * np.ones(record.n_samples)
                                                for t in shell.library.terms[dof]]))
    return {dof: np.vstack(b) for dof, b in blocks.items()}


def _remedy_vifs(problems: dict[str, Design], shell: AbkowitzModel, ship: Ship
                 ) -> list[tuple[str, bool, dict]]:
    """VIFs of every term after appending each candidate's samples."""
    from .manoeuvres import fly
    from .mmg import MMGModel

    candidates = _candidates(ship)
    # every candidate manoeuvre flown in one batch (one integration, whatever their number)
    flown = iter(fly(MMGModel(ship), [m for _, captive, what in candidates if not captive
                                      for m in what]))
    out = []
    for label, captive, what in candidates:
        if captive:
            frame = what.assign(t=np.arange(len(what), dtype=float), x=0.0, y=0.0, psi=0.0,
                                delta_c=what["delta"])
            extra = _features(shell, [Trajectory(frame, name="captive")])
        else:
            extra = _features(shell, [next(flown) for _ in what])
        combined = {}
        for dof in DOFS:
            rows = np.vstack([problems[dof].features, extra[dof]])
            combined[dof] = Design(features=rows, target=np.zeros(len(rows)),
                                   groups=np.zeros(len(rows), dtype=int),
                                   terms=problems[dof].terms)
        out.append((label, captive, library_conditioning(combined)))
    return out


def _group(dof, members, ci, problem, vif, values, shell, tie_bound, remedies):
    terms = tuple(problem.terms[j] for j in sorted(members))
    term_objects = {t.text: t for t in shell.library.terms[dof]}
    used = set().union(*(term_objects[t].variables for t in terms))
    variables = tuple(v for v in _CORE if v in used)
    max_vif = max(vif[t] for t in terms)
    found = []
    for label, captive, conditioning in remedies:
        new = max(conditioning[dof]["vif"][t] for t in terms)
        found.append({"test": label, "captive": captive, "max_vif": _finite(new),
                      "factor": _finite(max_vif / new) if new > 0 else None})
    # best first: a remedy from exact collinearity to a finite VIF (factor None) beats any
    # finite factor; one that leaves the VIF infinite comes last
    found.sort(key=lambda r: (r["max_vif"] is None,
                              -(math.inf if r["factor"] is None else r["factor"])))
    return CollinearGroup(dof=dof, terms=terms, condition_index=ci, max_vif=max_vif,
                          variables=variables, ties=_ties(values, variables, tie_bound),
                          remedies=found)


def identifiability(records: Sequence[Trajectory], ship: Ship, *,
                    library="abkowitz", effects: Sequence[str] = (), optimizer: str = "ls",
                    params: dict | None = None,
                    rudder_signal: str = "actual", vif_bound: float = VIF_BOUND,
                    condition_bound: float = CONDITION_BOUND,
                    proportion_bound: float = PROPORTION_BOUND, tie_bound: float = TIE_BOUND,
                    remedies: bool = True) -> Identifiability:
    """Terms the records cannot separate, and which tests would separate them.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records (SI).
    ship : Ship
        The ship (L, U0, inertia; its MMG model flies the candidate manoeuvres).
    library, effects, rudder_signal
        As for :func:`sindyship.identify.fit`.
    optimizer : str
        Method of the leave-one-manoeuvre-out fits (default least squares).
    params : dict, optional
        Its parameters (:func:`sindyship.optimizers.make_optimizer`).
    vif_bound : float
        Terms above it are reported (module docstring: why 1e5).
    condition_bound, proportion_bound : float
        Belsley's condition index (30) and variance-proportion (0.5) bounds for groups.
    tie_bound : float
        R^2 above which two variables count as moving together.
    remedies : bool
        Try candidate manoeuvres and captive tests (needs the library to use only du, v, r
        and delta; otherwise no remedies are tried).

    Returns
    -------
    Identifiability
    """
    records = list(records)
    if not records:
        raise SindyshipInputError("no records to judge; pass at least one record.")
    lib = resolve_library(library, effects)
    rudder_signal = resolve_rudder_signal(records, rudder_signal)
    problems = design(records, ship, lib, rudder_signal=rudder_signal)
    conditioning = library_conditioning(problems)
    vif = {dof: conditioning[dof]["vif"] for dof in DOFS}
    model = fit(records, ship, library=lib, optimizer="ls", problems=problems,
                rudder_signal=rudder_signal)
    residual = {}
    for dof in DOFS:
        p = problems[dof]
        error = p.features @ model.coefficient_vector(dof) - p.target
        residual[dof] = float(np.sqrt(np.mean(error**2)) / max(np.std(p.target), 1e-300))
    flips = {dof: {} for dof in DOFS}
    if len(records) >= 2:
        lomo = ensemble(records, ship, optimizer, params=params, scheme="lomo",
                        problems=problems, n_jobs=1)
        for dof in DOFS:
            coef = lomo.coefficients[dof]
            for j, term in enumerate(lomo.terms[dof]):
                if np.any(coef[:, j] > 0) and np.any(coef[:, j] < 0):
                    flips[dof][term] = [float(coef[:, j].min()), float(coef[:, j].max())]
    shell = AbkowitzModel(ship=ship, library=lib, coefficients={}, rudder_signal=rudder_signal)
    tried = []
    if remedies and set(lib.variables) <= set(_CORE):
        tried = _remedy_vifs(problems, shell, ship)
    values = {name: np.concatenate([shell.variables(r)[name] for r in records])
              for name in _CORE}
    groups = []
    for dof in DOFS:
        for members, ci in _belsley_groups(problems[dof], condition_bound, proportion_bound):
            group = _group(dof, members, ci, problems[dof], vif[dof], values, shell,
                           tie_bound, tried)
            if group.max_vif > vif_bound:
                groups.append(group)
    high = {dof: sorted((t for t, v in vif[dof].items() if v > vif_bound),
                        key=lambda t: -vif[dof][t]) for dof in DOFS}
    return Identifiability(
        vif=vif, high_vif=high, sign_flips=flips, groups=groups, relative_residual=residual,
        bounds={"vif": vif_bound, "condition_index": condition_bound,
                "proportion": proportion_bound, "tie": tie_bound},
        records=[r.name for r in records],
    )

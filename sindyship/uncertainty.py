"""Uncertainty of identified coefficients: ensembles, conditioning and parameter drift.

The paper's "parameter drift" (section 3.3) is the symptom of an ill-conditioned regression:
when library columns are nearly linear combinations of each other, small changes in the data
move the coefficients a lot, in correlated directions, while the fitted forces barely change.
This module measures it in three ways.

:func:`ensemble`
    Refits the model many times on perturbed training sets: ``"bagging"`` draws the samples
    with replacement (optionally in blocks, see ``block``), ``"lomo"`` leaves one manoeuvre out
    at a time.  Every coefficient gets a mean, a standard deviation, quantiles and an
    inclusion probability (the share of models in which it is non-zero: 1 for least squares,
    informative for sparse optimizers).  :meth:`EnsembleResult.correlation` gives the
    correlations between coefficients over the ensemble: coefficients that drift together.
:func:`library_conditioning`
    The condition number of the column-scaled library matrix of each degree of freedom
    (Belsley, Kuh & Welsch 1980: columns scaled to unit length, not centred, so collinearity
    with the constant term counts) and of the centred and standardised matrix, and the
    variance inflation factor (VIF) of every non-constant term: ``VIF_j = 1 / (1 - R_j^2)``
    with ``R_j^2`` from regressing column j on the others.  For least squares the sampling
    variance of a standardised coefficient is proportional to its VIF, so the ensemble spreads
    and the VIFs should rank the terms alike (:func:`spread_vif_agreement`).
:func:`drift_figure`
    The correlation matrix of one equation's ensemble coefficients as a heat map, terms
    ordered so that groups drifting together sit next to each other.

Reproducibility and parallelism
-------------------------------
Randomness enters only through ``seed``: member i draws from
``numpy.random.default_rng(numpy.random.SeedSequence(seed).spawn(n_models)[i])``, and each
member runs with a single BLAS thread, so the result is identical bit for bit whatever
``n_jobs`` is and wherever the members run.  Members are spread over workers with joblib.  On
a cluster, select a joblib backend around the call and leave ``n_jobs`` unset (it then comes
from the configuration)::

    import joblib
    from dask.distributed import Client          # pip install "dask[distributed]"

    client = Client("tcp://scheduler:8786")      # or Client() for a local cluster
    with joblib.parallel_config(backend="dask", n_jobs=-1):
        result = ensemble(records, ship, n_models=1000, seed=1)

The same works for :func:`sindyship.smoothing.choose_smoothing`, the flights and scores of
:func:`sindyship.diagnose.diagnose` and the delay grid of :func:`sindyship.diagnose.discover`
(``tests/test_cluster.py`` runs all four on a two-process ``LocalCluster`` and finds the
numbers of one process).  Ray's joblib backend (``ray.util.joblib.register_ray``) takes the
same route but is not tested here.  The training data travel to
every worker once per batch of members (``batch_size``); keep batches large when the network
is slow.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from .errors import SindyshipInputError
from .identify import Design, design, dof_params, resolve_library, resolve_rudder_signal
from .ships import Ship
from .targets import DOFS
from .trajectory import Trajectory

__all__ = [
    "EnsembleResult",
    "drift_figure",
    "ensemble",
    "library_conditioning",
    "spread_vif_agreement",
]

SCHEMES = ("bagging", "lomo")
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
#: Relative range below which a column counts as constant (as in sindyship.optimizers).
_CONSTANT_RTOL = 1e-12


@dataclass(frozen=True)
class EnsembleResult:
    """Coefficients of an ensemble of models fitted to perturbed training sets.

    Attributes
    ----------
    scheme : {"bagging", "lomo"}
        How the training sets were perturbed.
    optimizer : str
        The regression method.
    seed : int
        The seed the members' random streams were spawned from.
    terms : dict of str to tuple of str
        Term texts per degree of freedom, the columns of ``coefficients``.
    coefficients : dict of str to ndarray, shape (n_models, n_terms)
        The members' coefficients (Prime I).
    scale : dict of str to ndarray, shape (n_terms,)
        ``std(column) / std(target)`` on the full training set: a coefficient times its scale
        is the coefficient of the standardised problem (dimensionless and comparable between
        terms).  For a constant column, ``1 / std(target)``.
    members : tuple of str
        What each member was fitted on (``"bootstrap 7"``, ``"without zz20_20"``).
    """

    scheme: str
    optimizer: str
    seed: int
    terms: dict[str, tuple[str, ...]]
    coefficients: dict[str, np.ndarray]
    scale: dict[str, np.ndarray]
    members: tuple[str, ...] = field(default=())

    @property
    def n_models(self) -> int:
        return int(next(iter(self.coefficients.values())).shape[0])

    def mean(self, dof: str) -> np.ndarray:
        """Mean coefficient over the members."""
        return self._coef(dof).mean(axis=0)

    def std(self, dof: str) -> np.ndarray:
        """Standard deviation over the members (ddof=1; 0 for a single member)."""
        c = self._coef(dof)
        return c.std(axis=0, ddof=1) if c.shape[0] > 1 else np.zeros(c.shape[1])

    def standardised_std(self, dof: str) -> np.ndarray:
        """Spread of the standardised coefficients (``std * scale``): comparable between terms."""
        return self.std(dof) * self.scale[dof]

    def quantiles(self, dof: str, q: Sequence[float] = QUANTILES) -> np.ndarray:
        """Quantiles over the members, shape (len(q), n_terms)."""
        return np.quantile(self._coef(dof), np.asarray(q, dtype=float), axis=0)

    def inclusion(self, dof: str) -> np.ndarray:
        """Share of the members in which each coefficient is non-zero, in [0, 1]."""
        return np.mean(self._coef(dof) != 0.0, axis=0)

    def correlation(self, dof: str) -> np.ndarray:
        """Correlation between coefficients over the members, shape (n_terms, n_terms).

        NaN for a coefficient that does not vary over the ensemble (always zero, or a
        single member); 1 on the diagonal otherwise.
        """
        c = self._coef(dof)
        centred = c - c.mean(axis=0)
        norm = np.sqrt(np.sum(centred**2, axis=0))
        with np.errstate(invalid="ignore", divide="ignore"):
            z = centred / np.where(norm > 0, norm, np.nan)
        return z.T @ z

    def summary(self) -> pd.DataFrame:
        """One row per coefficient: mean, std, standardised std, quantiles, inclusion."""
        rows = []
        for dof in DOFS:
            q = self.quantiles(dof)
            mean, std, sstd = self.mean(dof), self.std(dof), self.standardised_std(dof)
            inclusion = self.inclusion(dof)
            for j, term in enumerate(self.terms[dof]):
                row = {"equation": dof, "term": term, "mean": mean[j], "std": std[j],
                       "standardised_std": sstd[j]}
                row.update({f"q{round(100 * level):02d}": q[k, j]
                            for k, level in enumerate(QUANTILES)})
                row["inclusion"] = inclusion[j]
                rows.append(row)
        return pd.DataFrame(rows)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the settings and, per equation and term, the summary statistics."""
        table = self.summary()
        out: dict[str, Any] = {"scheme": self.scheme, "optimizer": self.optimizer,
                               "seed": self.seed, "n_models": self.n_models,
                               "members": list(self.members), "coefficients": {}}
        for dof in DOFS:
            part = table[table["equation"] == dof].drop(columns="equation")
            out["coefficients"][dof] = {row.pop("term"): {k: float(v) for k, v in row.items()}
                                        for row in part.to_dict("records")}
        return out

    def _coef(self, dof: str) -> np.ndarray:
        if dof not in self.coefficients:
            raise SindyshipInputError(f"unknown equation {dof!r}; choose one of X, Y, N.")
        return self.coefficients[dof]


# ---------------------------------------------------------------------------------------------
# Ensembles
# ---------------------------------------------------------------------------------------------
def _block_indices(rng: np.random.Generator, groups: np.ndarray, block: int) -> np.ndarray:
    """Bootstrap sample indices: i.i.d. samples (block 1) or moving blocks inside records."""
    n = groups.size
    if block <= 1:
        return np.sort(rng.integers(0, n, n))
    # a block may start where the next block - 1 samples belong to the same record
    same = np.ones(n, dtype=bool)
    if block - 1 < n:
        same[: n - block + 1] = groups[: n - block + 1] == groups[block - 1:]
        same[n - block + 1:] = False
    else:
        same[:] = False
    starts = np.flatnonzero(same)
    if starts.size == 0:
        raise SindyshipInputError(
            f"the bootstrap block of {block} samples is longer than every record; choose a "
            "shorter block."
        )
    count = -(-n // block)
    chosen = starts[rng.integers(0, starts.size, count)]
    return np.sort((chosen[:, None] + np.arange(block)).ravel()[:n])


def _member_random_state(child: np.random.SeedSequence) -> int:
    return int(child.generate_state(1, dtype=np.uint32)[0] % (2**31 - 1))


def _fit_members(problems: Mapping[str, Design], jobs: Sequence[tuple[int, Any, Any]],
                 optimizer: str, params: Mapping[str, Any] | None, scheme: str,
                 block: int, ship: Ship) -> list[dict[str, np.ndarray]]:
    """Fit a batch of members; ``jobs`` holds (index, SeedSequence, left-out group).  Every
    equation gets its own parameters (:func:`sindyship.identify.dof_params`: the ship's prior
    for ``prior``)."""
    from sklearn.base import clone
    from threadpoolctl import threadpool_limits

    from .optimizers import make_optimizer

    groups = problems[DOFS[0]].groups
    out = []
    with threadpool_limits(limits=1, user_api="blas"):
        for _, child, left_out in jobs:
            rng = np.random.default_rng(child)
            if scheme == "bagging":
                rows = _block_indices(rng, groups, block)
            else:
                rows = np.flatnonzero(groups != left_out)
            member_params = dict(params or {})
            estimator = make_optimizer(optimizer, **member_params)
            if "random_state" in estimator.get_params() and "random_state" not in member_params:
                estimator.set_params(random_state=_member_random_state(child))
            coef = {}
            for dof in DOFS:
                problem = problems[dof]
                est = clone(estimator).set_params(**{
                    k: v for k, v in dof_params(optimizer, {}, ship, dof, problem.terms).items()
                    if k not in member_params})
                est.fit(problem.features[rows], problem.target[rows],
                        groups=problem.groups[rows])
                coef[dof] = np.asarray(est.coef_, dtype=float).reshape(-1)
            out.append(coef)
    return out


def ensemble(records: Sequence[Trajectory], ship: Ship, optimizer: str = "ls",
             scheme: str = "bagging", n_models: int = 50, seed: int = 0,
             n_jobs: int | None = None, *, library="abkowitz", effects: Sequence[str] = (),
             params: Mapping[str, Any] | None = None, rudder_signal: str = "actual",
             derivative: str = "five-point", window: float = 21.0, block: int = 1,
             batch_size: int | None = None,
             problems: Mapping[str, Design] | None = None) -> EnsembleResult:
    """Fit an ensemble of models on perturbed training sets.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records.
    ship : Ship
        The ship (L, U0, inertia).
    optimizer : str
        Regression method (:func:`sindyship.optimizers.make_optimizer`); ``params`` go to its
        constructor.  An optimizer with a ``random_state`` gets one per member from the seed.
    scheme : {"bagging", "lomo"}
        ``"bagging"``: each member is fitted on a bootstrap sample of the training samples
        (the same rows for X, Y and N).  ``"lomo"``: member k leaves record k out
        (``n_models`` is then the number of records).
    n_models : int
        Number of bootstrap members.
    seed : int
        Seed of every random choice (module docstring).
    n_jobs : int, optional
        joblib workers (``None``: from ``joblib.parallel_config``, else one; ``-1``: every
        core).  The result does not depend on it.
    library, effects, rudder_signal, derivative, window
        As for :func:`sindyship.identify.fit`.
    block : int
        Bootstrap block length in samples.  1 draws samples independently (bagging over
        samples); a longer block keeps runs of neighbouring, correlated samples together
        (moving-block bootstrap inside each record), which gives honest spreads when the
        residuals are correlated in time.
    batch_size : int, optional
        Members per joblib task (default: spread the members evenly, four tasks per worker).
    problems : dict, optional
        Precomputed :func:`sindyship.identify.design` of the same records.

    Returns
    -------
    EnsembleResult

    Raises
    ------
    SindyshipInputError
        For an unknown scheme, fewer than two records for ``"lomo"``, or ``n_models < 2``.

    Examples
    --------
    >>> from sindyship import load_ship, MMGModel, Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> runs = fly(MMGModel(ship), [Manoeuvre("zigzag", rudder=20, check=20, duration=800),
    ...                             Manoeuvre("turning-circle", rudder=-35, duration=800)])
    >>> result = ensemble(runs, ship, n_models=8, seed=3)
    >>> result.coefficients["Y"].shape
    (8, 22)
    >>> bool(np.all(result.inclusion("N") == 1.0))  # least squares keeps every term
    True
    """
    from joblib import Parallel, delayed, effective_n_jobs

    from .arguments import as_ship

    if scheme not in SCHEMES:
        raise SindyshipInputError(
            f"unknown ensemble scheme {scheme!r}; choose one of {', '.join(SCHEMES)}."
        )
    ship = as_ship(ship)
    records = list(records)
    rudder_signal = resolve_rudder_signal(records, rudder_signal)
    if problems is None:
        lib = resolve_library(library, effects)
        problems = design(records, ship, lib, rudder_signal=rudder_signal,
                          derivative=derivative, window=window)
    groups = problems[DOFS[0]].groups
    labels = np.unique(groups)
    names = [r.name or f"record {k}" for k, r in enumerate(records)]
    if len(names) < labels.size:
        names = [f"record {g}" for g in labels]
    if scheme == "lomo":
        if labels.size < 2:
            raise SindyshipInputError(
                "a leave-one-manoeuvre-out ensemble needs at least two training records."
            )
        left_out = list(labels)
        members = tuple(f"without {names[int(g)]}" for g in labels)
    else:
        if not (isinstance(n_models, int | np.integer) and n_models >= 2):
            raise SindyshipInputError(
                f"an ensemble needs at least 2 models, not {n_models!r}."
            )
        if not (isinstance(block, int | np.integer) and block >= 1):
            raise SindyshipInputError(f"the bootstrap block must be a whole number >= 1, "
                                      f"not {block!r}.")
        left_out = [None] * int(n_models)
        members = tuple(f"bootstrap {k}" for k in range(int(n_models)))
    children = np.random.SeedSequence(seed).spawn(len(left_out))
    jobs = list(zip(range(len(left_out)), children, left_out, strict=True))

    parallel = Parallel(n_jobs=n_jobs)
    if batch_size is None:
        workers = max(int(effective_n_jobs(n_jobs)), 1)
        batch_size = max(1, math.ceil(len(jobs) / (4 * workers)))
    batches = [jobs[i:i + batch_size] for i in range(0, len(jobs), batch_size)]
    fitted = parallel(delayed(_fit_members)(problems, batch, optimizer, params, scheme, block,
                                             ship)
                      for batch in batches)
    flat = [coef for batch in fitted for coef in batch]
    coefficients = {dof: np.vstack([c[dof] for c in flat]) for dof in DOFS}
    return EnsembleResult(
        scheme=scheme, optimizer=optimizer, seed=int(seed),
        terms={dof: tuple(problems[dof].terms) for dof in DOFS},
        coefficients=coefficients,
        scale={dof: _standard_scale(problems[dof]) for dof in DOFS},
        members=members,
    )


def _constant_columns(X: np.ndarray) -> np.ndarray:
    top = np.max(X, axis=0)
    bottom = np.min(X, axis=0)
    magnitude = np.maximum(np.abs(top), np.abs(bottom))
    return (top - bottom) <= _CONSTANT_RTOL * magnitude


def _standard_scale(problem: Design) -> np.ndarray:
    X, y = problem.features, problem.target
    y_std = float(np.std(y))
    y_std = y_std if y_std > 0 else 1.0
    x_std = np.std(X, axis=0)
    constant = _constant_columns(X)
    return np.where(constant, 1.0, x_std) / y_std


# ---------------------------------------------------------------------------------------------
# Conditioning
# ---------------------------------------------------------------------------------------------
def library_conditioning(problems: Mapping[str, Design]) -> dict[str, dict[str, Any]]:
    """Condition numbers and variance inflation factors of the library on the data.

    Parameters
    ----------
    problems : dict of str to Design
        :func:`sindyship.identify.design` output (one regression problem per equation).

    Returns
    -------
    dict
        Per equation: ``condition_number`` (columns scaled to unit length, not centred; the
        constant term included), ``condition_number_standardised`` (non-constant columns
        centred and scaled to unit variance), ``vif`` (``{term: VIF}``; NaN for a constant
        or all-zero column, inf for an exactly collinear one) and ``n_samples``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> a, b, c = rng.normal(size=(3, 500))
    >>> X = np.column_stack([np.ones(500), a, b, a + 0.1 * b + 0.1 * c])
    >>> problem = Design(X, X @ [1.0, 2.0, 3.0, 4.0], np.zeros(500), ("1", "a", "b", "ab"))
    >>> report = library_conditioning({"X": problem})["X"]
    >>> {k: round(v) for k, v in report["vif"].items() if np.isfinite(v)}
    {'a': 102, 'b': 2, 'ab': 103}
    """
    out = {}
    for dof, problem in problems.items():
        X = np.asarray(problem.features, dtype=float)
        n, p = X.shape
        norms = np.linalg.norm(X, axis=0)
        used = norms > 0
        scaled = X[:, used] / norms[used]
        sv = np.linalg.svd(scaled, compute_uv=False) if scaled.size else np.zeros(0)
        cond = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else math.inf
        constant = _constant_columns(X)
        free = ~constant & used
        Z = X[:, free] - X[:, free].mean(axis=0)
        Z = Z / np.sqrt(np.mean(Z**2, axis=0))
        vif = np.full(p, np.nan)
        cond_std = math.nan
        if Z.shape[1]:
            corr = (Z.T @ Z) / n
            w, V = np.linalg.eigh(0.5 * (corr + corr.T))
            tiny = w <= 1e-13 * w.max()
            inv_w = np.where(tiny, 0.0, 1.0 / np.where(tiny, 1.0, w))
            collinear = np.any((V**2 > 1e-12) & tiny[None, :], axis=1)
            vif[free] = np.where(collinear, np.inf, (V**2) @ inv_w)
            cond_std = float(math.sqrt(w.max() / w.min())) if w.min() > 0 else math.inf
        out[dof] = {
            "condition_number": cond,
            "condition_number_standardised": cond_std,
            "vif": dict(zip(problem.terms, vif.tolist(), strict=True)),
            "n_samples": int(n),
        }
    return out


def spread_vif_agreement(result: EnsembleResult, conditioning: Mapping[str, Mapping]
                         ) -> dict[str, Any]:
    """Spearman rank correlation between ensemble spreads and variance inflation factors.

    The spread of a term is its standardised standard deviation over the ensemble
    (:meth:`EnsembleResult.standardised_std`); terms with a finite VIF and a non-zero spread
    take part (the constant term has no VIF).

    Returns
    -------
    dict
        ``pooled`` (all equations together), ``per_equation`` (``{dof: rho}``) and
        ``n_terms``.
    """
    from scipy.stats import spearmanr

    spreads, vifs, per = [], [], {}
    for dof in DOFS:
        s = result.standardised_std(dof)
        v = np.array([conditioning[dof]["vif"][t] for t in result.terms[dof]], dtype=float)
        ok = np.isfinite(v) & (s > 0)
        spreads.append(s[ok])
        vifs.append(v[ok])
        per[dof] = float(spearmanr(s[ok], v[ok]).statistic) if ok.sum() > 2 else math.nan
    s_all, v_all = np.concatenate(spreads), np.concatenate(vifs)
    pooled = float(spearmanr(s_all, v_all).statistic) if s_all.size > 2 else math.nan
    return {"pooled": pooled, "per_equation": per, "n_terms": int(s_all.size)}


# ---------------------------------------------------------------------------------------------
# Figure
# ---------------------------------------------------------------------------------------------
def drift_figure(result: EnsembleResult, dof: str, ax=None, *, order: str = "cluster"):
    """Heat map of the correlations between one equation's ensemble coefficients.

    The axes of :func:`sindyship.plotting.plot_coefficient_drift` (which returns the figure).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from .plotting.coefficients import plot_coefficient_drift

    fig = plot_coefficient_drift(result, dof, ax=ax, order=order)
    return ax if ax is not None else fig.axes[0]

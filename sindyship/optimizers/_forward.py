"""Forward selection: least squares on a growing set of columns chosen by cross-validation."""

from __future__ import annotations

from numbers import Integral, Real
from typing import Any

import numpy as np
from numpy.typing import NDArray
from sklearn.utils._param_validation import Interval

from ._base import _FitData, _LinearModel
from ._compressed import _lstsq

__all__ = ["ForwardSelection"]


class ForwardSelection(_LinearModel):
    """Least squares on the first ``n_fixed`` columns plus the others that earn their place.

    Starting from the fixed columns, the column whose addition gives the least
    cross-validation error is added, one at a time, while it cuts that error by at least
    ``min_gain`` times the error of the fixed columns alone and at most ``max_terms`` columns
    were added.  Every trial is a least-squares solve on the compressed fold factors
    (:mod:`sindyship.optimizers._compressed`), so a step costs a few dozen small solves per
    fold however many samples there are.  This is the sparse search of
    :func:`sindyship.diagnose.discover`: the library's columns fixed, candidate terms after
    them.

    Parameters
    ----------
    n_fixed : int, default=0
        Leading columns always in the model (a constant column is always fitted).
    max_terms : int, default=4
        Most columns added beyond the fixed ones.
    min_gain : float, default=0.01
        Least fall of the cross-validation error for a column to be added, as a share of the
        error of the fixed columns alone.
    cv : None, int, splitter or iterable, default=None
        Cross-validation scheme (package docstring): leave one group out when ``groups`` is
        given.

    Attributes
    ----------
    coef_ : ndarray, shape (n_targets, n_features)
    selected_ : list of list of int
        Per target, the added columns (indices into ``X``), in increasing order.
    cv_path_ : list of list of float
        Per target, the cross-validation error after each step (the fixed columns first).
    cv_ : cross-validation splitter

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> v, r = rng.uniform(-0.3, 0.3, size=(2, 400))
    >>> X = np.column_stack([np.ones(400), v, r, v**3, v * r**2, r**3])
    >>> y = X @ np.array([0.0, -1.2e-2, 2.6e-3, -0.2, 0.0, 0.0])
    >>> model = ForwardSelection(n_fixed=3).fit(X, y, groups=np.repeat(np.arange(4), 100))
    >>> model.selected_, np.round(model.coef_[0, 3], 6)
    ([[3]], np.float64(-0.2))
    """

    _parameter_constraints: dict = {
        "n_fixed": [Interval(Integral, 0, None, closed="left")],
        "max_terms": [Interval(Integral, 0, None, closed="left")],
        "min_gain": [Interval(Real, 0, None, closed="left")],
        "cv": ["cv_object"],
    }

    def __init__(self, *, n_fixed: int = 0, max_terms: int = 4, min_gain: float = 0.01,
                 cv: Any = None) -> None:
        self.n_fixed = n_fixed
        self.max_terms = max_terms
        self.min_gain = min_gain
        self.cv = cv

    def _reduce(self, data: _FitData) -> NDArray:
        free = np.flatnonzero(data.roles[0])  # the varying columns; a constant is the intercept
        position = {int(c): k for k, c in enumerate(free)}
        n_fixed = min(int(self.n_fixed), data.n_features)
        fixed = [position[c] for c in range(n_fixed) if c in position]
        candidates = [position[c] for c in range(n_fixed, data.n_features) if c in position]
        folds = list(data.folds())
        full, R, Z, _ = data.full
        coef = np.zeros((data.n_targets, data.n_features))
        self.selected_, self.cv_path_ = [], []
        for t in range(data.n_targets):
            chosen, path = self._select(folds, fixed, candidates, len(free), t, data.n_features)
            w = np.zeros(len(free))
            if chosen:
                w[chosen] = _lstsq(R[:, chosen], Z[:, t])
            coef[t] = full.physical(w, 0.0, t, data.n_features)
            self.selected_.append(sorted(int(free[j]) for j in chosen if j not in fixed))
            self.cv_path_.append(path)
        return coef

    def _select(self, folds, fixed, candidates, n_free, t, n_features):
        def cv_error(columns):
            total = 0.0
            for _, fold, Rf, Zf, error in folds:
                w = np.zeros((n_free, 1))
                if columns:
                    w[columns, 0] = _lstsq(Rf[:, columns], Zf[:, t])
                total += float(error(fold.physical(w, np.zeros(1), t, n_features), t)[0])
            return total / len(folds)

        chosen = list(fixed)
        path = [cv_error(chosen)]
        while len(chosen) - len(fixed) < self.max_terms:
            trials = [(cv_error([*chosen, j]), j) for j in candidates if j not in chosen]
            if not trials:
                break
            best, j = min(trials)
            if best > path[-1] - self.min_gain * path[0]:
                break
            chosen.append(j)
            path.append(best)
        return chosen, path

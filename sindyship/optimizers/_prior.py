"""Least squares drawn toward prior coefficients (generalised Tikhonov): :class:`PriorRidge`."""

from __future__ import annotations

from numbers import Real

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from sklearn.utils._param_validation import Interval

from ._base import _FitData, _LinearModel


class PriorRidge(_LinearModel):
    """Least squares with a Gaussian prior on the coefficients.

    Minimises, per target,

    ``||y - X w||^2 + strength * ||y||^2 * sum_k ((w_j(k) - c_k w_i(k) - mean_k) / scale_k)^2``

    where every column ``j`` has one prior row: toward ``mean_j`` with standard deviation
    ``scale_j``, or, for a column named in ``relations``, toward ``c`` times the coefficient of
    another column ``i`` (a relation such as "the force grows with the speed squared").  A
    deviation of one standard deviation costs ``strength`` times the target's sum of squares:
    where the data determine a combination of coefficients, a small ``strength`` leaves it to
    them; along the combinations the data cannot tell apart (collinear columns, the
    "parameter drift" of the paper's section 4) the prior decides.  With ``strength=0`` this
    is :class:`~sindyship.optimizers.LeastSquares`.

    A ``scale`` of NaN (the default for every column) is the *weak* prior: the root mean square
    of ``y`` over that of the column, i.e. one standard deviation is a term that alone explains
    as much force as there is.  Relation rows use the weak scale of column ``j``.

    Parameters
    ----------
    strength : float, default=1e-5
        Weight of the prior against the data (see above).
    mean : sequence of float or None, default=None
        Prior mean of every coefficient (physical scale); ``None`` is zero.
    scale : sequence of float or None, default=None
        Prior standard deviation of every coefficient (physical scale); NaN or ``None`` is the
        weak prior.
    relations : sequence of (j, i, c) or None, default=None
        Coefficient ``j`` is drawn toward ``c`` times coefficient ``i`` instead of toward
        ``mean_j``.

    Attributes
    ----------
    coef_ : ndarray, shape (n_targets, n_features)
        Coefficients on the physical scale.
    n_features_in_ : int
        Number of library columns seen in ``fit``.

    Examples
    --------
    Two identical columns: least squares cannot split the coefficient between them, the prior
    can.

    >>> import numpy as np
    >>> v = np.linspace(-0.3, 0.3, 101)
    >>> X = np.column_stack([v, v])
    >>> model = PriorRidge(strength=1e-6, mean=[-0.01, 0.0], scale=[0.005, 0.005])
    >>> np.round(model.fit(X, -0.03 * v).coef_ * 1e3, 2)
    array([[-20., -10.]])
    """

    _parameter_constraints: dict = {
        "strength": [Interval(Real, 0, None, closed="left")],
        "mean": ["array-like", None],
        "scale": ["array-like", None],
        "relations": ["array-like", None],
    }

    def __init__(self, *, strength: float = 1e-5, mean=None, scale=None,
                 relations=None) -> None:
        self.strength = strength
        self.mean = mean
        self.scale = scale
        self.relations = relations

    def _uses_cv(self) -> bool:
        return False

    def _vector(self, values, default: float, p: int, what: str) -> NDArray:
        if values is None:
            return np.full(p, default)
        out = np.array(values, dtype=float).reshape(-1)  # a copy: the relations write to it
        if out.shape != (p,):
            raise ValueError(f"the prior {what} has {out.size} value(s) for {p} columns; give "
                             "one per column.")
        return out

    def _prior_rows(self, p: int) -> tuple[NDArray, NDArray, NDArray]:
        """``(D, m, scale)``: one prior row per column, ``D w ~ m`` with that scale."""
        mean = self._vector(self.mean, 0.0, p, "mean")
        scale = self._vector(self.scale, np.nan, p, "scale")
        if not np.all(np.isfinite(mean)):
            raise ValueError(f"the prior mean of column {int(np.argmin(np.isfinite(mean)))} "
                             "is not a finite number; give a number for every column.")
        bad = np.isinf(scale) | (np.isfinite(scale) & (scale <= 0))
        if bad.any():
            raise ValueError(f"the prior scale of column {int(np.argmax(bad))} is not a "
                             "positive number; give a positive standard deviation, or NaN "
                             "(None) for the weak prior.")
        D = np.eye(p)
        for j, i, c in ([] if self.relations is None else self.relations):
            if not (float(j).is_integer() and float(i).is_integer() and np.isfinite(c)):
                raise ValueError(f"the prior relation ({j}, {i}, {c}) is not two column "
                                 "numbers and a finite factor; give (j, i, c).")
            j, i = int(j), int(i)
            if not (0 <= j < p and 0 <= i < p) or i == j:
                raise ValueError(f"the prior relation ({j}, {i}, {c}) names a column outside "
                                 f"0..{p - 1} or the column itself; relate two columns.")
            D[j, i] = -float(c)
            mean[j], scale[j] = 0.0, np.nan
        return D, mean, scale

    def _augmented(self, data: _FitData, target: int) -> tuple[NDArray, NDArray]:
        """``(lhs, rhs)`` of one target: the data (compressed) over the prior rows, whose
        least-squares solution is the fit."""
        p = data.n_features
        D, mean, scale = self._prior_rows(p)
        A, B = data.scaled_problem(np.ones(p))
        total = data.n_samples * float(data.y_mean_square[target])  # ||y||^2
        finite = np.isfinite(scale)
        # weak scale rms(y) / rms(X_j) makes the row weight sqrt(strength) * ||X_j||
        weight = np.where(finite, np.sqrt(self.strength * total)
                          / np.where(finite, scale, 1.0),
                          np.sqrt(self.strength) * data.column_norms())
        return (np.vstack([A, D * weight[:, None]]),
                np.concatenate([B[:, target], weight * mean]))

    def _reduce(self, data: _FitData) -> NDArray:
        """The stacked least-squares problem of data and prior rows, per target."""
        coef = np.empty((data.n_targets, data.n_features))
        for t in range(data.n_targets):
            lhs, rhs = self._augmented(data, t)
            coef[t] = scipy.linalg.lstsq(lhs, rhs, lapack_driver="gelsd",
                                         check_finite=False)[0]
        return coef

    def objective_rows(self, X, y) -> tuple[NDArray, NDArray, float, float]:
        """The fit's objective as least-squares rows: ``(lhs, rhs, y_norm2, offset)`` with
        ``||lhs w - rhs||^2 + offset`` equal to ``||y - X w||^2 + strength ||y||^2 sum_k
        (...)^2`` (the class docstring; ``offset`` is the part of y no coefficients reach)
        and ``y_norm2 = ||y||^2``.  A refinement of the fitted coefficients keeps this
        objective as its penalty (:func:`sindyship.refine.refine`).

        Examples
        --------
        >>> X = np.column_stack([np.linspace(0, 1, 50), np.ones(50)])
        >>> y = 2.0 * X[:, 0] + 1.0
        >>> model = PriorRidge(strength=0.0)
        >>> lhs, rhs, norm2, offset = model.objective_rows(X, y)
        >>> w = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
        >>> np.round(w, 6).tolist(), round(norm2, 3)
        ([2.0, 1.0], 217.347)
        """
        X = np.asarray(X, dtype=float)
        Y = np.asarray(y, dtype=float).reshape(-1, 1)
        data = _FitData(X, Y, None)
        lhs, rhs = self._augmented(data, 0)
        norm2 = float(Y[:, 0] @ Y[:, 0])
        data_rows = lhs.shape[0] - X.shape[1]  # the compressed data, then the prior rows
        reached = float(rhs[:data_rows] @ rhs[:data_rows])
        return lhs, rhs, norm2, max(norm2 - reached, 0.0) if data_rows < X.shape[0] else 0.0

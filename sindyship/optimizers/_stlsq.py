"""Sequentially thresholded least squares (Brunton et al. 2016): :class:`STLSQ`."""

from __future__ import annotations

from numbers import Integral, Real
from typing import Any

import numpy as np
from numpy.typing import NDArray
from sklearn.utils._param_validation import Interval, StrOptions

from ._base import _FitData, _LinearModel
from ._compressed import _lstsq
from ._cv import _pick


def _stlsq(R: NDArray, z: NDArray, threshold: float, max_iter: int) -> tuple[NDArray, int]:
    """STLSQ on a compressed problem ``min ||z - R w||`` (standardised coefficients).

    Parameters
    ----------
    R : ndarray, shape (m, n_columns)
        Triangular factor of the standardised columns (:func:`_qr`).
    z : ndarray, shape (m,)
        The target compressed by the same factorisation.
    threshold : float
        Coefficients below it in absolute value are removed.
    max_iter : int
        Maximum number of threshold-and-refit rounds.

    Returns
    -------
    w : ndarray, shape (n_columns,)
    n_iter : int

    Examples
    --------
    >>> R = np.array([[2.0, 1.0], [0.0, 1.0]])
    >>> w, n_iter = _stlsq(R, R @ np.array([1.0, 0.05]), 0.1, 20)
    >>> print(w, n_iter)
    [1.025 0.   ] 2
    """
    support = np.linalg.norm(R, axis=0) > 0
    w = np.zeros(R.shape[1])
    for it in range(1, max_iter + 1):
        w = np.zeros(R.shape[1])
        if support.any():
            w[support] = _lstsq(R[:, support], z)
        keep = support & (np.abs(w) >= threshold)
        if np.array_equal(keep, support):
            return w, it
        support = keep
    w = np.zeros(R.shape[1])
    if support.any():
        w[support] = _lstsq(R[:, support], z)
    return w, max_iter


def _threshold_grid(R: NDArray, z: NDArray, n_thresholds: int) -> NDArray:
    """Log-spaced thresholds from half the smallest to the largest absolute standardised
    least-squares coefficient (never below ``1e-10`` times the largest)."""
    magnitude = np.abs(_lstsq(R, z)) if R.shape[1] else np.zeros(0)
    magnitude = magnitude[magnitude > 0]
    if magnitude.size == 0:
        magnitude = np.ones(1)
    top = magnitude.max()
    low = max(0.5 * magnitude.min(), 1e-10 * top)
    return np.geomspace(low, top, n_thresholds)


class STLSQ(_LinearModel):
    """Sequentially thresholded least squares (Brunton, Proctor & Kutz 2016, PNAS 113:3932).

    Least squares, then repeatedly: set to zero every coefficient below ``threshold`` and
    refit the others by least squares, until the set of terms stops changing.

    The threshold applies to the coefficients of the *standardised* problem: coefficient
    ``w_j`` of column ``x_j`` is kept when ``|w_j| * std(x_j) / std(y) >= threshold``.  So one
    threshold means the same for ``v`` and ``v^3`` and for every degree of freedom; it reads
    as "the change in ``y``, in standard deviations of ``y``, that one standard deviation of
    the term causes".  The constant column is the (centred-out) intercept and is never
    thresholded: in the Abkowitz model it carries the propeller's port-starboard asymmetry.

    Parameters
    ----------
    threshold : float or "cv", default="cv"
        A threshold for every target, or ``"cv"``: for every target choose, by
        cross-validation, the threshold from ``n_thresholds`` log-spaced values between
        half the smallest and the largest absolute standardised least-squares coefficient
        (from "nothing removed", i.e. least squares, to "nearly everything removed").  Ties
        in cross-validation error go to the larger threshold (the sparser model).
    n_thresholds : int, default=30
        Size of the threshold grid when ``threshold="cv"``.
    max_iter : int, default=20
        Maximum number of threshold-and-refit rounds.
    cv : None, int, splitter or iterable, default=None
        Cross-validation scheme when ``threshold="cv"`` (package docstring): leave one group
        out when ``groups`` is given, else 5 contiguous blocks with a warning
        (``LeaveOneTrajectoryOut`` leaves one trajectory out through ``pysindy.SINDy``).

    Attributes
    ----------
    coef_ : ndarray, shape (n_targets, n_features)
        Coefficients on the physical scale.
    threshold_ : ndarray, shape (n_targets,)
        The threshold used for each target.
    n_iter_ : ndarray of int, shape (n_targets,)
        Threshold-and-refit rounds of the final fit.
    cv_results_ : dict of ndarray
        Only with ``threshold="cv"``.  ``"threshold"`` (n_targets, n_thresholds) the grid,
        ``"mean_mse"`` (n_targets, n_thresholds) the cross-validation error, ``"mse"``
        (n_targets, n_thresholds, n_folds) per fold, ``"n_nonzero"`` (n_targets,
        n_thresholds) the number of terms of the fit on all data.
    coef_path_ : ndarray, shape (n_targets, n_features, n_thresholds)
        Only with ``threshold="cv"``: coefficients of the fit on all data at every grid
        threshold (for sparsity-path plots); ``coef_`` is one of its columns.
    cv_ : cross-validation splitter
        The splitter used (only with ``threshold="cv"``).
    n_features_in_ : int
        Number of library columns seen in ``fit``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> v, r = rng.uniform(-0.3, 0.3, size=(2, 400))
    >>> X = np.column_stack([np.ones(400), v, r, v**3, v * r**2])
    >>> y = X @ np.array([1e-5, -1.2e-2, 2.6e-3, 0.0, 0.0])
    >>> model = STLSQ(threshold=0.05).fit(X, y)
    >>> print(np.flatnonzero(model.coef_[0]))
    [0 1 2]
    >>> model = STLSQ().fit(X, y, groups=np.repeat(np.arange(4), 100))
    >>> print(np.flatnonzero(model.coef_[0]), type(model.cv_).__name__)
    [0 1 2] LeaveOneGroupOut
    """

    _parameter_constraints: dict = {
        "threshold": [Interval(Real, 0, None, closed="left"), StrOptions({"cv"})],
        "n_thresholds": [Interval(Integral, 2, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "cv": ["cv_object"],
    }

    def __init__(
        self,
        *,
        threshold: float | str = "cv",
        n_thresholds: int = 30,
        max_iter: int = 20,
        cv: Any = None,
    ) -> None:
        self.threshold = threshold
        self.n_thresholds = n_thresholds
        self.max_iter = max_iter
        self.cv = cv

    def _uses_cv(self) -> bool:
        return self.threshold == "cv"

    def _reduce(self, data: _FitData) -> NDArray:
        """The path of thresholds on all data; with ``threshold="cv"`` the choice among them
        by the cross-validation error."""
        full, R, Z, _ = data.full
        n_targets, n_features = data.n_targets, data.n_features
        if self.threshold != "cv":
            thresholds = np.full((n_targets, 1), float(self.threshold))
        else:
            thresholds = np.vstack(
                [_threshold_grid(R, Z[:, t], self.n_thresholds) for t in range(n_targets)]
            )
        coef_path = np.zeros((n_targets, n_features, thresholds.shape[1]))
        iters = np.zeros((n_targets, thresholds.shape[1]), dtype=int)
        for t in range(n_targets):
            for k, thr in enumerate(thresholds[t]):
                w, iters[t, k] = _stlsq(R, Z[:, t], thr, self.max_iter)
                coef_path[t, :, k] = full.physical(w, 0.0, t, n_features)

        chosen = np.zeros(n_targets, dtype=int)
        if self.threshold == "cv":
            chosen = self._cross_validate(data, thresholds, coef_path)
        idx = np.arange(n_targets)
        self.threshold_ = thresholds[idx, chosen]
        self.n_iter_ = iters[idx, chosen]
        return coef_path[idx, :, chosen]

    def _cross_validate(self, data: _FitData, thresholds: NDArray, coef_path: NDArray) -> NDArray:
        """Held-out error of every threshold on every fold; the chosen grid index per target.

        Sets ``cv_results_`` and ``coef_path_``.
        """
        n_targets, n_features = data.n_targets, data.n_features
        mse = np.zeros((n_targets, thresholds.shape[1], data.n_folds))
        for f, fold, Rf, Zf, error in data.folds():
            for t in range(n_targets):
                W = np.column_stack(
                    [_stlsq(Rf, Zf[:, t], thr, self.max_iter)[0] for thr in thresholds[t]]
                )
                mse[t, :, f] = error(fold.physical(W, np.zeros(W.shape[1]), t, n_features), t)
        mean_mse = mse.mean(axis=2)
        y_ms = data.y_mean_square
        self.cv_results_ = {
            "threshold": thresholds,
            "mean_mse": mean_mse,
            "mse": mse,
            "n_nonzero": np.count_nonzero(coef_path, axis=1),
        }
        self.coef_path_ = coef_path
        return np.array([_pick(mean_mse[t], thresholds[t], y_ms[t]) for t in range(n_targets)])

"""Regression back-ends that identify the Abkowitz coefficients (paper sections 3.3-3.5).

One regression per degree of freedom: a library matrix ``X`` (one column per term, e.g. the 22
sway terms of eq. 17b) and a force target ``y`` (the right-hand side of eq. 16).  The four
estimators below are plain scikit-learn regressors, usable directly and as
``pysindy.SINDy(optimizer=...)``:

=================  ==============================================  ===========================
name               estimator                                       paper
=================  ==============================================  ===========================
``"ls"``           :class:`LeastSquares`                           section 3.3, eq. 19
``"stlsq"``        :class:`STLSQ` (Brunton et al. 2016)            (SINDy's default)
``"lasso"``        :class:`LassoCV`                                section 3.4, eq. 20
``"svr"``          :class:`SVR` (linear epsilon-SVR)               section 3.5, eq. 22-24
=================  ==============================================  ===========================

:func:`make_optimizer` builds one by name; :data:`OPTIMIZERS` maps the names to the classes.

Conventions shared by all four
------------------------------
No separate intercept.
    The library may contain a constant column (the term ``"1"``); its coefficient plays the
    role of the intercept.  A column is constant when its range is at most ``1e-12`` times its
    largest absolute value.  The penalised estimators (:class:`STLSQ`, :class:`LassoCV`,
    :class:`SVR`) treat the first non-zero constant column as an *unpenalised* intercept: they
    centre the other columns and the target, fit, and map the intercept back to that column's
    coefficient.  Further constant columns (duplicates, all-zero columns) get coefficient 0.
    Without a constant column nothing is centred: the model goes through the origin.
Standardised columns.
    The penalised estimators work on columns divided by their standard deviation (their root
    mean square when there is no constant column) and on the target divided by its own, so
    that one threshold, penalty or tube width means the same for ``v`` (~0.1) as for
    ``v^3`` (~1e-3) and for the surge force as for the yaw moment.  Coefficients are reported
    on the physical scale of ``X`` and ``y``.
Shapes.
    ``coef_`` always has shape ``(n_targets, n_features)``, also for a 1-D ``y`` (then
    ``(1, n_features)``): this is what ``pysindy.SINDy`` reads (it iterates over the rows of
    ``coef_``) and what pysindy's own optimizers produce.  ``predict`` returns the shape of the
    ``y`` seen in ``fit``.  Per-target hyper-parameters (``threshold_``, ``alpha_``, ``C_``,
    ``epsilon_``) are arrays of shape ``(n_targets,)``.
Cross-validation.
    ``fit(X, y, groups=None)``.  ``cv=None`` (the default) means leave-one-group-out when
    ``groups`` is given (one group per manoeuvre: a held-out manoeuvre shares no samples with
    the training set) and 5 contiguous, unshuffled blocks (``KFold(5, shuffle=False)``) when it
    is not.  An integer ``cv=k`` means ``k`` contiguous blocks, whatever ``groups`` is; the
    paper's 10-fold cross-validation is ``cv=10`` (MATLAB shuffles its folds: pass
    ``cv=KFold(10, shuffle=True, random_state=seed)`` for that, and note that on noise-free
    1 Hz data shuffled folds leak neighbouring samples and pick almost no regularisation).
    Any scikit-learn splitter or iterable of ``(train, test)`` index pairs is accepted too;
    ``groups`` is handed to its ``split``.  The splitter used is stored in ``cv_``.  The
    cross-validation error is the mean over folds of the held-out mean squared error, in the
    units of ``y`` squared.  Errors within ``1e-12`` relatively of the smallest, or below
    ``1e-20`` times the target's mean square (rounding on noise-free data), count as ties,
    which go to the more regularised candidate.
Parameters are JSON-serialisable by default (strings, numbers, ``None``, lists), so a saved
model can record ``{"name": ..., "params": estimator.get_params()}``.  Randomness enters only
through ``random_state`` (used by :class:`SVR` with ``solver="liblinear"``); everything else
is deterministic.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable
from numbers import Integral, Real
from typing import Any, TypeVar

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, MultiOutputMixin, RegressorMixin
from sklearn.exceptions import ConvergenceWarning
from sklearn.model_selection import KFold, LeaveOneGroupOut, check_cv
from sklearn.svm import LinearSVR
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted, validate_data
from threadpoolctl import threadpool_limits

from sindyship.errors import SindyshipInputError

__all__ = [
    "OPTIMIZERS",
    "LassoCV",
    "LeastSquares",
    "STLSQ",
    "SVR",
    "make_optimizer",
]

#: Relative range below which a column counts as constant.
_CONSTANT_RTOL = 1e-12
#: Number of contiguous blocks when neither ``cv`` nor ``groups`` is given.
_DEFAULT_N_BLOCKS = 5
#: Cross-validation errors within this relative tolerance of the smallest count as ties (ties
#: go to the more regularised candidate) ...
_TIE_RTOL = 1e-12
#: ... and so do errors below this fraction of the target's mean square: a held-out RMS error
#: under 1e-10 of the target's RMS is rounding, not a difference between models.
_TIE_FLOOR = 1e-20


# --------------------------------------------------------------------------------------------
# Shared machinery
# --------------------------------------------------------------------------------------------


_F = TypeVar("_F", bound=Callable[..., Any])


def _one_blas_thread(fit: _F) -> _F:
    """Run ``fit`` with BLAS limited to one thread.

    Every product here is tall and skinny (``n_features`` ~ 20 columns), where threads gain
    little, and a multi-threaded BLAS competing with other processes for the cores slows such
    products down by an order of magnitude (measured: 0.5 s becoming 4-18 s for one SVR fit).
    """

    @functools.wraps(fit)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with threadpool_limits(limits=1, user_api="blas"):
            return fit(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


def _column_roles(X: NDArray) -> tuple[NDArray, int | None]:
    """Split the columns into free ones and an intercept column.

    Returns
    -------
    free : ndarray of bool, shape (n_features,)
        Columns that vary (the regressors).
    intercept : int or None
        Index of the first constant, non-zero column, which carries the intercept.
    """
    col_max = X.max(axis=0)
    col_min = X.min(axis=0)
    magnitude = np.maximum(np.abs(col_max), np.abs(col_min))
    constant = (col_max - col_min) <= _CONSTANT_RTOL * magnitude
    nonzero = np.flatnonzero(constant & (magnitude > 0))
    intercept = int(nonzero[0]) if nonzero.size else None
    return ~constant, intercept


class _Standardiser:
    """Centre (when there is an intercept) and scale the free columns and the targets.

    Statistics come from the rows handed to the constructor (a training fold); the same
    transform is applied to held-out rows.  Columns that do not vary on those rows are set to
    zero, so they never enter a model.
    """

    def __init__(self, X: NDArray, Y: NDArray, free: NDArray, intercept: int | None) -> None:
        self.free = free
        self.intercept = intercept
        Xf = X[:, free]
        if intercept is not None:
            self.x_mean = Xf.mean(axis=0)
            self.y_mean = Y.mean(axis=0)
            self.const_value = float(X[0, intercept])
        else:
            self.x_mean = np.zeros(Xf.shape[1])
            self.y_mean = np.zeros(Y.shape[1])
            self.const_value = 1.0
        x_scale = np.sqrt(np.mean((Xf - self.x_mean) ** 2, axis=0))
        magnitude = np.abs(Xf).max(axis=0, initial=0.0)
        self.dead = ~(x_scale > _CONSTANT_RTOL * magnitude)
        x_scale[self.dead] = 1.0
        self.x_scale = x_scale
        y_scale = np.sqrt(np.mean((Y - self.y_mean) ** 2, axis=0))
        y_scale[~(y_scale > 0)] = 1.0
        self.y_scale = y_scale

    def transform_X(self, X: NDArray) -> NDArray:
        Xs = (X[:, self.free] - self.x_mean) / self.x_scale
        Xs[:, self.dead] = 0.0
        return Xs

    def transform_Y(self, Y: NDArray) -> NDArray:
        return (Y - self.y_mean) / self.y_scale

    def physical(self, W: NDArray, b: NDArray | float, t: int, n_features: int) -> NDArray:
        """Map standardised coefficients of target ``t`` back to the physical scale.

        Parameters
        ----------
        W : ndarray, shape (n_free,) or (n_free, n_models)
            Coefficients of the standardised free columns.
        b : float or ndarray, shape (n_models,)
            Intercept on the standardised target scale (zero unless the solver fits one).
        t : int
            Target index.
        n_features : int
            Number of library columns.

        Returns
        -------
        ndarray, shape (n_features,) or (n_features, n_models)
        """
        W = np.asarray(W, dtype=float)
        w_free = W * (self.y_scale[t] / self.x_scale).reshape((-1,) + (1,) * (W.ndim - 1))
        coef = np.zeros((n_features,) + W.shape[1:])
        coef[self.free] = w_free
        if self.intercept is not None:
            intercept = self.y_mean[t] + self.y_scale[t] * np.asarray(b) - self.x_mean @ w_free
            coef[self.intercept] = intercept / self.const_value
        return coef


def _resolve_cv(cv: Any, groups: NDArray | None) -> tuple[Any, NDArray | None]:
    """The splitter that ``cv`` and ``groups`` select, and the groups to hand to it.

    See the module docstring: leave one group out when ``groups`` is given and ``cv`` is not,
    else contiguous blocks; an integer always means contiguous blocks (groups unused).
    """
    if cv is None and groups is not None:
        return LeaveOneGroupOut(), groups
    if cv is None:
        return KFold(n_splits=_DEFAULT_N_BLOCKS, shuffle=False), None
    if isinstance(cv, Integral):
        return KFold(n_splits=int(cv), shuffle=False), None
    return check_cv(cv), groups


def _splits(
    splitter: Any, X: NDArray, Y: NDArray, groups: NDArray | None
) -> list[tuple[NDArray, NDArray]]:
    if isinstance(splitter, LeaveOneGroupOut) and np.unique(groups).size < 2:
        raise SindyshipInputError(
            "leave-one-group-out cross-validation needs samples from at least two groups "
            "(manoeuvres); pass more manoeuvres, or cv=<number of folds> for contiguous blocks."
        )
    splits = list(splitter.split(X, Y, groups))
    if not splits:
        raise ValueError("the cross-validation splitter produced no folds.")
    return splits


def _check_groups(groups: ArrayLike | None, n_samples: int) -> NDArray | None:
    if groups is None:
        return None
    groups = np.asarray(groups)
    if groups.ndim != 1 or groups.shape[0] != n_samples:
        raise SindyshipInputError(
            f"groups must be a 1-D array with one label per sample ({n_samples}); "
            f"got shape {groups.shape}."
        )
    return groups


def _qr(Xs: NDArray, Ys: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Compress a least-squares problem to its ``R`` factor.

    ``||Ys - Xs W||^2 = ||Z - R W||^2 + rest`` for every ``W``, with ``Xs = Q R``,
    ``Z = Q^T Ys`` and ``rest = ||Ys||^2 - ||Z||^2`` per target.  Every later solve is on the
    tiny ``(R, Z)`` and as well conditioned as a QR solve on the full data.
    """
    Q, R = np.linalg.qr(Xs)
    Z = Q.T @ Ys
    rest = np.maximum(np.sum(Ys**2, axis=0) - np.sum(Z**2, axis=0), 0.0)
    return R, Z, rest


#: Rows per block of the blocked QR (a block of ~24 columns fits in the CPU cache).
_BLOCK_ROWS = 16384


class _Compressed:
    """A regression problem compressed to one small QR factor per block of rows.

    Each block's rows of ``A = [c | X_free | Y]`` (``c`` the intercept column, when there is
    one) are reduced to their triangular factor; the factor of any union of blocks is the QR
    of their stacked factors.  From it come, exactly and without another pass over the data,
    the column means and scales of those rows, the standardised least-squares problem
    ``(R, Z, rest)`` of :func:`_qr`, and the squared error of any coefficients on them.  So a
    cross-validation fold costs a QR of a few dozen rows, and fitting is linear in the number
    of samples (no copies of ``X`` per fold).
    """

    def __init__(self, X: NDArray, Y: NDArray, free: NDArray, intercept: int | None,
                 blocks: list[NDArray]) -> None:
        self.free = free
        self.intercept = intercept
        self.n_free = int(free.sum())
        self.n_targets = Y.shape[1]
        self.const_value = float(X[0, intercept]) if intercept is not None else 1.0
        self.blocks = []
        for rows in blocks:
            parts = [X[rows][:, [intercept]]] if intercept is not None else []
            A = np.hstack([*parts, X[rows][:, free], Y[rows]])
            R = np.linalg.qr(A, mode="r")
            magnitude = np.abs(A).max(axis=0, initial=0.0) if len(rows) else np.zeros(A.shape[1])
            self.blocks.append((R, magnitude, len(rows)))

    def _factor(self, which) -> tuple[NDArray, NDArray, int]:
        parts = [self.blocks[b] for b in which]
        R = np.linalg.qr(np.vstack([p[0] for p in parts]), mode="r")
        magnitude = np.max([p[1] for p in parts], axis=0)
        return R, magnitude, sum(p[2] for p in parts)

    def problem(self, which) -> tuple[_Standardiser, NDArray, NDArray, NDArray]:
        """The standardiser and ``(R, Z, rest)`` of the rows of the blocks ``which``."""
        R, magnitude, n = self._factor(which)
        p, k = self.n_free, 1 if self.intercept is not None else 0
        if k:
            x_mean = self.const_value * R[0, 1:1 + p] / R[0, 0]
            y_mean = self.const_value * R[0, 1 + p:] / R[0, 0]
            Rc = R[1:, 1:]
        else:
            x_mean, y_mean, Rc = np.zeros(p), np.zeros(self.n_targets), R
        scale = np.sqrt(np.sum(Rc**2, axis=0) / n)
        x_scale, y_scale = scale[:p].copy(), scale[p:].copy()
        dead = ~(x_scale > _CONSTANT_RTOL * magnitude[k:k + p])
        x_scale[dead] = 1.0
        y_scale[~(y_scale > 0)] = 1.0
        st = _Standardiser.__new__(_Standardiser)
        st.free, st.intercept, st.const_value = self.free, self.intercept, self.const_value
        st.x_mean, st.y_mean, st.x_scale, st.y_scale, st.dead = (
            x_mean, y_mean, x_scale, y_scale, dead)
        Rs = Rc / np.concatenate([x_scale, y_scale])
        Rs[:, :p][:, dead] = 0.0  # zero columns keep the factor triangular
        return st, Rs[:p, :p], Rs[:p, p:], np.sum(Rs[p:, p:] ** 2, axis=0)

    def squared_error(self, which, coef: NDArray, t: int) -> NDArray:
        """Mean squared error of target ``t`` on the blocks ``which`` for physical
        coefficients ``coef`` of shape (n_features, n_models)."""
        R, _, n = self._factor(which)
        parts = [coef[[self.intercept]]] if self.intercept is not None else []
        minus_y = np.zeros((self.n_targets, coef.shape[1]))
        minus_y[t] = -1.0
        V = np.vstack([*parts, coef[self.free], minus_y])
        return np.sum((R @ V) ** 2, axis=0) / n


def _row_blocks(n: int, splits: list[tuple[NDArray, NDArray]] | None
                ) -> tuple[list[NDArray], list[list[int]] | None]:
    """Blocks of rows, and for each split the blocks of its test rows, or None when the test
    sets do not partition the rows (then folds are fitted directly)."""
    if splits is not None:
        tests = [np.sort(test) for _, test in splits]
        covered = np.zeros(n, dtype=int)
        for test in tests:
            covered[test] += 1
        if np.all(covered == 1):
            blocks, fold_blocks = [], []
            for test in tests:
                pieces = np.array_split(test, max(1, int(np.ceil(len(test) / _BLOCK_ROWS))))
                fold_blocks.append(list(range(len(blocks), len(blocks) + len(pieces))))
                blocks.extend(pieces)
            return blocks, fold_blocks
    pieces = np.array_split(np.arange(n), max(1, int(np.ceil(n / _BLOCK_ROWS))))
    return pieces, None


def _folds(compressed: _Compressed, splits, fold_blocks, X: NDArray, Y: NDArray):
    """For every split: its index, the training standardiser, the standardised problem
    ``(R, Z)`` and a function ``error(coef, t)`` giving the held-out mean squared error of
    target ``t`` for physical coefficients (n_features, n_models)."""
    for f, (train, test) in enumerate(splits):
        if fold_blocks is not None:
            held_out = fold_blocks[f]
            kept = [b for b in range(len(compressed.blocks)) if b not in set(held_out)]
            fold, Rf, Zf, _ = compressed.problem(kept)

            def error(coef, t, held_out=held_out):
                return compressed.squared_error(held_out, coef, t)
        else:  # overlapping test sets: fit the fold's rows directly
            fold = _Standardiser(X[train], Y[train], compressed.free, compressed.intercept)
            Rf, Zf, _ = _qr(fold.transform_X(X[train]), fold.transform_Y(Y[train]))

            def error(coef, t, test=test):
                return np.mean((X[test] @ coef - Y[test, t][:, None]) ** 2, axis=0)
        yield f, fold, Rf, Zf, error


def _lstsq(A: NDArray, b: NDArray) -> NDArray:
    return scipy.linalg.lstsq(A, b, lapack_driver="gelsd", check_finite=False)[0]


def _pick(mean_mse: NDArray, prefer: NDArray, y_mean_square: float) -> int:
    """Index of the smallest error; among ties, the one with the largest ``prefer``."""
    best = np.nanmin(mean_mse)
    near = np.flatnonzero(mean_mse <= best + max(_TIE_RTOL * abs(best), _TIE_FLOOR * y_mean_square))
    return int(near[np.argmax(prefer[near])])


def _as_2d(y: NDArray) -> NDArray:
    return y.reshape(-1, 1) if y.ndim == 1 else y


class _LinearModel(MultiOutputMixin, RegressorMixin, BaseEstimator):
    """``predict``, ``complexity`` and input validation common to the four estimators."""

    def _validate_fit_input(
        self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None
    ) -> tuple[NDArray, NDArray, NDArray | None]:
        X, y = validate_data(
            self, X, y, multi_output=True, y_numeric=True, dtype=np.float64, copy=False
        )
        X = np.asarray(X, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        self._y_ndim = y.ndim
        return X, _as_2d(y), _check_groups(groups, X.shape[0])

    def predict(self, X: ArrayLike) -> NDArray:
        """Predict the target from the library columns.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Library columns.

        Returns
        -------
        ndarray, shape (n_samples,) or (n_samples, n_targets)
            Same number of dimensions as the ``y`` seen in ``fit``.
        """
        check_is_fitted(self)
        X = np.asarray(validate_data(self, X, reset=False, dtype=np.float64))
        pred = X @ self.coef_.T
        return pred[:, 0] if self._y_ndim == 1 else pred

    @property
    def complexity(self) -> int:
        """Number of non-zero coefficients (read by ``pysindy.SINDy.complexity``)."""
        check_is_fitted(self)
        return int(np.count_nonzero(self.coef_))


# --------------------------------------------------------------------------------------------
# Least squares
# --------------------------------------------------------------------------------------------


class LeastSquares(_LinearModel):
    """Ordinary least squares (paper section 3.3, eq. 19), solved by SVD.

    Minimises ``||y - X w||^2`` with :func:`scipy.linalg.lstsq` (LAPACK ``gelsd``), never
    through the normal equations of eq. 19, whose condition number is the square of that of
    ``X``.  The constant column, if any, is an ordinary column here.

    Parameters
    ----------
    column_scaling : bool, default=True
        Divide every column by its Euclidean norm before solving (and the coefficients by the
        same norms after).  This equilibrates monomials of very different size (``v`` ~ 0.1,
        ``du^2 v`` ~ 1e-5), which makes the rank decision of ``cond`` meaningful and the
        solution less sensitive to rounding; all-zero columns are left alone (coefficient 0).
    cond : float or None, default=None
        Singular values below ``cond`` times the largest are treated as zero (minimum-norm
        solution).  ``None`` uses LAPACK's machine-precision default.

    Attributes
    ----------
    coef_ : ndarray, shape (n_targets, n_features)
        Coefficients on the physical scale.
    rank_ : int
        Effective rank of the (scaled) library matrix.
    singular_values_ : ndarray, shape (min(n_samples, n_features),)
        Singular values of the (scaled) library matrix; their ratio is the conditioning behind
        the paper's "parameter drift".
    n_features_in_ : int
        Number of library columns seen in ``fit``.
    feature_names_in_ : ndarray of str
        Column names, when ``X`` was a DataFrame with string column names.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> v, r = rng.uniform(-0.3, 0.3, size=(2, 200))
    >>> X = np.column_stack([np.ones(200), v, r, v**3])
    >>> y = X @ np.array([2e-5, -1.2e-2, 2.6e-3, -2.0e-1])
    >>> model = LeastSquares().fit(X, y)
    >>> np.allclose(model.coef_, [[2e-5, -1.2e-2, 2.6e-3, -2.0e-1]], rtol=1e-10, atol=0)
    True
    >>> model.coef_.shape, model.predict(X).shape
    ((1, 4), (200,))
    """

    _parameter_constraints: dict = {
        "column_scaling": ["boolean"],
        "cond": [Interval(Real, 0, None, closed="left"), None],
    }

    def __init__(self, *, column_scaling: bool = True, cond: float | None = None) -> None:
        self.column_scaling = column_scaling
        self.cond = cond

    @_one_blas_thread
    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> LeastSquares:
        """Fit by least squares.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Library columns.
        y : array-like, shape (n_samples,) or (n_samples, n_targets)
            Targets.
        groups : array-like, shape (n_samples,), optional
            Accepted for a uniform interface; unused.

        Returns
        -------
        self : LeastSquares
        """
        self._validate_params()
        X, Y, _ = self._validate_fit_input(X, y, groups)
        scale = np.ones(X.shape[1])
        if self.column_scaling:
            norms = np.linalg.norm(X, axis=0)
            scale[norms > 0] = norms[norms > 0]
        n, p = X.shape
        if n > 2 * (p + Y.shape[1]):
            # compress [X | Y] block by block to its triangular factor: the same solution
            # (and singular values) as on the full matrix, in time linear in n
            R = np.zeros((0, p + Y.shape[1]))
            for rows in np.array_split(np.arange(n), max(1, int(np.ceil(n / _BLOCK_ROWS)))):
                block = np.hstack([X[rows] / scale, Y[rows]])
                R = np.linalg.qr(np.vstack([R, block]), mode="r")
            A, B = R[:p, :p], R[:p, p:]
        else:
            A, B = X / scale, Y
        W, _, rank, sv = scipy.linalg.lstsq(
            A, B, cond=self.cond, lapack_driver="gelsd", check_finite=False
        )
        self.coef_ = (W / scale[:, None]).T
        self.rank_ = int(rank)
        self.singular_values_ = sv
        return self


# --------------------------------------------------------------------------------------------
# Sequentially thresholded least squares
# --------------------------------------------------------------------------------------------


def _stlsq(R: NDArray, z: NDArray, threshold: float, max_iter: int) -> tuple[NDArray, int]:
    """STLSQ on a compressed problem ``min ||z - R w||`` (standardised coefficients)."""
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
        Cross-validation scheme when ``threshold="cv"`` (module docstring): leave one group
        out when ``groups`` is given, else 5 contiguous blocks.

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

    @_one_blas_thread
    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> STLSQ:
        """Fit, choosing the threshold by cross-validation when ``threshold="cv"``.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Library columns.
        y : array-like, shape (n_samples,) or (n_samples, n_targets)
            Targets.
        groups : array-like, shape (n_samples,), optional
            Group (manoeuvre) label of every sample, for leave-one-group-out
            cross-validation.

        Returns
        -------
        self : STLSQ
        """
        self._validate_params()
        X, Y, groups = self._validate_fit_input(X, y, groups)
        n_features, n_targets = X.shape[1], Y.shape[1]
        free, intercept = _column_roles(X)
        splits = None
        if self.threshold == "cv":
            self.cv_, split_groups = _resolve_cv(self.cv, groups)
            splits = _splits(self.cv_, X, Y, split_groups)
        blocks, fold_blocks = _row_blocks(X.shape[0], splits)
        compressed = _Compressed(X, Y, free, intercept, blocks)
        full, R, Z, _ = compressed.problem(range(len(blocks)))

        if self.threshold != "cv":
            thresholds = np.full((n_targets, 1), float(self.threshold))
        else:
            thresholds = np.empty((n_targets, self.n_thresholds))
            for t in range(n_targets):
                magnitude = np.abs(_lstsq(R, Z[:, t])) if R.shape[1] else np.zeros(0)
                magnitude = magnitude[magnitude > 0]
                if magnitude.size == 0:
                    magnitude = np.ones(1)
                top = magnitude.max()
                low = max(0.5 * magnitude.min(), 1e-10 * top)
                thresholds[t] = np.geomspace(low, top, self.n_thresholds)

        coef_path = np.zeros((n_targets, n_features, thresholds.shape[1]))
        iters = np.zeros((n_targets, thresholds.shape[1]), dtype=int)
        for t in range(n_targets):
            for k, thr in enumerate(thresholds[t]):
                w, iters[t, k] = _stlsq(R, Z[:, t], thr, self.max_iter)
                coef_path[t, :, k] = full.physical(w, 0.0, t, n_features)

        if self.threshold != "cv":
            chosen = np.zeros(n_targets, dtype=int)
        else:
            mse = np.zeros((n_targets, thresholds.shape[1], len(splits)))
            for f, fold, Rf, Zf, error in _folds(compressed, splits, fold_blocks, X, Y):
                for t in range(n_targets):
                    W = np.column_stack(
                        [_stlsq(Rf, Zf[:, t], thr, self.max_iter)[0] for thr in thresholds[t]]
                    )
                    mse[t, :, f] = error(fold.physical(W, np.zeros(W.shape[1]), t, n_features),
                                         t)
            mean_mse = mse.mean(axis=2)
            y_ms = np.mean(Y**2, axis=0)
            chosen = np.array(
                [_pick(mean_mse[t], thresholds[t], y_ms[t]) for t in range(n_targets)]
            )
            self.cv_results_ = {
                "threshold": thresholds,
                "mean_mse": mean_mse,
                "mse": mse,
                "n_nonzero": np.count_nonzero(coef_path, axis=1),
            }
            self.coef_path_ = coef_path

        idx = np.arange(n_targets)
        self.threshold_ = thresholds[idx, chosen]
        self.coef_ = coef_path[idx, :, chosen]
        self.n_iter_ = iters[idx, chosen]
        return self


# --------------------------------------------------------------------------------------------
# LASSO
# --------------------------------------------------------------------------------------------


def _lasso_path_exact(R: NDArray, z: NDArray, lams: NDArray, max_events: int) -> NDArray:
    """Exact LASSO solutions along a decreasing grid by homotopy (the LARS-lasso path).

    Solves ``min 0.5 ||z - R w||^2 + lam ||w||_1`` for every ``lam`` in ``lams`` (decreasing).
    The solution is piecewise linear in ``lam``; the path is followed from ``w = 0`` through
    every kink (a term joins or leaves the active set), with the active coefficients
    recomputed exactly (by QR of the active columns of ``R``) at every kink and every grid
    value, so no tolerance or iteration count shapes the answer.

    Returns
    -------
    ndarray, shape (n_columns, n_lams)
    """
    p = R.shape[1]
    W = np.zeros((p, lams.size))
    usable = np.linalg.norm(R, axis=0) > 0
    active = np.zeros(p, dtype=bool)
    signs = np.zeros(p)
    w = np.zeros(p)
    c = R.T @ z
    if not usable.any():
        return W
    lam = float(np.max(np.abs(c[usable])))
    events = 0
    just_joined = -1

    cache: dict[bytes, tuple[NDArray, NDArray, NDArray, bool]] = {}

    def factor() -> tuple[NDArray, NDArray, NDArray, bool]:
        """Active set ``A``, ``x0``, ``d`` and whether ``R_A`` has full column rank.

        On a fixed active set with fixed signs ``s`` the solution is ``x0 - lam d`` with
        ``R_A = Q T``, ``x0 = T^-1 Q^T z`` and ``d = T^-1 T^-T s``: one QR per active set.
        """
        key = active.tobytes() + signs.tobytes()
        if key not in cache:
            A = np.flatnonzero(active)
            Q, T = np.linalg.qr(R[:, A])
            diag = np.abs(np.diag(T))
            full_rank = bool(diag.min() > 1e-13 * diag.max())
            u = scipy.linalg.solve_triangular(T, signs[A], trans="T", check_finite=False)
            d = scipy.linalg.solve_triangular(T, u, check_finite=False)
            x0 = scipy.linalg.solve_triangular(T, Q.T @ z, check_finite=False)
            cache.clear()
            cache[key] = (A, x0, d, full_rank)
        return cache[key]

    def refresh(at: float) -> tuple[NDArray, NDArray, NDArray]:
        """Active set, its exact coefficients at ``lam = at``, and their rate ``-dx/dlam``."""
        A, x0, d, _ = factor()
        return A, x0 - at * d, d

    for k, target in enumerate(lams):
        while lam > target:
            if not active.any():
                j = int(np.argmax(np.where(usable, np.abs(c), -1.0)))
                if abs(c[j]) <= target:
                    lam = float(target)
                    break
                lam = float(abs(c[j]))
                active[j], signs[j], just_joined = True, np.sign(c[j]), j
            A, x, d = refresh(lam)
            w[:] = 0.0
            w[A] = x
            c = R.T @ (z - R @ w)
            a = R.T @ (R[:, A] @ d)  # rate of change of the correlations as lam decreases
            step, event, who = lam - float(target), "target", -1
            # a term joins when its correlation reaches +-lam
            candidates = usable & ~active
            with np.errstate(divide="ignore", invalid="ignore"):
                up = np.where(1.0 - a > 1e-12, (lam - c) / (1.0 - a), np.inf)
                down = np.where(1.0 + a > 1e-12, (lam + c) / (1.0 + a), np.inf)
            join = np.where(candidates, np.minimum(up, down), np.inf)
            join[join < 0] = np.inf
            if join.size and np.min(join) < step:
                who = int(np.argmin(join))
                step, event = float(join[who]), "join"
            # a term leaves when its coefficient reaches zero
            with np.errstate(divide="ignore", invalid="ignore"):
                cross = np.where(d != 0, -x / d, np.inf)
            cross[(cross <= 0) | (A == just_joined)] = np.inf
            if cross.size and np.min(cross) < step:
                i = int(np.argmin(cross))
                step, event, who = float(cross[i]), "drop", int(A[i])
            lam -= step
            just_joined = -1
            if event == "join":
                active[who], signs[who] = True, np.sign(c[who] - step * a[who])
                if not factor()[3]:
                    # numerically collinear with the active terms: it cannot enter
                    active[who], signs[who], usable[who] = False, 0.0, False
                else:
                    just_joined = who
            elif event == "drop":
                active[who], signs[who] = False, 0.0
            events += 1
            if events > max_events:
                warnings.warn(
                    f"the LASSO homotopy passed {max_events} kinks without reaching the end of "
                    "the penalty grid; the remaining solutions keep the last active set.",
                    ConvergenceWarning,
                    stacklevel=4,
                )
                max_events = np.inf
        lam = float(target)
        if active.any():
            A, x, _ = refresh(lam)
            w[:] = 0.0
            w[A] = x
            c = R.T @ (z - R @ w)
        W[:, k] = w
    return W


class LassoCV(_LinearModel):
    """LASSO with the penalty chosen by cross-validation (paper section 3.4, eq. 20).

    For every target, minimises ``1/(2 n) ||y_s - X_s w||^2 + alpha ||w||_1`` on standardised
    columns ``X_s`` and the standardised target ``y_s`` (module docstring; the constant column
    is an unpenalised intercept), so ``alpha`` is dimensionless and comparable between the
    surge, sway and yaw equations.

    The solutions are exact: each fold's problem is compressed by one QR factorisation to a
    ``n_features``-square triangular system, and the LASSO path is followed through its kinks
    (homotopy / LARS-lasso) with the active coefficients recomputed by QR at every kink and
    grid value.  Coordinate descent (``sklearn.linear_model.lasso_path``) is not used: on
    this noise-free, ill-conditioned problem the penalties that win are tiny, where its
    convergence rate is set by the conditioning; even at ``tol=1e-12`` and ``max_iter=1e6``
    it stops far from the optimum, and the chosen ``alpha`` becomes an artefact of ``tol``.

    Parameters
    ----------
    alphas : None, int or array-like, default=None
        Penalty grid.  ``None`` means 100 values, an integer that many, log-spaced from
        ``alpha_max`` (the smallest penalty with all coefficients zero) down to
        ``alpha_min``.  ``alpha_min / alpha_max`` is ``1e-6``, or smaller when needed to reach
        least squares: the grid ends where the LASSO's in-sample mean squared error exceeds
        that of least squares by at most 0.1 %, estimated as ``alpha^2 * s^T (X_s^T X_s /
        n)^-1 s`` with ``s`` the least-squares signs, and never below ``1e-12 alpha_max``.
        On noise-free, ill-conditioned data this floor is far below ``1e-6 alpha_max``.
        An array gives the grid itself (the same for every target).
    selection : {"min", "one_se"}, default="min"
        ``"min"``: the penalty with the smallest cross-validation error.  ``"one_se"``: the
        largest penalty whose error is within one standard error (over folds) of it.
    cv : None, int, splitter or iterable, default=None
        Cross-validation scheme (module docstring): leave one group out when ``groups`` is
        given, else 5 contiguous blocks; ``cv=10`` for the paper's 10 folds.

    Attributes
    ----------
    coef_ : ndarray, shape (n_targets, n_features)
        Coefficients on the physical scale, refitted on all data at ``alpha_``.
    alpha_ : ndarray, shape (n_targets,)
        The chosen penalty for each target.
    alphas_ : ndarray, shape (n_targets, n_alphas)
        The penalty grid for each target, decreasing.
    mse_path_ : ndarray, shape (n_targets, n_alphas, n_folds)
        Held-out mean squared error for every penalty and fold, in units of ``y`` squared.
    coef_path_ : ndarray, shape (n_targets, n_features, n_alphas)
        Coefficients of the fit on all data at every penalty, on the physical scale (for
        sparsity-path plots); ``coef_`` is one of its columns.
    cv_ : cross-validation splitter
        The splitter used.
    n_features_in_ : int
        Number of library columns seen in ``fit``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> v, r = rng.uniform(-0.3, 0.3, size=(2, 400))
    >>> X = np.column_stack([np.ones(400), v, r, v**3, v * r**2])
    >>> y = X @ np.array([1e-5, -1.2e-2, 2.6e-3, -2e-1, 0.0]) + 1e-5 * np.sin(40 * v)
    >>> model = LassoCV(alphas=30).fit(X, y, groups=np.repeat(np.arange(4), 100))
    >>> model.coef_.shape, model.alphas_.shape, model.mse_path_.shape
    ((1, 5), (1, 30), (1, 30, 4))
    >>> bool(model.alpha_[0] < model.alphas_[0, 0])
    True
    """

    _parameter_constraints: dict = {
        "alphas": [None, Interval(Integral, 2, None, closed="left"), "array-like"],
        "selection": [StrOptions({"min", "one_se"})],
        "cv": ["cv_object"],
    }

    def __init__(
        self,
        *,
        alphas: int | ArrayLike | None = None,
        selection: str = "min",
        cv: Any = None,
    ) -> None:
        self.alphas = alphas
        self.selection = selection
        self.cv = cv

    def _grid(self, R: NDArray, z: NDArray, rest: float, n: int) -> NDArray:
        if self.alphas is not None and not isinstance(self.alphas, Integral):
            grid = np.sort(np.asarray(self.alphas, dtype=float).ravel())[::-1]
            if grid.size == 0 or np.any(grid <= 0) or not np.all(np.isfinite(grid)):
                raise ValueError("alphas must be positive, finite penalties.")
            return grid
        n_alphas = 100 if self.alphas is None else int(self.alphas)
        alpha_max = float(np.max(np.abs(R.T @ z), initial=0.0)) / n
        if alpha_max <= 0:
            return np.geomspace(1.0, 1e-6, n_alphas)
        ratio = 1e-6
        usable = np.linalg.norm(R, axis=0) > 0
        if usable.any():
            Ru = R[:, usable]
            w_ls = _lstsq(Ru, z)
            resid = rest + float(np.sum((z - Ru @ w_ls) ** 2))
            if np.all(w_ls != 0):
                try:
                    _, T = np.linalg.qr(Ru)
                    u = scipy.linalg.solve_triangular(T, np.sign(w_ls), trans="T")
                    excess_per_alpha2 = n * float(u @ u)  # in-sample MSE excess / alpha^2
                    floor = np.sqrt(1e-3 * (resid / n) / excess_per_alpha2)
                    if np.isfinite(floor):
                        ratio = min(ratio, max(floor / alpha_max, 1e-12))
                except (np.linalg.LinAlgError, ValueError):
                    pass
        return alpha_max * np.geomspace(1.0, ratio, n_alphas)

    @_one_blas_thread
    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> LassoCV:
        """Fit the LASSO path on every fold, choose the penalty, refit on all data.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Library columns.
        y : array-like, shape (n_samples,) or (n_samples, n_targets)
            Targets.
        groups : array-like, shape (n_samples,), optional
            Group (manoeuvre) label of every sample, for leave-one-group-out
            cross-validation.

        Returns
        -------
        self : LassoCV
        """
        self._validate_params()
        X, Y, groups = self._validate_fit_input(X, y, groups)
        n_samples, n_features = X.shape
        n_targets = Y.shape[1]
        free, intercept = _column_roles(X)
        max_events = 50 * n_features + 100

        self.cv_, split_groups = _resolve_cv(self.cv, groups)
        splits = _splits(self.cv_, X, Y, split_groups)
        blocks, fold_blocks = _row_blocks(n_samples, splits)
        compressed = _Compressed(X, Y, free, intercept, blocks)
        full, R, Z, rest = compressed.problem(range(len(blocks)))
        grids = [self._grid(R, Z[:, t], rest[t], n_samples) for t in range(n_targets)]
        alphas = np.vstack(grids)

        mse = np.zeros((n_targets, alphas.shape[1], len(splits)))
        for f, fold, Rf, Zf, error in _folds(compressed, splits, fold_blocks, X, Y):
            n_train = n_samples - len(splits[f][1])
            for t in range(n_targets):
                W = _lasso_path_exact(Rf, Zf[:, t], n_train * alphas[t], max_events)
                mse[t, :, f] = error(fold.physical(W, np.zeros(W.shape[1]), t, n_features), t)

        coef_path = np.zeros((n_targets, n_features, alphas.shape[1]))
        chosen = np.zeros(n_targets, dtype=int)
        for t in range(n_targets):
            W = _lasso_path_exact(R, Z[:, t], n_samples * alphas[t], max_events)
            coef_path[t] = full.physical(W, np.zeros(W.shape[1]), t, n_features)
            mean = mse[t].mean(axis=1)
            best = _pick(mean, alphas[t], float(np.mean(Y[:, t] ** 2)))
            if self.selection == "one_se" and mse.shape[2] > 1:
                se = mse[t, best].std(ddof=1) / np.sqrt(mse.shape[2])
                within = np.flatnonzero(mean <= mean[best] + se)
                best = int(within[np.argmax(alphas[t, within])])
            chosen[t] = best

        idx = np.arange(n_targets)
        self.alphas_ = alphas
        self.mse_path_ = mse
        self.coef_path_ = coef_path
        self.alpha_ = alphas[idx, chosen]
        self.coef_ = coef_path[idx, :, chosen]
        return self


# --------------------------------------------------------------------------------------------
# Support vector regression
# --------------------------------------------------------------------------------------------


def _svr_objective(r: NDArray, w: NDArray, C: float, eps: float) -> float:
    """The SVR primal objective from the residuals ``r`` and the penalised weights ``w``."""
    return 0.5 * float(w @ w) + C * float(np.sum(np.maximum(np.abs(r) - eps, 0.0) ** 2))


def _svr_line_search(
    r: NDArray, Xd: NDArray, w: NDArray, dw: NDArray, C: float, eps: float
) -> float:
    """Exact line search along a Newton step, capped at the full step.

    ``phi(s)`` (the objective at ``w + s dw``) is convex and piecewise quadratic, so its slope
    is piecewise linear and increasing: a safeguarded Newton iteration on the slope finds the
    minimum in a few evaluations.
    """

    def slope(s: float) -> tuple[float, float]:
        rr = r - s * Xd
        outside = np.abs(rr) > eps
        e = (np.abs(rr) - eps) * np.sign(rr) * outside
        d1 = float((w + s * dw) @ dw) - 2.0 * C * float(e @ Xd)
        d2 = float(dw @ dw) + 2.0 * C * float(np.sum(Xd[outside] ** 2))
        return d1, d2

    step = 1.0
    d1, d2 = slope(step)
    if d1 <= 0:
        return step
    lo, hi = 0.0, 1.0
    for _ in range(60):
        trial = step - d1 / d2 if d2 > 0 else 0.5 * (lo + hi)
        if not lo < trial < hi:
            trial = 0.5 * (lo + hi)
        step = trial
        d1, d2 = slope(step)
        if d1 > 0:
            hi = step
        else:
            lo = step
        if abs(d1) <= 1e-13 * max(1.0, d2) or hi - lo <= 1e-15:
            break
    return step


def _svr_newton(
    Xb: NDArray,
    y: NDArray,
    C: float,
    eps: float,
    wb: NDArray,
    fit_b: bool,
    tol: float,
    max_iter: int,
) -> tuple[NDArray, int, bool]:
    """Finite Newton method for the squared epsilon-insensitive linear SVR primal.

    Minimises ``0.5 ||w||^2 + C sum_i max(0, |y_i - x_i w - b| - eps)^2`` over
    ``wb = (w, b)``, where ``Xb = [X, 1]`` and ``b`` is unpenalised (kept at zero unless
    ``fit_b``).  The objective is piecewise quadratic and once differentiable; each step
    solves the ridge problem of the samples outside the tube with targets shifted by ``eps``
    toward the tube (the generalised Newton step) and is followed by an exact line search.
    Stops when the pattern of samples outside the tube repeats after a full step (then the
    point is the exact minimum), or when the objective stops decreasing by more than ``tol``
    relatively.

    Returns
    -------
    wb : ndarray, shape (n_features + 1,)
    n_iter : int
    converged : bool
    """
    m = Xb.shape[1] if fit_b else Xb.shape[1] - 1
    X = Xb[:, :m]
    wb = wb.copy()
    w = wb[:m]  # a view: updates of w update wb
    ridge = np.ones(m)
    if fit_b:
        ridge[-1] = 0.0
    r = y - X @ w
    f_old = _svr_objective(r, w * ridge, C, eps)
    side_old = None
    for it in range(1, max_iter + 1):
        side = np.sign(r) * (np.abs(r) > eps)
        if side_old is not None and np.array_equal(side, side_old):
            # the last full step minimised the quadratic that the objective equals on this
            # pattern of sides: it reached the exact minimum
            return wb, it - 1, True
        out = side != 0
        sol = np.zeros(m)
        if fit_b:
            sol[-1] = w[-1]
        if out.any():
            Xa = X[out]
            H = 2.0 * C * (Xa.T @ Xa)
            H[np.diag_indices(m)] += ridge
            g = 2.0 * C * (Xa.T @ (y[out] - eps * side[out]))
            try:
                sol = scipy.linalg.solve(H, g, assume_a="pos", check_finite=False)
            except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
                sol = _lstsq(H, g)
        dw = sol - w
        Xd = X @ dw
        step = _svr_line_search(r, Xd, w * ridge, dw * ridge, C, eps)
        w += step * dw
        r = r - step * Xd
        f_new = _svr_objective(r, w * ridge, C, eps)
        if f_old - f_new <= tol * max(abs(f_new), np.finfo(float).tiny):
            return wb, it, True
        side_old = side if step == 1.0 else None
        f_old = f_new
    return wb, max_iter, False


def _with_ones(Xs: NDArray) -> NDArray:
    return np.column_stack([Xs, np.ones(Xs.shape[0])])


def _svr_intercept(r: NDArray, eps: float) -> float:
    """The unpenalised intercept minimising ``sum max(0, |r_i - b| - eps)^2``."""
    lo, hi = float(r.min()), float(r.max())
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        rr = r - mid
        slope = -np.sum((np.abs(rr) - eps) * np.sign(rr) * (np.abs(rr) > eps))
        if slope > 0:
            hi = mid
        else:
            lo = mid
        if hi - lo <= 1e-15 * max(1.0, abs(mid)):
            break
    return 0.5 * (lo + hi)


class SVR(_LinearModel):
    """Linear epsilon-support-vector regression with C and epsilon chosen by cross-validation.

    Paper section 3.5 (eq. 22-24), with a linear kernel (the Abkowitz model is linear in its
    coefficients) and the squared epsilon-insensitive loss of liblinear's L2-loss SVR::

        min_w  1/2 ||w||^2 + C sum_i max(0, |y_s,i - x_s,i w - b| - epsilon)^2

    on standardised columns ``x_s`` and the standardised target ``y_s`` (module docstring);
    ``b`` is the unpenalised intercept (the constant column's coefficient) and ``epsilon`` is
    therefore a fraction of the target's standard deviation.

    Why the squared loss: liblinear solves the L1 (plain epsilon-insensitive, eq. 24) loss
    only in the dual, with one variable per sample (25,600 here): on this ill-conditioned
    library its coordinate descent stops at ``max_iter`` (measured on a sway-like problem:
    15 s per fit, 10,000 iterations, not converged).  The squared loss has a primal that is
    once differentiable and piecewise quadratic in ~22 unknowns, which a Newton method
    minimises exactly in a few to a few tens of steps.

    Parameters
    ----------
    Cs : None or array-like of float, default=None
        Candidate values of ``C``; ``None`` means ``[1e-2, 1, 1e2, 1e4, 1e6]``.  With unit
        columns and target, and ``epsilon = 0``, the fit is ridge regression with a
        per-sample penalty ``1 / (2 C n)``: the top of the grid is least squares for all
        practical purposes at ``n`` ~ 1e4 samples (on noise-free manoeuvre data it is what
        cross-validation picks), the bottom strongly regularised.
    epsilons : None or array-like of float, default=None
        Candidate tube half-widths as fractions of the target's standard deviation; ``None``
        means ``[0, 0.01, 0.1]``.  The default grid has 15 candidates, each fitted on every
        fold (8 for the paper's manoeuvres), which is the cost of this estimator.
    solver : {"newton", "liblinear"}, default="newton"
        ``"newton"``: an exact finite Newton method on the primal, continued along increasing
        ``C`` with warm starts.  ``"liblinear"``: :class:`sklearn.svm.LinearSVR` (primal
        trust-region Newton, ``dual=False``), one fit per candidate without warm starts, the
        intercept then set by a one-dimensional exact minimisation.  Both minimise the same
        objective, but liblinear stops on a relative gradient tolerance.  Measured on a
        sway-like problem: at scikit-learn's default ``tol=1e-4`` and ``C = 1e6`` its
        objective was 1e4 times the minimum (and the cross-validated fit's held-out RMS
        error 13 times that of least squares);
        at ``tol=1e-10`` it stays up to 7 % above the minimum when ``epsilon > 0``, takes 2-15
        times longer than ``"newton"`` and stops at ``max_iter``.
    tol : float, default=1e-10
        ``"newton"``: stop when the relative decrease of the objective falls below ``tol``
        (the method usually stops earlier, exactly).  ``"liblinear"``: passed to
        :class:`~sklearn.svm.LinearSVR`.
    max_iter : int, default=1000
        Maximum Newton steps (``"newton"``) or liblinear iterations per fit.
    random_state : int, default=0
        Seed handed to :class:`~sklearn.svm.LinearSVR` (``solver="liblinear"``); the Newton
        solver is deterministic.
    cv : None, int, splitter or iterable, default=None
        Cross-validation scheme (module docstring).

    Attributes
    ----------
    coef_ : ndarray, shape (n_targets, n_features)
        Coefficients on the physical scale, refitted on all data with ``C_`` and ``epsilon_``.
    C_ : ndarray, shape (n_targets,)
        The chosen ``C`` for each target.
    epsilon_ : ndarray, shape (n_targets,)
        The chosen tube half-width for each target, as a fraction of the target's standard
        deviation.
    cv_results_ : dict of ndarray
        ``"C"``, ``"epsilon"`` (n_candidates,) the grid, ``"mean_mse"`` (n_targets,
        n_candidates) the cross-validation error, ``"mse"`` (n_targets, n_candidates,
        n_folds) per fold.
    cv_ : cross-validation splitter
        The splitter used.
    n_iter_ : ndarray of int, shape (n_targets,)
        Solver iterations of the final fit, summed over its warm-started path of ``C``.
    n_features_in_ : int
        Number of library columns seen in ``fit``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> v, r = rng.uniform(-0.3, 0.3, size=(2, 400))
    >>> X = np.column_stack([np.ones(400), v, r, v**3])
    >>> y = X @ np.array([1e-5, -1.2e-2, 2.6e-3, -2e-1])
    >>> model = SVR(Cs=[1.0, 1e4], epsilons=[0.0, 0.1]).fit(X, y)
    >>> print(model.C_, model.epsilon_)
    [10000.] [0.]
    >>> np.allclose(model.coef_, [[1e-5, -1.2e-2, 2.6e-3, -2e-1]], rtol=1e-3, atol=1e-7)
    True
    """

    _parameter_constraints: dict = {
        "Cs": [None, "array-like"],
        "epsilons": [None, "array-like"],
        "solver": [StrOptions({"newton", "liblinear"})],
        "tol": [Interval(Real, 0, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
        "cv": ["cv_object"],
    }

    def __init__(
        self,
        *,
        Cs: ArrayLike | None = None,
        epsilons: ArrayLike | None = None,
        solver: str = "newton",
        tol: float = 1e-10,
        max_iter: int = 1000,
        random_state: int | None = 0,
        cv: Any = None,
    ) -> None:
        self.Cs = Cs
        self.epsilons = epsilons
        self.solver = solver
        self.tol = tol
        self.max_iter = max_iter
        self.random_state = random_state
        self.cv = cv

    def _grid(self) -> tuple[NDArray, NDArray]:
        Cs = np.sort(
            np.asarray([1e-2, 1.0, 1e2, 1e4, 1e6] if self.Cs is None else self.Cs, float).ravel()
        )
        eps = np.asarray([0.0, 0.01, 0.1] if self.epsilons is None else self.epsilons, float)
        eps = eps.ravel()
        if Cs.size == 0 or np.any(Cs <= 0) or not np.all(np.isfinite(Cs)):
            raise ValueError("Cs must be positive, finite values.")
        if eps.size == 0 or np.any(eps < 0) or not np.all(np.isfinite(eps)):
            raise ValueError("epsilons must be non-negative, finite values.")
        return Cs, eps

    def _path(
        self, Xb: NDArray, ys: NDArray, Cs: NDArray, eps: float, fit_b: bool, state: list
    ) -> tuple[NDArray, NDArray, int]:
        """Solutions for increasing ``Cs`` at one ``eps``, each warm-starting the next.

        ``Xb`` is the standardised library with a column of ones appended (the intercept).

        Returns
        -------
        W : ndarray, shape (n_free, n_C)
        B : ndarray, shape (n_C,)
        n_iter : int
            Solver iterations summed over the path.
        """
        p = Xb.shape[1] - 1
        W = np.zeros((p, Cs.size))
        B = np.zeros(Cs.size)
        wb = np.zeros(p + 1)
        n_iter = 0
        for k, C in enumerate(Cs):
            if self.solver == "newton":
                wb, it, ok = _svr_newton(Xb, ys, C, eps, wb, fit_b, self.tol, self.max_iter)
            else:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always", ConvergenceWarning)
                    svr = LinearSVR(
                        C=C,
                        epsilon=eps,
                        loss="squared_epsilon_insensitive",
                        dual=False,
                        fit_intercept=False,
                        tol=self.tol,
                        max_iter=self.max_iter,
                        random_state=self.random_state,
                    ).fit(Xb[:, :p], ys)
                ok = not any(issubclass(c.category, ConvergenceWarning) for c in caught)
                it = int(svr.n_iter_)
                wb[:p] = svr.coef_
                wb[p] = _svr_intercept(ys - Xb[:, :p] @ wb[:p], eps) if fit_b else 0.0
            state[0] += 0 if ok else 1
            n_iter += it
            W[:, k], B[k] = wb[:p], wb[p]
        return W, B, n_iter

    @_one_blas_thread
    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> SVR:
        """Choose C and epsilon by cross-validation, then refit on all data.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Library columns.
        y : array-like, shape (n_samples,) or (n_samples, n_targets)
            Targets.
        groups : array-like, shape (n_samples,), optional
            Group (manoeuvre) label of every sample, for leave-one-group-out
            cross-validation.

        Returns
        -------
        self : SVR
        """
        self._validate_params()
        X, Y, groups = self._validate_fit_input(X, y, groups)
        n_features, n_targets = X.shape[1], Y.shape[1]
        Cs, eps_grid = self._grid()
        free, intercept = _column_roles(X)
        fit_b = intercept is not None
        unconverged = [0]

        self.cv_, split_groups = _resolve_cv(self.cv, groups)
        splits = _splits(self.cv_, X, Y, split_groups)
        cand_C = np.tile(Cs, eps_grid.size)
        cand_eps = np.repeat(eps_grid, Cs.size)
        mse = np.zeros((n_targets, cand_C.size, len(splits)))
        for f, (train, test) in enumerate(splits):
            fold = _Standardiser(X[train], Y[train], free, intercept)
            Xb = _with_ones(fold.transform_X(X[train]))
            Ys = fold.transform_Y(Y[train])
            for t in range(n_targets):
                for e, eps in enumerate(eps_grid):
                    W, B, _ = self._path(Xb, Ys[:, t], Cs, eps, fit_b, unconverged)
                    pred = X[test] @ fold.physical(W, B, t, n_features)
                    cols = slice(e * Cs.size, (e + 1) * Cs.size)
                    mse[t, cols, f] = np.mean((pred - Y[test, t][:, None]) ** 2, axis=0)

        mean_mse = mse.mean(axis=2)
        full = _Standardiser(X, Y, free, intercept)
        Xb, Ys = _with_ones(full.transform_X(X)), full.transform_Y(Y)
        coef = np.zeros((n_targets, n_features))
        self.C_ = np.zeros(n_targets)
        self.epsilon_ = np.zeros(n_targets)
        n_iter = np.zeros(n_targets, dtype=int)
        for t in range(n_targets):
            # ties go to the smaller C, then to the wider tube (the more regularised model)
            order = np.lexsort((cand_eps, -cand_C))  # ascending preference
            rank = np.empty(order.size)
            rank[order] = np.arange(order.size)
            best = _pick(mean_mse[t], rank, float(np.mean(Y[:, t] ** 2)))
            self.C_[t], self.epsilon_[t] = cand_C[best], cand_eps[best]
            path_C = Cs[Cs <= cand_C[best]]
            W, B, n_iter[t] = self._path(Xb, Ys[:, t], path_C, cand_eps[best], fit_b, unconverged)
            coef[t] = full.physical(W[:, -1], B[-1], t, n_features)
        if unconverged[0]:
            warnings.warn(
                f"the SVR solver ({self.solver}) stopped at max_iter={self.max_iter} in "
                f"{unconverged[0]} fits; raise max_iter or tol.",
                ConvergenceWarning,
                stacklevel=3,
            )
        self.coef_ = coef
        self.n_iter_ = np.maximum(n_iter, 1)
        self.cv_results_ = {"C": cand_C, "epsilon": cand_eps, "mean_mse": mean_mse, "mse": mse}
        return self


# --------------------------------------------------------------------------------------------
# One interface
# --------------------------------------------------------------------------------------------

#: The optimizers by name, as used in saved models (``optimizer: {name, params}``) and on the
#: command line (``--optimizer``).
OPTIMIZERS: dict[str, type[_LinearModel]] = {
    "ls": LeastSquares,
    "stlsq": STLSQ,
    "lasso": LassoCV,
    "svr": SVR,
}


def make_optimizer(name: str, **params: Any) -> _LinearModel:
    """Build an optimizer by name.

    Parameters
    ----------
    name : {"ls", "stlsq", "lasso", "svr"}
        Which optimizer (:data:`OPTIMIZERS`).
    **params
        Its parameters, as returned by its ``get_params()``.

    Returns
    -------
    estimator
        An unfitted scikit-learn regressor.

    Raises
    ------
    SindyshipInputError
        For an unknown name or parameter.

    Examples
    --------
    >>> make_optimizer("stlsq", threshold=0.1)
    STLSQ(threshold=0.1)
    >>> make_optimizer("ridge")
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: unknown optimizer 'ridge': choose one of 'ls', 'stlsq', 'lasso', 'svr'.
    """  # noqa: E501
    if name not in OPTIMIZERS:
        valid = ", ".join(repr(k) for k in OPTIMIZERS)
        raise SindyshipInputError(f"unknown optimizer {name!r}: choose one of {valid}.")
    cls = OPTIMIZERS[name]
    allowed = cls().get_params()
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        valid = ", ".join(sorted(allowed))
        raise SindyshipInputError(
            f"optimizer {name!r} has no parameter {unknown[0]!r}: its parameters are {valid}."
        )
    return cls(**params)

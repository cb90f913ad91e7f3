"""The base class of the estimators: one ``fit`` template, ``predict`` and ``complexity``.

``fit`` validates the input, resolves the cross-validation folds (when the estimator uses
them) and hands a :class:`_FitData` to the estimator's hook ``_reduce``, which returns the
physical coefficients.  The column roles and the compressed problem of :class:`_FitData` are
computed on first use, so an estimator pays only for what it reads.
"""

from __future__ import annotations

from collections.abc import Iterator
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, MultiOutputMixin, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from ._compressed import _Compressed, _Fold, _folds, _row_blocks
from ._cv import _check_groups, _resolve_cv, _splits
from ._standardise import _column_roles, _Standardiser
from ._threads import one_blas_thread


def _as_2d(y: NDArray) -> NDArray:
    return y.reshape(-1, 1) if y.ndim == 1 else y


class _FitData:
    """The validated data of one ``fit``, and what is derived from them on demand.

    Parameters
    ----------
    X : ndarray, shape (n_samples, n_features)
        Library columns.
    Y : ndarray, shape (n_samples, n_targets)
        Targets (always 2-D).
    splits : list of (train, test) index pairs, or None
        Cross-validation folds, when the estimator uses them.
    """

    def __init__(
        self, X: NDArray, Y: NDArray, splits: list[tuple[NDArray, NDArray]] | None
    ) -> None:
        self.X, self.Y, self.splits = X, Y, splits
        self.n_samples, self.n_features = X.shape
        self.n_targets = Y.shape[1]

    @cached_property
    def roles(self) -> tuple[NDArray, int | None]:
        """``(free, intercept)``: the free columns and the intercept column, if any."""
        return _column_roles(self.X)

    @cached_property
    def _blocks(self) -> tuple[list[NDArray], list[list[int]] | None]:
        return _row_blocks(self.n_samples, self.splits)

    @cached_property
    def compressed(self) -> _Compressed:
        """The problem compressed per block of rows (test sets are unions of blocks)."""
        free, intercept = self.roles
        return _Compressed(self.X, self.Y, free, intercept, self._blocks[0])

    @cached_property
    def full(self) -> tuple[_Standardiser, NDArray, NDArray, NDArray]:
        """Standardiser and standardised ``(R, Z, rest)`` of all samples."""
        return self.compressed.problem(range(len(self.compressed.blocks)))

    def folds(self) -> Iterator[_Fold]:
        """The cross-validation folds of the compressed problem (:func:`_folds`)."""
        return _folds(self.compressed, self.splits, self._blocks[1], self.X, self.Y)


class _LinearModel(MultiOutputMixin, RegressorMixin, BaseEstimator):
    """``fit`` template, ``predict`` and ``complexity`` common to the estimators.

    A subclass implements ``_reduce(data) -> coef`` (physical coefficients, shape
    ``(n_targets, n_features)``), may set fitted attributes there, and overrides
    ``_uses_cv`` when it does not always cross-validate (then ``data.splits`` is None) and
    ``_check_grid`` to reject a bad grid before the folds are made.
    """

    def _uses_cv(self) -> bool:
        """Whether this fit needs cross-validation folds (read from ``self.cv``)."""
        return True

    def _check_grid(self) -> None:
        """Raise ``ValueError`` for an invalid explicit grid (before the folds are made)."""

    def _reduce(self, data: _FitData) -> NDArray:
        """The estimator's own fit: physical coefficients (n_targets, n_features)."""
        raise NotImplementedError

    @one_blas_thread
    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> Any:
        """Fit the coefficients, choosing hyper-parameters by cross-validation if any.

        Parameters
        ----------
        X : array-like, shape (n_samples, n_features)
            Library columns.
        y : array-like, shape (n_samples,) or (n_samples, n_targets)
            Targets.
        groups : array-like, shape (n_samples,), optional
            Group (manoeuvre) label of every sample, for leave-one-group-out
            cross-validation (unused by :class:`LeastSquares`).

        Returns
        -------
        self
            The fitted estimator.
        """
        self._validate_params()
        X, Y, groups = self._validate_fit_input(X, y, groups)
        self._check_grid()
        splits = None
        if self._uses_cv():
            self.cv_, split_groups = _resolve_cv(self.cv, groups)
            splits = _splits(self.cv_, X, Y, split_groups)
        self.coef_ = self._reduce(_FitData(X, Y, splits))
        return self

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

"""The base class of the estimators: one ``fit`` template, ``predict`` and ``complexity``.

``fit`` validates the input, resolves the cross-validation folds (when the estimator uses
them) and hands a :class:`_FitData` to the estimator's hook ``_reduce``, which returns the
physical coefficients.  The column roles and the compressed problem of :class:`_FitData` are
computed on first use, so an estimator pays only for what it reads.  ``fit_factors`` hands the
same hook the data of :mod:`._factored`, built from the factors of the records' rows.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import BaseEstimator, MultiOutputMixin, RegressorMixin
from sklearn.model_selection import LeaveOneGroupOut
from sklearn.utils.validation import check_is_fitted, validate_data

from sindyship.errors import SindyshipInputError

from ._compressed import RowFactor, _Compressed, _Fold, _folds, _row_blocks, _running_factor
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

    @property
    def n_folds(self) -> int:
        """Number of cross-validation folds."""
        return len(self.splits)

    def n_test(self, f: int) -> int:
        """Number of held-out samples of fold ``f``."""
        return len(self.splits[f][1])

    @cached_property
    def y_mean_square(self) -> NDArray:
        """Mean square of every target, shape (n_targets,)."""
        return np.mean(self.Y**2, axis=0)

    def column_norms(self) -> NDArray:
        """Euclidean norm of every column of ``X``."""
        return np.linalg.norm(self.X, axis=0)

    def scaled_problem(self, scale: NDArray) -> tuple[NDArray, NDArray]:
        """A least-squares problem ``(A, B)`` with the solutions of ``X / scale ~ Y``:
        the triangular factor of ``[X / scale | Y]`` when there are many more rows than
        columns (the same solution and singular values, in time linear in the rows), else
        the rows themselves."""
        X, Y = self.X, self.Y
        p = X.shape[1]
        if self.n_samples > 2 * (p + Y.shape[1]):
            R = _running_factor(X, Y, scale)
            return R[:p, :p], R[:p, p:]
        return X / scale, Y


class _LinearModel(MultiOutputMixin, RegressorMixin, BaseEstimator):
    """``fit`` template, ``predict`` and ``complexity`` common to the estimators.

    A subclass implements ``_reduce(data) -> coef`` (physical coefficients, shape
    ``(n_targets, n_features)``), may set fitted attributes there, and overrides
    ``_uses_cv`` when it does not always cross-validate (then ``data.splits`` is None) and
    ``_check_grid`` to reject a bad grid before the folds are made.
    """

    #: Whether the fit needs the samples themselves (not only the factors of their rows):
    #: such an estimator cannot :meth:`fit_factors`.
    _needs_rows: bool = False

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

    @property
    def cross_validates(self) -> bool:
        """Whether a fit with these parameters uses cross-validation folds."""
        return self._uses_cv()

    def check_factor_fit(self, n_records: int) -> None:
        """Refuse, before any work, what :meth:`fit_factors` cannot fit.

        Raises
        ------
        SindyshipInputError
            When the estimator needs the samples themselves (``svr``), when it is given a
            ``cv`` other than the default, or when it cross-validates over fewer than two
            records.
        """
        self._validate_params()
        name = type(self).__name__
        if self._needs_rows:
            raise SindyshipInputError(
                f"{name} needs every sample (its loss is not a least-squares one), so it cannot "
                "be fitted from factors of the records; use ls, stlsq, lasso or prior, or fit in "
                "memory (without --stream)."
            )
        self._check_grid()
        if self.cross_validates and getattr(self, "cv", None) is not None:
            raise SindyshipInputError(
                "a fit from factors of the records cross-validates leaving one record out; "
                f"leave the cv of {name} unset."
            )
        if self.cross_validates and n_records < 2:
            raise SindyshipInputError(
                "leave-one-record-out cross-validation needs at least two records; pass more "
                "records."
            )

    @one_blas_thread
    def fit_factors(self, records: Sequence[RowFactor], whole: RowFactor | None = None) -> Any:
        """Fit from the factors of the records' rows, without the rows.

        The same coefficients as :meth:`fit` on the stacked rows with one group per record
        (up to rounding): every estimator works on the triangular factor of ``[X | Y]``
        (the least-squares problem of the paper's eq. 18), a leave-one-record-out fold on the
        factor of all the other records.

        Parameters
        ----------
        records : sequence of RowFactor
            One factor per record (:meth:`RowFactor.of_rows` of its library columns and
            targets), in record order.  Not read when the estimator does not cross-validate
            and ``whole`` is given (an empty list will do).
        whole : RowFactor, optional
            The factor of all records (e.g. merged as a tree on a cluster); default
            :func:`tree_factor` of ``records``.

        Returns
        -------
        self
            The fitted estimator; ``cv_`` is leave-one-group-out when it cross-validates.

        Raises
        ------
        SindyshipInputError
            As :meth:`check_factor_fit`.
        """
        from ._factored import _FactorData

        self.check_factor_fit(len(records))
        uses_cv = self.cross_validates
        if uses_cv:
            self.cv_ = LeaveOneGroupOut()
        data = _FactorData(records, whole, cross_validate=uses_cv)
        self.n_features_in_ = data.n_features
        self._y_ndim = 1 if data.n_targets == 1 else 2
        self.coef_ = self._reduce(data)
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

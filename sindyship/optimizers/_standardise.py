"""Which column is the intercept, and the standardised scale the penalised estimators fit on.

The conventions ("no separate intercept", "standardised columns") are those of the package
docstring of :mod:`sindyship.optimizers`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Relative range below which a column counts as constant.
_CONSTANT_RTOL = 1e-12


def _column_roles(X: NDArray) -> tuple[NDArray, int | None]:
    """Split the columns into free ones and an intercept column.

    Parameters
    ----------
    X : ndarray, shape (n_samples, n_features)
        Library columns.

    Returns
    -------
    free : ndarray of bool, shape (n_features,)
        Columns that vary (the regressors).
    intercept : int or None
        Index of the first constant, non-zero column, which carries the intercept.

    Examples
    --------
    >>> X = np.array([[0.0, 2.0, 1.0, 2.0], [0.0, 2.0, 3.0, 2.0]])
    >>> free, intercept = _column_roles(X)
    >>> print(free, intercept)
    [False False  True False] 1
    """
    return _roles_from_range(X.min(axis=0), X.max(axis=0))


def _roles_from_range(col_min: NDArray, col_max: NDArray) -> tuple[NDArray, int | None]:
    """:func:`_column_roles` from the smallest and largest value of every column (so the
    roles of a union of row blocks follow from the ranges of the blocks).

    Examples
    --------
    >>> free, intercept = _roles_from_range(np.array([0.0, 2.0, 1.0]), np.array([0.0, 2.0, 3.0]))
    >>> print(free, intercept)
    [False False  True] 1
    """
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

    Parameters
    ----------
    X : ndarray, shape (n_samples, n_features)
        Library columns of the rows that set the statistics.
    Y : ndarray, shape (n_samples, n_targets)
        Targets of those rows.
    free : ndarray of bool, shape (n_features,)
        Free columns (:func:`_column_roles`).
    intercept : int or None
        The intercept column (:func:`_column_roles`).
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

    @classmethod
    def from_moments(
        cls,
        free: NDArray,
        intercept: int | None,
        const_value: float,
        means: tuple[NDArray, NDArray],
        scales: tuple[NDArray, NDArray],
        dead: NDArray,
    ) -> _Standardiser:
        """A standardiser from statistics computed elsewhere (from a QR factor).

        ``means`` and ``scales`` are ``(x, y)`` pairs; ``dead`` marks the free columns that do
        not vary (their scale must already be 1).
        """
        st = cls.__new__(cls)
        st.free, st.intercept, st.const_value = free, intercept, const_value
        st.x_mean, st.y_mean = means
        st.x_scale, st.y_scale = scales
        st.dead = dead
        return st

    def transform_X(self, X: NDArray) -> NDArray:
        """Standardised free columns of ``X`` (dead columns zero)."""
        Xs = (X[:, self.free] - self.x_mean) / self.x_scale
        Xs[:, self.dead] = 0.0
        return Xs

    def transform_Y(self, Y: NDArray) -> NDArray:
        """Standardised targets."""
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

        Examples
        --------
        >>> X = np.column_stack([np.ones(4), [0.0, 1.0, 2.0, 3.0]])
        >>> Y = (2.0 + 3.0 * X[:, 1]).reshape(-1, 1)
        >>> st = _Standardiser(X, Y, *_column_roles(X))
        >>> st.physical(np.array([1.0]), 0.0, 0, 2)
        array([2., 3.])
        """
        W = np.asarray(W, dtype=float)
        w_free = W * (self.y_scale[t] / self.x_scale).reshape((-1,) + (1,) * (W.ndim - 1))
        coef = np.zeros((n_features,) + W.shape[1:])
        coef[self.free] = w_free
        if self.intercept is not None:
            intercept = self.y_mean[t] + self.y_scale[t] * np.asarray(b) - self.x_mean @ w_free
            coef[self.intercept] = intercept / self.const_value
        return coef

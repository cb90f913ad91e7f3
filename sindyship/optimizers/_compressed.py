"""The one compression engine: a regression problem reduced to small QR factors of row blocks.

Every estimator solves least-squares-like problems on a few dozen columns and up to millions
of rows.  Each block of rows of ``[X | Y]`` is reduced once to its triangular factor; the
factor of any union of blocks is the QR of their stacked factors.  So a cross-validation fold
or a refit without one record costs a QR of a few dozen rows, and fitting is linear in the
number of samples.

:class:`_Compressed` is the engine; :func:`_row_blocks` cuts the rows so that every
cross-validation test set is a union of blocks, and :func:`_folds` serves the folds from it.
:class:`GroupedProblem` is the public face of the same engine for least-squares refits of
column subsets, one block set per record (leave-one-record-out predictions).
:class:`RowFactor` carries one block's factor with the column ranges the roles need, so that
records reduced elsewhere (on the workers of a cluster) can be combined as a tree (TSQR:
:func:`merge_factors`) and fitted by the estimators without their rows
(:meth:`_Compressed.from_factors`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from ._cv import _check_groups
from ._standardise import _CONSTANT_RTOL, _Standardiser
from ._threads import one_blas_thread

__all__ = ["GroupedProblem", "RowFactor", "merge_factors", "pairwise_tree", "tree_factor"]

#: Rows per block of the blocked QR (a block of ~24 columns fits in the CPU cache).
_BLOCK_ROWS = 16384


def _lstsq(A: NDArray, b: NDArray) -> NDArray:
    """Minimum-norm least-squares solution of ``A x = b`` by SVD (LAPACK ``gelsd``)."""
    return scipy.linalg.lstsq(A, b, lapack_driver="gelsd", check_finite=False)[0]


def _qr(Xs: NDArray, Ys: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Compress a least-squares problem to its ``R`` factor.

    ``||Ys - Xs W||^2 = ||Z - R W||^2 + rest`` for every ``W``, with ``Xs = Q R``,
    ``Z = Q^T Ys`` and ``rest = ||Ys||^2 - ||Z||^2`` per target.  Every later solve is on the
    tiny ``(R, Z)`` and as well conditioned as a QR solve on the full data.

    Parameters
    ----------
    Xs : ndarray, shape (n_samples, n_columns)
    Ys : ndarray, shape (n_samples, n_targets)

    Returns
    -------
    R : ndarray, shape (min(n_samples, n_columns), n_columns)
    Z : ndarray, shape (min(n_samples, n_columns), n_targets)
    rest : ndarray, shape (n_targets,)

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> Xs, Ys = rng.normal(size=(50, 3)), rng.normal(size=(50, 1))
    >>> R, Z, rest = _qr(Xs, Ys)
    >>> W = rng.normal(size=(3, 1))
    >>> bool(np.isclose(np.sum((Ys - Xs @ W) ** 2), np.sum((Z - R @ W) ** 2) + rest[0]))
    True
    """
    Q, R = np.linalg.qr(Xs)
    Z = Q.T @ Ys
    rest = np.maximum(np.sum(Ys**2, axis=0) - np.sum(Z**2, axis=0), 0.0)
    return R, Z, rest


def _stack(factors: Sequence[NDArray]) -> NDArray:
    """The triangular factor of the union of row blocks given by their factors: the QR of
    the stacked factors (one step of TSQR)."""
    return np.linalg.qr(np.vstack(factors), mode="r")


@dataclass(frozen=True)
class RowFactor:
    """The rows ``[X | Y]`` of a regression problem reduced to what a fit needs from them.

    ``R`` is their triangular factor (``||Y - X W||^2 = ||R [W; -I]||^2`` for every ``W``: the
    least-squares problem of the paper's eq. 18 on a few dozen rows), ``low`` and ``high``
    the smallest and largest value of every column (which columns are constant), ``first``
    the first row (the value of a constant column) and ``n`` the number of rows.  Factors of
    disjoint row sets combine exactly (:func:`merge_factors`), in any grouping.

    Attributes
    ----------
    R : ndarray, shape (min(n, n_columns), n_columns)
    low, high, first : ndarray, shape (n_columns,)
    n : int
    n_targets : int
        The last ``n_targets`` columns are the targets ``Y``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X, Y = rng.normal(size=(40, 3)), rng.normal(size=(40, 1))
    >>> whole = RowFactor.of_rows(X, Y)
    >>> halves = merge_factors(RowFactor.of_rows(X[:15], Y[:15]),
    ...                        RowFactor.of_rows(X[15:], Y[15:]))
    >>> bool(np.allclose(np.abs(halves.R), np.abs(whole.R))), halves.n
    (True, 40)
    """

    R: NDArray
    low: NDArray
    high: NDArray
    first: NDArray
    n: int
    n_targets: int

    @classmethod
    @one_blas_thread
    def of_rows(cls, X: NDArray, Y: NDArray) -> RowFactor:
        """The factor of the rows ``[X | Y]`` (reduced one block of rows at a time, on one
        BLAS thread: :func:`~._threads.one_blas_thread`)."""
        X = np.asarray(X, dtype=float)
        Y = np.asarray(Y, dtype=float).reshape(X.shape[0], -1)
        if X.shape[0] == 0:
            raise ValueError("a row factor needs at least one row.")
        R = _running_factor(X, Y, np.ones(X.shape[1]))
        low = np.concatenate([X.min(axis=0), Y.min(axis=0)])
        high = np.concatenate([X.max(axis=0), Y.max(axis=0)])
        first = np.concatenate([X[0], Y[0]])
        return cls(R, low, high, first, int(X.shape[0]), int(Y.shape[1]))

    @property
    def n_features(self) -> int:
        """Number of columns of ``X``."""
        return self.R.shape[1] - self.n_targets


def merge_factors(a: RowFactor, b: RowFactor) -> RowFactor:
    """The factor of the rows of ``a`` followed by those of ``b`` (one step of TSQR)."""
    if a.R.shape[1] != b.R.shape[1] or a.n_targets != b.n_targets:
        raise ValueError("row factors of different columns cannot be merged.")
    return RowFactor(_stack([a.R, b.R]), np.minimum(a.low, b.low), np.maximum(a.high, b.high),
                     a.first, a.n + b.n, a.n_targets)


def pairwise_tree(items: Sequence, merge: Callable):
    """``items`` merged pairwise as a binary tree, in order: ``merge(a, b)`` of neighbours,
    level by level, an odd last item carried up (the reduction of TSQR)."""
    level = list(items)
    if not level:
        raise ValueError("nothing to merge.")
    while len(level) > 1:
        pairs = [merge(a, b) for a, b in zip(level[::2], level[1::2], strict=False)]
        level = pairs + ([level[-1]] if len(level) % 2 else [])
    return level[0]


def tree_factor(factors: Sequence[RowFactor]) -> RowFactor:
    """The factor of all rows, merged pairwise as a binary tree (TSQR)."""
    return pairwise_tree(factors, merge_factors)


def _block_rows(rows: NDArray) -> list[NDArray]:
    """``rows`` cut into consecutive pieces of at most :data:`_BLOCK_ROWS` (at least one)."""
    return np.array_split(rows, max(1, int(np.ceil(len(rows) / _BLOCK_ROWS))))


class _Compressed:
    """A regression problem compressed to one small QR factor per block of rows.

    Each block's rows of ``A = [c | X_free | Y]`` (``c`` the intercept column, when there is
    one) are reduced to their triangular factor; the factor of any union of blocks is the QR
    of their stacked factors.  From it come, exactly and without another pass over the data,
    the column means and scales of those rows, the standardised least-squares problem
    ``(R, Z, rest)`` of :func:`_qr`, and the squared error of any coefficients on them.  So a
    cross-validation fold costs a QR of a few dozen rows, and fitting is linear in the number
    of samples (no copies of ``X`` per fold).

    Parameters
    ----------
    X : ndarray, shape (n_samples, n_features)
        Library columns.
    Y : ndarray, shape (n_samples, n_targets)
        Targets.
    free, intercept
        Column roles (:func:`~sindyship.optimizers._standardise._column_roles`); pass all
        columns free and no intercept for plain least squares.
    blocks : list of ndarray
        Row indices of every block (:func:`_row_blocks`).
    """

    def __init__(
        self, X: NDArray, Y: NDArray, free: NDArray, intercept: int | None, blocks: list[NDArray]
    ) -> None:
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

    @classmethod
    def from_factors(
        cls, factors: Sequence[RowFactor], free: NDArray, intercept: int | None
    ) -> _Compressed:
        """The engine on blocks given by their factors (one :class:`RowFactor` per block, of
        the rows ``[X | Y]`` in library order) instead of their rows.

        Each block's factor of ``[c | X_free | Y]`` is the QR of the columns of its factor in
        that order (``A P = Q (R P)``), so this is the engine ``__init__`` builds from rows,
        up to rounding.
        """
        self = cls.__new__(cls)
        self.free, self.intercept = free, intercept
        self.n_free = int(free.sum())
        n_features = free.size
        self.n_targets = factors[0].R.shape[1] - n_features
        self.const_value = float(factors[0].first[intercept]) if intercept is not None else 1.0
        head = [intercept] if intercept is not None else []
        order = np.concatenate(
            [head, np.flatnonzero(free), n_features + np.arange(self.n_targets)]
        ).astype(int)
        self.blocks = []
        for factor in factors:
            magnitude = np.maximum(np.abs(factor.low), np.abs(factor.high))[order]
            R = np.linalg.qr(factor.R[:, order], mode="r")
            self.blocks.append((R, magnitude, factor.n))
        return self

    def factor(self, which: Iterable[int]) -> tuple[NDArray, NDArray, int]:
        """The triangular factor of ``A`` on the blocks ``which``, the largest absolute value
        of every column of ``A`` on them, and their number of rows."""
        parts = [self.blocks[b] for b in which]
        R = _stack([p[0] for p in parts])
        magnitude = np.max([p[1] for p in parts], axis=0)
        return R, magnitude, sum(p[2] for p in parts)

    def problem(self, which: Iterable[int]) -> tuple[_Standardiser, NDArray, NDArray, NDArray]:
        """The standardiser and ``(R, Z, rest)`` of the rows of the blocks ``which``."""
        R, magnitude, n = self.factor(which)
        p, k = self.n_free, 1 if self.intercept is not None else 0
        if k:
            x_mean = self.const_value * R[0, 1 : 1 + p] / R[0, 0]
            y_mean = self.const_value * R[0, 1 + p :] / R[0, 0]
            Rc = R[1:, 1:]
        else:
            x_mean, y_mean, Rc = np.zeros(p), np.zeros(self.n_targets), R
        scale = np.sqrt(np.sum(Rc**2, axis=0) / n)
        x_scale, y_scale = scale[:p].copy(), scale[p:].copy()
        dead = ~(x_scale > _CONSTANT_RTOL * magnitude[k : k + p])
        x_scale[dead] = 1.0
        y_scale[~(y_scale > 0)] = 1.0
        st = _Standardiser.from_moments(
            self.free,
            self.intercept,
            self.const_value,
            (x_mean, y_mean),
            (x_scale, y_scale),
            dead,
        )
        Rs = Rc / np.concatenate([x_scale, y_scale])
        Rs[:, :p][:, dead] = 0.0  # zero columns keep the factor triangular
        return st, Rs[:p, :p], Rs[:p, p:], np.sum(Rs[p:, p:] ** 2, axis=0)

    def squared_error(self, which: Iterable[int], coef: NDArray, t: int) -> NDArray:
        """Mean squared error of target ``t`` on the blocks ``which`` for physical
        coefficients ``coef`` of shape (n_features, n_models)."""
        R, _, n = self.factor(which)
        parts = [coef[[self.intercept]]] if self.intercept is not None else []
        minus_y = np.zeros((self.n_targets, coef.shape[1]))
        minus_y[t] = -1.0
        V = np.vstack([*parts, coef[self.free], minus_y])
        return np.sum((R @ V) ** 2, axis=0) / n


def _row_blocks(
    n: int, splits: Sequence[tuple[NDArray, NDArray]] | None
) -> tuple[list[NDArray], list[list[int]] | None]:
    """Blocks of rows, and for each split the blocks of its test rows, or None when the test
    sets do not partition the rows (then folds are fitted directly).

    Examples
    --------
    >>> blocks, fold_blocks = _row_blocks(4, [([2, 3], [0, 1]), ([0, 1], [3, 2])])
    >>> [b.tolist() for b in blocks], fold_blocks
    ([[0, 1], [2, 3]], [[0], [1]])
    """
    if splits is not None:
        tests = [np.sort(test) for _, test in splits]
        covered = np.zeros(n, dtype=int)
        for test in tests:
            covered[test] += 1
        if np.all(covered == 1):
            blocks, fold_blocks = [], []
            for test in tests:
                pieces = _block_rows(test)
                fold_blocks.append(list(range(len(blocks), len(blocks) + len(pieces))))
                blocks.extend(pieces)
            return blocks, fold_blocks
    return _block_rows(np.arange(n)), None


_Fold = tuple[int, _Standardiser, NDArray, NDArray, Callable[[NDArray, int], NDArray]]


def _folds(
    compressed: _Compressed,
    splits: Sequence[tuple[NDArray, NDArray]],
    fold_blocks: list[list[int]] | None,
    X: NDArray,
    Y: NDArray,
) -> Iterator[_Fold]:
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


class GroupedProblem:
    """A least-squares problem compressed per group (record), for fast refits of column subsets.

    Columns are scaled to unit Euclidean norm over all samples (all-zero columns are left
    alone); each group's rows of ``[x | y]`` are reduced to their triangular factor by the
    engine the estimators use (:class:`_Compressed`), so a least-squares fit of any subset of
    columns on all groups but one is a small SVD solve (LAPACK ``gelsd``) on the QR of the
    stacked factors of the other groups, never another pass over the data.

    Parameters
    ----------
    features : array-like, shape (n_samples, n_features)
        Regression columns.
    target : array-like, shape (n_samples,)
        Regression target.
    groups : array-like, shape (n_samples,)
        Group (record) label of every sample.

    Attributes
    ----------
    scale : ndarray, shape (n_features,)
        Euclidean norm of every column (1 for all-zero columns); coefficients returned by
        :meth:`solve` are those of ``features / scale``.
    members : list of ndarray
        Sample indices of every group, groups in the order of ``numpy.unique(groups)``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> x = rng.normal(size=(60, 3))
    >>> y = x @ np.array([1.0, -2.0, 0.5]) + 0.01 * rng.normal(size=60)
    >>> problem = GroupedProblem(x, y, np.repeat([0, 1, 2], 20))
    >>> w = problem.solve([0, 1, 2], leave_out=1) / problem.scale
    >>> np.round(w, 2)
    array([ 1. , -2. ,  0.5])
    >>> errors = problem.lomo_errors([0, 1, 2])
    >>> errors.shape, bool(np.sqrt(np.mean(errors**2)) < 0.02)
    ((60,), True)
    """

    def __init__(self, features: ArrayLike, target: ArrayLike, groups: ArrayLike) -> None:
        features = np.asarray(features, dtype=float)
        target = np.asarray(target, dtype=float)
        groups = _check_groups(groups, features.shape[0])
        scale = np.linalg.norm(features, axis=0)
        scale[~(scale > 0)] = 1.0
        self.scale = scale
        self.x = features / scale
        self.y = target
        self.members = [np.flatnonzero(groups == g) for g in np.unique(groups)]
        blocks, self._group_blocks = _row_blocks(
            features.shape[0], [(np.zeros(0, dtype=int), rows) for rows in self.members]
        )
        free = np.ones(features.shape[1], dtype=bool)
        self._compressed = _Compressed(self.x, target.reshape(-1, 1), free, None, blocks)
        self._factors: dict[int | None, NDArray] = {}

    def _factor(self, leave_out: int | None) -> NDArray:
        """The triangular factor of ``[x | y]`` on all groups but ``leave_out`` (cached)."""
        if leave_out not in self._factors:
            held_out = set() if leave_out is None else set(self._group_blocks[leave_out])
            kept = [b for b in range(len(self._compressed.blocks)) if b not in held_out]
            self._factors[leave_out] = self._compressed.factor(kept)[0]
        return self._factors[leave_out]

    def solve(self, columns: ArrayLike, leave_out: int | None = None) -> NDArray:
        """Scaled coefficients of ``columns`` fitted on all groups but ``leave_out``.

        Parameters
        ----------
        columns : array-like of int
            Column indices to fit with.
        leave_out : int or None
            Position of the group to leave out (in ``members``); None fits on all groups.

        Returns
        -------
        ndarray, shape (len(columns),)
            Minimum-norm least-squares coefficients of ``features[:, columns] / scale``.
        """
        R = self._factor(leave_out)
        return _lstsq(R[:, columns], R[:, self.x.shape[1]])

    def lomo_errors(self, columns: ArrayLike) -> NDArray:
        """Leave-one-group-out prediction errors of a fit on ``columns``, per sample.

        Parameters
        ----------
        columns : array-like of int
            Column indices to fit with; none gives the target itself.

        Returns
        -------
        ndarray, shape (n_samples,)
            Target minus the prediction of the fit on all other groups.
        """
        errors = self.y.copy()
        if len(columns) == 0:
            return errors
        for g, rows in enumerate(self.members):
            w = self.solve(columns, leave_out=g)
            errors[rows] = self.y[rows] - self.x[np.ix_(rows, columns)] @ w
        return errors


def _running_factor(X: NDArray, Y: NDArray, scale: NDArray) -> NDArray:
    """Triangular factor of ``[X / scale | Y]``, folding in one block of rows at a time.

    Each block is stacked under the factor so far and reduced again, so only one block of
    ``X`` is ever copied: the same solution (and singular values) as on the full matrix, in
    time linear in the number of rows.  (:class:`_Compressed` instead reduces every block on
    its own, so that unions of blocks can be formed later.)

    Returns
    -------
    ndarray, shape (min(n_samples, n_columns), n_columns)
        ``n_columns = n_features + n_targets``.
    """
    R = np.zeros((0, X.shape[1] + Y.shape[1]))
    for rows in _block_rows(np.arange(X.shape[0])):
        block = np.hstack([X[rows] / scale, Y[rows]])
        R = np.linalg.qr(np.vstack([R, block]), mode="r")
    return R

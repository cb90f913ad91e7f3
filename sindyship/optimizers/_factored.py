"""The fit data of an estimator when only the factors of the records' rows are at hand.

:class:`_FactorData` offers what the estimators read from :class:`~._base._FitData` (column
roles, the compressed problem of all samples, the leave-one-record-out folds, the targets'
mean squares, the least-squares problem of the scaled columns), computed from one
:class:`~._compressed.RowFactor` per record instead of from the rows.  The leave-one-out
factors come from running factors over the records from the front and from the back
(:class:`_LeaveOneOut`): the fold without record ``k`` is the QR of two small triangles, so
all folds together cost a number of small QRs linear in the number of records.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from ._compressed import RowFactor, _Compressed, _Fold, _folds, _stack, tree_factor
from ._standardise import _roles_from_range, _Standardiser


class _LeaveOneOut(_Compressed):
    """The engine with one block per record, serving the union of all blocks but one from
    prefix and suffix factors (any other union is stacked as usual)."""

    @cached_property
    def _prefix(self) -> list[tuple[NDArray, NDArray] | None]:
        """``_prefix[k]``: the factor and column magnitudes of blocks ``0 .. k-1`` (None for
        none)."""
        out: list[tuple[NDArray, NDArray] | None] = [None]
        for R, magnitude, _ in self.blocks:
            last = out[-1]
            out.append((R, magnitude) if last is None else
                       (_stack([last[0], R]), np.maximum(last[1], magnitude)))
        return out

    @cached_property
    def _suffix(self) -> list[tuple[NDArray, NDArray] | None]:
        """``_suffix[k]``: the factor and column magnitudes of blocks ``k ..`` (None for
        none)."""
        out: list[tuple[NDArray, NDArray] | None] = [None]
        for R, magnitude, _ in reversed(self.blocks):
            last = out[-1]
            out.append((R, magnitude) if last is None else
                       (_stack([R, last[0]]), np.maximum(magnitude, last[1])))
        return out[::-1]

    def factor(self, which: Iterable[int]) -> tuple[NDArray, NDArray, int]:
        which = set(which)
        count = len(self.blocks)
        if count < 2 or len(which) != count - 1 or not which <= set(range(count)):
            return super().factor(sorted(which))
        (k,) = set(range(count)) - which
        parts = [part for part in (self._prefix[k], self._suffix[k + 1]) if part is not None]
        if len(parts) == 1:
            R, magnitude = parts[0]
        else:
            R = _stack([parts[0][0], parts[1][0]])
            magnitude = np.maximum(parts[0][1], parts[1][1])
        return R, magnitude, self._rows - self.blocks[k][2]

    @cached_property
    def _rows(self) -> int:
        return sum(b[2] for b in self.blocks)


class _FactorData:
    """What an estimator's ``_reduce`` reads, from per-record factors (no rows).

    Parameters
    ----------
    records : sequence of RowFactor
        One factor per record, in record order.
    whole : RowFactor or None
        The factor of all records (default: :func:`tree_factor` of ``records``).
    cross_validate : bool
        Whether the estimator uses the leave-one-record-out folds.
    """

    def __init__(self, records: Sequence[RowFactor], whole: RowFactor | None, *,
                 cross_validate: bool) -> None:
        self.records = list(records)
        self.whole = whole if whole is not None else tree_factor(self.records)
        self.n_samples = self.whole.n
        self.n_targets = self.whole.n_targets
        self.n_features = self.whole.n_features
        p = self.n_features
        self.roles = _roles_from_range(self.whole.low[:p], self.whole.high[:p])
        self.splits = [(None, None)] * len(self.records) if cross_validate else None

    @cached_property
    def compressed(self) -> _Compressed:
        """The engine with one block per record."""
        return _LeaveOneOut.from_factors(self.records, *self.roles)

    @cached_property
    def full(self) -> tuple[_Standardiser, NDArray, NDArray, NDArray]:
        """Standardiser and standardised ``(R, Z, rest)`` of all samples (from ``whole``)."""
        return _Compressed.from_factors([self.whole], *self.roles).problem([0])

    def folds(self) -> Iterator[_Fold]:
        """The leave-one-record-out folds (:func:`~._compressed._folds`)."""
        held_out = [[k] for k in range(len(self.records))]
        return _folds(self.compressed, self.splits, held_out, None, None)

    @property
    def n_folds(self) -> int:
        return len(self.records)

    def n_test(self, f: int) -> int:
        return self.records[f].n

    @cached_property
    def y_mean_square(self) -> NDArray:
        """Mean square of every target: the squared norm of its column of the factor."""
        return np.sum(self.whole.R[:, self.n_features:] ** 2, axis=0) / self.n_samples

    def column_norms(self) -> NDArray:
        """Euclidean norm of every column of ``X``: that of its column of the factor."""
        return np.linalg.norm(self.whole.R[:, : self.n_features], axis=0)

    def scaled_problem(self, scale: NDArray) -> tuple[NDArray, NDArray]:
        """The factor of ``[X / scale | Y]``: that of ``[X | Y]`` with its columns scaled."""
        p = self.n_features
        R = self.whole.R
        return R[:p, :p] / scale, R[:p, p:]

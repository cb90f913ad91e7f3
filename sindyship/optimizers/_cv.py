"""Cross-validation shared by the estimators: the splitter, its folds, and the choice.

The conventions (leave one group out when ``groups`` is given, else contiguous blocks; ties
go to the more regularised candidate) are those of the package docstring of
:mod:`sindyship.optimizers`.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from numbers import Integral
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.model_selection import (
    BaseCrossValidator,
    KFold,
    LeaveOneGroupOut,
    PredefinedSplit,
    check_cv,
)

from sindyship.errors import SindyshipInputError

#: The group label of samples that are always trained on and never held out (the captive
#: rows of a hybrid fit, :mod:`sindyship.hybrid`): not a manoeuvre of their own.
ALWAYS_TRAINED = -1
#: Number of contiguous blocks when neither ``cv`` nor ``groups`` is given.
_DEFAULT_N_BLOCKS = 5
#: Cross-validation errors within this relative tolerance of the smallest count as ties (ties
#: go to the more regularised candidate) ...
_TIE_RTOL = 1e-12
#: ... and so do errors below this fraction of the target's mean square: a held-out RMS error
#: under 1e-10 of the target's RMS is rounding, not a difference between models.
_TIE_FLOOR = 1e-20


def _resolve_cv(cv: Any, groups: NDArray | None) -> tuple[Any, NDArray | None]:
    """The splitter that ``cv`` and ``groups`` select, and the groups to hand to it.

    Leave one group out when ``groups`` is given and ``cv`` is not (samples labelled
    :data:`ALWAYS_TRAINED` are in every training set and no test set: a
    ``PredefinedSplit``), else 5 contiguous blocks with a ``UserWarning`` (a fit that
    receives no groups, as through ``pysindy.SINDy``, would otherwise change the protocol
    silently); an integer always means contiguous blocks (groups unused).

    Parameters
    ----------
    cv : None, int, splitter or iterable
        The estimator's ``cv`` parameter.
    groups : ndarray or None
        Group label of every sample.

    Returns
    -------
    splitter : cross-validation splitter
    groups : ndarray or None
        What to pass to ``splitter.split``.

    Examples
    --------
    >>> _resolve_cv(5, np.array([0, 0, 1, 1]))
    (KFold(n_splits=5, random_state=None, shuffle=False), None)
    >>> _resolve_cv(None, np.array([0, 0, 1, 1]))[0]
    LeaveOneGroupOut()
    >>> splitter, _ = _resolve_cv(None, np.array([0, 0, 1, 1, -1]))
    >>> [test.tolist() for _, test in splitter.split()]
    [[0, 1], [2, 3]]
    """
    if cv is None and groups is not None and np.any(groups == ALWAYS_TRAINED):
        _check_two_groups(groups[groups != ALWAYS_TRAINED])
        return PredefinedSplit(groups), None
    if cv is None and groups is not None:
        return LeaveOneGroupOut(), groups
    if cv is None:
        warnings.warn(
            "no groups given: cross-validating over 5 contiguous blocks, not leaving one "
            "manoeuvre out; pass groups= to fit, or cv=LeaveOneTrajectoryOut(lengths) when "
            "pysindy.SINDy fits this optimizer, or cv=5 to ask for the blocks.",
            UserWarning,
            stacklevel=4,
        )
        return KFold(n_splits=_DEFAULT_N_BLOCKS, shuffle=False), None
    if isinstance(cv, Integral):
        return KFold(n_splits=int(cv), shuffle=False), None
    return check_cv(cv), groups


class LeaveOneTrajectoryOut(BaseCrossValidator):
    """Leave one trajectory out, for samples that come as consecutive trajectories.

    ``pysindy.SINDy.fit`` stacks the samples of a list of trajectories in order and calls the
    optimizer's ``fit(X, y)`` without groups; give this splitter as the optimizer's ``cv`` to
    keep the leave-one-manoeuvre-out protocol there.

    Parameters
    ----------
    lengths : sequence of int
        Number of samples of every trajectory, in the order ``SINDy.fit`` receives them.

    Raises
    ------
    SindyshipInputError
        From :meth:`split` when the samples are not as many as the lengths add up to.

    Examples
    --------
    >>> cv = LeaveOneTrajectoryOut([2, 3])
    >>> [test.tolist() for _, test in cv.split(np.zeros((5, 1)))]
    [[0, 1], [2, 3, 4]]
    """

    def __init__(self, lengths: Sequence[int]):
        self.lengths = [int(n) for n in lengths]

    def get_n_splits(self, X=None, y=None, groups=None) -> int:
        return len(self.lengths)

    def _iter_test_indices(self, X=None, y=None, groups=None) -> Iterator[NDArray]:
        n_samples = np.asarray(X).shape[0]
        total = sum(self.lengths)
        if n_samples != total:
            raise SindyshipInputError(
                f"the optimizer received {n_samples} samples but the trajectories of "
                f"LeaveOneTrajectoryOut add up to {total}; give the lengths of the trajectories "
                "as the fit receives them."
            )
        if len(self.lengths) < 2:
            raise SindyshipInputError(
                "leave-one-trajectory-out cross-validation needs at least two trajectories."
            )
        ends = np.cumsum(self.lengths)
        for start, end in zip(ends - self.lengths, ends, strict=True):
            yield np.arange(start, end)

    def __repr__(self) -> str:
        return f"LeaveOneTrajectoryOut({self.lengths})"


def _splits(
    splitter: Any, X: NDArray, Y: NDArray, groups: NDArray | None
) -> list[tuple[NDArray, NDArray]]:
    """The ``(train, test)`` index pairs of ``splitter`` on these samples.

    Raises
    ------
    SindyshipInputError
        For leave-one-group-out with fewer than two groups.
    ValueError
        When the splitter produces no folds.
    """
    if isinstance(splitter, LeaveOneGroupOut):
        _check_two_groups(groups)
    splits = list(splitter.split(X, Y, groups))
    if not splits:
        raise ValueError("the cross-validation splitter produced no folds.")
    return splits


def _check_two_groups(groups: NDArray) -> None:
    """Refuse leave-one-group-out cross-validation over fewer than two groups."""
    if np.unique(groups).size < 2:
        raise SindyshipInputError(
            "leave-one-group-out cross-validation needs samples from at least two groups "
            "(manoeuvres); pass more manoeuvres, or cv=<number of folds> for contiguous blocks."
        )


def _check_groups(groups: ArrayLike | None, n_samples: int) -> NDArray | None:
    """``groups`` as an array with one label per sample, or None.

    Raises
    ------
    SindyshipInputError
        When ``groups`` is not 1-D with ``n_samples`` entries.
    """
    if groups is None:
        return None
    groups = np.asarray(groups)
    if groups.ndim != 1 or groups.shape[0] != n_samples:
        raise SindyshipInputError(
            f"groups must be a 1-D array with one label per sample ({n_samples}); "
            f"got shape {groups.shape}."
        )
    return groups


def _pick(mean_mse: NDArray, prefer: NDArray, y_mean_square: float) -> int:
    """Index of the smallest error; among ties, the one with the largest ``prefer``.

    Parameters
    ----------
    mean_mse : ndarray, shape (n_candidates,)
        Cross-validation error of every candidate.
    prefer : ndarray, shape (n_candidates,)
        Larger means more regularised (preferred among ties).
    y_mean_square : float
        Mean square of the target, which sets the absolute tie floor.

    Returns
    -------
    int

    Examples
    --------
    >>> _pick(np.array([1.0, 0.5, 0.5 + 1e-14]), np.array([3.0, 1.0, 2.0]), 1.0)
    2
    """
    best = np.nanmin(mean_mse)
    near = np.flatnonzero(mean_mse <= best + max(_TIE_RTOL * abs(best), _TIE_FLOOR * y_mean_square))
    return int(near[np.argmax(prefer[near])])

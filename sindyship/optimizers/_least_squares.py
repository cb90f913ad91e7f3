"""Ordinary least squares by SVD (paper section 3.3, eq. 19): :class:`LeastSquares`."""

from __future__ import annotations

from numbers import Real

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from sklearn.utils._param_validation import Interval

from ._base import _FitData, _LinearModel


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
    cond : float or None, default=1e-12
        Singular values below ``cond`` times the largest are treated as zero (minimum-norm
        solution).  ``None`` uses LAPACK's machine-precision default, which keeps a direction
        the scaled columns hold only by rounding: with revolutions n at two settings, ``1``,
        ``n`` and ``n^2`` are exactly dependent, and it gave coefficients near 1e8 that cancel
        (the default gives at most 0.83 and flies the held-out records within 0.07 L of them).

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

    def __init__(self, *, column_scaling: bool = True, cond: float | None = 1e-12) -> None:
        self.column_scaling = column_scaling
        self.cond = cond

    def _uses_cv(self) -> bool:
        return False

    def _reduce(self, data: _FitData) -> NDArray:
        """Least squares on all samples (``groups`` unused)."""
        scale = np.ones(data.n_features)
        if self.column_scaling:
            norms = data.column_norms()
            scale[norms > 0] = norms[norms > 0]
        # [X / scale | Y] compressed to its triangular factor when there are many rows: the
        # same solution (and singular values) as on the full matrix, in time linear in n
        A, B = data.scaled_problem(scale)
        W, _, rank, sv = scipy.linalg.lstsq(
            A, B, cond=self.cond, lapack_driver="gelsd", check_finite=False
        )
        self.rank_ = int(rank)
        self.singular_values_ = sv
        return (W / scale[:, None]).T

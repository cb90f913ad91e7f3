"""LASSO with the penalty chosen by cross-validation (paper section 3.4, eq. 20).

:func:`_lasso_path_exact` follows the exact LASSO path of a compressed problem through its
kinks (homotopy, the LARS-lasso path; :class:`_Homotopy` holds its state);
:class:`LassoCV` runs it on every fold and on all data.
"""

from __future__ import annotations

import warnings
from numbers import Integral
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray
from sklearn.exceptions import ConvergenceWarning
from sklearn.utils._param_validation import Interval, StrOptions

from ._base import _FitData, _LinearModel
from ._compressed import _lstsq
from ._cv import _pick

#: Warnings of the path point at the caller of ``fit``: _lasso_path_exact, a LassoCV helper,
#: LassoCV._reduce, _LinearModel.fit, the one-BLAS-thread wrapper, the caller.
_WARN_STACKLEVEL = 6


class _Homotopy:
    """The state of the LASSO homotopy ``min 0.5 ||z - R w||^2 + lam ||w||_1`` at ``lam``.

    Starts at the smallest ``lam`` with ``w = 0`` and moves to smaller ``lam`` one segment
    (between two kinks, or a kink and a grid value) at a time.  On a fixed active set ``A``
    with fixed signs ``s`` the solution is ``x0 - lam d`` with ``R_A = Q T``,
    ``x0 = T^-1 Q^T z`` and ``d = T^-1 T^-T s``: one QR per active set, recomputed exactly at
    every kink and grid value.

    Parameters
    ----------
    R : ndarray, shape (m, n_columns)
        Compressed library (:func:`_qr`).
    z : ndarray, shape (m,)
        Compressed target.
    """

    def __init__(self, R: NDArray, z: NDArray) -> None:
        self.R, self.z = R, z
        p = R.shape[1]
        self.usable = np.linalg.norm(R, axis=0) > 0
        self.active = np.zeros(p, dtype=bool)
        self.signs = np.zeros(p)
        self.w = np.zeros(p)
        self.c = R.T @ z  # correlations of the columns with the residual
        self.lam = float(np.max(np.abs(self.c[self.usable]))) if self.usable.any() else 0.0
        self.just_joined = -1
        self._cache: dict[bytes, tuple[NDArray, NDArray, NDArray, bool]] = {}

    def _factor(self) -> tuple[NDArray, NDArray, NDArray, bool]:
        """Active set ``A``, ``x0``, ``d`` and whether ``R_A`` has full column rank."""
        key = self.active.tobytes() + self.signs.tobytes()
        if key not in self._cache:
            A = np.flatnonzero(self.active)
            Q, T = np.linalg.qr(self.R[:, A])
            diag = np.abs(np.diag(T))
            full_rank = bool(diag.min() > 1e-13 * diag.max())
            u = scipy.linalg.solve_triangular(T, self.signs[A], trans="T", check_finite=False)
            d = scipy.linalg.solve_triangular(T, u, check_finite=False)
            x0 = scipy.linalg.solve_triangular(T, Q.T @ self.z, check_finite=False)
            self._cache.clear()
            self._cache[key] = (A, x0, d, full_rank)
        return self._cache[key]

    def _refresh(self) -> tuple[NDArray, NDArray]:
        """Put the exact solution at ``lam`` in ``w`` and ``c``; the active set and the rate
        ``-dx/dlam`` of its coefficients."""
        A, x0, d, _ = self._factor()
        self.w[:] = 0.0
        self.w[A] = x0 - self.lam * d
        self.c = self.R.T @ (self.z - self.R @ self.w)
        return A, d

    def _start(self, target: float) -> bool:
        """Activate the first term; False when ``lam`` reaches ``target`` before any term."""
        j = int(np.argmax(np.where(self.usable, np.abs(self.c), -1.0)))
        if abs(self.c[j]) <= target:
            self.lam = float(target)
            return False
        self.lam = float(abs(self.c[j]))
        self.active[j], self.signs[j], self.just_joined = True, np.sign(self.c[j]), j
        return True

    def _join_steps(self, a: NDArray) -> NDArray:
        """Decrease of ``lam`` at which every inactive term's correlation reaches ``+-lam``."""
        lam, c = self.lam, self.c
        with np.errstate(divide="ignore", invalid="ignore"):
            up = np.where(1.0 - a > 1e-12, (lam - c) / (1.0 - a), np.inf)
            down = np.where(1.0 + a > 1e-12, (lam + c) / (1.0 + a), np.inf)
        join = np.where(self.usable & ~self.active, np.minimum(up, down), np.inf)
        join[join < 0] = np.inf
        return join

    def _drop_steps(self, A: NDArray, d: NDArray) -> NDArray:
        """Decrease of ``lam`` at which every active coefficient reaches zero (not the term
        that has just joined)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = np.where(d != 0, -self.w[A] / d, np.inf)
        cross[(cross <= 0) | (A == self.just_joined)] = np.inf
        return cross

    def _apply(self, event: str, who: int, step: float, a: NDArray) -> None:
        """Move ``lam`` down by ``step`` and let ``who`` join or leave the active set."""
        self.lam -= step
        self.just_joined = -1
        if event == "join":
            self.active[who], self.signs[who] = True, np.sign(self.c[who] - step * a[who])
            if not self._factor()[3]:
                # numerically collinear with the active terms: it cannot enter
                self.active[who], self.signs[who], self.usable[who] = False, 0.0, False
            else:
                self.just_joined = who
        elif event == "drop":
            self.active[who], self.signs[who] = False, 0.0

    def advance(self, target: float) -> bool:
        """Follow the path from ``lam`` to the next kink, or to ``target`` if that comes first.

        Returns
        -------
        bool
            False when ``lam`` reached ``target`` with no term active (no kink passed).
        """
        if not self.active.any() and not self._start(target):
            return False
        A, d = self._refresh()
        a = self.R.T @ (self.R[:, A] @ d)  # rate of change of the correlations as lam decreases
        step, event, who = self.lam - float(target), "target", -1
        join = self._join_steps(a)
        if join.size and np.min(join) < step:
            who = int(np.argmin(join))
            step, event = float(join[who]), "join"
        cross = self._drop_steps(A, d)
        if cross.size and np.min(cross) < step:
            i = int(np.argmin(cross))
            step, event, who = float(cross[i]), "drop", int(A[i])
        self._apply(event, who, step, a)
        return True

    def solution_at(self, target: float) -> NDArray:
        """Set ``lam = target`` and return the exact solution there (a view of ``w``)."""
        self.lam = float(target)
        if self.active.any():
            self._refresh()
        return self.w


def _lasso_path_exact(R: NDArray, z: NDArray, lams: NDArray, max_events: int) -> NDArray:
    """Exact LASSO solutions along a decreasing grid by homotopy (the LARS-lasso path).

    Solves ``min 0.5 ||z - R w||^2 + lam ||w||_1`` for every ``lam`` in ``lams`` (decreasing).
    The solution is piecewise linear in ``lam``; the path is followed from ``w = 0`` through
    every kink (a term joins or leaves the active set), with the active coefficients
    recomputed exactly (by QR of the active columns of ``R``) at every kink and every grid
    value, so no tolerance or iteration count shapes the answer.

    Parameters
    ----------
    R : ndarray, shape (m, n_columns)
        Compressed library (:func:`_qr`).
    z : ndarray, shape (m,)
        Compressed target.
    lams : ndarray, shape (n_lams,)
        Decreasing penalties.
    max_events : int
        Kinks after which a :class:`~sklearn.exceptions.ConvergenceWarning` is raised (the
        path is still followed to the end).

    Returns
    -------
    ndarray, shape (n_columns, n_lams)

    Examples
    --------
    Above ``max|R^T z| = 1.5`` all coefficients are zero, at ``lam = 0`` the path ends at
    least squares, and in between the correlations of the active terms equal ``+-lam``:

    >>> R, z = np.array([[1.0, 0.5], [0.0, 1.0]]), np.array([1.0, 1.0])
    >>> W = _lasso_path_exact(R, z, np.array([2.0, 0.5, 0.0]), 100)
    >>> W
    array([[0.   , 0.125, 0.5  ],
           [0.   , 0.75 , 1.   ]])
    >>> R.T @ (z - R @ W[:, 1])
    array([0.5, 0.5])
    """
    W = np.zeros((R.shape[1], lams.size))
    path = _Homotopy(R, z)
    if not path.usable.any():
        return W
    events = 0
    for k, target in enumerate(lams):
        while path.lam > target:
            if not path.advance(target):
                break
            events += 1
            if events > max_events:
                warnings.warn(
                    f"the LASSO homotopy passed {max_events} kinks without reaching the end of "
                    "the penalty grid; the remaining solutions keep the last active set.",
                    ConvergenceWarning,
                    stacklevel=_WARN_STACKLEVEL,
                )
                max_events = np.inf
        W[:, k] = path.solution_at(target)
    return W


class LassoCV(_LinearModel):
    """LASSO with the penalty chosen by cross-validation (paper section 3.4, eq. 20).

    For every target, minimises ``1/(2 n) ||y_s - X_s w||^2 + alpha ||w||_1`` on standardised
    columns ``X_s`` and the standardised target ``y_s`` (package docstring; the constant
    column is an unpenalised intercept), so ``alpha`` is dimensionless and comparable between
    the surge, sway and yaw equations.

    The solutions are exact: each fold's problem is compressed by one QR factorisation to a
    ``n_features``-square triangular system, and the LASSO path is followed through its kinks
    (homotopy / LARS-lasso, :func:`_lasso_path_exact`) with the active coefficients recomputed
    by QR at every kink and grid value.  Coordinate descent (``sklearn.linear_model.lasso_path``)
    is not used: on this noise-free, ill-conditioned problem the penalties that win are tiny,
    where its convergence rate is set by the conditioning; even at ``tol=1e-12`` and
    ``max_iter=1e6`` it stops far from the optimum, and the chosen ``alpha`` becomes an
    artefact of ``tol``.

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
        Cross-validation scheme (package docstring): leave one group out when ``groups`` is
        given, else 5 contiguous blocks with a warning; ``cv=10`` for the paper's 10 folds.

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
        """The decreasing penalty grid of one target (see ``alphas``)."""
        if self.alphas is not None and not isinstance(self.alphas, Integral):
            grid = np.sort(np.asarray(self.alphas, dtype=float).ravel())[::-1]
            if grid.size == 0 or np.any(grid <= 0) or not np.all(np.isfinite(grid)):
                raise ValueError("alphas must be positive, finite penalties.")
            return grid
        n_alphas = 100 if self.alphas is None else int(self.alphas)
        alpha_max = float(np.max(np.abs(R.T @ z), initial=0.0)) / n
        if alpha_max <= 0:
            return np.geomspace(1.0, 1e-6, n_alphas)
        ratio = min(1e-6, _least_squares_ratio(R, z, rest, n, alpha_max))
        return alpha_max * np.geomspace(1.0, ratio, n_alphas)

    def _reduce(self, data: _FitData) -> NDArray:
        """The exact path on every fold and on all data; the penalty chosen per target."""
        n_samples, n_targets = data.n_samples, data.n_targets
        max_events = 50 * data.n_features + 100
        _, R, Z, rest = data.full
        alphas = np.vstack([self._grid(R, Z[:, t], rest[t], n_samples) for t in range(n_targets)])
        mse = self._fold_errors(data, alphas, max_events)
        coef_path = self._full_path(data, alphas, max_events)
        chosen = np.array(
            [self._choose(mse[t], alphas[t], data.y_mean_square[t]) for t in range(n_targets)],
            dtype=int,
        )
        idx = np.arange(n_targets)
        self.alphas_ = alphas
        self.mse_path_ = mse
        self.coef_path_ = coef_path
        self.alpha_ = alphas[idx, chosen]
        return coef_path[idx, :, chosen]

    def _fold_errors(self, data: _FitData, alphas: NDArray, max_events: int) -> NDArray:
        """Held-out mean squared error, shape (n_targets, n_alphas, n_folds)."""
        mse = np.zeros((data.n_targets, alphas.shape[1], data.n_folds))
        for f, fold, Rf, Zf, error in data.folds():
            n_train = data.n_samples - data.n_test(f)
            for t in range(data.n_targets):
                W = _lasso_path_exact(Rf, Zf[:, t], n_train * alphas[t], max_events)
                zeros = np.zeros(W.shape[1])
                mse[t, :, f] = error(fold.physical(W, zeros, t, data.n_features), t)
        return mse

    def _full_path(self, data: _FitData, alphas: NDArray, max_events: int) -> NDArray:
        """Physical coefficients on all data, shape (n_targets, n_features, n_alphas)."""
        full, R, Z, _ = data.full
        coef_path = np.zeros((data.n_targets, data.n_features, alphas.shape[1]))
        for t in range(data.n_targets):
            W = _lasso_path_exact(R, Z[:, t], data.n_samples * alphas[t], max_events)
            coef_path[t] = full.physical(W, np.zeros(W.shape[1]), t, data.n_features)
        return coef_path

    def _choose(self, mse: NDArray, alphas: NDArray, y_mean_square: float) -> int:
        """Grid index of the chosen penalty from the fold errors (n_alphas, n_folds)."""
        mean = mse.mean(axis=1)
        best = _pick(mean, alphas, float(y_mean_square))
        if self.selection == "one_se" and mse.shape[1] > 1:
            se = mse[best].std(ddof=1) / np.sqrt(mse.shape[1])
            within = np.flatnonzero(mean <= mean[best] + se)
            best = int(within[np.argmax(alphas[within])])
        return best


def _least_squares_ratio(R: NDArray, z: NDArray, rest: float, n: int, alpha_max: float) -> float:
    """``alpha_min / alpha_max`` at which the LASSO's in-sample mean squared error exceeds
    that of least squares by about 0.1 % (never below ``1e-12``; 1 when it cannot be
    estimated).

    The excess is ``alpha^2 * s^T (R^T R / n)^-1 s`` with ``s`` the least-squares signs
    (exact while the LASSO keeps every term with the least-squares signs).
    """
    usable = np.linalg.norm(R, axis=0) > 0
    if not usable.any():
        return 1.0
    Ru = R[:, usable]
    w_ls = _lstsq(Ru, z)
    resid = rest + float(np.sum((z - Ru @ w_ls) ** 2))
    if not np.all(w_ls != 0):
        return 1.0
    try:
        _, T = np.linalg.qr(Ru)
        u = scipy.linalg.solve_triangular(T, np.sign(w_ls), trans="T")
        excess_per_alpha2 = n * float(u @ u)  # in-sample MSE excess / alpha^2
        floor = np.sqrt(1e-3 * (resid / n) / excess_per_alpha2)
    except (np.linalg.LinAlgError, ValueError):
        return 1.0
    return max(floor / alpha_max, 1e-12) if np.isfinite(floor) else 1.0

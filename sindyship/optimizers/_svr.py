"""Linear epsilon-support-vector regression (paper section 3.5, eq. 22-24): :class:`SVR`.

:func:`_svr_newton` is the exact finite Newton solver of the primal (with its line search
:func:`_svr_line_search`); :class:`SVR` runs it, or liblinear, along a grid of ``C`` and
``epsilon`` on every fold and chooses by the cross-validation error.
"""

from __future__ import annotations

import warnings
from numbers import Integral, Real
from typing import Any

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray
from sklearn.exceptions import ConvergenceWarning
from sklearn.svm import LinearSVR
from sklearn.utils._param_validation import Interval, StrOptions

from ._base import _FitData, _LinearModel
from ._compressed import _lstsq
from ._cv import _pick
from ._standardise import _Standardiser

#: The solver warning points at the caller of ``fit``: SVR._reduce, _LinearModel.fit, the
#: one-BLAS-thread wrapper, the caller.
_WARN_STACKLEVEL = 4


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

    on standardised columns ``x_s`` and the standardised target ``y_s`` (package docstring);
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
        Cross-validation scheme (package docstring).

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
    >>> model = SVR(Cs=[1.0, 1e4], epsilons=[0.0, 0.1], cv=5).fit(X, y)
    >>> print(model.C_, model.epsilon_)
    [10000.] [0.]
    >>> np.allclose(model.coef_, [[1e-5, -1.2e-2, 2.6e-3, -2e-1]], rtol=1e-3, atol=1e-7)
    True
    """

    _needs_rows = True  # the epsilon-insensitive loss is not a least-squares one

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

    def _check_grid(self) -> None:
        self._grid()

    def _reduce(self, data: _FitData) -> NDArray:
        """Choose ``C`` and ``epsilon`` by cross-validation, then refit on all data."""
        Cs, eps_grid = self._grid()
        fit_b = data.roles[1] is not None
        unconverged = [0]
        cand_C = np.tile(Cs, eps_grid.size)
        cand_eps = np.repeat(eps_grid, Cs.size)
        mse = self._fold_errors(data, Cs, eps_grid, fit_b, unconverged)
        mean_mse = mse.mean(axis=2)
        coef = self._refit(data, Cs, (cand_C, cand_eps), mean_mse, fit_b, unconverged)
        if unconverged[0]:
            warnings.warn(
                f"the SVR solver ({self.solver}) stopped at max_iter={self.max_iter} in "
                f"{unconverged[0]} fits; raise max_iter or tol.",
                ConvergenceWarning,
                stacklevel=_WARN_STACKLEVEL,
            )
        self.cv_results_ = {"C": cand_C, "epsilon": cand_eps, "mean_mse": mean_mse, "mse": mse}
        return coef

    def _fold_errors(
        self, data: _FitData, Cs: NDArray, eps_grid: NDArray, fit_b: bool, unconverged: list
    ) -> NDArray:
        """Held-out mean squared error, shape (n_targets, n_candidates, n_folds); candidates
        run over ``Cs`` fastest."""
        X, Y, n_features = data.X, data.Y, data.n_features
        free, intercept = data.roles
        mse = np.zeros((data.n_targets, Cs.size * eps_grid.size, len(data.splits)))
        for f, (train, test) in enumerate(data.splits):
            fold = _Standardiser(X[train], Y[train], free, intercept)
            Xb = _with_ones(fold.transform_X(X[train]))
            Ys = fold.transform_Y(Y[train])
            for t in range(data.n_targets):
                for e, eps in enumerate(eps_grid):
                    W, B, _ = self._path(Xb, Ys[:, t], Cs, eps, fit_b, unconverged)
                    pred = X[test] @ fold.physical(W, B, t, n_features)
                    cols = slice(e * Cs.size, (e + 1) * Cs.size)
                    mse[t, cols, f] = np.mean((pred - Y[test, t][:, None]) ** 2, axis=0)
        return mse

    def _refit(
        self,
        data: _FitData,
        Cs: NDArray,
        candidates: tuple[NDArray, NDArray],
        mean_mse: NDArray,
        fit_b: bool,
        unconverged: list,
    ) -> NDArray:
        """Pick the candidate of every target and refit it on all data.

        Sets ``C_``, ``epsilon_`` and ``n_iter_``; returns the physical coefficients.
        """
        X, Y, n_features = data.X, data.Y, data.n_features
        cand_C, cand_eps = candidates
        full = _Standardiser(X, Y, *data.roles)
        Xb, Ys = _with_ones(full.transform_X(X)), full.transform_Y(Y)
        coef = np.zeros((data.n_targets, n_features))
        self.C_ = np.zeros(data.n_targets)
        self.epsilon_ = np.zeros(data.n_targets)
        n_iter = np.zeros(data.n_targets, dtype=int)
        # ties go to the smaller C, then to the wider tube (the more regularised model)
        order = np.lexsort((cand_eps, -cand_C))  # ascending preference
        rank = np.empty(order.size)
        rank[order] = np.arange(order.size)
        for t in range(data.n_targets):
            best = _pick(mean_mse[t], rank, float(np.mean(Y[:, t] ** 2)))
            self.C_[t], self.epsilon_[t] = cand_C[best], cand_eps[best]
            path_C = Cs[Cs <= cand_C[best]]
            W, B, n_iter[t] = self._path(Xb, Ys[:, t], path_C, cand_eps[best], fit_b, unconverged)
            coef[t] = full.physical(W[:, -1], B[-1], t, n_features)
        self.n_iter_ = np.maximum(n_iter, 1)
        return coef

"""A Levenberg-Marquardt search on the normal equations, for problems with many residuals and
few parameters (the refinement's: hundreds of thousands of compared samples, tens of
coefficients).

A trust-region search of :func:`scipy.optimize.least_squares` factorises the whole Jacobian
at every step (a singular value decomposition of a matrix of residuals x parameters); here
only its Gram matrix J^T J and J^T r are formed, and every step solves a system of the size of
the parameters.  Marquardt's scaling by the diagonal of J^T J makes the steps independent of
the parameters' units (Nocedal & Wright 2006, *Numerical Optimization*, ch. 10; Madsen,
Nielsen & Tingleff 2004, *Methods for non-linear least squares problems*, the damping update
of their eq. 2.21).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["Search", "levenberg_marquardt"]

#: Relative decrease of the cost, and relative size of a step, below which the search has
#: converged.
TOLERANCE = 1e-9


@dataclass(frozen=True)
class Search:
    """The end of a search: the parameters, half the sum of squared residuals there, the
    evaluations of the residuals and of the Jacobian, and why it stopped."""

    x: np.ndarray
    cost: float
    evaluations: int
    jacobians: int
    converged: bool
    message: str


def levenberg_marquardt(residuals: Callable[[np.ndarray], np.ndarray],
                        normal: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
                        x0: np.ndarray, *, max_evaluations: int = 40,
                        tolerance: float = TOLERANCE,
                        on_step: Callable[[int, float], None] | None = None,
                        bound: float | None = None) -> Search:
    """Minimise half the sum of squares of ``residuals(x)`` from ``x0``.

    Parameters
    ----------
    residuals : callable
        ``x -> r`` (shape (m,)).
    normal : callable
        ``x -> (J^T J, J^T r)`` with J the Jacobian of the residuals at ``x`` (shapes (n, n)
        and (n,)); called only at points ``residuals`` has been called at.
    x0 : ndarray, shape (n,)
    max_evaluations : int
        Most calls of ``residuals`` (every trial step is one).
    tolerance : float
        Converged when an accepted step lowers the cost by less than this share, or moves
        ``x`` by less than this share of its size (plus ``tolerance``), or the scaled gradient
        vanishes.
    on_step : callable, optional
        Called after every accepted step with its number and the cost.
    bound : float, optional
        Every parameter stays within [-bound, bound] (a trial step is cut back to the box).

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 50)
    >>> y = 2.0 * np.exp(-1.5 * t)
    >>> def residuals(p):
    ...     return p[0] * np.exp(-p[1] * t) - y
    >>> def normal(p):
    ...     J = np.column_stack([np.exp(-p[1] * t), -p[0] * t * np.exp(-p[1] * t)])
    ...     return J.T @ J, J.T @ residuals(p)
    >>> found = levenberg_marquardt(residuals, normal, np.array([1.0, 0.5]))
    >>> np.round(found.x, 6).tolist(), found.converged
    ([2.0, 1.5], True)
    """
    x = np.array(x0, dtype=float)
    r = residuals(x)
    cost = 0.5 * float(r @ r)
    evaluations, jacobians, damping, accepted = 1, 0, None, 0
    message = "the most evaluations were made"
    converged = False
    while evaluations < max_evaluations:
        gram, gradient = normal(x)
        jacobians += 1
        scale = np.sqrt(np.maximum(np.diag(gram), 1e-300))
        if np.max(np.abs(gradient) / scale) <= tolerance * max(math.sqrt(2.0 * cost), 1e-300):
            converged, message = True, "the gradient vanishes"
            break
        if damping is None:
            damping = 1e-3  # in the scaled parameters, where J^T J has a unit diagonal
        improved = False
        while evaluations < max_evaluations:
            step = _step(gram, gradient, scale, damping)
            if bound is not None:
                step = np.clip(x + step, -bound, bound) - x
            trial = x + step
            r_trial = residuals(trial)
            evaluations += 1
            cost_trial = 0.5 * float(r_trial @ r_trial)
            predicted = -(step @ gradient + 0.5 * step @ gram @ step)
            gain = (cost - cost_trial) / predicted if predicted > 0 else -1.0
            if np.isfinite(cost_trial) and gain > 0:
                small_step = np.linalg.norm(step) <= tolerance * (np.linalg.norm(x) + tolerance)
                small_gain = cost - cost_trial <= tolerance * cost
                x, r, cost = trial, r_trial, cost_trial
                damping *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)
                accepted += 1
                improved = True
                if on_step is not None:
                    on_step(accepted, cost)
                if small_step or small_gain:
                    converged = True
                    message = ("the step became too small to matter" if small_step else
                               "the cost stopped falling")
                break
            damping *= 4.0
        if converged or not improved:
            break
    return Search(x, cost, evaluations, jacobians, converged, message)


def _step(gram: np.ndarray, gradient: np.ndarray, scale: np.ndarray, damping: float
          ) -> np.ndarray:
    """The damped Gauss-Newton step (J^T J + damping diag(J^T J)) dx = -J^T r, solved in
    the scaled parameters."""
    scaled = gram / np.outer(scale, scale) + damping * np.eye(len(scale))
    try:
        return -np.linalg.solve(scaled, gradient / scale) / scale
    except np.linalg.LinAlgError:
        return -np.linalg.lstsq(scaled, gradient / scale, rcond=None)[0] / scale

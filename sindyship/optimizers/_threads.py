"""The one-BLAS-thread guard of every fit (:func:`one_blas_thread`)."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread"]

_F = TypeVar("_F", bound=Callable[..., Any])


def one_blas_thread(fit: _F) -> _F:
    """Run ``fit`` with BLAS limited to one thread.

    Every product here is tall and skinny (``n_features`` ~ 20 columns), where threads gain
    little, and a multi-threaded BLAS competing with other processes for the cores slows such
    products down by an order of magnitude (measured: 0.5 s becoming 4-18 s for one SVR fit).

    Parameters
    ----------
    fit : callable
        The function to guard (typically an estimator's ``fit``).

    Returns
    -------
    callable
        ``fit`` with the same signature and docstring, run under
        ``threadpoolctl.threadpool_limits(limits=1, user_api="blas")``.

    Examples
    --------
    >>> from threadpoolctl import threadpool_info
    >>> @one_blas_thread
    ... def blas_threads():
    ...     return {p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}
    >>> blas_threads() <= {1}
    True
    """

    @functools.wraps(fit)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with threadpool_limits(limits=1, user_api="blas"):
            return fit(*args, **kwargs)

    return wrapper  # type: ignore[return-value]

"""The optimizers by name: :data:`OPTIMIZERS` and :func:`make_optimizer`."""

from __future__ import annotations

from typing import Any

from sindyship.errors import SindyshipInputError

from ._base import _LinearModel
from ._lasso import LassoCV
from ._least_squares import LeastSquares
from ._prior import PriorRidge
from ._stlsq import STLSQ
from ._svr import SVR

__all__ = ["OPTIMIZERS", "make_optimizer"]

#: The optimizers by name, as used in saved models (``optimizer: {name, params}``) and on the
#: command line (``--optimizer``).
OPTIMIZERS: dict[str, type[_LinearModel]] = {
    "ls": LeastSquares,
    "stlsq": STLSQ,
    "lasso": LassoCV,
    "svr": SVR,
    "prior": PriorRidge,
}


def make_optimizer(name: str, **params: Any) -> _LinearModel:
    """Build an optimizer by name.

    Parameters
    ----------
    name : {"ls", "stlsq", "lasso", "svr", "prior"}
        Which optimizer (:data:`OPTIMIZERS`).
    **params
        Its parameters, as returned by its ``get_params()``.

    Returns
    -------
    estimator
        An unfitted scikit-learn regressor.

    Raises
    ------
    SindyshipInputError
        For an unknown name or parameter.

    Examples
    --------
    >>> make_optimizer("stlsq", threshold=0.1)
    STLSQ(threshold=0.1)
    >>> make_optimizer("ridge")
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: unknown optimizer 'ridge': choose one of 'ls', 'stlsq', 'lasso', 'svr', 'prior'.
    """  # noqa: E501
    if name not in OPTIMIZERS:
        valid = ", ".join(repr(k) for k in OPTIMIZERS)
        raise SindyshipInputError(f"unknown optimizer {name!r}: choose one of {valid}.")
    cls = OPTIMIZERS[name]
    allowed = cls().get_params()
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        valid = ", ".join(sorted(allowed))
        raise SindyshipInputError(
            f"optimizer {name!r} has no parameter {unknown[0]!r}: its parameters are {valid}."
        )
    return cls(**params)

"""The forces of an identified model (paper eq. 15) compiled by numba.

:meth:`sindyship.model.AbkowitzModel.forces_from_values` is the reference: it evaluates each
distinct factor base of the active terms once, raises it to its powers, multiplies each term's
factors and sums the columns with the coefficients.  :func:`forces` does the same arithmetic
as a loop over the states of a batch, so that a right-hand side of a flight costs a few
microseconds instead of tens.  The model runs it when numba can be imported; this module is
imported at the first call, so ``import sindyship`` does not import numba.

Results equal the numpy path to rounding: a power is formed by repeated multiplication here
and by ``numpy.power`` there.
"""

from __future__ import annotations

import math

import numpy as np

try:  # optional: pip install "sindyship[fast]"
    import numba
except ImportError:
    numba = None

#: Whether :func:`forces` is compiled (numba could be imported).
COMPILED = numba is not None

#: Codes of the term grammar's functions of a variable (0: the variable itself).
FUNCTION_CODES = {None: 0, "abs": 1, "sign": 2, "sin": 3, "cos": 4}


def _forces(variables, base_variable, base_function, factor_base, factor_power, slots,
            weights):
    """Forces (3, B) of eq. 15 from the variables (n_variables, B) of B states.

    Parameters
    ----------
    variables : ndarray, shape (n_variables, B)
    base_variable, base_function : ndarray of int, shape (n_bases,)
        Each factor base: the row of ``variables`` it reads and its function code
        (:data:`FUNCTION_CODES`).
    factor_base, factor_power : ndarray of int, shape (n_factors,)
        Each distinct factor: its base and its power.
    slots : ndarray of int, shape (width, n_terms)
        Each term's factors, padded with ``n_factors`` (a factor of one).
    weights : ndarray, shape (3, n_terms)
        The coefficients of the terms in X, Y and N.
    """
    n_states = variables.shape[1]
    n_bases = base_variable.shape[0]
    n_factors = factor_base.shape[0]
    width, n_terms = slots.shape
    out = np.zeros((3, n_states))
    base = np.empty(n_bases)
    factor = np.ones(n_factors + 1)
    for b in range(n_states):
        for k in range(n_bases):
            x = variables[base_variable[k], b]
            code = base_function[k]
            if code == 1:
                x = abs(x)
            elif code == 2:
                x = (x > 0.0) - (x < 0.0) if x == x else x
            elif code == 3:
                x = math.sin(x)
            elif code == 4:
                x = math.cos(x)
            base[k] = x
        for f in range(n_factors):
            x = base[factor_base[f]]
            value = x
            for _ in range(factor_power[f] - 1):
                value *= x
            factor[f] = value
        for j in range(n_terms):
            column = factor[slots[0, j]]
            for s in range(1, width):
                column *= factor[slots[s, j]]
            out[0, b] += weights[0, j] * column
            out[1, b] += weights[1, j] * column
            out[2, b] += weights[2, j] * column
    return out


forces = numba.njit(cache=True, nogil=True)(_forces) if COMPILED else _forces

"""The forces and accelerations of an identified model (paper eq. 14-15) compiled by numba.

:meth:`sindyship.model.AbkowitzModel.forces_from_values` is the reference: it evaluates each
distinct factor base of the active terms once, raises it to its powers, multiplies each term's
factors and sums the columns with the coefficients.  :func:`forces` does the same arithmetic
as a loop over the states of a batch, so that a right-hand side of a flight costs a few
microseconds instead of tens; :func:`accelerations` adds the Coriolis terms and the mass
matrix of eq. 14 as :meth:`sindyship.model.AbkowitzDynamics.accelerations` does.  The model
runs them when numba can be imported; this module is imported when a model is built, so
``import sindyship`` does not import numba.

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


#: The first rows of :func:`accelerations`' variables come from the state: du, v, r, delta and
#: psi (:data:`sindyship.model.STATE_VARIABLES`); the model's other variables follow.
N_STATE_VARIABLES = 5


def _accelerations(u, v, r, delta, psi, extra, base_variable, base_function, factor_base,
                   factor_power, slots, weights, inertia, inverse_mass, U0, L):
    """Accelerations (3, B) in SI of eq. 14 at SI states (1-D arrays of B states).

    ``extra`` (n_extra, B) holds the variables beyond the state's (library
    scaling), ``inertia`` the Prime I Coriolis factors ``(m - Y_vdot, m x_G - Y_rdot,
    m - X_udot, X_udot - Y_vdot)`` (:func:`sindyship.targets.coriolis`) and ``inverse_mass``
    the inverse of eq. 14's mass matrix; the other arguments are :func:`_forces`'.
    """
    n_states = u.shape[0]
    variables = np.empty((N_STATE_VARIABLES + extra.shape[0], n_states))
    for b in range(n_states):
        variables[0, b] = u[b] / U0 - 1.0
        variables[1, b] = v[b] / U0
        variables[2, b] = r[b] * L / U0
        variables[3, b] = delta[b]
        variables[4, b] = psi[b]
    variables[N_STATE_VARIABLES:] = extra
    out = forces(variables, base_variable, base_function, factor_base, factor_power, slots,
                 weights)
    scale = U0 * U0 / L
    for b in range(n_states):
        un = variables[0, b] + 1.0
        vn = variables[1, b]
        rn = variables[2, b]
        X = out[0, b] + (inertia[0] * vn * rn + inertia[1] * rn * rn)
        Y = out[1, b] + (-inertia[2] * un * rn)
        N = out[2, b] + (-inertia[1] * un * rn - inertia[3] * un * vn)
        out[0, b] = inverse_mass[0, 0] * X * scale
        out[1, b] = (inverse_mass[1, 1] * Y + inverse_mass[1, 2] * N) * scale
        out[2, b] = (inverse_mass[2, 1] * Y + inverse_mass[2, 2] * N) * scale / L
    return out


if COMPILED:
    forces = numba.njit(cache=True, nogil=True)(_forces)
    accelerations = numba.njit(cache=True, nogil=True)(_accelerations)
else:
    forces, accelerations = _forces, _accelerations

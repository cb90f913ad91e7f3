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

from .errors import SindyshipInputError
from .terms import is_shape_name, parse_shape, shape_values

try:  # optional: pip install "sindyship[fast]"
    import numba
except ImportError:
    numba = None

#: Whether :func:`forces` is compiled (numba could be imported).
COMPILED = numba is not None

#: Codes of the term grammar's functions of a variable (0: the variable itself).
FUNCTION_CODES = {None: 0, "abs": 1, "sign": 2, "sin": 3, "cos": 4}


def _forces(variables, base_variable, base_function, factor_base, factor_power, slots,
            weights, weight_set):
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
    weights : ndarray, shape (3, n_terms, n_sets)
        Sets of coefficients of the terms in X, Y and N (one set for a model).
    weight_set : ndarray of int, shape (B,)
        The set each state takes.
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
        w = weight_set[b]
        for j in range(n_terms):
            column = factor[slots[0, j]]
            for s in range(1, width):
                column *= factor[slots[s, j]]
            out[0, b] += weights[0, j, w] * column
            out[1, b] += weights[1, j, w] * column
            out[2, b] += weights[2, j, w] * column
    return out


#: The first rows of :func:`accelerations`' variables come from the state; the model's other
#: variables follow (:func:`tables`).
STATE_VARIABLES = ("du", "v", "r", "delta", "psi")
N_STATE_VARIABLES = len(STATE_VARIABLES)


def _accelerations(u, v, r, delta, psi, extra, base_variable, base_function, factor_base,
                   factor_power, slots, weights, weight_set, inertia, inverse_mass, U0, L):
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
                 weights, weight_set)
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


def tables(bases, factors, slots):
    """``(variable names, integer tables)`` of a model's factor table for :func:`forces` and
    :func:`accelerations`, or None when a factor's base is a number (the numpy path runs).

    ``bases``, ``factors`` and ``slots`` are :class:`sindyship.model.AbkowitzModel`'s: each
    factor base with the factors it gives and their powers, the distinct factors, and each
    term's factors padded with ``len(factors)``.
    """
    if any(not isinstance(base.base, str) for base, _, _ in bases):
        return None
    used = {base.base for base, _, _ in bases}
    names = list(STATE_VARIABLES) + sorted(used - set(STATE_VARIABLES))
    base_variable = np.array([names.index(base.base) for base, _, _ in bases], dtype=np.int64)
    base_function = np.array([FUNCTION_CODES[base.function] for base, _, _ in bases],
                             dtype=np.int64)
    factor_base = np.empty(len(factors), dtype=np.int64)
    for k, (_, rows, _) in enumerate(bases):
        factor_base[rows] = k
    factor_power = np.array([f.power for f in factors], dtype=np.int64)
    return names, (base_variable, base_function, factor_base, factor_power,
                   slots.astype(np.int64))


def run_accelerations(dynamics, u, v, r, delta, psi, t, members, position, rudder_rate):
    """:meth:`sindyship.model.AbkowitzDynamics.accelerations` through :func:`accelerations`,
    or None when the state values are not 1-D float64 arrays (the numpy path runs).  Strided
    views, read-only and byte-swapped arrays are copied: one compiled form serves every call."""
    for a in (u, v, r, delta, psi):
        if type(a) is not np.ndarray or a.ndim != 1 or a.dtype.char != "d":
            return None
    u, v, r, delta, psi = (np.require(a, np.float64, requirements="CW")
                           for a in (u, v, r, delta, psi))
    model = dynamics.model
    names, integer_tables = model._compiled
    extra = _extra_variables(dynamics, names[N_STATE_VARIABLES:], u.shape[0], t, members,
                             position, rudder_rate)
    a = accelerations(u, v, r, delta, psi, extra, *integer_tables, model._weights[:, :, None],
                      np.zeros(u.shape[0], dtype=np.int64), model._inertia,
                      model.inverse_mass, model.ship.U0, model.ship.L)
    return a[0], a[1], a[2]


def _extra_variables(dynamics, names, n_states, t, members, position, rudder_rate):
    """The variables beyond the state's (library scaling), one row each, as
    :meth:`sindyship.model.AbkowitzDynamics.accelerations` forms them."""
    extra = np.zeros((len(names), n_states))
    if not names:
        return extra
    recorded = dynamics.series.at(t, members) if dynamics.series is not None else {}
    L, U0 = dynamics.model.ship.L, dynamics.model.ship.U0
    for k, name in enumerate(names):
        if name in recorded:
            extra[k] = recorded[name]
        elif name in dynamics.channels:
            extra[k] = dynamics.channels[name]
        elif name in ("x", "y"):
            if position is not None:
                extra[k] = position[0 if name == "x" else 1]
        elif is_shape_name(name):  # without a position, away from every line (0)
            if position is not None:
                extra[k] = shape_values(parse_shape(name), position[0], position[1], L)
        elif name == "delta_rate":
            if rudder_rate is not None:
                extra[k] = rudder_rate * L / U0
        else:
            raise SindyshipInputError(
                f"the model needs the variable {name!r}, which the data do not provide."
            )
    return extra

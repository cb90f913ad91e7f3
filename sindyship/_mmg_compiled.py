"""The MMG accelerations of :class:`sindyship.mmg.MMGModel` compiled by numba (paper eq. 1-11).

:mod:`sindyship.mmg` is the reference: its numpy functions state the physics once, readably.
This module repeats the same equations as scalar loops over a batch of states, with the same
operations in the same order, so both give the same numbers (to rounding in the library
functions sin, cos, atan2, exp) while a right-hand side of the integrator costs a few
microseconds instead of tens.  :meth:`sindyship.mmg.MMGModel.accelerations` and
:meth:`~sindyship.mmg.MMGModel.switching` (beta_R, whose sign chooses gamma_R) run it for the
plain model (no ``extra_forces``, ``conditions`` or ``bank``) when numba can be imported; they
import this module at their first call, so ``import sindyship`` does not import numba.

The ship enters as one vector of numbers (:func:`parameters`): the coefficients, and the
constants the numpy functions form from them before they meet a state.  Everything is
compiled with ``numba.njit(cache=True)`` (nopython, numpy's floating-point error model:
a division by zero gives inf or nan, as in numpy); the machine code is kept in the package's
``__pycache__`` (or numba's user cache directory when the package's is read-only), so only
the first process after an installation or a change of this file compiles.
"""

from __future__ import annotations

import math

import numpy as np

from .ships import HULL_COEFFICIENTS, Ship

try:  # optional: pip install "sindyship[fast]"
    import numba
except ImportError:
    numba = None

#: Whether the functions below are compiled (numba could be imported).
COMPILED = numba is not None

# Places in the parameter vector (parameters()): the speed scales, the rudder's offset and
# stall angle, the model's switches, then the propeller, rudder, Coriolis and mass-matrix
# constants, then the hull coefficients in the order of HULL_COEFFICIENTS[hull_form].
(_U0, _L, _OFFSET, _STALL, _STANDARD_HULL, _INSTANTANEOUS, _DRIFT_WAKE,
 _A0, _A1, _A2, _NN_DD, _THRUST, _ONE_MINUS_TP, _ONE_MINUS_W, _W_P0, _X_P,
 _KAPPA, _EPSILON, _ETA, _ONE_MINUS_ETA, _L_R, _GAMMA_STBD, _GAMMA_PORT, _NORMAL,
 _X_RUDDER, _Y_RUDDER, _N_RUDDER,
 _M_VR, _M_UR, _MXG, _MINUS_MXG,
 _S_XX, _S_YY, _S_YN, _S_NY, _S_NN, _HULL) = range(37)
#: Length of the parameter vector.
N_PARAMETERS = _HULL + 17


def parameters(ship: Ship, scaled_inverse_mass: np.ndarray, rudder_offset: float = 0.0,
               stall: float | None = None) -> np.ndarray:
    """The numbers the compiled accelerations need, as one vector.

    Constants that :mod:`sindyship.mmg` forms from coefficients alone (say ``1 - t_P`` or
    ``D_P^4 n_P^2 / (0.5 d / L)``) are formed here by the same Python float operations.

    Parameters
    ----------
    ship : Ship
        A ship with MMG coefficients (``ship.has_mmg``).
    scaled_inverse_mass : ndarray, shape (3, 3)
        The inverse of the mass matrix of eq. 1 with the Prime II -> SI scaling folded in, as
        :class:`sindyship.mmg.MMGModel` holds it.
    rudder_offset : float
        Rudder-angle sensor offset [rad] (:class:`sindyship.mmg.MMGModel`).
    stall : float, optional
        Rudder stall angle [rad]; none is an infinite one (the same numbers).

    Returns
    -------
    ndarray, shape (N_PARAMETERS,)

    Examples
    --------
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.ships import load_ship
    >>> model = MMGModel(load_ship("kcs"))
    >>> p = parameters(model.ship, model._scaled_inverse_mass)
    >>> p.shape == (N_PARAMETERS,), float(p[_U0])
    (True, 12.348)
    """
    L, U0 = ship.particulars.L, ship.particulars.U0
    prop, rud, mass = ship.propeller, ship.rudder, ship.mass
    D_nd = prop.D_P / L  # eq. 4-6 as mmg._propeller forms them
    n_nd = prop.n_P * L / U0
    m, mxg = mass.m, mass.m * ship.x_G_nd  # eq. 11 as mmg._coriolis forms them
    added = ship.coriolis == "with-added-mass"
    S = scaled_inverse_mass
    values = {
        _U0: U0, _L: L, _OFFSET: rudder_offset, _STALL: math.inf if stall is None else stall,
        _STANDARD_HULL: ship.hull_form == "standard",
        _INSTANTANEOUS: ship.speed_reference == "instantaneous",
        _DRIFT_WAKE: prop.wake_model == "drift",
        _A0: prop.K_T[0], _A1: prop.K_T[1], _A2: prop.K_T[2], _NN_DD: n_nd * D_nd,
        _THRUST: D_nd**4 * n_nd**2 / (0.5 * ship.d_over_L), _ONE_MINUS_TP: 1.0 - prop.t_P,
        _ONE_MINUS_W: 1.0 - prop.w_P0, _W_P0: prop.w_P0, _X_P: prop.x_P,
        _KAPPA: rud.kappa, _EPSILON: rud.epsilon, _ETA: rud.eta, _ONE_MINUS_ETA: 1.0 - rud.eta,
        _L_R: rud.l_R, _GAMMA_STBD: rud.gamma_R_stbd, _GAMMA_PORT: rud.gamma_R_port,
        _NORMAL: rud.A_R / (ship.particulars.L * ship.particulars.d) * rud.f_alpha,
        _X_RUDDER: -(1.0 - rud.t_R), _Y_RUDDER: -(1.0 + rud.a_H),
        _N_RUDDER: -(rud.x_R + rud.a_H * rud.x_H),
        _M_VR: m + mass.m_y if added else m, _M_UR: -(m + mass.m_x) if added else -m,
        _MXG: mxg, _MINUS_MXG: -mxg,
        _S_XX: S[0, 0], _S_YY: S[1, 1], _S_YN: S[1, 2], _S_NY: S[2, 1], _S_NN: S[2, 2],
    }
    p = np.empty(N_PARAMETERS)
    for place, value in values.items():
        p[place] = value
    p[_HULL:] = [ship.hull[name] for name in HULL_COEFFICIENTS[ship.hull_form]]
    return p


def _jit(function):
    """``function`` compiled by numba (nopython, numpy's error model, cached) when numba is
    there, else itself."""
    if not COMPILED:
        return function
    return numba.njit(cache=True, error_model="numpy")(function)


@_jit
def _hull(p, u, v, r, beta):
    """Hull forces (paper eq. 3, or the v', r' form of Yasukawa & Yoshimura), as mmg._hull."""
    coefficients = p[_HULL:_HULL + 17]
    if p[_STANDARD_HULL] == 0.0:  # X_bbb multiplies beta^4, Y_bb and N_bb beta^3
        (X_0, X_bb, X_br_minus_my, X_rr, X_bbb, Y_b, Y_r_minus_mx, Y_bb, Y_bbr, Y_brr, Y_rrr,
         N_b, N_r, N_bb, N_bbr, N_brr, N_rrr) = coefficients
        b2 = beta * beta
        r2 = r * r
        X_H = X_0 * u * u + X_bb * b2 + X_br_minus_my * beta * r + X_rr * r2 + X_bbb * b2 * b2
        Y_H = (beta * (Y_b + Y_bb * b2 + Y_brr * r2)
               + r * (Y_r_minus_mx + Y_bbr * b2 + Y_rrr * r2))
        N_H = beta * (N_b + N_bb * b2 + N_brr * r2) + r * (N_r + N_bbr * b2 + N_rrr * r2)
        return X_H, Y_H, N_H
    (R_0, X_vv, X_vr, X_rr, X_vvvv, Y_v, Y_r, Y_vvv, Y_vvr, Y_vrr, Y_rrr,
     N_v, N_r, N_vvv, N_vvr, N_vrr, N_rrr) = coefficients
    U2 = u * u + v * v
    U = math.sqrt(U2)
    vU = v / U
    rU = r / U
    v2 = vU * vU
    r2 = rU * rU
    X_H = U2 * (-R_0 + X_vv * v2 + X_vr * vU * rU + X_rr * r2 + X_vvvv * v2 * v2)
    Y_H = U2 * (vU * (Y_v + Y_vvv * v2 + Y_vrr * r2) + rU * (Y_r + Y_vvr * v2 + Y_rrr * r2))
    N_H = U2 * (vU * (N_v + N_vvv * v2 + N_vrr * r2) + rU * (N_r + N_vvr * v2 + N_rrr * r2))
    return X_H, Y_H, N_H


@_jit
def _propeller(p, u, v, r, beta):
    """Propeller thrust (paper eq. 4-6) with the wake, advance ratio and K_T, as
    mmg._propeller at the ship's constant revolutions."""
    if p[_DRIFT_WAKE] != 0.0:
        beta_P = beta - p[_X_P] * r / math.sqrt(u * u + v * v)
        one_minus_w = 1.0 - p[_W_P0] * math.exp(-4.0 * beta_P * beta_P)
    else:
        one_minus_w = p[_ONE_MINUS_W]
    J = u * one_minus_w / p[_NN_DD]
    K_T = p[_A0] + p[_A1] * J + p[_A2] * J * J
    X_P = p[_ONE_MINUS_TP] * K_T * p[_THRUST]
    return X_P, one_minus_w, J, K_T


@_jit
def _gamma_R(p, beta_R, starboard):
    """The flow straightening factor: ``starboard`` 1 or 0 chooses it, -1 the sign of beta_R."""
    stbd = beta_R > 0.0 if starboard < 0 else starboard == 1
    return p[_GAMMA_STBD] if stbd else p[_GAMMA_PORT]


@_jit
def _rudder(p, u, v, r, delta, beta, one_minus_w, J, K_T, starboard):
    """Rudder forces (paper eq. 7-10), as mmg._rudder; ``starboard`` is 1 or 0 to choose
    gamma_R, -1 to follow the sign of beta_R."""
    race = 1.0 + p[_KAPPA] * (math.sqrt(1.0 + 8.0 * K_T / (math.pi * J * J)) - 1.0)
    u_R = (p[_EPSILON] * u) * one_minus_w * math.sqrt(p[_ETA] * race * race + p[_ONE_MINUS_ETA])
    l_R = p[_L_R]
    if p[_INSTANTANEOUS] != 0.0:
        U = math.sqrt(u * u + v * v)
        beta_R = beta - l_R * r / U
        lateral = U * _gamma_R(p, beta_R, starboard) * beta_R
    else:
        beta_R = beta - l_R * r
        lateral = -_gamma_R(p, beta_R, starboard) * (v + l_R * r)
    alpha_R = delta - math.atan2(lateral, u_R)
    # np.clip(alpha_R, -stall, stall): nan stays nan, an infinite stall changes nothing
    if alpha_R < -p[_STALL]:
        alpha_R = -p[_STALL]
    if alpha_R > p[_STALL]:
        alpha_R = p[_STALL]
    F_N = p[_NORMAL] * (u_R * u_R + lateral * lateral) * math.sin(alpha_R)
    F_cos = F_N * math.cos(delta)
    return p[_X_RUDDER] * F_N * math.sin(delta), p[_Y_RUDDER] * F_cos, p[_N_RUDDER] * F_cos


@_jit
def _coriolis(p, u, v, r):
    """Coriolis and centripetal terms (paper eq. 11), as mmg._coriolis."""
    return (p[_M_VR] * v * r + p[_MXG] * r * r, p[_M_UR] * u * r, p[_MINUS_MXG] * u * r)


def _jit_for(signature):
    """A decorator: the function compiled for the one ``signature``, cached like :func:`_jit`
    (numba compiles it, or loads it from its cache, when this module is imported)."""
    def decorate(function):
        if not COMPILED:
            return function
        return numba.njit(signature, cache=True, error_model="numpy")(function)
    return decorate


if COMPILED:  # states are 1-d float64 arrays of any stride (rows of the integrator's batch)
    _ROW = numba.float64[:]
    _ACCELERATIONS = numba.float64[:, ::1](_ROW, _ROW, _ROW, _ROW, numba.boolean[:],
                                           numba.float64[::1])
    _SWITCHING = numba.float64[::1](numba.float64[:, :], numba.float64[::1])
else:
    _ACCELERATIONS = _SWITCHING = None


@_jit_for(_ACCELERATIONS)
def _accelerations(u, v, r, delta, branch, p):
    """Accelerations (du/dt, dv/dt, dr/dt) [SI] of the states ``u, v, r, delta`` [SI] as rows
    of a (3, k) array, as MMGModel.accelerations: the forces of eq. 2-11 summed in the order
    hull, propeller, rudder, Coriolis, then M^-1 of eq. 1 and the scaling to SI.

    ``branch`` holds k gamma_R choices (True: starboard), or none to follow beta_R's sign.
    """
    k = u.shape[0]
    if v.shape[0] != k or r.shape[0] != k or delta.shape[0] != k:
        raise ValueError("u, v, r and delta differ in length")
    if branch.shape[0] != k and branch.shape[0] != 0:
        raise ValueError("branch differs in length from the states")
    U0 = p[_U0]
    out = np.empty((3, k))
    for j in range(k):
        un = u[j] / U0
        vn = v[j] / U0
        rn = r[j] * p[_L] / U0
        beta = math.atan2(-vn, un)
        starboard = -1 if branch.shape[0] == 0 else (1 if branch[j] else 0)
        X_H, Y_H, N_H = _hull(p, un, vn, rn, beta)
        X_P, one_minus_w, J, K_T = _propeller(p, un, vn, rn, beta)
        X_R, Y_R, N_R = _rudder(p, un, vn, rn, delta[j] - p[_OFFSET], beta, one_minus_w, J,
                                K_T, starboard)
        X_C, Y_C, N_C = _coriolis(p, un, vn, rn)
        X = X_H + X_P + X_R + X_C
        Y = Y_H + Y_R + Y_C
        N = N_H + N_R + N_C
        out[0, j] = p[_S_XX] * X
        out[1, j] = p[_S_YY] * Y + p[_S_YN] * N
        out[2, j] = p[_S_NY] * Y + p[_S_NN] * N
    return out


@_jit_for(_SWITCHING)
def _switching(state, p):
    """beta_R (k,) of the SI states (7, k), as mmg.rudder_inflow_angle."""
    k = state.shape[1]
    U0 = p[_U0]
    out = np.empty(k)
    for j in range(k):
        un = state[0, j] / U0
        vn = state[1, j] / U0
        rn = state[2, j] * p[_L] / U0
        beta = math.atan2(-vn, un)
        if p[_INSTANTANEOUS] != 0.0:
            out[j] = beta - p[_L_R] * rn / math.sqrt(un * un + vn * vn)
        else:
            out[j] = beta - p[_L_R] * rn
    return out


def switching(p: np.ndarray, state) -> np.ndarray | None:
    """beta_R at SI states (7, k), whose sign selects gamma_R (as
    :meth:`sindyship.mmg.MMGModel.switching`), or None for states other than a 2-d float64
    array (left to the numpy functions)."""
    try:
        return _switching(state, p)
    except TypeError:  # numba finds no matching signature
        return None


#: The branch argument that lets beta_R's sign choose gamma_R.
_FOLLOW_SIGN = np.zeros(0, dtype=bool)


def accelerations(p: np.ndarray, u, v, r, delta, branch=None):
    """Accelerations (du/dt [m/s^2], dv/dt [m/s^2], dr/dt [rad/s^2]) of the plain MMG model.

    Parameters
    ----------
    p : ndarray
        The ship's numbers (:func:`parameters`).
    u, v, r, delta : float or ndarray
        Surge and sway [m/s], yaw rate [rad/s] and rudder angle [rad], broadcast together.
    branch : bool or ndarray, optional
        gamma_R's branch (True: starboard), as :func:`sindyship.mmg.force_components` takes
        ``starboard``; default the sign of beta_R.

    Returns
    -------
    tuple of ndarray or float, or None
        The three accelerations in the inputs' broadcast shape (numpy floats for scalars), or
        None for inputs left to the numpy functions: other array types (pandas, sympy),
        other floating dtypes than float64 (whose precision numpy keeps), or shapes that do not
        broadcast.

    Examples
    --------
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.ships import load_ship
    >>> model = MMGModel(load_ship("kcs"))
    >>> p = parameters(model.ship, model._scaled_inverse_mass)
    >>> [round(float(a), 7) for a in accelerations(p, 12.348, 0.0, 0.0, 0.0)]
    [1.4e-05, 0.0, 0.0]
    """
    try:  # what the integrator passes: 1-d float64 states of one length
        out = _accelerations(u, v, r, delta, _FOLLOW_SIGN if branch is None else branch, p)
    except (TypeError, ValueError):  # numba finds no matching signature, or lengths differ
        return _broadcast(p, u, v, r, delta, branch)
    return out[0], out[1], out[2]


def _takes(value) -> bool:
    """Whether ``value`` is a number or ndarray whose numpy result would be float64."""
    if isinstance(value, bool | int | float):
        return True
    if type(value) is np.ndarray or isinstance(value, np.generic):
        return value.dtype == np.float64 or value.dtype.kind in "biu"
    return False


def _broadcast(p, u, v, r, delta, branch):
    """:func:`accelerations` of inputs of any shape: flattened, computed, shaped back."""
    values = (u, v, r, delta) if branch is None else (u, v, r, delta, branch)
    if not all(_takes(value) for value in values):
        return None
    try:
        shape = np.broadcast_shapes(*(np.shape(value) for value in values))
    except ValueError:  # the numpy functions raise their own error
        return None
    # flat copies: writable, whatever the inputs were (numba takes no read-only arrays here)
    u, v, r, delta = (np.broadcast_to(np.asarray(value, dtype=float), shape).flatten()
                      for value in (u, v, r, delta))
    branch = (_FOLLOW_SIGN if branch is None
              else np.broadcast_to(np.asarray(branch, dtype=bool), shape).flatten())
    out = _accelerations(u, v, r, delta, branch, p)
    if shape == ():
        return out[0, 0], out[1, 0], out[2, 0]
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)

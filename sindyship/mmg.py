"""The MMG manoeuvring model (paper section 2.1): hull, propeller, rudder and Coriolis forces.

Every force is written once, in :func:`force_components`; the simulator's right-hand side
(:class:`MMGModel`) and any force breakdown call that same function.  It is the reference of
the compiled copy :mod:`sindyship._mmg_compiled` that the plain model's accelerations run
where numba is installed (:class:`MMGModel`, Notes).  Inputs and outputs are
non-dimensional in Prime II with the constant design speed U0 (u' = u / U0, v' = v / U0,
r' = r L / U0); all functions accept numpy arrays (vectorised over samples or manoeuvres).

Two hull forms are supported:

* ``beta`` (the paper's KCS, eq. 3 with Table 3, read as the protocol fixes it): X'_bbb
  multiplies beta^4, Y'_bb and N'_bb multiply beta^3, beta = atan2(-v', u').
* ``standard`` (Yasukawa & Yoshimura 2015, KVLCC2): a Taylor series in v'_U = v / U and
  r'_U = r L / U with the instantaneous speed U, scaled back to U0 by (U / U0)^2.
"""

from __future__ import annotations

import functools
import os
from dataclasses import dataclass

import numpy as np

from .conditions import wind_force
from .errors import SindyshipInputError
from .ships import Ship, load_ship
from .simulation.kernels import ChannelSeries


def thrust_coefficient(ship: Ship, J):
    """Open-water thrust coefficient K_T = a0 + a1 J + a2 J^2 (paper eq. 5)."""
    a0, a1, a2 = ship.propeller.K_T
    return a0 + a1 * J + a2 * J * J


def rudder_inflow_angle(ship: Ship, u, v, r):
    """beta_R = beta - l'_R r', the drift angle at the rudder; gamma_R switches on its sign."""
    beta = np.arctan2(-v, u)
    if ship.speed_reference == "instantaneous":
        return beta - ship.rudder.l_R * r / np.sqrt(u * u + v * v)
    return beta - ship.rudder.l_R * r


def force_components(ship: Ship, u, v, r, delta, starboard=None, n=None, stall=None
                     ) -> dict[str, tuple]:
    """Hull, propeller, rudder and Coriolis forces of the MMG model (paper eq. 2-11).

    Parameters
    ----------
    ship : Ship
        The ship.
    u, v, r : float or ndarray
        Surge, sway and yaw rate, non-dimensional with U0 (r' = r L / U0).
    delta : float or ndarray
        Rudder angle the water sees [rad].
    starboard : bool or ndarray, optional
        Which flow straightening factor gamma_R to use (True: ``gamma_R_stbd``).  By default
        it follows the sign of beta_R (:func:`rudder_inflow_angle`); the simulator freezes it
        over each integration step and splits steps where it changes.
    n : float or ndarray, optional
        Propeller revolutions [rps]; default the ship's constant ``n_P``.
    stall : float, optional
        Rudder stall angle [rad]: the rudder's normal force stops growing when its effective
        angle of attack alpha_R (eq. 8) exceeds it (lift saturates; default no stall).

    Returns
    -------
    dict
        ``{"hull": (X, Y, N), "propeller": (X, Y, N), "rudder": (X, Y, N),
        "coriolis": (X, Y, N)}``, Prime II with U0.  Their sum is the right-hand side of paper
        eq. 1.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> parts = force_components(load_ship("kcs"), 1.0, 0.0, 0.0, 0.0)
    >>> round(float(parts["propeller"][0] + parts["hull"][0]), 5)  # thrust balances resistance
    0.0
    """
    beta = np.arctan2(-v, u)
    zero = 0.0 * u
    X_P, one_minus_w, J, K_T = _propeller(ship, u, v, r, beta, n)
    return {
        "hull": _hull(ship, u, v, r, beta),
        "propeller": (X_P, zero, zero),
        "rudder": _rudder(ship, u, v, r, delta, beta, one_minus_w, J, K_T, starboard, stall),
        "coriolis": _coriolis(ship, u, v, r),
    }


def _hull(ship: Ship, u, v, r, beta) -> tuple:
    """Hull forces (paper eq. 3, or the standard v', r' form of Yasukawa & Yoshimura)."""
    hull = ship.hull
    if ship.hull_form == "beta":
        b2 = beta * beta
        r2 = r * r
        X_H = (hull["X_0"] * u * u + hull["X_bb"] * b2 + hull["X_br_minus_my"] * beta * r
               + hull["X_rr"] * r2 + hull["X_bbb"] * b2 * b2)
        Y_H = (beta * (hull["Y_b"] + hull["Y_bb"] * b2 + hull["Y_brr"] * r2)
               + r * (hull["Y_r_minus_mx"] + hull["Y_bbr"] * b2 + hull["Y_rrr"] * r2))
        N_H = (beta * (hull["N_b"] + hull["N_bb"] * b2 + hull["N_brr"] * r2)
               + r * (hull["N_r"] + hull["N_bbr"] * b2 + hull["N_rrr"] * r2))
        return X_H, Y_H, N_H
    U2 = u * u + v * v
    U = np.sqrt(U2)
    vU = v / U
    rU = r / U
    v2, r2 = vU * vU, rU * rU
    X_H = U2 * (-hull["R_0"] + hull["X_vv"] * v2 + hull["X_vr"] * vU * rU
                + hull["X_rr"] * r2 + hull["X_vvvv"] * v2 * v2)
    Y_H = U2 * (vU * (hull["Y_v"] + hull["Y_vvv"] * v2 + hull["Y_vrr"] * r2)
                + rU * (hull["Y_r"] + hull["Y_vvr"] * v2 + hull["Y_rrr"] * r2))
    N_H = U2 * (vU * (hull["N_v"] + hull["N_vvv"] * v2 + hull["N_vrr"] * r2)
                + rU * (hull["N_r"] + hull["N_vvr"] * v2 + hull["N_rrr"] * r2))
    return X_H, Y_H, N_H


def _propeller(ship: Ship, u, v, r, beta, n=None) -> tuple:
    """Propeller thrust (paper eq. 4-6) and the wake, advance ratio and K_T the rudder needs;
    ``n`` [rps] defaults to the ship's constant ``n_P``."""
    prop = ship.propeller
    L, U0 = ship.particulars.L, ship.particulars.U0
    D_nd = prop.D_P / L
    n_nd = (prop.n_P if n is None else n) * L / U0
    if prop.wake_model == "drift":
        beta_P = beta - prop.x_P * r / np.sqrt(u * u + v * v)
        one_minus_w = 1.0 - prop.w_P0 * np.exp(-4.0 * beta_P * beta_P)
    else:
        one_minus_w = 1.0 - prop.w_P0
    J = u * one_minus_w / (n_nd * D_nd)
    K_T = thrust_coefficient(ship, J)
    X_P = (1.0 - prop.t_P) * K_T * (D_nd**4 * n_nd**2 / (0.5 * ship.d_over_L))
    return X_P, one_minus_w, J, K_T


def _rudder(ship: Ship, u, v, r, delta, beta, one_minus_w, J, K_T, starboard, stall=None
            ) -> tuple:
    """Rudder forces (paper eq. 7-10).

    ``lateral`` is -v'_R of eq. 10b, so that alpha_R = delta - atan2(lateral, u'_R) (eq. 8);
    with the instantaneous speed it is U gamma_R beta_R.
    """
    rud = ship.rudder
    eta = rud.eta
    race = 1.0 + rud.kappa * (np.sqrt(1.0 + 8.0 * K_T / (np.pi * J * J)) - 1.0)
    u_R = (rud.epsilon * u) * one_minus_w * np.sqrt(eta * race * race + (1.0 - eta))
    if ship.speed_reference == "instantaneous":
        U = np.sqrt(u * u + v * v)
        beta_R = beta - rud.l_R * r / U
        stbd = beta_R > 0.0 if starboard is None else starboard
        gamma = np.where(stbd, rud.gamma_R_stbd, rud.gamma_R_port)
        lateral = U * gamma * beta_R
    else:
        beta_R = beta - rud.l_R * r
        stbd = beta_R > 0.0 if starboard is None else starboard
        gamma = np.where(stbd, rud.gamma_R_stbd, rud.gamma_R_port)
        lateral = -gamma * (v + rud.l_R * r)
    alpha_R = delta - np.arctan2(lateral, u_R)
    if stall is not None:
        alpha_R = np.clip(alpha_R, -stall, stall)
    F_N = (rud.A_R / (ship.particulars.L * ship.particulars.d) * rud.f_alpha) \
        * (u_R * u_R + lateral * lateral) * np.sin(alpha_R)
    F_cos = F_N * np.cos(delta)
    X_R = -(1.0 - rud.t_R) * F_N * np.sin(delta)
    Y_R = -(1.0 + rud.a_H) * F_cos
    N_R = -(rud.x_R + rud.a_H * rud.x_H) * F_cos
    return X_R, Y_R, N_R


def _coriolis(ship: Ship, u, v, r) -> tuple:
    """Coriolis and centripetal terms (paper eq. 11), moved to the right-hand side."""
    mass = ship.mass
    m = mass.m
    mxg = mass.m * ship.x_G_nd
    if ship.coriolis == "rigid-body":
        X_C = m * v * r + mxg * r * r
        Y_C = -m * u * r
    else:
        X_C = (m + mass.m_y) * v * r + mxg * r * r
        Y_C = -(m + mass.m_x) * u * r
    N_C = -mxg * u * r
    return X_C, Y_C, N_C


def _bank_force(ship: Ship, bank: tuple[float, float], y_east, psi) -> tuple:
    """Suction toward a bank along north at y = y_bank (see :class:`MMGModel`), Prime II."""
    y_bank, strength = bank
    distance = np.maximum(np.abs(y_bank - y_east), 0.5 * ship.L)
    east = np.sign(y_bank - y_east) * strength * (ship.L / distance) ** 2
    Y = east * np.cos(psi)
    return east * np.sin(psi), Y, -0.25 * Y


def patch_share(ship: Ship, patch: tuple[float, float, float], x_north, y_east):
    """How far the ship is over a shallow patch (see :class:`MMGModel`): 0 in deep water, 1
    on the patch, a smooth step of half a ship length across its edge."""
    distance, direction, _ = patch
    across = x_north * np.cos(direction) + y_east * np.sin(direction) - distance
    return 0.5 * (1.0 + np.tanh(across / (0.5 * ship.L)))


def _patch_force(ship: Ship, increase, u, v, r) -> tuple:
    """The linear hull forces (paper eq. 3, or the standard form) times ``increase``, Prime II
    with U0 (u, v, r non-dimensional with U0)."""
    hull = ship.hull
    if ship.hull_form == "beta":
        beta = np.arctan2(-v, u)
        return (0.0 * u, increase * (hull["Y_b"] * beta + hull["Y_r_minus_mx"] * r),
                increase * (hull["N_b"] * beta + hull["N_r"] * r))
    U = np.sqrt(u * u + v * v)
    return (0.0 * u, increase * U * (hull["Y_v"] * v + hull["Y_r"] * r),
            increase * U * (hull["N_v"] * v + hull["N_r"] * r))


def mass_matrix(ship: Ship) -> np.ndarray:
    """Prime II mass matrix of paper eq. 1 (rigid body plus added mass, about midship)."""
    m = ship.mass
    mxg = m.m * ship.x_G_nd
    return np.array([
        [m.m + m.m_x, 0.0, 0.0],
        [0.0, m.m + m.m_y, mxg],
        [0.0, mxg, m.I_zz + m.J_zz],
    ])


@dataclass(frozen=True)
class MMGModel:
    """The MMG model as simulator dynamics: accelerations from the state (paper eq. 1).

    Parameters
    ----------
    ship : Ship
        The ship.
    extra_forces : tuple of callables
        Additional Prime II forces ``f(u, v, r, delta, psi) -> (X, Y, N)`` (physical effects such
        as a steady earth-fixed load or cross-flow drag), added to the right-hand side.
    rudder_offset : float
        Rudder-angle sensor offset [rad]: the water sees ``delta - rudder_offset``.
    current : tuple of float
        Uniform current (north, east) [m/s]; the integrator moves the ship with it.
    stall : float, optional
        Rudder stall angle [rad] (:func:`force_components`).
    bank : tuple of float, optional
        ``(y_bank, strength)``: a straight bank along north at ``y = y_bank`` [m] that pulls
        the ship toward it with an earth-fixed force ``strength (L / d)^2`` (Prime II, d the
        distance to the bank), acting a quarter length aft of midship (bank suction on the
        stern turns the bow away).  The integrator then passes the ship's position.
    patch : tuple of float, optional
        ``(distance, direction, increase)``: shallow water beyond a straight edge ``distance``
        [m] from the origin along ``direction`` [rad, clockwise from north], where the linear
        hull derivatives (Y'_v, Y'_r, N'_v, N'_r, or the beta form's Y'_b, Y'_r - m'_x, N'_b,
        N'_r) are ``1 + increase`` times their deep-water values (a smooth step half a ship
        length wide, :func:`patch_share`); no depth is recorded.  The integrator then passes
        the ship's position.
    conditions : ChannelSeries, optional
        Conditions that vary in time, one row per flight of a batch, SI as the measurement CSV
        names them: ``n`` [rps] replaces the constant revolutions ``n_P``; ``wind_speed`` [m/s]
        and ``wind_dir`` [rad, from] add the wind force
        (:func:`sindyship.conditions.wind_force`).

    Notes
    -----
    With numba installed (``pip install "sindyship[fast]"``), :meth:`accelerations` and
    :meth:`switching` of the plain model -- no ``extra_forces``, no ``conditions``, no
    ``bank`` or ``patch`` -- run a compiled copy of eq. 1-11
    (:mod:`sindyship._mmg_compiled`): both hull forms, speed references, Coriolis forms and
    wake models, ``rudder_offset``, ``stall``, ``current`` and a given or free ``branch``, on
    float64 (or integer) numbers and numpy arrays.  It agrees with the numpy functions of
    this module to rounding (``tests/test_mmg_compiled.py``).  Other models and inputs
    (pandas, sympy, float32), and every model built while the environment variable
    ``SINDYSHIP_NO_COMPILE`` is ``1``, run the numpy functions.  numba is imported at the
    first compiled call, which also loads the machine code from numba's cache or, once per
    installation, compiles it.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> model = MMGModel(load_ship("kcs"))
    >>> acc = model.accelerations(12.348, 0.0, 0.0, 0.0, 0.0)
    >>> [round(float(a), 7) for a in acc]  # thrust slightly exceeds resistance at u' = 1
    [1.4e-05, 0.0, 0.0]
    """

    ship: Ship
    extra_forces: tuple = ()
    rudder_offset: float = 0.0
    current: tuple[float, float] = (0.0, 0.0)
    conditions: ChannelSeries | None = None
    stall: float | None = None
    bank: tuple[float, float] | None = None
    patch: tuple[float, float, float] | None = None

    def __post_init__(self):
        if isinstance(self.ship, str | os.PathLike):  # a built-in name or a ship file
            object.__setattr__(self, "ship", load_ship(self.ship))
        if not isinstance(self.ship, Ship):
            raise TypeError(f"ship must be a Ship, a built-in ship name such as 'kcs' or a ship "
                            f"TOML file, not {type(self.ship).__name__}.")
        ship = self.ship
        if not ship.has_mmg:
            raise SindyshipInputError(
                f"ship {ship.name!r} has no MMG hull, propeller and rudder coefficients: it can "
                "be identified and an identified model flown, but not simulated; add the "
                "[hull], [propeller] and [rudder] sections (see sindyship/ships/kcs.toml)."
            )
        scale = np.array([[1.0], [1.0], [1.0 / ship.L]]) * ship.U0**2 / ship.L
        object.__setattr__(self, "_scaled_inverse_mass",
                           scale * np.linalg.inv(mass_matrix(ship)))
        # the compiled accelerations (see Notes): their parameter vector, made at the first call
        plain = (not self.extra_forces and self.conditions is None and self.bank is None
                 and self.patch is None)
        refused = os.environ.get("SINDYSHIP_NO_COMPILE") == "1"
        object.__setattr__(self, "_compile", plain and not refused)
        object.__setattr__(self, "_compiled_parameters", None)

    def switching(self, state: np.ndarray) -> np.ndarray:
        """beta_R at SI states (7, k): the sign selects gamma_R (see :func:`force_components`);
        compiled for the plain model where numba is installed, as :meth:`accelerations`."""
        if self._compile and (code := self._compiled_code()) is not None:
            beta_R = code[0].switching(code[1], state)
            if beta_R is not None:
                return beta_R
        ship = self.ship
        return rudder_inflow_angle(ship, state[0] / ship.U0, state[1] / ship.U0,
                                   state[2] * ship.L / ship.U0)

    @property
    def uses_position(self) -> bool:
        """Whether the forces depend on the ship's position (a bank, a shallow patch)."""
        return self.bank is not None or self.patch is not None

    @property
    def time_varying(self) -> bool:
        """Whether conditions vary in the flight (the integrator then passes the time)."""
        return self.conditions is not None

    def forces(self, u, v, r, delta, psi, branch=None, now=None, position=None
               ) -> dict[str, tuple]:
        """Force breakdown (Prime II) at SI state values; ``"effects"`` holds extra forces.

        ``now`` holds the conditions at this time (:attr:`conditions`), SI arrays by name;
        ``position`` the ship's (x, y) [m] for a bank or a shallow patch."""
        ship = self.ship
        U0 = ship.U0
        now = now or {}
        un, vn, rn = u / U0, v / U0, r * ship.L / U0
        parts = force_components(ship, un, vn, rn, delta - self.rudder_offset, starboard=branch,
                                 n=now.get("n"), stall=self.stall)
        extra = list(self.extra_forces)
        if self.bank is not None and position is not None:
            y_east = position[1]
            extra.append(lambda u_, v_, r_, d_, psi_: _bank_force(ship, self.bank, y_east, psi_))
        if self.patch is not None and position is not None:
            increase = self.patch[2] * patch_share(ship, self.patch, position[0], position[1])
            extra.append(lambda u_, v_, r_, d_, psi_: _patch_force(ship, increase, u_, v_, r_))
        if "wind_speed" in now:
            speed, come_from = now["wind_speed"], now["wind_dir"]
            extra.append(lambda u_, v_, r_, d_, psi_: wind_force(ship, u_, v_, psi_, speed,
                                                                 come_from))
        if extra:
            X = Y = N = 0.0 * un
            for force in extra:
                dX, dY, dN = force(un, vn, rn, delta - self.rudder_offset, psi)
                X, Y, N = X + dX, Y + dY, N + dN
            parts["effects"] = (X, Y, N)
        return parts

    def accelerations(self, u, v, r, delta, psi, branch=None, t=None, members=None,
                      position=None):
        """Accelerations (du/dt [m/s^2], dv/dt [m/s^2], dr/dt [rad/s^2]) at SI state values;
        with :attr:`conditions`, those at time ``t`` of the flights ``members``; with a bank,
        at the ``position`` (x, y) [m].  The plain model runs compiled code where numba is
        installed (see Notes of :class:`MMGModel`); the lines below are the reference."""
        if self._compile and (code := self._compiled_code()) is not None:
            acc = code[0].accelerations(code[1], u, v, r, delta, branch)
            if acc is not None:
                return acc
        now = self.conditions.at(t, members) if self.conditions is not None else None
        parts = self.forces(u, v, r, delta, psi, branch=branch, now=now, position=position)
        X = Y = N = 0.0
        for pX, pY, pN in parts.values():
            X = X + pX
            Y = Y + pY
            N = N + pN
        # M^-1 (paper eq. 1) and the Prime II -> SI scaling folded into one matrix
        S = self._scaled_inverse_mass
        return S[0, 0] * X, S[1, 1] * Y + S[1, 2] * N, S[2, 1] * Y + S[2, 2] * N

    def _compiled_code(self):
        """``(sindyship._mmg_compiled, this model's parameter vector)``, or None where numba
        cannot be imported."""
        compiled = _compiled_module()
        if compiled is None:
            return None
        p = self._compiled_parameters
        if p is None:
            p = compiled.parameters(self.ship, self._scaled_inverse_mass, self.rudder_offset,
                                    self.stall)
            object.__setattr__(self, "_compiled_parameters", p)
        return compiled, p


@functools.cache
def _compiled_module():
    """:mod:`sindyship._mmg_compiled` if numba can be imported, else None; imported at the
    first compiled call, not with sindyship (numba takes longer to import than sindyship)."""
    from . import _mmg_compiled

    return _mmg_compiled if _mmg_compiled.COMPILED else None

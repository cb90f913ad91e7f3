"""Ship particulars as frozen, typed groups (paper Tables 1-6)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

BUILTIN_SHIPS = ("kcs", "kvlcc2")


@dataclass(frozen=True)
class Particulars:
    """Main dimensions.

    Attributes
    ----------
    L : float
        Length between perpendiculars [m].
    B, d : float
        Breadth and draught [m].
    displacement : float
        Displaced volume [m^3].
    rho : float
        Water density [kg/m^3].
    U0 : float
        Design (approach) speed [m/s]; the reference speed of both prime systems.
    x_G : float
        Longitudinal centre of gravity from midship, positive forward [m].
    scale : float
        Model scale of measurements that belong to this ship (1 for a full-scale ship).
    """

    L: float
    B: float
    d: float
    displacement: float
    rho: float
    U0: float
    x_G: float
    scale: float = 1.0


@dataclass(frozen=True)
class MassProperties:
    """Mass, inertia about midship and added masses, Prime II (paper Table 2).

    Attributes
    ----------
    m, I_zz : float
        Mass / (0.5 rho L^2 d) and yaw inertia about midship / (0.5 rho L^4 d).
    m_x, m_y, J_zz : float
        Surge and sway added mass and added yaw inertia, same units.
    """

    m: float
    I_zz: float
    m_x: float
    m_y: float
    J_zz: float


@dataclass(frozen=True)
class Propeller:
    """Propeller (paper eq. 4-6, Table 4).

    Attributes
    ----------
    t_P : float
        Thrust deduction factor.
    D_P : float
        Diameter [m].
    n_P : float
        Revolutions [rps], constant in a manoeuvre.
    w_P0 : float
        Effective wake fraction in straight motion.
    x_P : float
        Longitudinal position x/L (where a propeller side force acts).
    wake_model : str
        ``"constant"`` (w = w_P0) or ``"drift"`` (w = w_P0 exp(-4 beta_P^2) with
        beta_P = beta - x'_P r').
    K_T : tuple of float
        Open-water thrust coefficient K_T = a0 + a1 J + a2 J^2 (eq. 5).
    """

    t_P: float
    D_P: float
    n_P: float
    w_P0: float
    x_P: float
    wake_model: str
    K_T: tuple[float, float, float]


@dataclass(frozen=True)
class Rudder:
    """Rudder (paper eq. 7-10, Table 5).

    Attributes
    ----------
    A_R : float
        Movable rudder area [m^2].
    t_R, a_H : float
        Steering resistance deduction factor and rudder-to-hull interaction factor.
    x_H, x_R, l_R : float
        Positions x/L of the hull-induced lateral force and of the rudder, and the flow
        straightening correction for yaw rate.
    gamma_R_stbd, gamma_R_port : float
        Flow straightening factor for beta_R > 0 (turning to starboard) and otherwise.
    kappa, epsilon, eta : float
        Propeller-race factor, wake ratio (1 - w_R) / (1 - w_P), and D_P / H_R.
    f_alpha : float
        Rudder lift gradient (from the aspect ratio lambda as 6.13 lambda / (2.25 + lambda), eq. 9,
        when the file gives ``lambda``).
    """

    A_R: float
    t_R: float
    a_H: float
    x_H: float
    x_R: float
    l_R: float
    gamma_R_stbd: float
    gamma_R_port: float
    kappa: float
    epsilon: float
    eta: float
    f_alpha: float

    @property
    def gamma_R_mean(self) -> float:
        """Mean of the two flow straightening factors (the Taylor expansion point)."""
        return 0.5 * (self.gamma_R_stbd + self.gamma_R_port)


@dataclass(frozen=True)
class Servo:
    """Rudder servo (paper eq. 12-13).

    Attributes
    ----------
    T_R : float
        Time constant in units of L / U0 (the paper's T'_R).
    rate_max : float
        Rudder rate limit [deg/s] at this ship's scale.
    delta_max : float
        Largest rudder angle [deg].
    """

    T_R: float
    rate_max: float
    delta_max: float


@dataclass(frozen=True)
class Ship:
    """A ship for the MMG simulator and for identification.

    Attributes
    ----------
    name, title : str
        Identifier and a one-line description.
    hull_form : str
        ``"beta"`` (hull forces in drift angle beta, paper eq. 3) or ``"standard"`` (in v', r',
        Yasukawa & Yoshimura 2015).
    speed_reference : str
        ``"design"``: forces scale with the constant U0 (the paper's KCS); ``"instantaneous"``:
        with U = sqrt(u^2 + v^2) (Yasukawa & Yoshimura).
    coriolis : str
        ``"rigid-body"`` (paper eq. 11; added-mass terms inside the hull coefficients) or
        ``"with-added-mass"``.
    hull : dict
        Hull coefficients by name, Prime II (empty for a ship file made for identification
        only, which has no propeller and rudder either: :attr:`has_mmg`).
    abkowitz : dict
        Prime I acceleration derivatives X_udot, Y_vdot, Y_rdot, N_vdot, N_rdot used by the
        identification (paper Table 6); derived from the Prime II added masses when absent.
    assumptions : tuple of str
        What a ship file made for identification left out and sindyship assumed (added
        masses, servo), one sentence each; empty for a complete file.  Not part of the
        ship's identity: a saved model keeps the values, not the assumptions.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> ship = load_ship("kcs")
    >>> round(ship.time_scale, 2)
    18.63
    """

    name: str
    title: str
    hull_form: str
    speed_reference: str
    coriolis: str
    particulars: Particulars
    mass: MassProperties
    hull: dict[str, float]
    propeller: Propeller | None
    rudder: Rudder | None
    servo: Servo
    abkowitz: dict[str, float]
    assumptions: tuple[str, ...] = field(default=(), compare=False)

    @property
    def has_mmg(self) -> bool:
        """Whether the ship carries the MMG hull, propeller and rudder coefficients (needed to
        simulate it with :class:`sindyship.mmg.MMGModel`, not to identify or fly a model)."""
        return self.propeller is not None and self.rudder is not None and bool(self.hull)

    @property
    def L(self) -> float:
        return self.particulars.L

    @property
    def U0(self) -> float:
        return self.particulars.U0

    @property
    def time_scale(self) -> float:
        """L / U0 [s]: one unit of non-dimensional time."""
        return self.particulars.L / self.particulars.U0

    @property
    def x_G_nd(self) -> float:
        """x_G / L."""
        return self.particulars.x_G / self.particulars.L

    @property
    def d_over_L(self) -> float:
        return self.particulars.d / self.particulars.L

    def prime_i_inertia(self) -> dict[str, float]:
        """Mass, inertia and acceleration derivatives in Prime I (paper eq. 14, Table 6).

        Returns
        -------
        dict
            ``m``, ``x_G``, ``I_zz``, ``X_udot``, ``Y_vdot``, ``Y_rdot``, ``N_vdot``, ``N_rdot``.

        Examples
        --------
        >>> from sindyship.ships import load_ship
        >>> inertia = load_ship("kcs").prime_i_inertia()
        >>> round(inertia["m"] * 1e5, 1), inertia["Y_vdot"] * 1e5
        (855.9, -732.0)
        """
        k = self.d_over_L
        out = {"m": self.mass.m * k, "x_G": self.x_G_nd, "I_zz": self.mass.I_zz * k}
        derived = {
            "X_udot": -self.mass.m_x * k,
            "Y_vdot": -self.mass.m_y * k,
            "Y_rdot": 0.0,
            "N_vdot": 0.0,
            "N_rdot": -self.mass.J_zz * k,
        }
        derived.update(self.abkowitz)
        out.update(derived)
        return out

    def with_servo(self, **changes: float) -> Ship:
        """A copy with servo settings changed (e.g. ``T_R=0.1`` to make the rate limit bind)."""
        return replace(self, servo=replace(self.servo, **changes))

    def with_rudder(self, **changes: float) -> Ship:
        """A copy with rudder settings changed (e.g. a symmetric ``gamma_R_port``)."""
        return replace(self, rudder=replace(self.rudder, **changes))

    def scaled(self, scale: float) -> Ship:
        """The same ship Froude-scaled by ``scale`` (lengths x scale, speeds x sqrt(scale)).

        Non-dimensional coefficients are unchanged; the rudder area scales by scale^2, and
        revolutions and the rudder rate limit by 1 / sqrt(scale), so the scaled ship flies the
        same manoeuvres in ship lengths and L / U0.
        """
        p = self.particulars
        s = float(scale)
        particulars = replace(
            p,
            L=p.L * s,
            B=p.B * s,
            d=p.d * s,
            displacement=p.displacement * s**3,
            U0=p.U0 * math.sqrt(s),
            x_G=p.x_G * s,
            scale=p.scale / s,
        )
        propeller = None if self.propeller is None else replace(
            self.propeller, D_P=self.propeller.D_P * s, n_P=self.propeller.n_P / math.sqrt(s))
        rudder = None if self.rudder is None else replace(self.rudder,
                                                          A_R=self.rudder.A_R * s**2)
        servo = replace(self.servo, rate_max=self.servo.rate_max / math.sqrt(s))
        return replace(self, name=f"{self.name}-x{s:g}",
                       title=f"{self.title}, Froude-scaled by {s:g}", particulars=particulars,
                       propeller=propeller, rudder=rudder, servo=servo)

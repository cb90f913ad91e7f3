"""Ship particulars as data: built-in ships by name, a user's own ship from a TOML file.

A ship is a frozen, typed :class:`Ship` made of small frozen groups (particulars, mass,
propeller, rudder, servo).  The built-in ``kcs`` holds the paper's Tables 1-6 with the choices
of the reproduction protocol; ``kvlcc2`` holds the L7 model of Yasukawa & Yoshimura (2015).
A user's ship is a TOML file with the same fields (copy ``sindyship/ships/kcs.toml``).

Non-dimensional conventions
---------------------------
* Prime II (MMG, paper section 2.1): forces / (0.5 rho L d U0^2), moments / (0.5 rho L^2 d U0^2),
  mass / (0.5 rho L^2 d), inertia / (0.5 rho L^4 d).
* Prime I (Abkowitz, paper section 2.2): forces / (0.5 rho L^2 U0^2), moments /
  (0.5 rho L^3 U0^2), mass / (0.5 rho L^3), inertia / (0.5 rho L^5).  A Prime II mass converts
  to Prime I by the factor d / L.
"""

from __future__ import annotations

from ._groups import BUILTIN_SHIPS, MassProperties, Particulars, Propeller, Rudder, Servo, Ship
from ._reading import (
    DEFAULT_SERVO,
    HULL_COEFFICIENTS,
    clarke_added_masses,
    load_ship,
    ship_digest,
    ship_from_dict,
    ship_to_dict,
    ship_to_toml,
)

__all__ = [
    "BUILTIN_SHIPS",
    "DEFAULT_SERVO",
    "HULL_COEFFICIENTS",
    "MassProperties",
    "Particulars",
    "Propeller",
    "Rudder",
    "Servo",
    "Ship",
    "clarke_added_masses",
    "load_ship",
    "ship_digest",
    "ship_from_dict",
    "ship_to_dict",
    "ship_to_toml",
]

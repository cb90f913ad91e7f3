"""Straight-run stability of an identified model: the linearised sway-yaw system of eq. 14.

About the straight run (u' = 1, v' = r' = delta = 0) the sway and yaw equations of paper
eq. 14 linearise to ``d/dt' [v', r'] = A [v', r']`` with ``A = M^-1 (F + C)``: ``M`` the
sway-yaw block of the mass matrix, ``F`` the fitted force derivatives (Y'_v, Y'_r, N'_v, N'_r)
and ``C`` the linearised Coriolis and Munk terms.  The model is straight-line stable when both
eigenvalues of ``A`` have negative real parts; a positive eigenvalue lambda makes any
disturbance grow as exp(lambda t U0 / L), which is why a flight of such a model diverges.

The Jacobian is taken by central differences of the model's own accelerations
(:meth:`sindyship.model.AbkowitzDynamics.accelerations`), so every term of any library enters,
not only the linear ones.

Examples
--------
>>> from sindyship.ships import load_ship
>>> from sindyship.model import paper_model
>>> result = straight_run_stability(paper_model(load_ship("kcs")))
>>> result.stable, len(result.eigenvalues)
(True, 2)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Stability", "straight_run_stability"]

#: Perturbation of v' and r' for the central differences.
_STEP = 1e-6


@dataclass(frozen=True)
class Stability:
    """Straight-run stability of a model.

    Attributes
    ----------
    eigenvalues : tuple of complex
        Of the linearised sway-yaw system, per unit of non-dimensional time t U0 / L.
    jacobian : ndarray, shape (2, 2)
        d(v'_dot, r'_dot) / d(v', r') at the straight run.
    stable : bool
        Both eigenvalues have negative real parts.
    doubling_time_L_over_U : float or None
        For an unstable model, the time a disturbance takes to double, in units of L/U0.
    """

    eigenvalues: tuple
    jacobian: np.ndarray
    stable: bool
    doubling_time_L_over_U: float | None

    def to_json(self) -> dict:
        return {
            "eigenvalues": [[float(z.real), float(z.imag)] for z in self.eigenvalues],
            "stable": self.stable,
            "doubling_time_L_over_U": self.doubling_time_L_over_U,
        }


def straight_run_stability(model) -> Stability:
    """Eigenvalues of the model's sway-yaw system linearised about the straight run.

    The recorded channels the library uses are held at zero (the heading at 0; a calm: the
    apparent wind is the ship's own headwind).

    Parameters
    ----------
    model : sindyship.model.AbkowitzModel

    Returns
    -------
    Stability
    """
    from .model import AbkowitzDynamics

    ship = model.ship
    U0, L = ship.U0, ship.L
    channels = {name: 0.0 for name in model.recorded_channels}
    dynamics = AbkowitzDynamics(model, channels)

    def sway_yaw(v_nd: float, r_nd: float) -> np.ndarray:
        _, a_v, a_r = dynamics.accelerations(U0, v_nd * U0, r_nd * U0 / L, 0.0, 0.0)
        return np.array([a_v * L / U0**2, a_r * L**2 / U0**2])

    jacobian = np.column_stack([
        (sway_yaw(_STEP, 0.0) - sway_yaw(-_STEP, 0.0)) / (2 * _STEP),
        (sway_yaw(0.0, _STEP) - sway_yaw(0.0, -_STEP)) / (2 * _STEP),
    ])
    eigenvalues = tuple(complex(z) for z in np.linalg.eigvals(jacobian))
    largest = max(z.real for z in eigenvalues)
    stable = bool(largest < 0.0)
    doubling = None if stable else float(np.log(2.0) / largest) if largest > 0 else None
    return Stability(eigenvalues, jacobian, stable, doubling)

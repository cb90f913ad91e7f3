"""Force residuals (paper eq. 16 minus eq. 15) by time, phase and binned state."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..identify import Design, design
from ..library import (
    DOFS,
)
from ..model import AbkowitzModel
from ..optimizers import one_blas_thread
from ..ships import Ship
from ..trajectory import Trajectory
from .phases import manoeuvre_phases


@dataclass(frozen=True)
class StateBins:
    """How one state variable is binned for the residual plots and the effects' regimes.

    Attributes
    ----------
    name : str
        Short name for text (``"yaw rate r'"``).
    label : str
        Axis label with unit.
    edges : tuple of float
        Inner bin edges; values below the first or above the last fall into open end bins.
    unit : str
        Unit for the regime text.
    """

    name: str
    label: str
    edges: tuple[float, ...]
    unit: str


#: The state variables the residuals are binned over.  Drift angle beta = atan2(-v, u) and
#: rudder angle in degrees, yaw rate r' = r L / U0, heading psi modulo 360 degrees.
STATE_BINS: dict[str, StateBins] = {
    "drift_angle": StateBins(
        "drift angle",
        "drift angle beta [deg]",
        (-15.0, -8.0, -4.0, -1.5, 1.5, 4.0, 8.0, 15.0),
        "deg",
    ),
    "yaw_rate": StateBins(
        "yaw rate r'",
        "yaw rate r' = r L / U0 [-]",
        (-0.6, -0.35, -0.15, -0.03, 0.03, 0.15, 0.35, 0.6),
        "",
    ),
    "rudder_angle": StateBins(
        "rudder angle",
        "rudder angle delta [deg]",
        (-25.0, -15.0, -7.5, -1.0, 1.0, 7.5, 15.0, 25.0),
        "deg",
    ),
    "heading": StateBins(
        "heading",
        "heading psi (0-360) [deg]",
        (45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0),
        "deg",
    ),
}


def _bin_labels(bins: StateBins, variable: str) -> list[str]:
    edges = bins.edges
    fmt = "{:g}"
    if variable == "heading":
        cuts = (0.0, *edges, 360.0)
        return [
            f"{fmt.format(a)}-{fmt.format(b)}" for a, b in zip(cuts[:-1], cuts[1:], strict=True)
        ]
    inner = [
        f"{fmt.format(a)} to {fmt.format(b)}" for a, b in zip(edges[:-1], edges[1:], strict=True)
    ]
    return [f"< {fmt.format(edges[0])}", *inner, f"> {fmt.format(edges[-1])}"]


def _bin_index(values: np.ndarray, bins: StateBins) -> np.ndarray:
    return np.digitize(values, bins.edges)


@dataclass(frozen=True)
class Residuals:
    """Force residuals of a model on records: measured (eq. 16) minus model (eq. 15).

    Attributes
    ----------
    names : tuple of str
        The records, in order.
    groups : ndarray of int, shape (n_samples,)
        Index into ``names`` of each sample.
    t : ndarray, shape (n_samples,)
        Record time of each sample [s].
    measured, residual : dict of str to ndarray
        Per degree of freedom (``X``, ``Y``, ``N``): the measured force and the residual,
        Prime I.
    state : dict of str to ndarray
        The binned state variables (keys of :data:`STATE_BINS`).
    phases : tuple of tuple of Phase
        :func:`manoeuvre_phases` of each record.
    """

    names: tuple[str, ...]
    groups: np.ndarray = field(repr=False)
    t: np.ndarray = field(repr=False)
    measured: dict = field(repr=False)
    residual: dict = field(repr=False)
    state: dict = field(repr=False)
    phases: tuple = field(repr=False)

    @property
    def bins(self) -> dict[str, StateBins]:
        """How each state variable is binned (:data:`STATE_BINS`)."""
        return STATE_BINS

    def record(self, name: str) -> pd.DataFrame:
        """One record's residuals and state over time, a row per sample."""
        if name not in self.names:
            raise KeyError(f"no record named {name!r}; the records are {', '.join(self.names)}")
        mask = self.groups == self.names.index(name)
        columns = {"t": self.t[mask]}
        for dof in DOFS:
            columns[f"measured_{dof}"] = self.measured[dof][mask]
            columns[f"residual_{dof}"] = self.residual[dof][mask]
        for variable, values in self.state.items():
            columns[variable] = values[mask]
        return pd.DataFrame(columns)

    def binned(self, variable: str) -> pd.DataFrame:
        """Residual statistics per bin of a state variable, per degree of freedom.

        Returns
        -------
        pandas.DataFrame
            Columns ``dof``, ``bin`` (label), ``count``, ``mean``, ``std``, ``rms`` of the
            residual (Prime I); empty bins are left out.
        """
        bins = STATE_BINS[variable]
        index = _bin_index(self.state[variable], bins)
        labels = _bin_labels(bins, variable)
        rows = []
        for dof in DOFS:
            values = self.residual[dof]
            for b, label in enumerate(labels):
                part = values[index == b]
                if part.size == 0:
                    continue
                rows.append(
                    {
                        "dof": dof,
                        "bin": label,
                        "count": int(part.size),
                        "mean": float(part.mean()),
                        "std": float(part.std()),
                        "rms": float(np.sqrt(np.mean(part**2))),
                    }
                )
        return pd.DataFrame(rows, columns=["dof", "bin", "count", "mean", "std", "rms"])

    def summary(self) -> dict[str, dict[str, float]]:
        """Per degree of freedom: RMS residual and its ratio to the RMS measured force."""
        out = {}
        for dof in DOFS:
            rms = float(np.sqrt(np.mean(self.residual[dof] ** 2)))
            scale = float(np.sqrt(np.mean(self.measured[dof] ** 2)))
            out[dof] = {"rms": rms, "relative": rms / scale if scale > 0 else math.nan}
        return out

    def worst_bins(self) -> dict[str, str]:
        """Per degree of freedom, the bin (over all state variables) of the largest RMS."""
        out = {}
        for dof in DOFS:
            best = (-1.0, "")
            for variable, bins in STATE_BINS.items():
                table = self.binned(variable)
                table = table[(table["dof"] == dof) & (table["count"] >= 0.02 * len(self.t))]
                if table.empty:
                    continue
                row = table.loc[table["rms"].idxmax()]
                if row["rms"] > best[0]:
                    best = (float(row["rms"]), f"{bins.name} {row['bin']} {bins.unit}".strip())
            out[dof] = best[1]
        return out


def _state_values(
    records: Sequence[Trajectory], ship: Ship, rudders: Sequence[np.ndarray]
) -> dict[str, np.ndarray]:
    u = np.concatenate([r["u"] for r in records])
    v = np.concatenate([r["v"] for r in records])
    r_rate = np.concatenate([r["r"] for r in records])
    psi = np.concatenate([r["psi"] for r in records])
    return {
        "drift_angle": np.degrees(np.arctan2(-v, u)),
        "yaw_rate": r_rate * ship.time_scale,
        "rudder_angle": np.degrees(np.concatenate(rudders)),
        "heading": np.mod(np.degrees(psi), 360.0),
    }


def _rudders(records: Sequence[Trajectory], rudder_signal: str) -> list[np.ndarray]:
    if rudder_signal == "commanded":
        return [r["delta_c"] if r.has("delta_c") else r.rudder for r in records]
    return [r.rudder for r in records]


def _residuals(
    problems: Mapping[str, Design],
    coefficients: Mapping[str, np.ndarray],
    records: Sequence[Trajectory],
    ship: Ship,
    rudder_signal: str,
) -> Residuals:
    measured = {dof: problems[dof].target for dof in DOFS}
    residual = {
        dof: problems[dof].target - problems[dof].features @ coefficients[dof] for dof in DOFS
    }
    return Residuals(
        names=tuple(r.name for r in records),
        groups=problems["X"].groups,
        t=np.concatenate([r.t for r in records]),
        measured=measured,
        residual=residual,
        state=_state_values(records, ship, _rudders(records, rudder_signal)),
        phases=tuple(manoeuvre_phases(r, ship) for r in records),
    )


@one_blas_thread
def force_residuals(
    model: AbkowitzModel,
    records: Sequence[Trajectory],
    *,
    derivative: str = "five-point",
    window: float = 21.0,
) -> Residuals:
    """Measured minus model force per equation, with phases and binned state.

    Parameters
    ----------
    model : AbkowitzModel
    records : sequence of Trajectory
    derivative, window
        How the measured forces are made (:func:`sindyship.identify.design`).

    Returns
    -------
    Residuals

    Examples
    --------
    >>> from sindyship import load_ship, paper_model, Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> model = paper_model(ship)
    >>> runs = fly(model.dynamics(), [Manoeuvre("zigzag", rudder=20, check=20, duration=500)])
    >>> summary = force_residuals(model, runs).summary()
    >>> bool(summary["N"]["relative"] < 1e-3)  # only the finite-difference error is left
    True
    """
    problems = design(
        records,
        model.ship,
        model.library,
        rudder_signal=model.rudder_signal,
        derivative=derivative,
        window=window,
    )
    coefficients = {dof: model.coefficient_vector(dof) for dof in DOFS}
    return _residuals(problems, coefficients, records, model.ship, model.rudder_signal)


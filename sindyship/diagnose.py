"""Where an identified model fails, and which physical effect is missing.

The questions a user asks after :func:`sindyship.identify.fit`, in order:

Compare
    :func:`compare` flies the identified model the way each record was flown (zig-zags
    closed loop, :func:`sindyship.evaluation.fly_like`) and summarises the error per
    manoeuvre: mean and maximum distance in ship lengths, RMS heading and speed error, and
    the time a flight diverged, if it did.
Where it fails
    :func:`force_residuals` gives the force residual of each equation, the measured force
    of paper eq. 16 minus the model's eq. 15, over time with the manoeuvre phases
    (:func:`manoeuvre_phases`: rudder steps and reversals, steady turns) and binned over
    drift angle, yaw rate, rudder angle and heading (:data:`STATE_BINS`).
Which effect is missing
    :func:`diagnose` scores every effect of the catalogue (``libraries/effects/*.toml``) by
    leave-one-manoeuvre-out cross-validation: for each training record in turn, the library
    alone and the library plus the effect's terms are fitted (least squares) on the other
    records and predict the held-out record's forces.  With SSE the summed squared error of
    those predictions, ``explained = mean over X, Y, N of clip(1 - SSE_with / SSE_without, 0,
    1)``: the share of the remaining force error that the effect's terms explain on
    manoeuvres they were not fitted on.  Both sides are refitted, so that the effect is not
    credited with error the library's own terms absorb once refitted.  The best candidates are
    then confirmed by refitting the library with them and re-flying the manoeuvres.  Effects
    whose channels the data lack are listed as not testable, with the channels to record.
Add it and watch the error fall
    :func:`before_after` refits with added effects and tabulates the error on every
    manoeuvre, training and held-out, before and after; :func:`diagnose_iteratively` repeats
    diagnosis and addition until no effect explains a meaningful share
    (:data:`MEANINGFUL_SHARE`).

A share is *meaningful* from 5 % (:data:`MEANINGFUL_SHARE`).  The reason is measured, not
assumed (``benchmarks/bench_diagnose.py``): on data made by an Abkowitz model itself every
catalogued effect explains 0.0 %; on the symmetric KCS without a hidden effect the effects
that are physically absent there (asymmetry, environment) explain at most 1.0 %; over a grid
of 41 hidden loads, currents, propeller side forces and rudder offsets the expected effect
explained 26 % to 94 %.  5 % is five times the false-alarm level and five times below the
weakest hidden effect.  A candidate is *confirmed* when refitting with it and re-flying the
training manoeuvres cuts their mean distance by at least 10 % (geometric mean over the
manoeuvres, :data:`CONFIRMING_RATIO`) without a new divergence.

The command ``sindyship diagnose`` is :func:`add_diagnose_parser` and :func:`cmd_diagnose`.

Examples
--------
>>> from sindyship.ships import load_ship
>>> from sindyship.mmg import MMGModel
>>> from sindyship.manoeuvres import Manoeuvre, fly
>>> ship = load_ship("kcs")
>>> runs = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=r, duration=400)
...                             for r in (35, -35, 20)])
>>> result = diagnose(runs, ship, effects=["asymmetry", "wind"], fly_training=False)
>>> result.ranking[0].effect.name, [n.effect.name for n in result.not_testable]
('asymmetry', ['wind'])
>>> 0.0 <= result.ranking[0].explained <= 1.0
True
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
import tempfile
import textwrap
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import scipy.linalg

from .errors import SindyshipInputError
from .evaluation import error_summary, fly_like, fly_like_batch
from .identify import Design, design, resolve_library
from .library import (
    DOFS,
    Effect,
    TermLibrary,
    available_effects,
    load_effect,
    nondimensional_variables,
)
from .model import AbkowitzDynamics, AbkowitzModel, write_text_atomic
from .optimizers import _one_blas_thread
from .ships import Ship
from .terms import Term, describe_variable
from .trajectory import Trajectory

__all__ = [
    "CONFIRMING_RATIO",
    "MEANINGFUL_SHARE",
    "STATE_BINS",
    "BeforeAfter",
    "Diagnosis",
    "EffectScore",
    "IterativeDiagnosis",
    "ManoeuvreComparison",
    "NotTestable",
    "Phase",
    "Residuals",
    "Round",
    "StateBins",
    "add_diagnose_parser",
    "before_after",
    "cmd_diagnose",
    "compare",
    "diagnose",
    "diagnose_iteratively",
    "fly_model",
    "force_residuals",
    "manoeuvre_phases",
]

#: Smallest share of the cross-validated force error an effect must explain to matter (see
#: the module docstring for why 5 %).
MEANINGFUL_SHARE = 0.05
#: Largest after/before ratio of the training flights' mean distance (geometric mean over the
#: manoeuvres) that confirms an effect: a 10 % gain, above the few per cent by which any
#: extra term moves a flight.
CONFIRMING_RATIO = 0.9

_DOF_NAMES = {"X": "surge force X", "Y": "sway force Y", "N": "yaw moment N"}
_SETS = ("training", "held-out")


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


# =============================================================================== flights
def _channel_means(model: AbkowitzModel, record: Trajectory) -> dict[str, float]:
    """The record's mean value of each channel the model needs beyond psi (non-dimensional)."""
    channels = sorted(model.library.channels - {"psi"})
    if not channels:
        return {}
    values = nondimensional_variables(record, model.ship.L, model.ship.U0, needed=channels)
    return {name: float(np.mean(values[name])) for name in channels}


def fly_model(model: AbkowitzModel, records: Sequence[Trajectory]) -> list[Trajectory]:
    """Fly an identified model the way each record was flown.

    The same flights as ``fly_like_batch(model.dynamics(), records)``
    (:mod:`sindyship.evaluation`): zig-zags closed loop, other records replaying their rudder,
    from each record's first row.  Channels the library uses beyond the heading (``n``,
    ``phi``, ...) are held at their mean over the record, since the flight does not compute
    them.

    Parameters
    ----------
    model : AbkowitzModel
    records : sequence of Trajectory

    Returns
    -------
    list of Trajectory
        In the order of ``records``; ``meta["diverged_at"]`` is the divergence time or None.
    """
    if not model.library.channels - {"psi"}:
        return fly_like_batch(model.dynamics(), records)
    out = []
    for record in records:
        dynamics = AbkowitzDynamics(model, _channel_means(model, record))
        out.extend(fly_like(dynamics, [record]))
    return out


def _model_payload(model: AbkowitzModel) -> dict:
    """What a worker process needs to rebuild a model (a TermLibrary does not pickle)."""
    return {
        "ship": model.ship,
        "library": model.library.to_dict(),
        "coefficients": {dof: dict(model.coefficients[dof]) for dof in DOFS},
        "rudder_signal": model.rudder_signal,
    }


def _fly_payload(payload: dict, records: Sequence[Trajectory]) -> list[Trajectory]:
    model = AbkowitzModel(
        ship=payload["ship"],
        library=TermLibrary.from_dict(payload["library"]),
        coefficients=payload["coefficients"],
        rudder_signal=payload["rudder_signal"],
    )
    return fly_model(model, records)


def _fly_many(
    jobs: Sequence[tuple[AbkowitzModel, Sequence[Trajectory]]],
    *,
    n_jobs: int,
    progress: bool,
    what: str,
) -> list[list[Trajectory]]:
    """Fly several (model, records) jobs, in parallel processes when ``n_jobs`` != 1."""
    from tqdm.auto import tqdm

    jobs = [(model, list(records)) for model, records in jobs if records]
    if not jobs:
        return []
    bar = tqdm(total=len(jobs), desc=what, file=sys.stderr, disable=not progress, leave=False)
    if n_jobs == 1 or len(jobs) == 1:
        out = []
        for model, records in jobs:
            out.append(fly_model(model, records))
            bar.update()
    else:
        from joblib import Parallel, delayed

        results = Parallel(n_jobs=n_jobs, return_as="generator")(
            delayed(_fly_payload)(_model_payload(model), records) for model, records in jobs
        )
        out = []
        for flown in results:
            out.append(flown)
            bar.update()
    bar.close()
    return out


# =============================================================================== compare
@dataclass(frozen=True)
class ManoeuvreComparison:
    """A record beside the model flown the same way, and the error summary.

    Attributes
    ----------
    name : str
        The record.
    set : {"training", "held-out"}
    record, flown : Trajectory
        The measurement and the flight.
    errors : dict
        ``mean_distance_L``, ``max_distance_L`` [ship lengths], ``diverged_at_s`` [s or
        None], ``rms_heading_deg``, ``rms_speed_m_s`` (:func:`sindyship.evaluation.error_summary`).
    """

    name: str
    set: str
    record: Trajectory = field(repr=False)
    flown: Trajectory = field(repr=False)
    errors: dict


def compare(
    model: AbkowitzModel,
    records: Sequence[Trajectory],
    *,
    kind: str = "training",
    flights: Sequence[Trajectory] | None = None,
) -> list[ManoeuvreComparison]:
    """Fly the model like each record and summarise the error per manoeuvre.

    Parameters
    ----------
    model : AbkowitzModel
    records : sequence of Trajectory
    kind : {"training", "held-out"}
        Which set the records belong to (for reports).
    flights : sequence of Trajectory, optional
        The flights, if already flown (:func:`fly_model`).

    Returns
    -------
    list of ManoeuvreComparison

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> from sindyship.model import paper_model
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> model = paper_model(ship)
    >>> (run,) = fly(model.dynamics(), [Manoeuvre("turning-circle", rudder=20, duration=300)])
    >>> (row,) = compare(model, [run])
    >>> row.errors["mean_distance_L"] < 1e-6, row.errors["diverged_at_s"]
    (True, None)
    """
    if kind not in _SETS:
        raise ValueError(f"kind must be one of {_SETS}, not {kind!r}")
    flown = list(flights) if flights is not None else fly_model(model, records)
    return [
        ManoeuvreComparison(rec.name, kind, rec, f, error_summary(f, rec, model.ship.L))
        for rec, f in zip(records, flown, strict=True)
    ]


# =============================================================================== phases
@dataclass(frozen=True)
class Phase:
    """A phase of a manoeuvre: an instant (rudder change) or an interval (steady turn).

    Attributes
    ----------
    kind : {"rudder step", "rudder reversal", "steady turn", "straight run"}
    start, end : float
        Times [s]; equal for an instant.
    label : str
        A short description for people.
    """

    kind: str
    start: float
    end: float
    label: str = ""


def manoeuvre_phases(record: Trajectory, ship: Ship) -> tuple[Phase, ...]:
    """Rudder steps and reversals, steady turns and straight runs of a record.

    Rudder changes come from the commanded rudder when recorded (a change of more than
    0.1 deg between samples; a reversal when the side changes), else from the actual rudder
    (each time it crosses to the other side beyond 1 deg, and the first move of more than
    1 deg).  A steady turn is a stretch of at least 2 L/U0 where |r'| > 0.05 and the yaw
    rate, averaged over 0.25 L/U0, changes by less than 0.005 per unit of L/U0; a straight
    run is a stretch as long with |r'| < 0.01 and the rudder within 1 deg of zero.

    Parameters
    ----------
    record : Trajectory
    ship : Ship
        Gives L and U0.

    Returns
    -------
    tuple of Phase
        In order of start time.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> from sindyship.mmg import MMGModel
    >>> from sindyship.manoeuvres import Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> (zz,) = fly(MMGModel(ship), [Manoeuvre("zigzag", rudder=20, check=20, duration=600)])
    >>> [p.kind for p in manoeuvre_phases(zz, ship)][:3]
    ['rudder step', 'rudder reversal', 'rudder reversal']
    """
    t = record.t
    deg = math.radians(1.0)
    phases: list[Phase] = []
    if record.has("delta_c"):
        cmd = record["delta_c"]
        if abs(cmd[0]) > 0.1 * deg:
            phases.append(
                Phase(
                    "rudder step",
                    float(t[0]),
                    float(t[0]),
                    f"rudder {math.degrees(cmd[0]):.1f} deg from the start",
                )
            )
        for k in np.flatnonzero(np.abs(np.diff(cmd)) > 0.1 * deg) + 1:
            before, after = cmd[k - 1], cmd[k]
            reversal = before * after < 0 and abs(before) > deg and abs(after) > deg
            kind = "rudder reversal" if reversal else "rudder step"
            phases.append(
                Phase(
                    kind,
                    float(t[k]),
                    float(t[k]),
                    f"rudder {math.degrees(before):.1f} -> {math.degrees(after):.1f} deg",
                )
            )
    else:
        delta = record.rudder
        moved = np.flatnonzero(np.abs(delta - delta[0]) > deg)
        if moved.size:
            k = int(moved[0])
            phases.append(Phase("rudder step", float(t[k]), float(t[k]), "rudder execute"))
        side = np.where(delta > deg, 1, np.where(delta < -deg, -1, 0))
        last = 0
        for k in np.flatnonzero(side):
            if last and side[k] != last:
                phases.append(
                    Phase(
                        "rudder reversal",
                        float(t[k]),
                        float(t[k]),
                        f"rudder to {'starboard' if side[k] > 0 else 'port'}",
                    )
                )
            last = side[k]
    scale = ship.time_scale
    r_nd = record["r"] * scale
    dt = record.dt
    width = max(1, int(round(0.25 * scale / dt)))
    smooth = np.convolve(r_nd, np.ones(width) / width, mode="same")
    rate = np.gradient(smooth, t / scale) if len(t) > 1 else np.zeros_like(t)
    rudder = record.rudder
    steady = (np.abs(r_nd) > 0.05) & (np.abs(rate) < 0.005)
    straight = (np.abs(r_nd) < 0.01) & (np.abs(rudder) < deg)
    for mask, kind in ((steady, "steady turn"), (straight, "straight run")):
        for start, stop in _runs(mask):
            if t[stop - 1] - t[start] < 2.0 * scale:
                continue
            label = kind
            if kind == "steady turn":
                mean = float(np.mean(r_nd[start:stop]))
                label = f"steady turn to {'starboard' if mean > 0 else 'port'}, r' = {mean:.2f}"
            phases.append(Phase(kind, float(t[start]), float(t[stop - 1]), label))
    return tuple(sorted(phases, key=lambda p: (p.start, p.end)))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Start and stop (exclusive) indices of the runs of True in ``mask``."""
    padded = np.concatenate([[False], mask, [False]]).astype(int)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


# =============================================================================== residuals
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


@_one_blas_thread
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
    >>> from sindyship.ships import load_ship
    >>> from sindyship.model import paper_model
    >>> from sindyship.manoeuvres import Manoeuvre, fly
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


# =============================================================================== scoring
def _least_squares(features: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Least squares on norm-scaled columns (LAPACK gelsd), as ``make_optimizer("ls")``."""
    scale = np.linalg.norm(features, axis=0)
    scale[~(scale > 0)] = 1.0
    solution = scipy.linalg.lstsq(
        features / scale, target, lapack_driver="gelsd", check_finite=False
    )[0]
    return solution / scale


class _GroupedProblem:
    """One equation's regression problem, compressed per record for fast refits.

    Columns are scaled to unit norm; each record's rows are reduced to their QR factor
    (``X_g = Q_g R_g``, ``Z_g = Q_g^T y_g``), so a least-squares fit of any column subset on
    any subset of records is a solve on the small stacked ``R_g`` and ``Z_g``.
    """

    def __init__(self, features: np.ndarray, target: np.ndarray, groups: np.ndarray) -> None:
        scale = np.linalg.norm(features, axis=0)
        scale[~(scale > 0)] = 1.0
        self.scale = scale
        self.x = features / scale
        self.y = target
        self.members = [np.flatnonzero(groups == g) for g in np.unique(groups)]
        self.r, self.z = [], []
        for rows in self.members:
            q, r = np.linalg.qr(self.x[rows])
            self.r.append(r)
            self.z.append(q.T @ target[rows])

    def solve(self, columns: np.ndarray, leave_out: int | None = None) -> np.ndarray:
        """Scaled coefficients of ``columns`` fitted on all records but ``leave_out``."""
        keep = [g for g in range(len(self.members)) if g != leave_out]
        a = np.vstack([self.r[g][:, columns] for g in keep])
        b = np.concatenate([self.z[g] for g in keep])
        return scipy.linalg.lstsq(a, b, lapack_driver="gelsd", check_finite=False)[0]

    def lomo_errors(self, columns: np.ndarray) -> np.ndarray:
        """Leave-one-record-out prediction errors of a fit on ``columns``, per sample."""
        errors = self.y.copy()
        if len(columns) == 0:
            return errors
        for g, rows in enumerate(self.members):
            w = self.solve(columns, leave_out=g)
            errors[rows] = self.y[rows] - self.x[np.ix_(rows, columns)] @ w
        return errors


@dataclass(frozen=True)
class NotTestable:
    """An effect the data cannot test, and the channels to record.

    Attributes
    ----------
    effect : Effect
    needs : tuple of str
        Channels absent from some record, or with one value throughout all of them.
    reason : str
    """

    effect: Effect
    needs: tuple[str, ...]
    reason: str

    def to_json(self) -> dict:
        return {
            "effect": self.effect.name,
            "title": self.effect.title,
            "needs": list(self.needs),
            "reason": self.reason,
        }


def _untestable(effect: Effect, records: Sequence[Trajectory]) -> NotTestable | None:
    """Why the data cannot test ``effect``, or None if they can.

    A channel is missing when some record lacks it, and carries no information when it has
    one value throughout all the records (a channel constant within each record but
    different between records, such as the depth of runs in two waters, is testable).
    """
    needs, reasons = [], []
    for channel in effect.channels:
        variable = describe_variable(channel)
        what = "" if variable.description.startswith("channel ") else f" ({variable.description})"
        missing = [r.name for r in records if not r.has(variable.column)]
        if missing:
            needs.append(channel)
            where = "every record" if len(missing) == len(records) else ", ".join(missing)
            reasons.append(f"{channel}{what} is absent from {where}")
            continue
        values = np.concatenate([r[variable.column] for r in records])
        finite = values[np.isfinite(values)]
        spread = float(np.ptp(finite)) if finite.size else 0.0
        if spread <= 1e-12 * max(1.0, float(np.max(np.abs(finite), initial=0.0))):
            needs.append(channel)
            value = f" ({finite[0]:g})" if finite.size else ""
            reasons.append(f"{channel}{what} has one value{value} throughout all the records")
    if not needs:
        return None
    advice = f"record {', '.join(needs)} in every record, with values that change"
    return NotTestable(effect, tuple(needs), "; ".join(reasons) + f": {advice}.")


@dataclass
class EffectScore:
    """How much of the remaining force error one catalogued effect explains.

    Attributes
    ----------
    effect : Effect
    explained : float
        Mean over X, Y and N of clip(1 - SSE_with / SSE_without, 0, 1) on
        leave-one-manoeuvre-out predictions (see the module docstring).
    explained_by_dof : dict of str to float
        The three terms of that mean.
    new_terms : dict of str to list of str
        The effect's terms the library did not have, per degree of freedom.
    regime : str
        Where the effect matters: the state bin and the manoeuvres that gain most.
    regime_detail : dict
        The numbers behind ``regime``.
    meaningful : bool
        ``explained`` reaches the threshold of :func:`diagnose`.
    confirmation : BeforeAfter or None
        The refit with the effect and its flights, for the best candidates.
    """

    effect: Effect
    explained: float
    explained_by_dof: dict[str, float]
    new_terms: dict[str, list[str]]
    regime: str
    regime_detail: dict
    meaningful: bool
    confirmation: BeforeAfter | None = None

    def to_json(self) -> dict:
        return _clean(
            {
                "effect": self.effect.name,
                "title": self.effect.title,
                "explained": self.explained,
                "explained_by_dof": self.explained_by_dof,
                "meaningful": self.meaningful,
                "regime": self.regime,
                "regime_detail": self.regime_detail,
                "physics": self.effect.physics,
                "channels": list(self.effect.channels),
                "new_terms": self.new_terms,
                "confirmation": None if self.confirmation is None else self.confirmation.to_json(),
            }
        )


def _regime(
    gain: np.ndarray,
    gain_by_dof: Mapping[str, float],
    residuals: Residuals,
    *,
    uses_heading: bool = False,
) -> tuple[str, dict]:
    """Describe where an effect's gain (per-sample error reduction) is concentrated."""
    total = float(gain.sum())
    if not total > 0:
        return "nowhere: it explains nothing on held-out manoeuvres", {}
    best = None
    for variable, bins in STATE_BINS.items():
        index = _bin_index(residuals.state[variable], bins)
        labels = _bin_labels(bins, variable)
        for b, label in enumerate(labels):
            mask = index == b
            share = float(gain[mask].sum()) / total
            samples = float(mask.mean())
            if samples == 0 or share < 0.25:
                continue
            lift = share / samples
            if best is None or lift > best["lift"]:
                best = {
                    "variable": variable,
                    "bin": f"{label} {bins.unit}".strip(),
                    "description": bins.name,
                    "gain_share": share,
                    "sample_share": samples,
                    "lift": lift,
                }
    by_record = {
        name: float(gain[residuals.groups == g].sum()) / total
        for g, name in enumerate(residuals.names)
    }
    ranked = sorted(by_record.items(), key=lambda item: -item[1])
    dof = max(gain_by_dof, key=gain_by_dof.get)
    parts = [f"mostly in the {_DOF_NAMES[dof]}"]
    if best is not None and best["lift"] >= 1.2:
        parts.append(
            f"at {best['description']} {best['bin']} ({best['gain_share']:.0%} of the "
            f"gain in {best['sample_share']:.0%} of the samples)"
        )
    else:
        parts.append("spread over all drift angles, yaw rates, rudder angles and headings")
    top = [f"{name} ({share:.0%})" for name, share in ranked[:2] if share > 0]
    if top:
        parts.append("largest on " + " and ".join(top))
    detail = {"dof": dof, "bin": best, "by_manoeuvre": by_record}
    if uses_heading:
        covered = _heading_coverage(residuals.state["heading"])
        detail["heading_coverage_deg"] = covered
        if covered < 180.0:
            parts.append(
                f"caution: the records cover only {covered:.0f} deg of heading, over "
                "which sin and cos of psi can stand in for any slow drift"
            )
    return "; ".join(parts), detail


def _heading_coverage(heading_deg: np.ndarray) -> float:
    """Degrees of the compass the records visit (in 10-degree sectors)."""
    sectors = np.unique(np.floor(np.mod(heading_deg, 360.0) / 10.0))
    return 10.0 * len(sectors)


def _score(
    effect: Effect,
    columns: Mapping[str, np.ndarray],
    grouped: Mapping[str, _GroupedProblem],
    base_errors: Mapping[str, np.ndarray],
    residuals: Residuals,
    new_terms: dict,
    threshold: float,
) -> EffectScore:
    explained, gain = {}, np.zeros(len(residuals.t))
    for dof in DOFS:
        e0 = base_errors[dof]
        sse0 = float(e0 @ e0)
        if not new_terms[dof] or not sse0 > 0:
            explained[dof] = 0.0
            continue
        e1 = grouped[dof].lomo_errors(columns[dof])
        explained[dof] = float(np.clip(1.0 - float(e1 @ e1) / sse0, 0.0, 1.0))
        if explained[dof] > 0.0:  # the regime follows the equations the effect helps
            gain += (e0**2 - e1**2) / sse0 / len(DOFS)
    share = float(np.mean([explained[dof] for dof in DOFS]))
    regime, detail = _regime(gain, explained, residuals, uses_heading="psi" in effect.variables)
    return EffectScore(
        effect, share, explained, new_terms, regime, detail, meaningful=share >= threshold
    )


# =============================================================================== before/after
def _geometric_mean_ratio(pairs: Iterable[tuple[dict, dict]]) -> float:
    """Geometric mean of after/before mean distances over flights that both finished."""
    logs = [
        math.log(max(a["mean_distance_L"], 1e-9) / max(b["mean_distance_L"], 1e-9))
        for b, a in pairs
        if b["diverged_at_s"] is None
        and a["diverged_at_s"] is None
        and math.isfinite(b["mean_distance_L"])
        and math.isfinite(a["mean_distance_L"])
    ]
    return math.exp(sum(logs) / len(logs)) if logs else math.nan


@dataclass
class BeforeAfter:
    """The error on every manoeuvre before and after adding effects to a library.

    Attributes
    ----------
    before, after : str
        Library names.
    added : tuple of str
        The effects added.
    rows : list of dict
        Per manoeuvre: ``manoeuvre``, ``set`` (training or held-out) and the error summaries
        ``before`` and ``after`` (:func:`sindyship.evaluation.error_summary`).
    model_before, model_after : AbkowitzModel
    """

    before: str
    after: str
    added: tuple[str, ...]
    rows: list[dict]
    model_before: AbkowitzModel | None = field(default=None, repr=False)
    model_after: AbkowitzModel | None = field(default=None, repr=False)

    @property
    def table(self) -> pd.DataFrame:
        """One row per manoeuvre: mean and max distance and divergence, before and after."""
        records = []
        for row in self.rows:
            entry = {"manoeuvre": row["manoeuvre"], "set": row["set"]}
            for when in ("before", "after"):
                err = row[when]
                entry[f"{when}_mean_L"] = err["mean_distance_L"]
                entry[f"{when}_max_L"] = err["max_distance_L"]
                entry[f"{when}_diverged_at_s"] = err["diverged_at_s"]
            entry["ratio"] = (
                entry["after_mean_L"] / entry["before_mean_L"]
                if entry["before_mean_L"] > 0
                else math.nan
            )
            records.append(entry)
        return pd.DataFrame(records)

    def ratio(self, kind: str = "training") -> float:
        """Geometric mean of after/before mean distance over the set's finished flights."""
        return _geometric_mean_ratio(
            (row["before"], row["after"]) for row in self.rows if row["set"] == kind
        )

    def divergences(self, kind: str = "training") -> tuple[int, int]:
        """Number of flights of the set (training or held-out) that diverged, before and after."""
        rows = [row for row in self.rows if row["set"] == kind]
        return (
            sum(row["before"]["diverged_at_s"] is not None for row in rows),
            sum(row["after"]["diverged_at_s"] is not None for row in rows),
        )

    @property
    def confirmed(self) -> bool | None:
        """Whether re-flying the training manoeuvres confirms the effect.

        True when the geometric-mean distance falls below :data:`CONFIRMING_RATIO` times
        its value before and no more training flights diverge than before (or fewer
        diverge); None without training flights.  Held-out flights never enter it (they
        would select the model on the test set).
        """
        if not any(row["set"] == "training" for row in self.rows):
            return None
        before, after = self.divergences("training")
        ratio = self.ratio("training")
        if after > before:
            return False
        if after < before:
            return True
        return bool(ratio <= CONFIRMING_RATIO)

    def report(self) -> str:
        """A plain-text table of the errors before and after."""
        w = max([16, *(len(row["manoeuvre"]) for row in self.rows)])
        lines = [
            f"Before/after: {self.before} -> {self.after} (mean / max distance in ship "
            "lengths; div = the flight diverged at that time)",
            f"  {'manoeuvre':{w}s} {'set':9s} {'before':>22s} {'after':>22s} {'ratio':>7s}",
        ]
        for row in self.rows:
            cells = [_error_cell(row[when]) for when in ("before", "after")]
            b, a = row["before"]["mean_distance_L"], row["after"]["mean_distance_L"]
            ratio = f"{b / a:6.1f}x" if a > 0 and math.isfinite(a) and math.isfinite(b) else ""
            lines.append(
                f"  {row['manoeuvre']:{w}s} {row['set']:9s} {cells[0]:>22s} "
                f"{cells[1]:>22s} {ratio:>7s}"
            )
        for kind in _SETS:
            ratio = self.ratio(kind)
            if math.isfinite(ratio):
                lines.append(
                    f"  {kind}: error x {ratio:.2f} (geometric mean over the finished "
                    f"flights); diverged {self.divergences(kind)[0]} -> "
                    f"{self.divergences(kind)[1]}"
                )
        return "\n".join(lines)

    def to_json(self) -> dict:
        return _clean(
            {
                "before": self.before,
                "after": self.after,
                "added": list(self.added),
                "confirmed": self.confirmed,
                "ratio": {kind: self.ratio(kind) for kind in _SETS},
                "errors": {
                    row["manoeuvre"]: {
                        "set": row["set"],
                        "before": row["before"],
                        "after": row["after"],
                    }
                    for row in self.rows
                },
            }
        )

    def figure(self, ax=None):
        """Bar chart of the mean distance per manoeuvre, before and after."""
        from .diagnose_plots import plot_before_after

        return plot_before_after(self, ax=ax)


def _error_cell(err: dict) -> str:
    cell = f"{err['mean_distance_L']:.3f} / {err['max_distance_L']:.3f}"
    if err["diverged_at_s"] is not None:
        cell += f" div {err['diverged_at_s']:.0f}s"
    return cell


def _fit(
    records: Sequence[Trajectory],
    ship: Ship,
    library: TermLibrary,
    problems: Mapping[str, Design],
    *,
    optimizer: str,
    rudder_signal: str,
    derivative: str,
    window: float,
) -> AbkowitzModel:
    """Least squares by :func:`_least_squares`, any other optimizer through identify.fit."""
    if optimizer != "ls":
        from .identify import fit

        return fit(
            records,
            ship,
            library=library,
            optimizer=optimizer,
            rudder_signal=rudder_signal,
            derivative=derivative,
            window=window,
            problems=dict(problems),
        )
    coefficients = {
        dof: dict(
            zip(
                problems[dof].terms,
                _least_squares(problems[dof].features, problems[dof].target).tolist(),
                strict=True,
            )
        )
        for dof in DOFS
    }
    info = {
        "training": [r.name for r in records],
        "n_samples": int(len(problems["X"].target)),
        "derivative": derivative,
        "window_s": window if derivative != "five-point" else None,
    }
    return AbkowitzModel(
        ship=ship,
        library=library,
        coefficients=coefficients,
        optimizer={"name": "ls", "params": {"column_scaling": True, "cond": None}},
        rudder_signal=rudder_signal,
        info=info,
    )


@_one_blas_thread
def before_after(
    train: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    effects: Sequence[str | Effect],
    test: Sequence[Trajectory] = (),
    optimizer: str = "ls",
    rudder_signal: str = "actual",
    derivative: str = "five-point",
    window: float = 21.0,
    fly_training: bool = True,
    n_jobs: int = 1,
    progress: bool = False,
) -> BeforeAfter:
    """Refit with effects added and compare the error on every manoeuvre, before and after.

    Parameters
    ----------
    train : sequence of Trajectory
        Training records: both models are fitted on them.
    ship : Ship
    library : str or TermLibrary
        The library before.
    effects : sequence of str or Effect
        The catalogued effects (names or files) to add.
    test : sequence of Trajectory
        Held-out records, flown but never fitted on.
    optimizer, rudder_signal, derivative, window
        As :func:`sindyship.identify.fit`.
    fly_training : bool
        Also fly the training records.
    n_jobs : int
        Processes for the flights (joblib).
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    BeforeAfter
        ``.table``, ``.report()``, ``.figure()``, ``.to_json()``.

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> from sindyship.effects import parse_effects, simulate_with_effects
    >>> from sindyship.manoeuvres import Manoeuvre
    >>> ship = load_ship("kcs")
    >>> plan = [Manoeuvre("turning-circle", rudder=35, duration=800),
    ...         Manoeuvre("turning-circle", rudder=-35, duration=800),
    ...         Manoeuvre("zigzag", rudder=20, check=20, duration=800),
    ...         Manoeuvre("zigzag", rudder=10, check=10, duration=800),
    ...         Manoeuvre("turning-circle", rudder=-20, duration=800)]
    >>> runs = simulate_with_effects(ship, plan, parse_effects(["current=0.5", "current_dir=90"]))
    >>> change = before_after(runs[:4], ship, effects=["environment"], test=runs[4:])
    >>> change.table[["manoeuvre", "set"]].values.tolist()[-1]
    ['tc20_port', 'held-out']
    >>> bool(change.ratio("held-out") < 0.5)
    True
    """
    base = resolve_library(library)
    added = [e if isinstance(e, Effect) else load_effect(e) for e in effects]
    extended = base.extended(*added)
    settings = {"rudder_signal": rudder_signal, "derivative": derivative, "window": window}
    models = []
    for lib in (base, extended):
        problems = design(train, ship, lib, **settings)
        models.append(_fit(train, ship, lib, problems, optimizer=optimizer, **settings))
    sets = ([("training", list(train))] if fly_training else []) + [("held-out", list(test))]
    sets = [(kind, records) for kind, records in sets if records]
    jobs = [(model, records) for model in models for _, records in sets]
    flown = _fly_many(jobs, n_jobs=n_jobs, progress=progress, what="before/after flights")
    rows = []
    for k, (kind, records) in enumerate(sets):
        for rec, before, after in zip(records, flown[k], flown[len(sets) + k], strict=True):
            rows.append(
                {
                    "manoeuvre": rec.name,
                    "set": kind,
                    "before": error_summary(before, rec, ship.L),
                    "after": error_summary(after, rec, ship.L),
                }
            )
    return BeforeAfter(
        base.name,
        extended.name,
        tuple(e.name for e in added),
        rows,
        model_before=models[0],
        model_after=models[1],
    )


# =============================================================================== diagnose
@dataclass
class Diagnosis:
    """The answer of :func:`diagnose`: comparison, residuals and the ranked missing effects.

    Attributes
    ----------
    ship : Ship
    library : TermLibrary
        The library diagnosed.
    model : AbkowitzModel
        The library fitted on the training records.
    threshold : float
        The share an effect must explain to be meaningful.
    ranking : list of EffectScore
        Testable effects, best first.
    not_testable : list of NotTestable
    in_library : list of str
        Catalogued effects whose terms the library already has.
    comparisons : list of ManoeuvreComparison
        The model flown like every training (if flown) and held-out record.
    residuals : Residuals
        On the training records.
    force_error : dict
        Per degree of freedom: the leave-one-manoeuvre-out error of the library relative to
        the measured force (RMS over RMS).
    settings : dict
    seconds : float
    """

    ship: Ship
    library: TermLibrary
    model: AbkowitzModel
    threshold: float
    ranking: list[EffectScore]
    not_testable: list[NotTestable]
    in_library: list[str]
    comparisons: list[ManoeuvreComparison]
    residuals: Residuals
    force_error: dict[str, float]
    settings: dict
    seconds: float = 0.0

    @property
    def complete(self) -> bool:
        """No testable effect explains a meaningful share of the force error."""
        return not any(score.meaningful for score in self.ranking)

    @property
    def warnings(self) -> list[str]:
        """Cautions about the data behind the verdict (empty when there are none)."""
        out = []
        noisy = [dof for dof in DOFS if self.force_error[dof] > 0.5]
        if noisy:
            names = " and ".join(_DOF_NAMES[dof] for dof in noisy)
            if self.settings.get("derivative") == "savgol":
                advice = (
                    f"the accelerations are already smoothed over "
                    f"{self.settings.get('window')} s; a verdict of 'complete' then means "
                    "that no catalogued effect describes the rest"
                )
            else:
                advice = (
                    "with noisy or quantised data, smooth the accelerations (derivative "
                    "savgol) before trusting a verdict of 'complete'"
                )
            out.append(
                f"the library predicts less than half of the measured {names} on "
                "held-out manoeuvres (noise in the accelerations, manoeuvres too unlike "
                "each other for one to be predicted from the rest, or physics no catalogued "
                f"effect describes); {advice}"
            )
        diverged = [c.name for c in self.comparisons if c.errors["diverged_at_s"] is not None]
        if diverged:
            out.append(
                f"the flights of {', '.join(diverged)} diverged: their mean distances "
                "cover only the time before the divergence"
            )
        return out

    @property
    def top(self) -> EffectScore | None:
        """The best meaningful effect, or None when the library is complete."""
        return next((s for s in self.ranking if s.meaningful), None)

    def score(self, name: str) -> EffectScore:
        """The score of one effect by name."""
        for score in self.ranking:
            if score.effect.name == name:
                return score
        raise KeyError(f"effect {name!r} was not scored (not testable or already in the library)")

    def rank(self, name: str) -> int | None:
        """1-based rank of an effect, None if it was not scored."""
        names = [s.effect.name for s in self.ranking]
        return names.index(name) + 1 if name in names else None

    def errors(self, kind: str | None = None) -> dict[str, dict]:
        """Error summaries of the flights by record name (optionally of one set)."""
        return {c.name: c.errors for c in self.comparisons if kind in (None, c.set)}

    # ------------------------------------------------------------------------------- text
    def report(self) -> str:
        """The diagnosis as text a person reads, best effect first."""
        n_terms = sum(len(self.library.terms[d]) for d in DOFS)
        sets = {kind: sum(c.set == kind for c in self.comparisons) for kind in _SETS}
        lines = [
            f"sindyship diagnose: ship {self.ship.name}, library {self.library.name} "
            f"({n_terms} terms), {len(self.residuals.names)} training records"
            + (f", {sets['held-out']} held-out" if sets["held-out"] else ""),
            "",
        ]
        if self.comparisons:
            w = max([16, *(len(c.name) for c in self.comparisons)])
            lines.append("Compare: the identified model flown like each record")
            lines.append(
                f"  {'manoeuvre':{w}s} {'set':9s} {'mean L':>8s} {'max L':>8s} "
                f"{'heading deg':>12s} {'speed m/s':>10s}  diverged"
            )
            for c in self.comparisons:
                e = c.errors
                div = "-" if e["diverged_at_s"] is None else f"at {e['diverged_at_s']:.0f} s"
                lines.append(
                    f"  {c.name:{w}s} {c.set:9s} {e['mean_distance_L']:8.3f} "
                    f"{e['max_distance_L']:8.3f} {e['rms_heading_deg']:12.2f} "
                    f"{e['rms_speed_m_s']:10.3f}  {div}"
                )
            lines.append("")
        summary = self.residuals.summary()
        worst = self.residuals.worst_bins()
        lines.append(
            "Where it fails: force residual (measured - model), RMS over the RMS "
            "measured force; the bin of the largest RMS"
        )
        for dof in DOFS:
            lines.append(
                f"  {_DOF_NAMES[dof]:13s} {100 * summary[dof]['relative']:7.2f} %   "
                f"cross-validated {100 * self.force_error[dof]:7.2f} %   worst at "
                f"{worst[dof]}"
            )
        lines.append("")
        lines.append(
            f"Which effect is missing: share of the leave-one-manoeuvre-out force "
            f"error each effect explains (meaningful from {100 * self.threshold:.0f} %)"
        )
        if not self.ranking:
            lines.append("  (no testable effect)")
        for k, score in enumerate(self.ranking, 1):
            by = ", ".join(f"{d} {100 * score.explained_by_dof[d]:.0f} %" for d in DOFS)
            mark = "" if score.meaningful else "  (not meaningful)"
            lines.append(
                f" {k}. {score.effect.name} - {score.effect.title}: explains "
                f"{100 * score.explained:.1f} % ({by}){mark}"
            )
            if score.meaningful:
                lines.append(
                    textwrap.fill(
                        f"where: {score.regime}",
                        width=96,
                        initial_indent="    ",
                        subsequent_indent="      ",
                    )
                )
                if score.confirmation is not None:
                    lines.append(
                        textwrap.fill(
                            _confirmation_text(score.confirmation),
                            width=96,
                            initial_indent="    ",
                            subsequent_indent="      ",
                        )
                    )
                lines.append(
                    textwrap.fill(
                        f"physics: {score.effect.physics}",
                        width=96,
                        initial_indent="    ",
                        subsequent_indent="      ",
                    )
                )
        if self.not_testable:
            lines.append("")
            lines.append("Not testable with these data (record the channel named):")
            for item in self.not_testable:
                lines.append(
                    textwrap.fill(
                        f"- {item.effect.name} ({item.effect.title}): {item.reason}",
                        width=96,
                        initial_indent="  ",
                        subsequent_indent="    ",
                    )
                )
        if self.in_library:
            lines.append(f"Already in the library: {', '.join(self.in_library)}.")
        lines.append("")
        for warning in self.warnings:
            lines.append(textwrap.fill(f"Caution: {warning}.", width=96, subsequent_indent="  "))
        if self.complete:
            lines.append(
                f"Verdict: complete - no catalogued effect explains "
                f"{100 * self.threshold:.0f} % or more of the remaining force error."
            )
        else:
            top = self.top
            lines.append(
                f"Verdict: add {top.effect.name}: sindyship fit DATA.csv... --ship "
                f"{_ship_argument(self.ship)} --effects "
                f"{','.join([*self.library.effects, top.effect.name])}; then diagnose "
                "again with the same --effects."
            )
        return "\n".join(lines)

    def to_json(self) -> dict:
        """The JSON document of ``sindyship diagnose --json`` (docs/command-line.md)."""
        return _clean(
            {
                "ship": self.ship.name,
                "library": self.library.name,
                "effects_in_library": list(self.library.effects),
                "threshold": self.threshold,
                "complete": self.complete,
                "ranking": [score.to_json() for score in self.ranking],
                "not_testable": [item.to_json() for item in self.not_testable],
                "in_library": list(self.in_library),
                "warnings": self.warnings,
                "errors": {c.name: {"set": c.set, **c.errors} for c in self.comparisons},
                "force_residual": {
                    dof: {**self.residuals.summary()[dof], "cross_validated": self.force_error[dof]}
                    for dof in DOFS
                },
                "settings": self.settings,
                "seconds": self.seconds,
            }
        )

    # ------------------------------------------------------------------------------- figures
    def save_figures(self, out_dir: str | Path, *, progress: bool = False) -> list[Path]:
        """Write the figures (PNG) and the before/after tables (CSV) to a folder.

        ``compare-<record>.png`` (track and time series), ``residuals-<record>.png`` (force
        residuals over time with the phases), ``residuals-binned.png``, ``ranking.png`` and,
        per confirmed candidate, ``before-after-<effect>.png`` and ``.csv``.

        Returns
        -------
        list of Path
            The files written.
        """
        from tqdm.auto import tqdm

        from . import diagnose_plots as plots

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written: list[Path] = []
        tasks = []
        for c in self.comparisons:
            tasks.append(
                (
                    f"compare-{_safe(c.name)}.png",
                    lambda c=c: plots.plot_comparison(
                        c.record, {self.library.name: c.flown}, L=self.ship.L, errors=c.errors
                    ),
                )
            )
        for name in self.residuals.names:
            tasks.append(
                (
                    f"residuals-{_safe(name)}.png",
                    lambda name=name: plots.plot_residual_time_series(self.residuals, name),
                )
            )
        tasks.append(("residuals-binned.png", lambda: plots.plot_residual_bins(self.residuals)))
        if self.ranking:
            tasks.append(("ranking.png", lambda: plots.plot_ranking(self)))
        for score in self.ranking:
            if score.confirmation is not None:
                tasks.append(
                    (f"before-after-{_safe(score.effect.name)}.png", score.confirmation.figure)
                )
                path = out / f"before-after-{_safe(score.effect.name)}.csv"
                write_text_atomic(path, score.confirmation.table.to_csv(index=False))
                written.append(path)
        for filename, draw in tqdm(
            tasks, desc="figures", file=sys.stderr, disable=not progress, leave=False
        ):
            written.append(_save_figure(draw(), out / filename))
        return written


def _ship_argument(ship: Ship) -> str:
    """The ``--ship`` argument that loads ``ship``: its name if built in, else a placeholder."""
    from .ships import load_ship

    try:
        return ship.name if load_ship(ship.name) == ship else "SHIP.toml"
    except SindyshipInputError:
        return "SHIP.toml"


def _confirmation_text(change: BeforeAfter) -> str:
    parts = []
    for kind in _SETS:
        ratio = change.ratio(kind)
        before, after = change.divergences(kind)
        if not any(row["set"] == kind for row in change.rows):
            continue
        text = f"{kind} error x {ratio:.2f}" if math.isfinite(ratio) else f"{kind} error n/a"
        if before or after:
            text += f" (diverged flights {before} -> {after})"
        parts.append(text)
    verdict = {True: "confirmed", False: "not confirmed", None: "flown"}[change.confirmed]
    return (
        f"{verdict} by refitting and re-flying: "
        + ", ".join(parts)
        + " (geometric mean of after/before mean distance)"
    )


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.+-]+", "_", name) or "record"


def _save_figure(fig, path: Path) -> Path:
    """Save a figure through a temporary file and a rename."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=110, format=path.suffix.lstrip(".") or "png")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _clean(value):
    """JSON-ready: numpy scalars to Python, non-finite floats to None."""
    if isinstance(value, Mapping):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, np.ndarray):
        return _clean(value.tolist())
    return value


def _catalogue(effects: Sequence[str | Effect] | None) -> list[Effect]:
    names = available_effects() if effects is None else effects
    out = [e if isinstance(e, Effect) else load_effect(e) for e in names]
    seen = set()
    for effect in out:
        if effect.name in seen:
            raise SindyshipInputError(f'the effect "{effect.name}" is given twice.')
        seen.add(effect.name)
    return out


@_one_blas_thread
def diagnose(
    records: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    effects: Sequence[str | Effect] | None = None,
    test: Sequence[Trajectory] = (),
    threshold: float = MEANINGFUL_SHARE,
    confirm: int = 2,
    fly_training: bool = True,
    optimizer: str = "ls",
    rudder_signal: str = "actual",
    derivative: str = "five-point",
    window: float = 21.0,
    n_jobs: int = 1,
    progress: bool = False,
) -> Diagnosis:
    """Fit a library, show where it fails and rank the catalogued effects that are missing.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records (at least two: effects are scored leave-one-manoeuvre-out).
    ship : Ship
    library : str or TermLibrary
        The library to diagnose (a name, a file, or an extended library).
    effects : sequence of str or Effect, optional
        Candidate effects; default the whole catalogue (:func:`available_effects`).
    test : sequence of Trajectory
        Held-out records: flown before and after, never fitted on, never used to choose.
    threshold : float
        Share of the cross-validated force error an effect must explain to be meaningful.
    confirm : int
        Number of best meaningful candidates to confirm by refitting and re-flying.
    fly_training : bool
        Fly the training records (compare, confirmation).  Without it only the held-out
        records are flown, and a candidate's ``confirmation.confirmed`` is None.
    optimizer : str
        The optimizer of the fitted model and of the confirmation refits (scoring always
        uses least squares).
    rudder_signal, derivative, window
        As :func:`sindyship.identify.fit`.
    n_jobs : int
        Parallel jobs: threads for scoring the effects, processes for the flights (joblib).
    progress : bool
        Progress bars on stderr.

    Returns
    -------
    Diagnosis
        ``.ranking``, ``.not_testable``, ``.report()``, ``.to_json()``, ``.save_figures()``.

    Raises
    ------
    SindyshipInputError
        Fewer than two training records, an unknown effect, or a record the library cannot
        be evaluated on.
    """
    from joblib import Parallel, delayed

    start = time.perf_counter()
    records, test = list(records), list(test)
    if len(records) < 2:
        raise SindyshipInputError(
            "diagnose needs at least two training records: effects are scored by "
            "leave-one-manoeuvre-out cross-validation."
        )
    if not 0.0 < threshold < 1.0:
        raise SindyshipInputError(f"the threshold must lie between 0 and 1, not {threshold}.")
    names = [r.name for r in records + test]
    if len(set(names)) != len(names):
        raise SindyshipInputError("two records share a name; give each file a distinct name.")
    base = resolve_library(library)
    settings = {"rudder_signal": rudder_signal, "derivative": derivative, "window": window}
    candidates, not_testable, in_library = [], [], []
    for effect in _catalogue(effects):
        if effect.name in base.effects:
            in_library.append(effect.name)
            continue
        reason = _untestable(effect, records)
        if reason is not None:
            not_testable.append(reason)
            continue
        present = {dof: {t.canonical(scale=False) for t in base.terms[dof]} for dof in DOFS}
        new = {
            dof: [t.text for t in effect.terms[dof] if t.canonical(scale=False) not in present[dof]]
            for dof in DOFS
        }
        if not any(new.values()):
            in_library.append(effect.name)
            continue
        candidates.append((effect, new))
    union = base.extended(*[effect for effect, _ in candidates])
    problems = design(records, ship, union, **settings)
    n_base = {dof: len(base.terms[dof]) for dof in DOFS}
    base_problems = {
        dof: Design(
            problems[dof].features[:, : n_base[dof]],
            problems[dof].target,
            problems[dof].groups,
            problems[dof].terms[: n_base[dof]],
        )
        for dof in DOFS
    }
    model = _fit(records, ship, base, base_problems, optimizer=optimizer, **settings)
    residuals = _residuals(
        base_problems,
        {dof: model.coefficient_vector(dof) for dof in DOFS},
        records,
        ship,
        rudder_signal,
    )
    grouped = {
        dof: _GroupedProblem(problems[dof].features, problems[dof].target, problems[dof].groups)
        for dof in DOFS
    }
    base_columns = {dof: np.arange(n_base[dof]) for dof in DOFS}
    base_errors = {dof: grouped[dof].lomo_errors(base_columns[dof]) for dof in DOFS}
    force_error = {
        dof: float(
            np.sqrt(np.mean(base_errors[dof] ** 2))
            / max(np.sqrt(np.mean(problems[dof].target ** 2)), 1e-300)
        )
        for dof in DOFS
    }
    index = {
        dof: {t.canonical(scale=False): i for i, t in enumerate(union.terms[dof])} for dof in DOFS
    }
    jobs = []
    for effect, new in candidates:
        columns = {
            dof: np.array(
                sorted(
                    set(base_columns[dof].tolist())
                    | {index[dof][Term(t).canonical(scale=False)] for t in new[dof]}
                ),
                dtype=int,
            )
            for dof in DOFS
        }
        jobs.append(
            delayed(_score)(effect, columns, grouped, base_errors, residuals, new, threshold)
        )
    ranking = list(Parallel(n_jobs=n_jobs, prefer="threads")(jobs)) if jobs else []
    ranking.sort(key=lambda s: (-s.explained, s.effect.name))

    sets = ([("training", records)] if fly_training else []) + [("held-out", test)]
    sets = [(kind, recs) for kind, recs in sets if recs]
    chosen = [s for s in ranking if s.meaningful][: max(int(confirm), 0)] if sets else []
    models = [model]
    for score in chosen:
        lib = base.extended(score.effect)
        models.append(
            _fit(
                records,
                ship,
                lib,
                design(records, ship, lib, **settings),
                optimizer=optimizer,
                **settings,
            )
        )
    flown = _fly_many(
        [(m, recs) for m in models for _, recs in sets],
        n_jobs=n_jobs,
        progress=progress,
        what="flights",
    )
    comparisons = []
    for k, (kind, recs) in enumerate(sets):
        comparisons += compare(model, recs, kind=kind, flights=flown[k])
    for j, score in enumerate(chosen, start=1):
        rows = []
        for k, (kind, recs) in enumerate(sets):
            for rec, before, after in zip(recs, flown[k], flown[j * len(sets) + k], strict=True):
                rows.append(
                    {
                        "manoeuvre": rec.name,
                        "set": kind,
                        "before": error_summary(before, rec, ship.L),
                        "after": error_summary(after, rec, ship.L),
                    }
                )
        score.confirmation = BeforeAfter(
            base.name,
            models[j].library.name,
            (score.effect.name,),
            rows,
            model_before=model,
            model_after=models[j],
        )
    return Diagnosis(
        ship=ship,
        library=base,
        model=model,
        threshold=threshold,
        ranking=ranking,
        not_testable=not_testable,
        in_library=in_library,
        comparisons=comparisons,
        residuals=residuals,
        force_error=force_error,
        settings={
            **settings,
            "optimizer": optimizer,
            "confirm": confirm,
            "fly_training": fly_training,
            "scoring": "least squares, leave-one-manoeuvre-out",
        },
        seconds=time.perf_counter() - start,
    )


# =============================================================================== iterative
@dataclass
class Round:
    """One round of :func:`diagnose_iteratively`.

    Attributes
    ----------
    diagnosis : Diagnosis
        Of the library at the start of the round.
    added : str or None
        The effect added in this round (None in the last round).
    change : BeforeAfter or None
        The errors before and after adding it.
    """

    diagnosis: Diagnosis
    added: str | None
    change: BeforeAfter | None


@dataclass
class IterativeDiagnosis:
    """Rounds of diagnosis and addition, until no effect explains a meaningful share.

    Attributes
    ----------
    rounds : list of Round
    stopped : str
        Why the iteration ended.
    """

    rounds: list[Round]
    stopped: str

    @property
    def final_library(self) -> TermLibrary:
        """The library of the last round (every added effect)."""
        last = self.rounds[-1]
        if last.change is not None and last.change.model_after is not None:
            return last.change.model_after.library
        return last.diagnosis.library

    @property
    def added(self) -> list[str]:
        return [r.added for r in self.rounds if r.added]

    @property
    def table(self) -> pd.DataFrame:
        """Mean distance of every flown manoeuvre with the library of each round."""
        rows = []
        for k, rnd in enumerate(self.rounds):
            for c in rnd.diagnosis.comparisons:
                rows.append(
                    {
                        "round": k + 1,
                        "library": rnd.diagnosis.library.name,
                        "manoeuvre": c.name,
                        "set": c.set,
                        **c.errors,
                    }
                )
            if k == len(self.rounds) - 1 and rnd.change is not None:
                for row in rnd.change.rows:
                    rows.append(
                        {
                            "round": k + 2,
                            "library": rnd.change.after,
                            "manoeuvre": row["manoeuvre"],
                            "set": row["set"],
                            **row["after"],
                        }
                    )
        return pd.DataFrame(rows)

    def report(self) -> str:
        """One paragraph per round, then the errors of every library."""
        lines = []
        for k, rnd in enumerate(self.rounds, 1):
            d = rnd.diagnosis
            top = ", ".join(f"{s.effect.name} {100 * s.explained:.1f} %" for s in d.ranking[:4])
            lines.append(
                f"Round {k}: library {d.library.name}: {top or 'no testable effect'}"
                + (f" -> add {rnd.added}" if rnd.added else "")
            )
        lines.append(f"Stopped: {self.stopped}")
        table = self.table
        if not table.empty:
            lines.append("")
            lines.append("Mean distance [ship lengths] per manoeuvre and library:")
            pivot = table.pivot_table(
                index=["set", "manoeuvre"], columns="round", values="mean_distance_L", sort=False
            )
            lines.append(pivot.to_string(float_format=lambda x: f"{x:.3f}"))
        return "\n".join(lines)

    def to_json(self) -> dict:
        return _clean(
            {
                "rounds": [
                    {
                        "round": k + 1,
                        "library": r.diagnosis.library.name,
                        "ranking": [
                            {"effect": s.effect.name, "explained": s.explained}
                            for s in r.diagnosis.ranking
                        ],
                        "complete": r.diagnosis.complete,
                        "added": r.added,
                        "errors": r.diagnosis.errors(),
                        "change": None if r.change is None else r.change.to_json(),
                    }
                    for k, r in enumerate(self.rounds)
                ],
                "final_library": self.final_library.name,
                "added": self.added,
                "stopped": self.stopped,
            }
        )

    def figure(self, ax=None):
        """Mean distance per manoeuvre after each round."""
        from .diagnose_plots import plot_rounds

        return plot_rounds(self, ax=ax)


def diagnose_iteratively(
    records: Sequence[Trajectory],
    ship: Ship,
    *,
    library: str | TermLibrary = "abkowitz",
    test: Sequence[Trajectory] = (),
    max_rounds: int = 4,
    progress: bool = False,
    **options,
) -> IterativeDiagnosis:
    """Diagnose, add the best effect, diagnose again, until the library is complete.

    Each round adds the best meaningful effect that re-flying the training records
    confirms (the best meaningful one when training records are not flown); the iteration
    stops when no effect explains a meaningful share, when no meaningful effect is
    confirmed, or after ``max_rounds`` additions.  Held-out records are flown every round
    and never used to choose.

    Parameters
    ----------
    records, ship, library, test
        As :func:`diagnose`.
    max_rounds : int
        Most effects to add.
    progress : bool
        Progress bar over the rounds on stderr.
    **options
        Passed to :func:`diagnose` (``effects``, ``threshold``, ``confirm``, ``fly_training``,
        ``optimizer``, ``n_jobs``, ...).

    Returns
    -------
    IterativeDiagnosis
    """
    from tqdm.auto import tqdm

    lib = resolve_library(library)
    rounds: list[Round] = []
    stopped = f"after {max_rounds} rounds"
    bar = tqdm(total=max_rounds, desc="rounds", file=sys.stderr, disable=not progress)
    for _ in range(max_rounds):
        result = diagnose(records, ship, library=lib, test=test, progress=progress, **options)
        meaningful = [s for s in result.ranking if s.meaningful]
        if not meaningful:
            rounds.append(Round(result, None, None))
            stopped = "no effect explains a meaningful share"
            break
        verdicts = [
            s
            for s in meaningful
            if s.confirmation is not None and s.confirmation.confirmed is not None
        ]
        if verdicts:
            pick = next((s for s in verdicts if s.confirmation.confirmed), None)
        else:
            pick = meaningful[0]
        if pick is None:
            rounds.append(Round(result, None, None))
            stopped = "no meaningful effect was confirmed by re-flying the training records"
            break
        change = pick.confirmation
        if change is None:
            change = before_after(
                records,
                ship,
                library=lib,
                effects=[pick.effect],
                test=test,
                fly_training=options.get("fly_training", True),
                optimizer=options.get("optimizer", "ls"),
                n_jobs=options.get("n_jobs", 1),
                **{
                    k: options[k] for k in ("rudder_signal", "derivative", "window") if k in options
                },
            )
        rounds.append(Round(result, pick.effect.name, change))
        lib = lib.extended(pick.effect)
        bar.update()
    bar.close()
    return IterativeDiagnosis(rounds, stopped)


# =============================================================================== command line
def add_diagnose_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``diagnose`` verb to the ``sindyship`` command line."""
    p = subparsers.add_parser(
        "diagnose",
        help="show where a fitted model fails and which effect is missing",
        description="Fit the library on the training records, fly it like each record, show "
        "the force residuals and rank the catalogued physical effects "
        "(libraries/effects/*.toml) by the share of the cross-validated force error they "
        "explain; confirm the best by refitting and re-flying.",
    )
    p.add_argument("data", nargs="+", help="training measurement CSV files (two or more)")
    p.add_argument("--ship", default="kcs", help="built-in ship (kcs, kvlcc2) or a TOML file")
    p.add_argument("--library", default="abkowitz", help="term library name or TOML file")
    p.add_argument(
        "--effects",
        default="",
        help="comma-separated effects already added to the library (diagnose "
        "again after adding them)",
    )
    p.add_argument(
        "--candidates",
        default="",
        help="comma-separated effects to score (default: the whole catalogue)",
    )
    p.add_argument(
        "--test",
        nargs="+",
        default=[],
        metavar="HELD_OUT.csv",
        help="held-out records: flown before and after, never fitted on",
    )
    p.add_argument("--out", default=None, help="folder for figures, report.txt and diagnose.json")
    p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
    p.add_argument(
        "--rounds",
        type=int,
        default=1,
        help="add the best confirmed effect and diagnose again, up to this many "
        "times (default 1: diagnose once)",
    )
    p.add_argument(
        "--threshold",
        type=float,
        default=MEANINGFUL_SHARE,
        help="share of the force error that is meaningful (default 0.05)",
    )
    p.add_argument(
        "--confirm",
        type=int,
        default=2,
        help="best candidates to confirm by refitting and re-flying (default 2)",
    )
    p.add_argument("--optimizer", default="ls", choices=["ls", "stlsq", "lasso", "svr"])
    p.add_argument("--rudder-signal", default="actual", choices=["actual", "commanded"])
    p.add_argument("--derivative", default="five-point", choices=["five-point", "savgol"])
    p.add_argument(
        "--window",
        type=float,
        default=21.0,
        help="Savitzky-Golay window [s] (with --derivative savgol)",
    )
    p.add_argument(
        "--resample",
        type=float,
        default=None,
        help="resample irregular records onto this interval [s]",
    )
    p.add_argument("--n-jobs", type=int, default=1, help="parallel jobs (joblib)")
    return p


def _split_names(text: str) -> list[str]:
    return [name.strip() for name in text.split(",") if name.strip()]


def cmd_diagnose(args) -> int:
    """Run ``sindyship diagnose``; text report on stdout, or one JSON document with --json."""
    from .measurements import read_csv
    from .ships import load_ship

    start = time.perf_counter()
    ship = load_ship(args.ship)
    records = [read_csv(p, resample=args.resample) for p in args.data]
    test = [read_csv(p, resample=args.resample) for p in args.test]
    library = resolve_library(args.library, _split_names(args.effects))
    if args.rounds < 1:
        raise SindyshipInputError(f"--rounds must be 1 or more, not {args.rounds}.")
    options = {
        "effects": _split_names(args.candidates) or None,
        "threshold": args.threshold,
        "confirm": args.confirm,
        "optimizer": args.optimizer,
        "rudder_signal": args.rudder_signal,
        "derivative": args.derivative,
        "window": args.window,
        "n_jobs": args.n_jobs,
    }
    progress = sys.stderr.isatty()
    print(
        f"sindyship diagnose: {len(records)} training and {len(test)} held-out records, "
        f"library {library.name}",
        file=sys.stderr,
        flush=True,
    )
    iterative = None
    if args.rounds > 1:
        iterative = diagnose_iteratively(
            records,
            ship,
            library=library,
            test=test,
            max_rounds=args.rounds,
            progress=progress,
            **options,
        )
        result = iterative.rounds[0].diagnosis
    else:
        result = diagnose(records, ship, library=library, test=test, progress=progress, **options)
    document = result.to_json()
    text = result.report()
    if iterative is not None:
        document.update(iterative.to_json())
        text += "\n\n" + iterative.report()
    document["seconds"] = time.perf_counter() - start
    if args.out:
        out = Path(args.out)
        result.save_figures(out, progress=progress)
        if iterative is not None:
            _save_figure(iterative.figure(), out / "rounds.png")
            for k, rnd in enumerate(iterative.rounds, 1):
                if rnd.change is not None:
                    _save_figure(rnd.change.figure(), out / f"round-{k}-before-after.png")
                    write_text_atomic(
                        out / f"round-{k}-before-after.csv", rnd.change.table.to_csv(index=False)
                    )
        write_text_atomic(out / "report.txt", text + "\n")
        write_text_atomic(out / "diagnose.json", json.dumps(document, indent=2) + "\n")
        print(
            f"sindyship diagnose: figures, report.txt and diagnose.json are in {out}/",
            file=sys.stderr,
            flush=True,
        )
    if args.json:
        sys.stdout.write(json.dumps(document, indent=2) + "\n")
    else:
        print(text)
    return 0

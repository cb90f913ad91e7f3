"""An identified model's forces against captive (towing-tank) tests.

A model that flies well may still have coefficients that are wrong as hydrodynamic
derivatives: collinear terms trade off against each other along the manoeuvres it was fitted
on and disagree away from them.  Captive tests measure the forces directly, on conditions
chosen by the experimenter, so they check the forces themselves.

:func:`model_captive_forces` gives what an identified :class:`~sindyship.model.AbkowitzModel`
predicts a captive dynamometer measures, in the convention of the captive CSV
(:mod:`sindyship.captive`: hydrodynamic forces, rigid-body inertia removed).  With the model's
fitted force F' of eq. 15 and the protocol's Coriolis terms C' of eq. 14 (rigid body plus added
mass with the Munk moment, :func:`sindyship.targets.coriolis`), in a steady condition the
right-hand side of eq. 14 is F' + C' (the full reading) and the hydrodynamic force is

    F_captive = F' + C' - C'_RB,

the fitted force plus the added-mass Coriolis and Munk terms, dimensionalised with the ship
(Prime I).  Comparing F' alone with a tank measurement would leave out e.g. the Munk moment
(Y'_vdot - X'_udot) u' v', which is larger than N'_v itself for the KCS.

:func:`compare_forces` reports, per force X, Y, N, the Pearson correlation and the relative
RMS error RMS(predicted - measured) / RMS(measured), over all conditions, per test type, and
inside and outside the training envelope: the box of the ranges of v', r' and delta that the
training records covered.  A box is generous: zig-zags tie v' to r', so the box includes
combinations (large v' with small r') that the training never saw.

Note on the KCS of the paper: the identification uses the added masses of Table 6, the MMG
those of Table 2, which differ (Table 6 has Y'_rdot = N'_vdot = -21e-5, the MMG none).  Even an
exact fit (the Taylor reference of :mod:`sindyship.taylor`) then predicts captive forces that
differ from the MMG's by (M_abk - M_MMG) a_MMG, the inertia mismatch times the acceleration the
ship would have if released; this, with the cubic series' own truncation, sets a floor under
the relative RMS error: the Taylor reference misses the KCS's virtual captive forces by 4 % in
N, 5 to 25 % in Y (pure yaw the most) and up to 11 % in X (42 % in drift and yaw, beyond the
cubic series' reach).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from .captive import (
    FORCE_COLUMNS,
    check_captive_scale,
    check_force_scale,
    classify_tests,
    force_scales,
    rigid_body_forces,
    steady_variables,
)
from .errors import SindyshipInputError
from .identify import ENVELOPE_VARIABLES, training_envelope
from .model import AbkowitzModel, coriolis_of_values
from .ships import Ship
from .targets import DOFS
from .trajectory import Trajectory

__all__ = [
    "ENVELOPE_VARIABLES",
    "ForceComparison",
    "compare_forces",
    "forces_report",
    "model_captive_forces",
    "plot_captive_forces",
    "training_envelope",
]

#: The horizontal axis of each test type's panels: a column of the table and its label.
_AXIS = {"static-drift": ("beta", "drift angle beta [deg]"),
         "rudder": ("delta_deg", "rudder angle delta [deg]"),
         "pure-yaw": ("r_nd", "yaw rate r' [-]"),
         "drift-yaw": ("beta", "drift angle beta [deg] (one line per r')"),
         "combined": ("index", "condition"), "straight": ("index", "condition"),
         "astern": ("index", "condition going astern")}
_UNITS = {"X": "X [MN]", "Y": "Y [MN]", "N": "N [MN m]"}


def _nondimensional(frame: pd.DataFrame, ship: Ship) -> dict[str, np.ndarray]:
    U0, L = ship.U0, ship.L
    return {"du": frame["u"].to_numpy(float) / U0 - 1.0, "v": frame["v"].to_numpy(float) / U0,
            "r": frame["r"].to_numpy(float) * L / U0, "delta": frame["delta"].to_numpy(float)}


def model_captive_forces(model: AbkowitzModel, captive: pd.DataFrame) -> pd.DataFrame:
    """What an identified model predicts a captive dynamometer measures (SI).

    Parameters
    ----------
    model : AbkowitzModel
        The identified model (its ship gives L, U0, rho and the Prime I inertia).
    captive : pandas.DataFrame
        Captive conditions: ``u``, ``v`` [m/s], ``r`` [rad/s], ``delta`` [rad] and any channel
        the model's library uses (``n`` [rps], ...), SI (as :func:`read_captive_csv` gives).
        Each row is a steady condition: a channel the library delays reads the value given,
        and the rudder rate (``delta_rate``) is zero.

    Returns
    -------
    pandas.DataFrame
        ``X``, ``Y`` [N] and ``N`` [N m]: F' + C' - C'_RB of the module docstring, in body
        axes at midship.

    Examples
    --------
    >>> from sindyship.captive import captive_tests
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> tests = captive_tests(kcs, "static-drift", points=3)
    >>> predicted = model_captive_forces(paper_model(kcs, "LS"), tests)
    >>> bool(predicted.Y.iloc[0] < 0 < predicted.Y.iloc[2])
    True
    """
    ship = model.ship
    values = steady_variables(captive, model.library, ship, model.rudder_signal)
    fitted = model.forces_from_values(values)
    full = coriolis_of_values(ship, values)
    scales = force_scales(ship, "prime-I")
    rigid = rigid_body_forces(ship, captive["u"].to_numpy(float), captive["v"].to_numpy(float),
                              captive["r"].to_numpy(float))
    out = {dof: scales[i] * (fitted[dof] + full[i]) - rigid[i]
           for i, dof in enumerate(FORCE_COLUMNS)}
    return pd.DataFrame(out, index=captive.index)


def _agreement(measured: np.ndarray, predicted: np.ndarray) -> dict[str, float | int | None]:
    """Pearson correlation and relative RMS error of one force on a set of conditions."""
    n = int(measured.size)
    if n == 0:
        return {"n": 0, "correlation": None, "relative_rms": None}
    rms = math.sqrt(float(np.mean(measured**2)))
    rel = math.sqrt(float(np.mean((predicted - measured) ** 2))) / rms if rms > 0 else None
    spread = n > 1 and np.std(measured) > 0 and np.std(predicted) > 0
    corr = float(np.corrcoef(measured, predicted)[0, 1]) if spread else None
    return {"n": n, "correlation": corr, "relative_rms": rel}


def _stats(table: pd.DataFrame, mask: np.ndarray) -> dict[str, dict]:
    return {dof: _agreement(table[f"{dof}_measured"].to_numpy()[mask],
                            table[f"{dof}_predicted"].to_numpy()[mask]) for dof in FORCE_COLUMNS}


@dataclass(frozen=True)
class ForceComparison:
    """An identified model's forces against captive tests (numbers only).

    Attributes
    ----------
    overall : dict
        ``{"X": {"n", "correlation", "relative_rms"}, "Y": ..., "N": ...}`` over all
        conditions going ahead (None where undefined, e.g. a correlation of a constant force).
    by_test : dict
        The same per test type (:func:`sindyship.captive.classify_tests`); the conditions
        going astern (u <= 0), which no other entry counts, are the test ``astern``: a model
        identified from a ship going ahead expands its forces about the design speed ahead.
    inside, outside : dict or None
        The same inside and outside the training envelope, going ahead; None when no envelope
        is known.
    envelope : dict or None
        ``{"v": [min, max], "r": [...], "delta": [...]}`` (v', r' over U0; delta [rad]).
    table : pandas.DataFrame
        Per condition: ``test``, ``beta`` [deg], ``r_nd``, ``delta_deg``, ``inside``,
        ``<F>_measured``, ``<F>_predicted`` (SI) for F in X, Y, N.
    """

    overall: dict[str, dict]
    by_test: dict[str, dict[str, dict]]
    inside: dict[str, dict] | None
    outside: dict[str, dict] | None
    envelope: dict[str, list[float]] | None
    table: pd.DataFrame = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (the per-condition table is left out)."""
        return {"overall": self.overall, "by_test": self.by_test, "inside": self.inside,
                "outside": self.outside, "envelope": self.envelope,
                "n_conditions": int(len(self.table))}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2, allow_nan=False)


def compare_forces(model: AbkowitzModel, captive: pd.DataFrame,
                   training_records: Sequence[Trajectory] | None = None) -> ForceComparison:
    """Compare a model's predicted captive forces with measured ones.

    Parameters
    ----------
    model : AbkowitzModel
    captive : pandas.DataFrame
        Captive conditions and measured ``X``, ``Y``, ``N`` (SI, the captive CSV convention).
    training_records : sequence of Trajectory, optional
        The model's training records, for the envelope; default ``model.info["envelope"]``
        when the model keeps one, else no envelope (``inside`` and ``outside`` are None).

    Returns
    -------
    ForceComparison

    Examples
    --------
    >>> from sindyship.captive import captive_tests
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> result = compare_forces(paper_model(kcs, "LS"), captive_tests(kcs, "rudder", points=9))
    >>> result.overall["Y"]["correlation"] > 0.99
    True
    """
    missing = [c for c in FORCE_COLUMNS if c not in captive.columns]
    if missing:
        raise SindyshipInputError(
            f"the captive table lacks the measured force '{missing[0]}'; give X, Y and N."
        )
    ship = model.ship
    check_captive_scale(captive, ship, reads_revolutions="n" in model.recorded_channels)
    predicted = model_captive_forces(model, captive)
    for dof in FORCE_COLUMNS:
        check_force_scale(dof, captive[dof].to_numpy(float), predicted[dof].to_numpy(float),
                          "the model predicts")
    values = _nondimensional(captive, ship)
    envelope = (training_envelope(training_records, ship) if training_records
                else model.info.get("envelope"))
    table = pd.DataFrame({
        "test": classify_tests(captive, ship),
        "beta": np.degrees(np.arctan2(-values["v"], values["du"] + 1.0)),
        "r_nd": values["r"], "delta_deg": np.degrees(values["delta"]),
    })
    inside = None
    if envelope is not None:
        inside = np.ones(len(table), dtype=bool)
        for name in ENVELOPE_VARIABLES:
            low, high = envelope[name]
            inside &= (values[name] >= low) & (values[name] <= high)
        table["inside"] = inside
    for dof in FORCE_COLUMNS:
        table[f"{dof}_measured"] = captive[dof].to_numpy(float)
        table[f"{dof}_predicted"] = predicted[dof].to_numpy()
    ahead = (table["test"] != "astern").to_numpy()
    tests = [t for t in ("static-drift", "rudder", "pure-yaw", "drift-yaw", "combined",
                         "straight", "astern") if np.any(table["test"] == t)]
    return ForceComparison(
        overall=_stats(table, ahead),
        by_test={t: _stats(table, (table["test"] == t).to_numpy()) for t in tests},
        inside=None if inside is None else _stats(table, inside & ahead),
        outside=None if inside is None else _stats(table, ~inside & ahead),
        envelope=None if envelope is None else {k: list(map(float, v))
                                                for k, v in envelope.items()},
        table=table,
    )


def forces_report(result) -> str:
    """Correlation and relative RMS error of X, Y, N per captive test type and envelope."""
    def cell(stats):
        corr, rel = stats["correlation"], stats["relative_rms"]
        c = "   n/a" if corr is None else f"{corr:6.3f}"
        r = "    n/a" if rel is None else f"{rel:7.3f}"
        return f"{c} {r}"

    astern = result.by_test.get("astern")
    rows = [("all ahead" if astern else "all", result.overall)]
    rows += [(test, stats) for test, stats in result.by_test.items() if test != "astern"]
    if result.inside is not None:
        rows += [("inside envelope", result.inside), ("outside envelope", result.outside)]
    lines = [f"{'conditions':<18}" + "".join(f"{dof + ' corr  relRMS':>16}"
                                             for dof in DOFS)]
    for name, stats in rows:
        lines.append(f"{name:<18}" + "".join(f"  {cell(stats[dof])}" for dof in DOFS))
    if astern:
        lines.append(f"{'astern (u <= 0)':<18}"
                     + "".join(f"  {cell(astern[dof])}" for dof in DOFS))
        lines.append(f"{astern['X']['n']} condition(s) going astern are compared apart: the "
                     "model's forces are expanded about its design speed ahead.")
    return "\n".join(lines)


def plot_captive_forces(result: ForceComparison, *, tests: Sequence[str] | None = None,
                        ax=None, labels: Mapping[str, str] | None = None):
    """Measured (markers) and predicted (lines) captive forces along each sweep.

    One row of X, Y, N panels per test type; points outside the training envelope are drawn
    hollow.  Drift-yaw grids draw one line per yaw rate.

    Parameters
    ----------
    result : ForceComparison
    tests : sequence of str, optional
        Test types to draw (default all in the result, ``straight`` left out).
    ax : array of matplotlib axes, optional
        ``len(tests)`` x 3 axes to draw in; a new figure otherwise.
    labels : dict, optional
        Legend labels ``{"measured": ..., "predicted": ...}``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    labels = {"measured": "captive (measured)", "predicted": "model", **(labels or {})}
    tests = [t for t in (tests or result.by_test) if t != "straight"]
    if not tests:
        raise SindyshipInputError("the comparison has no sweep to draw.")
    if ax is None:
        fig = Figure(figsize=(11.0, 2.8 * len(tests)), layout="constrained")
        axes = fig.subplots(len(tests), 3, squeeze=False)
    else:
        axes = np.asarray(ax, dtype=object).reshape(len(tests), 3)
        fig = axes[0, 0].figure
    table = result.table.assign(index=np.arange(len(result.table)))
    for row, test in enumerate(tests):
        rows = table[table["test"] == test]
        column, xlabel = _AXIS[test]
        lines = rows.groupby(np.round(rows["r_nd"], 9)) if test == "drift-yaw" else [(0, rows)]
        for col, dof in enumerate(FORCE_COLUMNS):
            axis = axes[row, col]
            for k, (_, part) in enumerate(lines):
                part = part.sort_values(column)
                x = part[column].to_numpy()
                hollow = ~part["inside"].to_numpy(bool) if "inside" in part else np.zeros(len(x),
                                                                                          bool)
                measured = part[f"{dof}_measured"].to_numpy() / 1e6
                axis.plot(x, part[f"{dof}_predicted"].to_numpy() / 1e6, color=f"C{k % 10}",
                          label=labels["predicted"] if k == 0 else None)
                axis.scatter(x[~hollow], measured[~hollow], s=14, color=f"C{k % 10}",
                             label=labels["measured"] if k == 0 else None)
                axis.scatter(x[hollow], measured[hollow], s=14, facecolors="none",
                             edgecolors=f"C{k % 10}")
            stats = result.by_test[test][dof]
            corr = stats["correlation"]
            axis.set_title(f"{test}: {dof}, r = {corr:.3f}" if corr is not None
                           else f"{test}: {dof}", fontsize=9)
            axis.set_xlabel(xlabel)
            axis.set_ylabel(_UNITS[dof])
            axis.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    return fig

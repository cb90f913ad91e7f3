"""Refine a fitted model's coefficients by the error of its flights (output error).

The fit of :func:`sindyship.identify.fit` is an equation-error fit: it matches the forces of
paper eq. 16 sample by sample, so it weighs every sample's force equally, whatever that force
does to a flight.  Small errors that a flight integrates (a steady yaw rate a tenth of a
percent off in a turning circle, a sway force that delays a zig-zag's overshoot) cost the
equation-error fit almost nothing and the flight ship lengths.  The output-error method of
flight-vehicle identification (Jategaonkar 2015, *Flight Vehicle System Identification*,
2nd ed., ch. 4) takes those flights as the measure instead: starting from the fitted
coefficients, Gauss-Newton steps (:func:`scipy.optimize.least_squares`, trust region)
minimise the differences between the records and the model's flights of them.

Here a flight is the one :func:`sindyship.evaluation.evaluate` judges: each record flown as
it was flown (a zig-zag closed loop from its execute, any other record replaying its rudder;
:mod:`sindyship.flights`), from its first row.  The differences are u', v', r' (Prime II,
over U0 and L/U0) and x/L, y/L at every ``sample_interval_s``; a sample after a flight
diverged counts as :data:`DIVERGED_RESIDUAL`.  Only the model's non-zero coefficients move
(the library and the sparsity pattern stay), each relative to its fitted value.  The Jacobian
is taken by forward differences, every perturbed coefficient set flown in one integration
(:func:`sindyship.flights.fly_coefficient_sets`).  A sample after a divergence costs the same
whatever the coefficients, so a model whose training flights diverge early has little to be
refined by: refine a fit that flies its training records, such as a ``prior`` fit.

Nothing pulls the refined coefficients toward the fitted ones: terms the records do not
separate can move far (check the forces, :mod:`sindyship.forces`, when the coefficients are
to be read as derivatives).

Nothing but the given records is flown: refine on training records only, and judge the
refined model on records it has not seen.

Examples
--------
>>> from sindyship.manoeuvres import Manoeuvre, fly
>>> from sindyship.mmg import MMGModel
>>> from sindyship.ships import load_ship
>>> from sindyship.identify import fit
>>> kcs = load_ship("kcs")
>>> runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=300)])
>>> refined = refine(fit(runs, kcs), runs, max_evaluations=10)
>>> report = refined.info["refined"]
>>> report["records"], report["cost_after"] < 0.5 * report["cost_before"]
(['zz20_20'], True)
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import least_squares

from .errors import SindyshipInputError
from .flights import fly_coefficient_sets, from_execute
from .model import AbkowitzModel
from .stability import straight_run_stability
from .trajectory import Trajectory

__all__ = ["DIVERGED_RESIDUAL", "refine", "flight_residuals"]

#: The residual of every channel at a sample after a flight diverged (non-dimensional: ten
#: ship lengths of position, ten times the design speed).
DIVERGED_RESIDUAL = 10.0
#: Forward-difference step of the Jacobian, relative to each coefficient.
RELATIVE_STEP = 1e-4
#: Scale of the relative coefficient changes for the trust region (``x_scale`` of
#: :func:`scipy.optimize.least_squares`): the first trial step may change the coefficients by
#: up to about their own size in norm.  A tenth needs more steps: from the KCS zig-zags, 10
#: evaluations refine the prior fit to a flight error of 0.076 with it, 0.023 with 1.
STEP_SCALE = 1.0


def flight_residuals(flights: Sequence[Trajectory], records: Sequence[Trajectory], L: float,
                     U0: float, sample_interval_s: float) -> np.ndarray:
    """Differences between flights and their records, non-dimensional, one vector.

    Per record, at the samples ``sample_interval_s`` apart from its first: u'/U0, v'/U0,
    r' L/U0, x/L and y/L of the flight minus the record's; :data:`DIVERGED_RESIDUAL` where the
    flight has no value (it diverged).
    """
    out = []
    for flown, record in zip(flights, records, strict=True):
        t = np.asarray(record.t, dtype=float)
        every = max(1, int(round(sample_interval_s / float(np.median(np.diff(t))))))
        rows = np.arange(0, len(t), every)
        for channel, scale in (("u", 1 / U0), ("v", 1 / U0), ("r", L / U0), ("x", 1 / L),
                               ("y", 1 / L)):
            error = (np.asarray(flown[channel])[rows] - np.asarray(record[channel])[rows]) * scale
            out.append(np.where(np.isfinite(error), error, DIVERGED_RESIDUAL))
    return np.concatenate(out)


def refine(model: AbkowitzModel, records: Sequence[Trajectory], *, max_evaluations: int = 8,
           sample_interval_s: float = 20.0, progress: bool = False) -> AbkowitzModel:
    """The model with its non-zero coefficients refined by the error of its flights.

    Parameters
    ----------
    model : AbkowitzModel
        A fitted model (its library, ship and rudder signal are kept).
    records : sequence of Trajectory
        The records to fly (the training records; never the ones the model is judged on).
    max_evaluations : int
        Most evaluations of the flight error (``max_nfev`` of
        :func:`scipy.optimize.least_squares`): every trial step flies the model once, and
        every accepted point adds a Jacobian, which flies it once per non-zero coefficient
        (all in one integration).  A trial step the error does not accept counts too, so a
        budget of 1 or 2 may refine nothing.
    sample_interval_s : float
        Seconds between the samples compared (:func:`flight_residuals`).
    progress : bool
        A progress bar over the evaluations on stderr.

    Returns
    -------
    AbkowitzModel
        The refined model.  ``info["refined"]`` holds the records flown, the cost (half the
        sum of squared residuals) before and after, the evaluations and Jacobians used, why
        the search stopped, the coefficient that moved most (relative to its fitted value;
        None when nothing moved), whether the refined model is stable in straight running
        (:func:`sindyship.stability.straight_run_stability`) and whether a refinement was
        refused for making a stable ``prior`` fit unstable (``refused_unstable``).  A
        refinement that does not lower the cost returns the fitted coefficients, and so does
        one that makes a straight-run-stable ``prior`` fit (``info["straight_run"]["stable"]``)
        unstable: its stability requirement holds for the refined model too.
    """
    if max_evaluations < 1:
        raise SindyshipInputError(
            f"max_evaluations must be at least 1, not {max_evaluations}; pass a positive "
            "number of flights."
        )
    if not math.isfinite(sample_interval_s) or sample_interval_s <= 0.0:
        raise SindyshipInputError(
            f"sample_interval_s must be a positive number of seconds, not {sample_interval_s}."
        )
    if not records:
        raise SindyshipInputError("refine needs at least one record to fly; pass the "
                                  "training records.")
    from tqdm.auto import tqdm

    flown = [from_execute(record) for record in records]
    keys = [(dof, term) for dof, terms in model.coefficients.items()
            for term, value in terms.items() if value != 0.0]
    fitted = np.array([model.coefficients[dof][term] for dof, term in keys])
    L, U0 = model.ship.L, model.ship.U0

    def coefficients(p: np.ndarray) -> dict:
        return dict(zip(keys, (fitted * (1.0 + p)).tolist(), strict=True))

    bar = tqdm(total=max_evaluations, desc="refining by flights", unit="flight",
               disable=not progress, leave=False)

    last: dict[bytes, np.ndarray] = {}  # the residuals of the last point flown

    def residuals(p: np.ndarray) -> np.ndarray:
        key = p.tobytes()
        if key not in last:
            (flights,) = fly_coefficient_sets(model, [coefficients(p)], flown)
            last.clear()
            last[key] = flight_residuals(flights, flown, L, U0, sample_interval_s)
        return last[key]

    def jacobian(p: np.ndarray) -> np.ndarray:
        base = residuals(p)  # scipy asks for the Jacobian where it has just flown
        steps = p + RELATIVE_STEP * np.eye(len(p))
        flights = fly_coefficient_sets(model, [coefficients(row) for row in steps], flown)
        bar.update(1)
        return np.column_stack([
            (flight_residuals(f, flown, L, U0, sample_interval_s) - base) / RELATIVE_STEP
            for f in flights])

    start = np.zeros(len(keys))
    before = residuals(start)
    cost_before = 0.5 * float(before @ before)
    if keys:
        result = least_squares(residuals, start, jac=jacobian, max_nfev=max_evaluations,
                               x_scale=STEP_SCALE)
        p, cost_after, stopped = result.x, float(result.cost), result.message
        evaluations, jacobians = int(result.nfev), int(result.njev or 0)
    else:
        p, cost_after, stopped = start, cost_before, "no active coefficient"
        evaluations = jacobians = 0
    bar.close()
    if not cost_after < cost_before:
        p, cost_after = start, cost_before
    info = dict(model.info)
    candidate = _with_changes(model, coefficients(p), info)
    stable = straight_run_stability(candidate).stable
    promised = bool(info.get("straight_run", {}).get("stable"))
    refused_unstable = promised and not stable
    if refused_unstable:  # a prior fit is straight-run stable; so is its refinement
        p, cost_after, stable = start, cost_before, True
        stopped = ("the refined model was unstable in straight running, which the fit it "
                   "started from is not; the fitted coefficients are kept")
        candidate = _with_changes(model, coefficients(p), info)
    if "straight_run" in info:  # the prior fit's record describes the model saved
        info["straight_run"] = {**info["straight_run"], "stable": stable}
    moved = int(np.argmax(np.abs(p))) if np.any(p) else None
    info["refined"] = {
        "records": [r.name for r in records], "sample_interval_s": float(sample_interval_s),
        "cost_before": cost_before, "cost_after": cost_after, "evaluations": evaluations,
        "jacobians": jacobians,
        "stopped": stopped,
        "largest_change": None if moved is None else {
            "coefficient": f"{keys[moved][0]}[{keys[moved][1]}]",
            "relative": float(p[moved])},
        "straight_run_stable": stable,
        "refused_unstable": refused_unstable,
    }
    return candidate


def _with_changes(model: AbkowitzModel, changes: dict, info: dict) -> AbkowitzModel:
    """The model with the coefficients ``{(dof, term): value}`` in place, and ``info``."""
    coefficients = {dof: dict(terms) for dof, terms in model.coefficients.items()}
    for (dof, term), value in changes.items():
        coefficients[dof][term] = value
    return AbkowitzModel(model.ship, model.library, coefficients, dict(model.optimizer),
                         model.rudder_signal, info)

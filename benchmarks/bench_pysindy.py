"""Side by side on the paper's experiment: a careful pysindy workflow against sindyship's.

Both identify the KCS from the protocol's 8 training manoeuvres (MMG, 1 Hz, 3200 s) and fly
the 3 held-out ones (docs/protocol.md); the metric is the mean distance between the tracks in ship
lengths (paper Table 10), ``sindyship.evaluation.distance_errors`` for every flight.

1. **pysindy, without sindyship's identification.**  A full cubic
   ``pysindy.PolynomialLibrary(degree=3)`` in the non-dimensional state u' = u/U0, v' = v/U0,
   r' = r L/U0 with the actual rudder angle delta as control input, time t' = t U0/L.
   Derivatives by pysindy's ``FiniteDifference(order=4)`` (a five-point stencil, one-sided at
   the two first and last samples: the same rule sindyship uses, so the derivative estimate is
   no difference between the workflows; pysindy's default second-order stencil is a variant).
   ``STLSQ`` with pysindy's defaults (ridge ``alpha=0.05``, unnormalised columns, an unbiased
   least-squares refit on the support) and its threshold chosen by leave-one-manoeuvre-out
   cross-validation over :data:`THRESHOLDS` (see :func:`cross_validate` for what it scores).
   The identified model is flown by a simulator written here (:func:`hand_fly`): scipy's
   ``solve_ivp`` (DOP853, rtol 1e-10) on [u', v', r', x/L, y/L, psi, delta] in t', the rudder
   servo of paper eq. 12-13, the zig-zag closed loop through a terminal heading event, and the
   divergence rule of docs/protocol.md as a terminal event.
2. **sindyship**: least squares on the paper's Abkowitz library (``sindyship.identify.fit``),
   and the library the iterative diagnosis reaches, run as ``sindyship reproduce`` runs it
   (``diagnose_iteratively(train, ship, test=test, max_rounds=3)``; its last round's model is
   reproduce's last diagnosed row), the recommended workflow (``sindyship fit``'s default: the
   ``prior`` fit on ``abkowitz-vr`` with the first effect the diagnosis names, refined by the
   error of its training flights, ``sindyship.refine.refine``: reproduce's last row), and the
   physics-consistent fit alone (``optimizer="prior"`` on the library ``abkowitz-vr``, as
   ``reproduce`` fits it), all flown by ``sindyship.evaluation.evaluate``.
3. A check that the hand-written simulator is not what makes the difference: fed the MMG
   accelerations it reproduces the MMG records, fed sindyship's identified models it
   reproduces sindyship's flights, each to better than 1e-3 L.

BLAS runs on one thread (pysindy's STLSQ hands BLAS non-contiguous arrays, which threads
slowly on a busy two-core machine).  Nothing is random.  Prints a table and saves
``benchmarks/results/pysindy.json``::

    python benchmarks/bench_pysindy.py [--no-variants]
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
import pysindy as ps
from scipy.integrate import solve_ivp
from threadpoolctl import threadpool_limits

from sindyship.evaluation import distance_errors, evaluate
from sindyship.flights import fly_like_batch
from sindyship.identify import fit
from sindyship.manoeuvres import Manoeuvre, fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.refine import refine
from sindyship.reproduce import METHOD_LIBRARIES, REFINE_EVALUATIONS
from sindyship.ships import Ship, load_ship
from sindyship.trajectory import Trajectory

OUT = Path(__file__).parent / "results" / "pysindy.json"
TEST_NAMES = ("tc15_port", "tc15_stbd", "zz10_10")
#: STLSQ thresholds tried (coefficients of the non-dimensional equations): 0 and 1e-4 ... 1.
THRESHOLDS = (0.0, *(float(v) for v in np.logspace(-4, 0, 17)))
#: pysindy's default STLSQ ridge.
ALPHA = 0.05
#: Accuracy order of pysindy's FiniteDifference (4: the five-point stencil).
FD_ORDER = 4
FEATURE_NAMES = ["u'", "v'", "r'", "delta"]
#: The pysindy workflow's choices, as saved with the results.
CHOICES = {
    "library": "pysindy.PolynomialLibrary(degree=3) over (u', v', r', delta): 35 terms per "
               "equation, delta the actual rudder angle as control input u",
    "time": "t' = t U0 / L",
    "derivatives": f"pysindy.FiniteDifference(order={FD_ORDER}): five-point central, one-sided "
                   "five-point at the two first and last samples of each manoeuvre (the rule "
                   "sindyship uses)",
    "optimizer": f"pysindy.STLSQ(threshold by CV, alpha={ALPHA}, normalize_columns=False, "
                 "unbias=True): pysindy's defaults but the threshold",
    "threshold_grid": "0 and 17 log-spaced values 1e-4 ... 1",
    "cv_score": "leave one of the 8 training manoeuvres out; per equation, sum over the "
                "left-out manoeuvres of (SINDy.predict - FiniteDifference derivative)^2 over "
                "the sum of squared derivatives of all 8; mean of du'/dt', dv'/dt', dr'/dt'; "
                "smallest score chosen (largest threshold among ties)",
    "simulator": "scipy solve_ivp DOP853 rtol 1e-10 atol 1e-12 on [u', v', r', x/L, y/L, psi, "
                 "delta] in t', servo of paper eq. 12-13, zig-zag reversed by a terminal "
                 "heading event, docs/protocol.md divergence rule as a terminal event",
}
#: Largest distance [L] at which the hand-written simulator counts as reproducing a flight.
SIMULATOR_TOLERANCE_L = 1e-3


# ---------------------------------------------------------------------------------------------
# Data
# ---------------------------------------------------------------------------------------------
def protocol_records(ship: Ship, duration: float = 3200.0):
    """The protocol's manoeuvres and their MMG records.

    Parameters
    ----------
    ship : Ship
    duration : float
        Record length [s] (the protocol's 3200 s; shorter for quick checks).

    Returns
    -------
    plan : dict
        ``{"train": [Manoeuvre], "test": [Manoeuvre]}``.
    train, test : list of Trajectory
        The MMG records of the plan.
    """
    plan = protocol_manoeuvres(duration)
    mmg = MMGModel(ship)
    return plan, fly(mmg, plan["train"]), fly(mmg, plan["test"])


def nondimensional(record: Trajectory, ship: Ship):
    """A record as the pysindy workflow sees it.

    Parameters
    ----------
    record : Trajectory
    ship : Ship

    Returns
    -------
    t : ndarray, shape (n,)
        t' = t U0 / L.
    x : ndarray, shape (n, 3)
        u' = u/U0, v' = v/U0, r' = r L/U0.
    u : ndarray, shape (n, 1)
        The actual rudder angle delta [rad].
    """
    L, U0 = ship.L, ship.U0
    x = np.column_stack([record["u"] / U0, record["v"] / U0, record["r"] * L / U0])
    return np.asarray(record.t) * U0 / L, x, np.asarray(record["delta"], dtype=float)[:, None]


# ---------------------------------------------------------------------------------------------
# The pysindy workflow
# ---------------------------------------------------------------------------------------------
def differentiation(fd_order: int = FD_ORDER) -> ps.FiniteDifference:
    """pysindy's finite differences of accuracy order ``fd_order`` along the time axis."""
    return ps.FiniteDifference(order=fd_order, axis=-2)


def fit_pysindy(records: Sequence[Trajectory], ship: Ship, threshold: float, *,
                alpha: float = ALPHA, fd_order: int = FD_ORDER) -> ps.SINDy:
    """Fit the cubic SINDy-with-control model to records.

    Parameters
    ----------
    records : sequence of Trajectory
        Training records, each a separate trajectory (differentiated separately).
    ship : Ship
    threshold : float
        STLSQ threshold.
    alpha : float
        STLSQ ridge.
    fd_order : int
        Accuracy order of the finite differences.

    Returns
    -------
    pysindy.SINDy
        Fitted on [u', v', r'] against t' with control delta.
    """
    data = [nondimensional(r, ship) for r in records]
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=threshold, alpha=alpha),
                     feature_library=ps.PolynomialLibrary(degree=3),
                     differentiation_method=differentiation(fd_order))
    with warnings.catch_warnings(), threadpool_limits(limits=1, user_api="blas"):
        # a large threshold empties an equation or stops STLSQ early: the score says so
        warnings.simplefilter("ignore")
        model.fit([d[1] for d in data], t=[d[0] for d in data], u=[d[2] for d in data],
                  feature_names=FEATURE_NAMES)
    return model


def cross_validate(records: Sequence[Trajectory], ship: Ship,
                   thresholds: Sequence[float] = THRESHOLDS, *, alpha: float = ALPHA,
                   fd_order: int = FD_ORDER) -> dict:
    """Leave-one-manoeuvre-out cross-validation of the STLSQ threshold.

    For every threshold and every record, the model is fitted on the other records and
    predicts the left-out record's derivatives (``SINDy.predict`` on its states and rudder)
    against that record's finite-difference derivatives (the same ``FiniteDifference``).  The
    score of an equation is the sum over the left-out records and their samples of the
    squared prediction error, divided by the sum of squares of that derivative over all
    records (a pooled, uncentred fraction of unexplained derivative signal); the score of a
    threshold is the mean over du'/dt', dv'/dt', dr'/dt'.  The chosen threshold has the
    smallest score (the largest threshold among equal ones).

    Parameters
    ----------
    records : sequence of Trajectory
        The training records (the folds).
    ship : Ship
    thresholds : sequence of float
    alpha : float
    fd_order : int

    Returns
    -------
    dict
        ``thresholds``, ``score`` (mean over the equations), ``score_per_equation`` (one list
        of three per threshold), ``active_terms`` (of the fit on every record), ``chosen``.
    """
    data = [nondimensional(r, ship) for r in records]
    fd = differentiation(fd_order)
    targets = [np.asarray(fd(x, t)) for t, x, _ in data]
    signal = np.sum(np.concatenate(targets) ** 2, axis=0)
    per_equation, active = [], []
    for threshold in thresholds:
        sse = np.zeros(3)
        for k, (_, x, u) in enumerate(data):
            rest = [r for j, r in enumerate(records) if j != k]
            model = fit_pysindy(rest, ship, threshold, alpha=alpha, fd_order=fd_order)
            sse += np.sum((np.asarray(model.predict(x, u=u)) - targets[k]) ** 2, axis=0)
        per_equation.append((sse / signal).tolist())
        full = fit_pysindy(records, ship, threshold, alpha=alpha, fd_order=fd_order)
        active.append(int(np.count_nonzero(full.coefficients())))
    score = np.mean(per_equation, axis=1)
    best = float(score.min())
    chosen = max(t for t, s in zip(thresholds, score, strict=True) if s <= best * (1 + 1e-9))
    return {"thresholds": [float(t) for t in thresholds], "score": score.tolist(),
            "score_per_equation": per_equation, "active_terms": active,
            "chosen": float(chosen)}


class PolynomialAccelerations:
    """The fitted SINDy right-hand side as a plain function of the non-dimensional state.

    Evaluates ``coefficients() @ prod(z ** powers_)`` with z = (u', v', r', delta): the same
    numbers as ``SINDy.predict`` (:meth:`max_difference_to_predict` checks it), without its
    per-call overhead.

    Parameters
    ----------
    model : pysindy.SINDy
        Fitted by :func:`fit_pysindy`.
    """

    def __init__(self, model: ps.SINDy):
        self.model = model
        self.powers = np.asarray(model.feature_library.powers_, dtype=float)
        self.coefficients = np.asarray(model.coefficients(), dtype=float)

    def __call__(self, up, vp, rp, delta, psi):
        """(du'/dt', dv'/dt', dr'/dt') at one state (psi is not used)."""
        z = np.array([up, vp, rp, delta])
        a = self.coefficients @ np.prod(z ** self.powers, axis=1)
        return a[0], a[1], a[2]

    def max_difference_to_predict(self, record: Trajectory, ship: Ship) -> float:
        """Largest difference to ``SINDy.predict`` over a record's samples."""
        _, x, u = nondimensional(record, ship)
        mine = np.array([self(*x[k], u[k, 0], 0.0) for k in range(len(x))])
        return float(np.max(np.abs(mine - np.asarray(self.model.predict(x, u=u)))))


class SIAccelerations:
    """An SI ``accelerations(u, v, r, delta, psi)`` (MMG or sindyship dynamics) in the
    non-dimensional form :func:`hand_fly` takes.

    Parameters
    ----------
    dynamics : object
        With ``accelerations(u, v, r, delta, psi)`` in SI units.
    ship : Ship
    """

    def __init__(self, dynamics, ship: Ship):
        self.dynamics = dynamics
        self.L, self.U0 = ship.L, ship.U0

    def __call__(self, up, vp, rp, delta, psi):
        """(du'/dt', dv'/dt', dr'/dt') at one state."""
        L, U0 = self.L, self.U0
        a_u, a_v, a_r = self.dynamics.accelerations(up * U0, vp * U0, rp * U0 / L, delta, psi)
        scale = L / U0**2
        return float(a_u) * scale, float(a_v) * scale, float(a_r) * (L / U0) ** 2


# ---------------------------------------------------------------------------------------------
# The hand-written simulator
# ---------------------------------------------------------------------------------------------
def _commanded(manoeuvre: Manoeuvre) -> tuple[float, float, int]:
    """(rudder [rad], check [rad, 0 for a constant command], first sign)."""
    if manoeuvre.kind in ("turning-circle", "straight"):
        return math.radians(manoeuvre.rudder), 0.0, 1
    if manoeuvre.kind == "zigzag":
        return (math.radians(manoeuvre.rudder), math.radians(manoeuvre.check),
                1 if manoeuvre.first_sign >= 0 else -1)
    raise ValueError(f"hand_fly flies turning circles, straight runs and zig-zags, "
                     f"not {manoeuvre.kind!r}")


def _right_hand_side(accel: Callable, ship: Ship, command: list) -> Callable:
    """d/dt' of [u', v', r', x/L, y/L, psi, delta] with the servo of paper eq. 12-13."""
    servo = ship.servo
    time_constant = servo.T_R  # in units of L/U0
    rate_max = math.radians(servo.rate_max) * ship.time_scale  # rad per unit t'
    delta_max = math.radians(servo.delta_max)

    def rhs(_t, y):
        up, vp, rp, _x, _y, psi, delta = y
        a_u, a_v, a_r = accel(up, vp, rp, delta, psi)
        target = min(max(command[0], -delta_max), delta_max)
        rate = min(max((target - delta) / time_constant, -rate_max), rate_max)
        c, s = math.cos(psi), math.sin(psi)
        return [a_u, a_v, a_r, up * c - vp * s, up * s + vp * c, rp, rate]

    return rhs


def _plausible(_t, y) -> float:
    """Positive while u' in (0, 2), |v'| <= 1 and |r'| <= 2 (docs/protocol.md, Divergence)."""
    return min(y[0], 2.0 - y[0], 1.0 - abs(y[1]), 2.0 - abs(y[2]))


_plausible.terminal = True
_plausible.direction = -1


def hand_fly(accel: Callable, manoeuvre: Manoeuvre, ship: Ship, *, t=None, state0=None,
             rtol: float = 1e-10, atol: float = 1e-12) -> Trajectory:
    """Fly a manoeuvre with non-dimensional accelerations, independently of sindyship.

    ``solve_ivp`` (DOP853) integrates [u', v', r', x/L, y/L, psi, delta] in t' = t U0/L with
    the rudder servo of paper eq. 12-13 (``ship.servo``).  A turning circle or straight run
    holds its commanded angle from t = 0; a zig-zag commands +-A and is reversed when the
    heading change reaches the check angle (a terminal event, the integration restarted from
    there).  Leaving the plausible range (docs/protocol.md) is a terminal event too, and an
    integrator failure ends the flight: the flight has diverged at the first output sample
    after it and holds NaN from there.

    Parameters
    ----------
    accel : callable
        ``accel(u', v', r', delta, psi) -> (du'/dt', dv'/dt', dr'/dt')``.
    manoeuvre : Manoeuvre
        Its kind, rudder, check and first sign define the rudder programme.
    ship : Ship
    t : ndarray, optional
        Output times [s]; default ``manoeuvre.times``.
    state0 : array_like, optional
        Initial [u', v', r', x/L, y/L, psi, delta]; default the protocol's (u' = 1).
    rtol, atol : float
        Tolerances of ``solve_ivp``.

    Returns
    -------
    Trajectory
        SI columns as the MMG records, ``meta["diverged_at"]`` the divergence time or None.
    """
    t_s = np.asarray(manoeuvre.times if t is None else t, dtype=float)
    tp = t_s / ship.time_scale
    rudder, check, sign = _commanded(manoeuvre)
    command = [sign * rudder]
    y = np.array([1.0, 0, 0, 0, 0, 0, 0] if state0 is None else state0, dtype=float)
    psi0 = y[5]

    def heading_check(_t, state):
        return np.sign(command[0]) * (state[5] - psi0) - check

    heading_check.terminal = True
    heading_check.direction = 1
    events = [_plausible] + ([heading_check] if manoeuvre.kind == "zigzag" else [])
    rhs = _right_hand_side(accel, ship, command)
    out = np.full((7, len(tp)), np.nan)
    cmd = np.full(len(tp), np.nan)
    out[:, 0], cmd[0] = y, command[0]
    start, ended = tp[0], None
    with np.errstate(all="ignore"):
        while start < tp[-1] and ended is None:
            sol = solve_ivp(rhs, (start, tp[-1]), y, method="DOP853", rtol=rtol, atol=atol,
                            events=events, dense_output=True)
            inside = (tp > start) & (tp <= sol.t[-1])
            if inside.any():
                out[:, inside] = sol.sol(tp[inside])
                cmd[inside] = command[0]
            if sol.status == -1 or (sol.status == 1 and sol.t_events[0].size):
                ended = sol.t[-1]  # integrator failure or implausible state
            elif sol.status == 1:
                command[0] = -command[0]  # the heading reached the check angle
            start, y = sol.t[-1], sol.y[:, -1]
    return _as_trajectory(out, cmd, t_s, tp, ended, manoeuvre.label, ship)


def _as_trajectory(out, cmd, t_s, tp, ended, name, ship) -> Trajectory:
    """Hand-flown states in the records' SI layout, cut at the divergence."""
    diverged_at = None
    if ended is not None:
        after = np.flatnonzero(tp > ended)
        if after.size:
            diverged_at = float(t_s[after[0]])
            out[:, after[0]:] = np.nan
            cmd[after[0]:] = np.nan
    L, U0 = ship.L, ship.U0
    frame = pd.DataFrame({"t": t_s, "u": out[0] * U0, "v": out[1] * U0, "r": out[2] * U0 / L,
                          "x": out[3] * L, "y": out[4] * L, "psi": out[5], "delta": out[6],
                          "delta_c": cmd})
    return Trajectory(frame, name=name, meta={"diverged_at": diverged_at})


def track_distance(a: Trajectory, b: Trajectory, L: float) -> float:
    """Largest distance [L] between two flights' positions over the samples both have."""
    d = np.hypot(np.asarray(a["x"]) - b["x"], np.asarray(a["y"]) - b["y"]) / L
    return float(np.nanmax(d)) if np.isfinite(d).any() else math.nan


# ---------------------------------------------------------------------------------------------
# Workflows
# ---------------------------------------------------------------------------------------------
def run_pysindy(train, test, test_plan, ship, *, thresholds=THRESHOLDS, alpha=ALPHA,
                fd_order=FD_ORDER, threshold=None) -> dict:
    """The pysindy workflow: cross-validate the threshold, fit, fly the held-out records.

    Parameters
    ----------
    train, test : list of Trajectory
    test_plan : list of Manoeuvre
        The held-out manoeuvres (flown by :func:`hand_fly`).
    ship : Ship
    thresholds : sequence of float
        The cross-validation grid.
    alpha, fd_order
        STLSQ ridge and finite-difference order.
    threshold : float, optional
        Skip the cross-validation and use this threshold.

    Returns
    -------
    dict
        ``threshold``, ``cv`` (None with a given threshold), ``selection_s`` (the
        cross-validation), ``fit_s`` (the final fit),
        ``active_terms``, ``errors`` per held-out record, ``predict_check`` and
        ``coefficients`` (non-zero ones, per equation).
    """
    t0 = time.perf_counter()
    cv = None
    if threshold is None:
        cv = cross_validate(train, ship, thresholds, alpha=alpha, fd_order=fd_order)
        threshold = cv["chosen"]
    cv_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = fit_pysindy(train, ship, threshold, alpha=alpha, fd_order=fd_order)
    fit_s = time.perf_counter() - t0
    accel = PolynomialAccelerations(model)
    errors = {}
    for rec, manoeuvre in zip(test, test_plan, strict=True):
        flown = hand_fly(accel, manoeuvre, ship, t=rec.t)
        errors[rec.name] = distance_errors(flown, rec, ship.L)
    names = model.get_feature_names()
    coefficients = {f"d{lhs}/dt'": {n: float(c) for n, c in zip(names, row, strict=True) if c}
                    for lhs, row in zip(FEATURE_NAMES, model.coefficients(), strict=False)}
    return {"threshold": float(threshold), "alpha": alpha, "fd_order": fd_order, "cv": cv,
            "selection_s": cv_s if cv is not None else None, "fit_s": fit_s,
            "active_terms": int(np.count_nonzero(model.coefficients())), "errors": errors,
            "predict_check": accel.max_difference_to_predict(test[-1], ship),
            "coefficients": coefficients, "model": model}


def run_sindyship(train, test, ship, *, rounds: int = 3) -> dict:
    """sindyship's workflows: least squares on the Abkowitz library, the diagnosed library, the
    recommended workflow (``sindyship fit``'s default, the ``prior`` fit on ``abkowitz-vr``
    refined by the error of its training flights, :func:`sindyship.refine.refine`, with the
    first effect the diagnosis names) and the ``prior`` fit alone.

    The diagnosis runs as ``sindyship reproduce`` runs it (held-out records flown every round,
    never used to choose); its last round's model is reproduce's last diagnosed row, and the
    recommended model (refined on the training records only) reproduce's last row.

    Parameters
    ----------
    train, test : list of Trajectory
    ship : Ship
    rounds : int
        ``max_rounds`` of the diagnosis (reproduce's 3).

    Returns
    -------
    dict
        ``{"ls": {...}, "diagnosed": {...}, "refined": {...}, "prior": {...}}``, each with
        ``library``, ``fit_s`` (one fit of the final library; the recommended model's fit
        and refinement), ``selection_s`` (the diagnosis; None for the others),
        ``active_terms``, ``errors`` (``evaluate`` on the held-out records) and ``model``.
    """
    from sindyship.diagnose import diagnose_iteratively

    t0 = time.perf_counter()
    ls = fit(train, ship)
    ls_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    prior = fit(train, ship, library=METHOD_LIBRARIES["prior"], optimizer="prior")
    prior_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    iterative = diagnose_iteratively(train, ship, test=test, max_rounds=rounds)
    diagnosis_s = time.perf_counter() - t0
    final = iterative.rounds[-1].diagnosis.model
    t0 = time.perf_counter()
    refit = fit(train, ship, library=final.library)
    refit_s = time.perf_counter() - t0
    refit_difference = max(abs(refit.coefficients[d][k] - c)
                           for d, terms in final.coefficients.items() for k, c in terms.items())
    t0 = time.perf_counter()
    recommended = fit(train, ship, library=METHOD_LIBRARIES["prior"],
                      effects=iterative.added[:1], optimizer="prior")
    refined = refine(recommended, train, max_evaluations=REFINE_EVALUATIONS)
    refine_s = time.perf_counter() - t0
    out = {}
    for key, model, fit_s, selection_s in (("ls", ls, ls_s, None),
                                           ("diagnosed", final, refit_s, diagnosis_s),
                                           ("refined", refined, refine_s, diagnosis_s),
                                           ("prior", prior, prior_s, None)):
        out[key] = {"library": model.library.name, "fit_s": fit_s, "selection_s": selection_s,
                    "active_terms": int(sum(model.n_active().values())),
                    "errors": evaluate(model, test), "model": model}
    out["diagnosed"].update({
        "added": iterative.added, "stopped": iterative.stopped,
        "selection_note": "diagnose_iteratively as reproduce runs it (held-out records flown "
                          "every round); fit_s refits the final library, max coefficient "
                          "difference to the diagnosis' model in refit_difference",
        "refit_difference": refit_difference})
    out["refined"]["refinement"] = refined.info["refined"]
    return out


def simulator_check(test, test_plan, ship, models: dict) -> dict:
    """How closely the hand-written simulator reproduces the flights it should.

    Parameters
    ----------
    test : list of Trajectory
        MMG records.
    test_plan : list of Manoeuvre
    ship : Ship
    models : dict
        Name to a sindyship fitted model; each is flown by sindyship
        (``fly_like_batch``) and by :func:`hand_fly` with its accelerations.

    Returns
    -------
    dict
        Per source (``"mmg"`` and every model) the largest track distance [L] per record, and
        ``passed``: every distance below :data:`SIMULATOR_TOLERANCE_L`.
    """
    sources = {"mmg": (MMGModel(ship), test)}
    for name, model in models.items():
        dynamics = model.dynamics()
        sources[name] = (dynamics, fly_like_batch(dynamics, test))
    out: dict = {}
    for name, (dynamics, reference) in sources.items():
        accel = SIAccelerations(dynamics, ship)
        out[name] = {}
        for rec, flown, manoeuvre in zip(test, reference, test_plan, strict=True):
            hand = hand_fly(accel, manoeuvre, ship, t=rec.t)
            same_end = hand.meta["diverged_at"] == flown.meta.get("diverged_at")
            out[name][rec.name] = track_distance(hand, flown, ship.L) if same_end else math.inf
    worst = max(v for per in out.values() for v in per.values())
    return {"max_distance_L": out, "worst_L": worst, "tolerance_L": SIMULATOR_TOLERANCE_L,
            "passed": bool(worst < SIMULATOR_TOLERANCE_L)}


def beats(ours: dict, theirs: dict) -> bool:
    """Whether flight ``ours`` is better than ``theirs`` (docs/protocol.md's comparison).

    A flight that diverges where the other does not (or earlier) is the worse one, whatever
    the means; two complete flights of one record cover the same samples and compare by mean.

    Parameters
    ----------
    ours, theirs : dict
        :func:`sindyship.evaluation.distance_errors` of two flights of one record.
    """
    a, b = ours["diverged_at_s"], theirs["diverged_at_s"]
    if a != b:
        return a is None or (b is not None and a > b)
    return bool(ours["mean_distance_L"] < theirs["mean_distance_L"])


# ---------------------------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------------------------
def _cell(err: dict) -> str:
    text = f"{err['mean_distance_L']:.3f}"
    if err["diverged_at_s"] is not None:
        text += f" (div {err['diverged_at_s']:.0f} s)"
    return text


def format_table(result: dict) -> str:
    """The readable table of :func:`run`'s result."""
    rows = [("workflow", "terms", "select [s]", "fit [s]", *TEST_NAMES)]
    every = [(f"{key}: {row['label']}", row) for key, row in result["workflows"].items()]
    every.insert(4, ("recommended sindyship beats pysindy", None))
    every += [(f"variant: {v['label']}", v) for v in result.get("variants", [])]
    for label, row in every:
        if row is None:
            rows.append((label, "", "", "",
                         *("yes" if result["beats"][n] else "no" for n in TEST_NAMES)))
            continue
        selection = "-" if row["selection_s"] is None else f"{row['selection_s']:.1f}"
        rows.append((label, str(row["active_terms"]), selection, f"{row['fit_s']:.2f}",
                     *(_cell(row["errors"][n]) for n in TEST_NAMES)))
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    lines = ["Held-out mean distance between tracks [ship lengths], 3200 s each"]
    for k, r in enumerate(rows):
        lines.append("  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                               for i, (c, w) in enumerate(zip(r, widths, strict=True))))
        if k == 0:
            lines.append("-" * len(lines[-1]))
    cv = result["workflows"]["pysindy"]["cv"]
    lines.append(f"\npysindy STLSQ threshold by leave-one-manoeuvre-out CV: {cv['chosen']:g} "
                 f"(alpha {ALPHA}, FiniteDifference(order={FD_ORDER}))")
    gain = 1.0 - min(cv["score"]) / cv["score"][0]
    lines.append(f"  the chosen threshold scores {100 * gain:.1f} % below threshold 0 "
                 "(least squares on the cubic library)")
    lines.append("  threshold   CV score   terms")
    for t, s, n in zip(cv["thresholds"], cv["score"], cv["active_terms"], strict=True):
        mark = "  <- chosen" if t == cv["chosen"] else ""
        lines.append(f"  {t:9.2e}  {s:9.3e}  {n:6d}{mark}")
    check = result["simulator_check"]
    lines.append(f"\nHand-written simulator against sindyship's integrator: worst track distance "
                 f"{check['worst_L']:.1e} L (tolerance {check['tolerance_L']:g} L): "
                 + ("passed" if check["passed"] else "FAILED"))
    for name, per in check["max_distance_L"].items():
        lines.append(f"  {name:10s} " + ", ".join(f"{k} {v:.1e}" for k, v in per.items()))
    return "\n".join(lines)


def _variants(train, test, test_plan, ship) -> list[dict]:
    """The pysindy workflow with one choice changed, each with its own cross-validation."""
    out = []
    for label, kwargs in (
        ("pysindy, threshold 0 (least squares on the cubic library)", {"threshold": 0.0}),
        ("pysindy, FiniteDifference(order=2) (pysindy's default)", {"fd_order": 2}),
        ("pysindy, STLSQ alpha=1e-6 (almost no ridge)", {"alpha": 1e-6}),
    ):
        run_ = run_pysindy(train, test, test_plan, ship, **kwargs)
        out.append({"label": label, "threshold": run_["threshold"],
                    "active_terms": run_["active_terms"], "fit_s": run_["fit_s"],
                    "selection_s": run_["selection_s"], "errors": run_["errors"],
                    "cv_score": None if run_["cv"] is None else run_["cv"]["score"]})
    return out


def run(variants: bool = True) -> dict:
    """The whole comparison; JSON-ready (models dropped)."""
    start = time.perf_counter()
    ship = load_ship("kcs")
    plan, train, test = protocol_records(ship)
    assert tuple(r.name for r in test) == TEST_NAMES
    with threadpool_limits(limits=1, user_api="blas"):
        pysindy_run = run_pysindy(train, test, plan["test"], ship)
        sindyship_run = run_sindyship(train, test, ship)
        check = simulator_check(test, plan["test"], ship,
                                {k: v["model"] for k, v in sindyship_run.items()})
        extra = _variants(train, test, plan["test"], ship) if variants else []
    pysindy_run.pop("model")
    pysindy_run["label"] = (f"cubic PolynomialLibrary + STLSQ (threshold "
                            f"{pysindy_run['threshold']:g} by CV)")
    for key, row in sindyship_run.items():
        row.pop("model")
        row["label"] = {"ls": "least squares, ", "diagnosed": "least squares, diagnosed ",
                        "refined": "prior + first diagnosed effect, refined by its training "
                                   "flights (the default fit), ",
                        "prior": "least squares with the ship's prior, "}[key] + row["library"]
    recommended = sindyship_run["refined"]
    return {
        "workflows": {"pysindy": pysindy_run, "sindyship_ls": sindyship_run["ls"],
                      "sindyship_diagnosed": sindyship_run["diagnosed"],
                      "sindyship_refined": recommended,
                      "sindyship_prior": sindyship_run["prior"]},
        "recommended": "sindyship_refined",
        "beats": {n: beats(recommended["errors"][n], pysindy_run["errors"][n])
                  for n in TEST_NAMES},
        "beats_ls": {n: beats(sindyship_run["ls"]["errors"][n], pysindy_run["errors"][n])
                     for n in TEST_NAMES},
        "choices": CHOICES,
        "pysindy_threshold": pysindy_run["threshold"],
        "pysindy_cv": pysindy_run["cv"],
        "simulator_check": check,
        "variants": extra,
        "seconds": time.perf_counter() - start,
    }


def main() -> None:
    """Run, print the table and save ``benchmarks/results/pysindy.json``."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--no-variants", action="store_true",
                        help="skip the pysindy variants (threshold 0, order 2, alpha 1e-6)")
    args = parser.parse_args()
    result = run(variants=not args.no_variants)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2, default=_json_default) + "\n")
    print(format_table(result))
    print(f"\n{result['seconds']:.0f} s; saved {OUT}")


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON-serialisable: {type(value).__name__}")


if __name__ == "__main__":
    main()

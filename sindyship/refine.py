"""Refine a fitted model's coefficients by the error of its flights (regularised output error,
by multiple shooting).

The fit of :func:`sindyship.identify.fit` is an equation-error fit: it matches the forces of
paper eq. 16 sample by sample, so it weighs every sample's force equally, whatever that force
does to a flight.  Small errors that a flight integrates (a steady yaw rate a tenth of a
percent off in a turning circle, a sway force that delays a zig-zag's overshoot) cost the
equation-error fit almost nothing and the flight ship lengths.  The output-error method of
flight-vehicle identification (Jategaonkar 2015, *Flight Vehicle System Identification*,
2nd ed., ch. 4) takes those flights as the measure instead: starting from the fitted
coefficients, Levenberg-Marquardt steps (:func:`sindyship.levenberg_marquardt`) minimise the
differences between the records and the model's flights of them.

The flights are those of multiple shooting (:mod:`sindyship.shooting`): every record from its
flight start (a zig-zag or a turn from its rudder execute; a manual approach is never flown)
cut into segments of ``segment_s`` seconds, each flown from the state measured at its start
with the recorded rudder, and compared in u', v', r' (over U0 and L/U0), x/L, y/L and psi at
every step.  A model whose whole flights would diverge still gives a gradient on every
segment, and the Jacobian is exact: the sensitivities are integrated beside the flights.
Only the model's non-zero coefficients move (the library and the sparsity pattern stay).

A fit keeps its own objective inside the refinement (regularised output error): the force
error of eq. 16 and, for a ``prior`` fit, the prior of :mod:`sindyship.priors`, weighted by
``prior_weight`` against the mean squared flight error.  Combinations of coefficients the
flights cannot tell apart stay where the fit put them: for a ``prior`` fit, where the prior
put them, so the refined model's forces keep agreeing with captive tests.  With
``prior_weight=0`` the flights alone decide, and terms the records do not separate can move
far (check the forces, :mod:`sindyship.forces`, before reading them as derivatives).

Nothing but the given records is flown: refine on training records only, and judge the
refined model on records it has not seen.

Examples
--------
>>> from sindyship.manoeuvres import Manoeuvre, fly
>>> from sindyship.mmg import MMGModel
>>> from sindyship.ships import load_ship
>>> from sindyship.identify import fit
>>> kcs = load_ship("kcs")
>>> runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=300),
...                            Manoeuvre("turning-circle", rudder=-20, duration=300)])
>>> refined = refine(fit(runs, kcs), runs, max_evaluations=10)
>>> report = refined.info["refined"]
>>> report["records"], report["cost_after"] < 0.5 * report["cost_before"]
(['zz20_20', 'tc20_port'], True)
"""

from __future__ import annotations

import functools
import math
import numbers
import sys
from collections.abc import Sequence

import numpy as np

from .errors import SindyshipInputError
from .hybrid import model_design
from .levenberg_marquardt import levenberg_marquardt
from .model import AbkowitzModel
from .optimizers import one_blas_thread
from .refine_checks import carries_over, turns_kept
from .refine_problem import DIVERGED_RESIDUAL, ShootingProblem, cost, penalty_rows
from .shooting import active_keys
from .stability import straight_run_stability
from .trajectory import Trajectory

__all__ = ["DIVERGED_RESIDUAL", "PRIOR_WEIGHT", "SEGMENT_TIMES", "default_segments",
           "force_change", "refine"]

#: Default lengths of the shooting segments, stage by stage, in units of L/U0 (for the KCS
#: 93, 279 and 838 s; for the KVLCC2 model 30, 89 and 267 s).
SEGMENT_TIMES = (5.0, 15.0, 45.0)
#: Relative fall of the cost below which a stage before the last stops (it only brings the
#: coefficients near enough for the next, longer segments), and the last one (converged: the
#: refined coefficients no longer move, whatever the machine's rounding).
STAGE_TOLERANCE = 1e-3
TOLERANCE = 1e-7
#: Fewest records a refinement is validated on (two halves of two records or more each).
VALIDATION_RECORDS = 4
#: Most a coefficient moves, relative to its fitted value (None: no bound).
RELATIVE_BOUND = None
#: Most evaluations of a stage before the last.
EARLY_EVALUATIONS = 5
#: How much faster than its unstable prior fit's a refined model's straight-run disturbance
#: may double before the refinement is refused (a margin, so that rounding never decides).
INSTABILITY_MARGIN = 1.25
#: Default weight of a ``prior`` fit's objective against the mean squared flight error.
PRIOR_WEIGHT = 0.01
#: Default most evaluations of the flight error.
MAX_EVALUATIONS = 60


def default_segments(ship, records: Sequence[Trajectory]) -> list[float | None]:
    """The default segment lengths [s], one stage each: :data:`SEGMENT_TIMES` times L/U0
    (None: whole flights), none longer than the longest record.

    Short segments first: every segment starts from a measured state, so a fit that flies
    far off still gives a gradient; then longer ones, which weigh the slow drifts a long
    flight integrates (a steady yaw rate a little off in a turn).  Whole flights, as
    :func:`sindyship.evaluation.evaluate` flies them (a zig-zag closed loop), are a stage of
    their own on request (``segment_s="whole"``): on the KCS they fly the held-out turns
    closer from the zig-zags alone and bend the forces of captive tests further
    (``benchmarks/bench_captive.py``).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> [round(s, 1) for s in default_segments(load_ship("kcs"), [])]
    [93.1, 279.4, 838.2]
    """
    longest = max((r.duration for r in records), default=math.inf)
    out = []
    for factor in SEGMENT_TIMES:
        length = None if factor is None else factor * ship.time_scale
        if length is not None and out and length > longest:
            continue
        out.append(length)
    return out


def _stages(ship, records, segment_s) -> list[float | None]:
    """The refinement's stages: the default ones, or those ``segment_s`` names (seconds, or
    ``"whole"`` for whole flights; one, or a sequence)."""
    if segment_s is None:
        return default_segments(ship, records)
    given = [segment_s] if isinstance(segment_s, str | numbers.Real) else list(segment_s)
    return [None if value == "whole" else float(value) for value in given]


def _check_arguments(model, records, max_evaluations, segment_s, prior_weight) -> None:
    if not isinstance(model, AbkowitzModel):
        raise TypeError(f"model must be an AbkowitzModel (sindyship.fit makes one), not "
                        f"{type(model).__name__}.")
    if not records:
        raise SindyshipInputError("refine needs at least one record to fly; pass the "
                                  "training records.")
    if isinstance(max_evaluations, bool) or not isinstance(max_evaluations, numbers.Integral) \
            or not 1 <= max_evaluations <= 10_000:
        raise ValueError(f"max_evaluations must be a whole number from 1 to 10000, not "
                         f"{max_evaluations!r}.")
    stages = [] if segment_s is None else (
        [segment_s] if isinstance(segment_s, str | numbers.Real) else list(segment_s))
    for value in stages:
        if value != "whole" and not _positive(value):
            raise ValueError(f"segment_s must be a positive number of seconds or 'whole' (or a "
                             f"list of them), not {segment_s!r}.")
    if not stages and segment_s is not None:
        raise ValueError("segment_s must name at least one stage.")
    if prior_weight is not None and not (_positive(prior_weight) or prior_weight == 0):
        raise ValueError(f"prior_weight must be a non-negative number, not {prior_weight!r}.")


def _refused_validation(check: dict) -> str:
    """Why the refinement was refused: a divergence first (the mean distances of a diverged
    flight cover only the time before it, and can read as closer), else the distances."""
    if check.get("half_refused"):
        return (f"refined on every other record ({', '.join(check['refined_on'])}), the "
                f"refinement kept the fitted coefficients there ({check['half_refused']}), so "
                "it cannot be shown to carry over to the others; the fitted coefficients are "
                "kept")
    if check["diverged"]:
        return ("refined on half of the records, the model diverged on "
                f"{', '.join(check['diverged'])} of the other half, which the fit flies longer "
                "(over the time both flights cover, "
                f"{check['ratio']:.3f} times as far off as fitted); the fitted coefficients are "
                "kept")
    return ("refined on half of the records, the model flew the other half "
            f"{check['ratio']:.3f} times as far off as fitted ({check['why']}); the fitted "
            "coefficients are kept")


def _positive(value) -> bool:
    return (not isinstance(value, bool) and isinstance(value, numbers.Real)
            and math.isfinite(value) and value > 0)


# one BLAS thread: BLAS threads spinning between products take the cores the segments fly on
# (measured on two cores: the protocol's refinement 6.1 -> 4.2 s, and 44 -> 7 s beside two
# busy processes)
@one_blas_thread
def refine(model: AbkowitzModel, records: Sequence[Trajectory], *,
           max_evaluations: int = MAX_EVALUATIONS, segment_s: float | None = None,
           prior_weight: float | None = None, progress: bool = False,
           n_jobs: int | None = 1, validate: bool = True) -> AbkowitzModel:
    """The model with its non-zero coefficients refined by the error of its flights.

    Parameters
    ----------
    model : AbkowitzModel
        A fitted model (its library, ship and rudder signal are kept).
    records : sequence of Trajectory
        The records to fly (the training records; never the ones the model is judged on).
        For a ``prior`` fit, the records it was fitted on (its objective is rebuilt on them).
    max_evaluations : int
        Most evaluations of the flight error; the search stops earlier once it converges
        (:func:`sindyship.levenberg_marquardt.levenberg_marquardt`).  Every accepted step
        adds a Jacobian, which costs a few flights of the segments whatever the number of
        coefficients.
    segment_s : float, "whole" or sequence of them, optional
        Length of the shooting segments [s], or ``"whole"`` for whole flights as
        :func:`sindyship.evaluation.evaluate` flies them; a sequence is a stage each, each
        started from the coefficients the last ended with; default the stages of
        :func:`default_segments`.
    prior_weight : float, optional
        Weight of the fit's own objective (the force error of eq. 16 over the targets' sum
        of squares, and the prior of a ``prior`` fit) against the mean squared flight error;
        default :data:`PRIOR_WEIGHT`; 0 refines by the flights alone.
    progress : bool
        Report each step on stderr (the flight error, the step's number).
    n_jobs : int or None
        joblib workers the segments are split across (``None``: from a
        ``joblib.parallel_config`` block, such as a Dask cluster's); the result does not
        depend on it.
    validate : bool
        With :data:`VALIDATION_RECORDS` records or more, check that refining carries over to
        flights it was not refined on (:func:`sindyship.refine_checks.carries_over`: fitted and
        refined on every other record by name, the model must fly the rest closer than its fit
        alone does), else keep the fitted coefficients; checked before the refinement on all
        records, which a refused check spares.  Trajectories
        with disturbances the library lacks (gusts, noise, roll) can be matched by terms they
        do not pin down, which then fly other manoeuvres worse.

    Returns
    -------
    AbkowitzModel
        The refined model.  ``info["refined"]`` holds the records flown, the segments, each
        stage's search (none where the validation refused the refinement), the cost (half the
        sum of squared residuals, flights and penalty) before and after, the flight error alone
        (root mean square over the compared samples) before and after, the evaluations and
        Jacobians used, why the search stopped and whether it converged, the
        coefficient that moved most for its size, how far each equation's force moved
        (:func:`force_change`), whether the refined model is stable in straight running
        (:func:`sindyship.stability.straight_run_stability`) and whether a refinement was
        refused for making a stable ``prior`` fit unstable, or an unstable one more unstable
        (a disturbance doubling more than :data:`INSTABILITY_MARGIN` times as fast;
        ``refused_unstable``).  A
        refinement that does not lower the cost returns the fitted coefficients, and so does
        one that would lose the hard-over turns the fit flies (``refused_turning`` says why:
        a turning circle at the rudder limit that diverges, or whose tactical diameter moves
        by more than a factor :data:`sindyship.refine_checks.TURN_CHECK_FACTOR`).
    """
    from .arguments import as_records, check_records

    records = as_records(records, allow_empty=True)
    _check_arguments(model, records, max_evaluations, segment_s, prior_weight)
    records = check_records(records, model.ship)
    settings = {"max_evaluations": int(max_evaluations), "segment_s": segment_s,
                "prior_weight": PRIOR_WEIGHT if prior_weight is None else float(prior_weight),
                "progress": "refining by flights" if progress else None, "n_jobs": n_jobs}
    check = None
    if validate and len(records) >= VALIDATION_RECORDS and active_keys(model):
        # checked first: a refinement that would be refused is never made on all records
        if progress:
            print("checking that refining carries over: fitted and refined on every other "
                  "record, the model flies the rest", file=sys.stderr, flush=True)
        check = carries_over(model, records, lambda fitted, half: _refined(
            fitted, half, **{**settings, "progress": "checking on every other record"
                             if progress else None}))
    if check is not None and not check["accepted"]:
        last = _stages(model.ship, records, segment_s)[-1]
        kept = _refined(model, records, **{**settings, "max_evaluations": 0, "progress": None,
                                           "segment_s": "whole" if last is None else last})
        kept.info["refined"].update(
            stages=[],  # its fitted flights were flown once, to report them; no stage ran
            stopped=_refused_validation(check),
            refused_validation=True, validation=check)
        if "straight_run" in model.info:  # the fit's own record, as it was
            kept.info["straight_run"] = dict(model.info["straight_run"])
        return kept
    refined = _refined(model, records, **settings)
    if check is not None:
        refined.info["refined"]["validation"] = check
    return refined


def _refined(model: AbkowitzModel, records, *, max_evaluations: int, segment_s,
             prior_weight: float, progress: str | None, n_jobs) -> AbkowitzModel:
    """The refinement itself (:func:`refine` without its validation); ``progress`` begins
    the line each accepted step writes on stderr (None: silent)."""
    stages = _stages(model.ship, records, segment_s)
    problems = _design(model, records)  # the penalty's and the report's design
    penalty = penalty_rows(model, problems) if prior_weight > 0 else None
    p, done, evaluations, jacobians, problem = _search_stages(
        model, records, stages, penalty, max_evaluations, prior_weight, progress, n_jobs)
    last = done[-1]
    cost_before, cost_after = last["cost_fitted"], last["cost_after"]
    if not cost_after < cost_before:
        p, cost_after = np.zeros_like(p), cost_before
    flight_before, flight_after = last["flight_rms_fitted"], last["flight_rms_after"]
    stopped, converged = last["stopped"], last["converged"]
    info = dict(model.info)
    candidate = _with_changes(model, problem.coefficients(p), info)
    after = straight_run_stability(candidate)
    stable, moved = after.stable, bool(np.any(p))  # the checks judge a model that moved
    promised = bool(info.get("straight_run", {}).get("stable"))
    doublings = None if promised or "straight_run" not in info or not moved \
        else _more_unstable(model, after)
    refused_unstable = moved and ((promised and not stable) or doublings is not None)
    turns = None if refused_unstable or not moved else turns_kept(model, candidate, records)
    if refused_unstable:  # a prior fit's straight running is never made less stable
        stopped = ("the refined model was unstable in straight running, which the fit it "
                   "started from is not; the fitted coefficients are kept") if promised else (
            f"in straight running a disturbance of the refined model doubles in "
            f"{doublings[1]:.3g} L/U0, of the fit it started from in {doublings[0]:.3g} L/U0 (an "
            "unstable prior fit is not refined to a more unstable model); the fitted "
            "coefficients are kept")
    elif turns is not None:  # it flew hard-over turns it can no longer fly
        stopped = f"the refined model {turns}; the fitted coefficients are kept"
    if refused_unstable or turns is not None:  # the fitted coefficients, as they were
        p, cost_after, flight_after = np.zeros_like(p), cost_before, flight_before
        candidate = _with_changes(model, problem.coefficients(p), info)
        stable = promised if refused_unstable else straight_run_stability(candidate).stable
    if "straight_run" in info:  # the prior fit's record describes the model saved
        info["straight_run"] = {**info["straight_run"], "stable": stable}
    largest = int(np.argmax(np.abs(p))) if np.any(p) else None
    keys = problem.keys
    info["refined"] = {
        "method": "multiple shooting", "records": [r.name for r in records],
        "segment_s": last["segment_s"], "segments": last["segments"], "stages": done,
        "prior_weight": float(prior_weight) if penalty else 0.0,
        "cost_before": cost_before, "cost_after": cost_after,
        "flight_rms_before": flight_before, "flight_rms_after": flight_after,
        "evaluations": evaluations, "jacobians": jacobians, "stopped": stopped,
        "converged": bool(converged),
        "largest_change": None if largest is None else {
            "coefficient": f"{keys[largest][0]}[{keys[largest][1]}]",
            "relative": float(p[largest])},
        "force_change": None if largest is None else force_change(
            model, candidate, records, problems=None if "captive" in info else problems),
        "straight_run_stable": stable,
        "refused_unstable": refused_unstable,
        "refused_turning": turns,
        "refused_validation": False,
    }
    candidate.info = info
    return candidate


def _more_unstable(fitted: AbkowitzModel, after) -> tuple[float, float] | None:
    """The doubling times [L/U0] of a straight-run disturbance of an unstable fit and its
    refinement when the refinement doubles more than :data:`INSTABILITY_MARGIN` times as
    fast, else None (also where either has no doubling time: a zero or undefined growth
    rate).  The records rarely hold the long straight runs that would pin the growth down,
    and a refinement that speeds it up trades the flights it was not refined on (a turn at
    another rudder angle, in other gusts) for the ones it was."""
    before = straight_run_stability(fitted)
    if before.stable or after.stable:
        return None
    slower, faster = before.doubling_time_L_over_U, after.doubling_time_L_over_U
    if slower is None or faster is None:
        return None
    return (slower, faster) if faster * INSTABILITY_MARGIN < slower else None


def _search_stages(model, records, stages, penalty, max_evaluations, prior_weight, progress,
                   n_jobs):
    """The Levenberg-Marquardt search stage by stage: the relative changes of the active
    coefficients, each stage's report, the evaluations and Jacobians, the last problem."""
    p = np.zeros(len(active_keys(model)))
    done, budget, evaluations, jacobians = [], int(max_evaluations), 0, 0
    # a stage before the last takes at most its share of half the evaluations
    early = max(2, min(EARLY_EVALUATIONS,
                       int(max_evaluations) // (2 * max(len(stages) - 1, 1))))
    for stage, length in enumerate(stages):
        final = stage == len(stages) - 1
        problem = ShootingProblem(model, list(records), length, float(prior_weight), penalty,
                                  n_jobs)
        start_cost = cost(problem.residuals(np.zeros_like(p)))
        start_rms = problem.flight_rms
        entry_cost = cost(problem.residuals(p))
        entry_rms = problem.flight_rms
        problem.reported_cost = entry_cost
        allowed = budget if final else min(budget, early)
        search = levenberg_marquardt(problem.residuals, problem.normal, p,
                                     max_evaluations=max(allowed, 1),
                                     tolerance=TOLERANCE if final else STAGE_TOLERANCE,
                                     bound=RELATIVE_BOUND,
                                     on_step=functools.partial(problem.report, label=progress)
                                     if progress else None) \
            if len(p) and allowed > 0 else None
        if search is not None and search.cost < entry_cost:
            p = search.x
        budget -= 0 if search is None else search.evaluations
        evaluations += 0 if search is None else search.evaluations
        jacobians += 0 if search is None else search.jacobians
        cost_after = cost(problem.residuals(p))  # and problem.flight_rms at p
        done.append({"segment_s": length, "segments": problem.n_segments,
                     "cost_fitted": start_cost, "flight_rms_fitted": start_rms,
                     "cost_before": entry_cost, "cost_after": cost_after,
                     "flight_rms_before": entry_rms, "flight_rms_after": problem.flight_rms,
                     "evaluations": 0 if search is None else search.evaluations,
                     "stopped": "no active coefficient" if not len(p) else (
                         "no evaluations left" if search is None else search.message),
                     "converged": search is not None and search.converged})
    return p, done, evaluations, jacobians, problem


def _design(model, records, *, captive: bool = True) -> dict:
    """The regression problems of eq. 16 on ``records``, made as the model's fit made them
    (with its captive rows, :func:`sindyship.hybrid.model_design`, unless ``captive`` is
    False)."""
    return model_design(model, records, captive=captive)


def force_change(fitted: AbkowitzModel, refined: AbkowitzModel, records, *,
                 problems: dict | None = None) -> dict:
    """How far the refinement moved each equation's force: the rms over the records (their
    design, ``problems``, when at hand) of the force the coefficients' changes add, over the
    measured force's (eq. 16's target), e.g. ``{"X": 0.012, "Y": 0.034, "N": 0.05}``; None
    where the records hold almost no force (under a thousandth of the rms of the fit's
    largest term, as on a straight run).  Unlike a coefficient's relative change, it stays
    small where a small term, or collinear terms against each other, move far."""
    def rms(values) -> float:
        return float(np.sqrt(np.mean(np.square(values), axis=0)).max())

    out = {}
    for dof, problem in (problems or _design(fitted, records, captive=False)).items():
        before = np.array([fitted.coefficients[dof][t] for t in problem.terms])
        change = np.array([refined.coefficients[dof][t] for t in problem.terms]) - before
        measured = rms(problem.target)
        out[dof] = (rms(problem.features @ change) / measured
                    if measured > 1e-3 * rms(problem.features * before) else None)
    return out


def _with_changes(model: AbkowitzModel, changes: dict, info: dict) -> AbkowitzModel:
    """The model with the coefficients ``{(dof, term): value}`` in place, and ``info``."""
    coefficients = {dof: dict(terms) for dof, terms in model.coefficients.items()}
    for (dof, term), value in changes.items():
        coefficients[dof][term] = value
    return AbkowitzModel(model.ship, model.library, coefficients, dict(model.optimizer),
                         model.rudder_signal, info)

"""The delay search of :func:`sindyship.diagnose.discover`: a channel read later over a grid
of delays, the library refitted at each leaving one manoeuvre out, the best delay between the
grid points, and its interval when the manoeuvres are resampled."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from .._diagnosis_thresholds import BOOTSTRAP
from ..library import DOFS, SPEED_FACTOR, TermLibrary, record_variables
from ..optimizers import GroupedProblem
from ..ships import Ship

__all__ = ["DELAY_MAX", "DELAY_RANGE", "DELAY_STEP", "delay_interval", "search_delay"]

#: Half-width of the delay grid [L/U0] and its step [L/U0]; a best delay at the edge of the
#: grid doubles its half-width, up to DELAY_MAX [L/U0].
DELAY_RANGE = 1.5
DELAY_STEP = 0.05
DELAY_MAX = 4.0


def lomo_errors(problem) -> np.ndarray:
    """Leave-one-manoeuvre-out errors of a least-squares fit on all of a design's columns."""
    grouped = GroupedProblem(problem.features, problem.target, problem.groups)
    return grouped.lomo_errors(np.arange(problem.features.shape[1]))


def delay_grid(ship: Ship, dt: float) -> np.ndarray:
    """Candidate delays [s]: steps of 0.05 L/U0 (at least one sample) out to 1.5 L/U0 (at
    least ten samples) on either side of zero."""
    step = max(dt, DELAY_STEP * ship.time_scale)
    reach = max(DELAY_RANGE * ship.time_scale, 10 * dt)
    half = np.arange(step, reach + 0.5 * step, step)
    return np.concatenate([-half[::-1], half])


def delay_errors(records, ship, library, channel, tau, settings, base):
    """Leave-one-manoeuvre-out errors of the library refitted with ``channel`` read ``tau``
    seconds later.

    ``base`` is ``(problems, variables)``: the library's design and each record's variables.
    Only the columns of terms in a variable the delay moves are evaluated again; the others
    and the targets are the base design's (the design of the delayed library, unchanged).
    """
    problems, unshifted = base
    delays = {**library.delays, channel: tau}
    shifted = TermLibrary(library.name, library.system, library.description, library.terms,
                          effects=library.effects, delays=delays, speed=library.speed)
    features = {dof: problems[dof].features.copy(order="F") for dof in DOFS}
    start = 0
    for record, before in zip(records, unshifted, strict=True):
        stop = start + record.n_samples
        after = record_variables(record, shifted, ship.L, ship.U0, settings["rudder_signal"])
        moved = {name for name in after if not np.array_equal(after[name], before[name])}
        factor = after.get(SPEED_FACTOR, 1.0)  # (U/U0)^2 of the instantaneous form
        for dof in DOFS:
            for j, term in enumerate(library.terms[dof]):
                if term.variables & moved:
                    features[dof][start:stop, j] = term.evaluate(after) * factor
        start = stop
    return {dof: lomo_errors(replace(problems[dof], features=features[dof])) for dof in DOFS}


def unshifted_variables(records, ship, library, settings) -> list[dict[str, np.ndarray]]:
    """Each record's variables as the library reads them (the base of :func:`delay_errors`)."""
    return [record_variables(r, library, ship.L, ship.U0, settings["rudder_signal"])
            for r in records]


def search_delay(records, ship, library, channel, e0, settings, problems, n_jobs=1):
    """The delay of ``channel`` with the least leave-one-manoeuvre-out error.

    The grid of :func:`delay_grid` is refitted point by point (``n_jobs`` joblib workers),
    widened while the best delay sits at its edge, and refined between grid points by a
    parabola (:func:`best_delay`).

    Returns
    -------
    tau : float
        The delay [s].
    errors : dict of str to ndarray
        Leave-one-manoeuvre-out errors per equation at ``tau``.
    curve : list of (float, float)
        Every delay tried and its cost (relative to no delay).
    interval : (float, float)
        The delay's interval when the manoeuvres are resampled (:func:`delay_interval`).
    """
    from joblib import Parallel, delayed

    sse0 = {dof: float(e0[dof] @ e0[dof]) or 1.0 for dof in DOFS}
    dt = float(np.median([r.dt for r in records]))

    def cost(errors):
        return float(np.mean([errors[d] @ errors[d] / sse0[d] for d in DOFS]))

    base = (problems, unshifted_variables(records, ship, library, settings))
    tried = {0.0: (1.0, e0)}
    grid = delay_grid(ship, dt)
    reach = float(grid[-1])
    while True:
        todo = [float(tau) for tau in grid if float(tau) not in tried]
        refits = Parallel(n_jobs=n_jobs)(
            delayed(delay_errors)(records, ship, library, channel, tau, settings, base)
            for tau in todo)
        for tau, errors in zip(todo, refits, strict=True):
            tried[tau] = (cost(errors), errors)
        taus = np.array(sorted(tried))
        costs = np.array([tried[t][0] for t in taus])
        k = int(np.argmin(costs))
        at_edge = k in (0, len(taus) - 1)
        if not at_edge or reach >= DELAY_MAX * ship.time_scale:
            break  # the best delay lies inside the grid, or the grid is as wide as it goes
        reach = min(2.0 * reach, DELAY_MAX * ship.time_scale)
        step = float(grid[1] - grid[0])
        half = np.arange(step, reach + 0.5 * step, step)
        grid = np.concatenate([-half[::-1], half])
    vertex = best_delay(taus, costs)  # between grid points: refitted there
    if vertex not in tried and abs(vertex) > 1e-9:
        errors = delay_errors(records, ship, library, channel, vertex, settings, base)
        tried[vertex] = (cost(errors), errors)
    best = min(tried, key=lambda t: tried[t][0])
    curve = [(t, tried[t][0]) for t in sorted(tried)]
    groups = problems["X"].groups
    taus = np.array(sorted(tried))
    sse = {dof: np.array([np.bincount(groups, tried[t][1][dof] ** 2) for t in taus])
           for dof in DOFS}
    return best, tried[best][1], curve, delay_interval(taus, sse, estimate=best)


def best_delay(taus: np.ndarray, costs: np.ndarray) -> float:
    """The delay of least cost: the vertex of the parabola through the least grid point and
    its neighbours when it opens upwards, else that grid point."""
    k = int(np.argmin(costs))
    if 0 < k < len(taus) - 1:
        (a, b, c), (fa, fb, fc) = taus[k - 1:k + 2], costs[k - 1:k + 2]
        denom = (a - b) * (a - c) * (b - c)
        A = (c * (fb - fa) + b * (fa - fc) + a * (fc - fb)) / denom
        B = (c * c * (fa - fb) + b * b * (fc - fa) + a * a * (fb - fc)) / denom
        if A > 0:
            return float(np.clip(-B / (2 * A), a, c))
    return float(taus[k])


def delay_interval(taus: np.ndarray, sse: Mapping[str, np.ndarray], *,
                   n_boot: int = BOOTSTRAP, level: float = 0.95,
                   estimate: float | None = None) -> tuple[float, float]:
    """The interval of a delay estimate when the manoeuvres are resampled.

    The records are drawn with replacement (``numpy.random.default_rng(0)``); each draw
    weighs every delay's leave-one-manoeuvre-out errors by how often each record was drawn,
    and takes the least of the resampled cost (relative squared error averaged over X, Y
    and N, as the search) with a parabola through its neighbours.  The fits are not
    repeated: the interval says how far the records agree on the delay the grid resolves.
    The search refits at its parabola's vertex, which the resampled rule cannot; given that
    ``estimate``, the interval is moved by its difference from the same rule on every record
    once, so that both rules' intervals are about the estimate the search reports.

    Parameters
    ----------
    taus : ndarray, shape (n_delays,)
        The delays tried [s], increasing; 0 among them.
    sse : mapping of str to ndarray, shape (n_delays, n_records)
        Per equation, each record's summed squared leave-one-manoeuvre-out error at each
        delay.
    n_boot : int
        Resamples.
    level : float
        Coverage of the interval.
    estimate : float, optional
        The delay the search reports (default: the resampled rule on every record once).

    Returns
    -------
    (float, float)
        The interval's ends [s].

    Examples
    --------
    >>> taus = np.array([-1.0, 0.0, 1.0, 2.0, 3.0])
    >>> one = (taus - 2.0) ** 2 + 1.0  # every record: least at 2 s
    >>> sse = {d: np.column_stack([one, 2 * one, 3 * one]) for d in "XYN"}
    >>> [round(x, 6) for x in delay_interval(taus, sse, n_boot=50)]
    [2.0, 2.0]
    """
    zero = int(np.argmin(np.abs(taus)))
    n_records = next(iter(sse.values())).shape[1]

    def resampled_best(weights):
        costs = np.zeros(len(taus))
        for table in sse.values():
            total = table @ weights
            costs += total / (total[zero] or 1.0)
        return best_delay(taus, costs / len(sse))

    rng = np.random.default_rng(0)
    best = np.array([resampled_best(np.bincount(rng.integers(0, n_records, n_records),
                                                minlength=n_records)) for _ in range(n_boot)])
    shift = 0.0 if estimate is None else estimate - resampled_best(np.ones(n_records))
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(best, [tail, 100 - tail]) + shift
    return float(low), float(high)

"""The search of :func:`sindyship.diagnose.discover` for effects that live in space.

A shallow patch or a bank changes the forces where the ship is.  A modulated family is a
:class:`~sindyship.terms.Shape` of the position times some of the library's own terms:

``edge``
    A smooth step across a line (:func:`sindyship.terms.shape_values`) times the constant and
    the linear terms of the library (``du`` in surge; ``v``, ``r``, ``delta`` in sway and
    yaw): hull and rudder derivatives that change across the line, as over a shallow patch
    or in a channel.  The step is half a ship length wide.
``bank``
    The pull of a line (``sign(d) (L/max(|d|, L/2))^2``) times ``sin(psi)`` and ``cos(psi)``
    in every equation: an earth-fixed force toward a bank that grows as the ship comes close.
    Only lines the ship never crosses are tried.

The line's place (its bearing and its distance from the origin) is searched as a delay is:
every line of a coarse grid (bearings every 15 deg; edges at 48 quantiles of the tracks along
the bearing, banks every ship length out to 20 L beyond the tracks) is scored by the
leave-one-manoeuvre-out error of the library refitted with all of the family's terms (from
per-manoeuvre Gram matrices, so that hundreds of lines cost a second), the best line is refined
on a finer grid about it (3 deg, 0.1 L), and :class:`~sindyship.optimizers.ForwardSelection`
then picks the family's terms at that line as for any other family.  The intervals of the
bearing and the distance come from resampling the manoeuvres over the fine grid, as for a
delay (:func:`sindyship.diagnose.delays.delay_interval`): they say how far the records agree
about the line near the best coarse one, each parameter's interval pooled over the other's.

Every record must share one earth frame (the lines are fixed in it); tracks farther than
:data:`FAR_ORIGIN` ship lengths from the origin are not searched (:func:`far_from_origin`):
a whole-degree bearing would place a line there too coarsely.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._diagnosis_thresholds import BOOTSTRAP
from ..library import DOFS
from ..terms import Term, parse_shape, shape_name, shape_values
from .candidates import Family, family_columns

#: The library terms each kind of shape multiplies, per equation ("1": the shape alone).
SHAPE_TERMS = {
    "edge": {"X": ("1", "du"), "Y": ("1", "v", "r", "delta"), "N": ("1", "v", "r", "delta")},
    "bank": dict.fromkeys(DOFS, ("sin(psi)", "cos(psi)")),
}
#: The width of an edge's step [ship lengths].
EDGE_WIDTH = 0.5
#: Coarse grid: bearing step [deg]; edges at as many quantiles of the tracks' samples along
#: the bearing, banks every ship length beyond the tracks; one sample in COARSE_STRIDE (in
#: FINE_STRIDE on the fine grid).
COARSE_BEARING, COARSE_EDGES, COARSE_STRIDE, FINE_STRIDE = 15.0, 48, 8, 2
#: Fine grid about the best coarse line: half-widths and steps [deg, ship lengths], on the
#: whole degrees and tenths the shape names carry.
FINE_BEARING, FINE_BEARING_STEP = 15.0, 3.0
FINE_DISTANCE, FINE_DISTANCE_STEP = 0.5, 0.1
#: Farthest median distance of the tracks from the origin that is searched [ship lengths].
FAR_ORIGIN = 100.0
#: Lines scored at once (memory: a few Gram matrices per line and manoeuvre).
CHUNK = 256
#: How far beyond the tracks a bank's line is tried [ship lengths].
BANK_REACH = 20.0


@dataclass
class ShapeSearch:
    """The best line of one kind of shape.

    Attributes
    ----------
    kind : str
    name : str
        The shape variable at the best line (``edge_b000_p020_w05``).
    cost : float
        Its leave-one-manoeuvre-out error with all the family's terms, relative to the
        library's (mean over X, Y and N).
    intervals : dict of str to [float, float]
        ``bearing_deg`` and ``distance_L``: 95 % intervals when the manoeuvres are resampled.
    lines : int
        Lines scored.
    """

    kind: str
    name: str
    cost: float
    intervals: dict[str, list[float]]
    lines: int

    def family(self, library) -> Family:
        """The family of terms at the best line, those the library has left out."""
        return shape_family(self.name, library)


def shape_family(name: str, library) -> Family:
    """The modulated family of shape ``name``: the shape times :data:`SHAPE_TERMS`."""
    shape = parse_shape(name)
    present = {dof: {t.canonical(scale=False) for t in library.terms[dof]} for dof in DOFS}
    terms = {}
    for dof in DOFS:
        texts = [name if base == "1" else f"{name} {base}" for base in SHAPE_TERMS[shape.kind][dof]]
        terms[dof] = tuple(t for t in texts if Term(t).canonical(scale=False) not in present[dof])
    return Family.of(shape.kind, terms)


def _coarse_lines(kind: str, positions, L: float) -> list[tuple[float, float]]:
    """(bearing, distance) of the coarse grid: bearings in [0, 180) (a line and its reverse
    give the same family), distances over the tracks' extent along the bearing (an edge) or
    beyond it on both sides (a bank the ship never crosses)."""
    x = np.concatenate([p[0] for p in positions])
    y = np.concatenate([p[1] for p in positions])
    lines = []
    for bearing in np.arange(0.0, 180.0, COARSE_BEARING):
        b = np.radians(bearing)
        along = (x * np.cos(b) + y * np.sin(b)) / L
        low, high = float(along.min()), float(along.max())
        if kind == "edge":  # where the tracks are: quantiles of their samples
            distances = np.unique(np.round(np.quantile(
                along, np.linspace(0.0, 1.0, COARSE_EDGES)) / 0.1) * 0.1)
        else:
            beyond = np.arange(1.0, BANK_REACH + 1.0, 1.0)
            distances = np.round(np.concatenate([low - beyond[::-1], high + beyond]), 1)
        lines += [(float(bearing), float(d)) for d in distances]
    return lines


def _fine_lines(kind: str, best: tuple[float, float], positions, L: float):
    bearings = best[0] + np.arange(-FINE_BEARING, FINE_BEARING + 1e-9, FINE_BEARING_STEP)
    distances = np.round(best[1] + np.arange(-FINE_DISTANCE, FINE_DISTANCE + 1e-9,
                                             FINE_DISTANCE_STEP), 1)
    lines = [(float(b), float(d)) for b in bearings for d in distances]
    if kind == "bank":  # a bank's line stays off the tracks
        lines = [line for line in lines if not _crosses(line, positions, L)]
    return lines


def _crosses(line, positions, L: float) -> bool:
    b = np.radians(line[0])
    along = np.concatenate([(p[0] * np.cos(b) + p[1] * np.sin(b)) / L for p in positions])
    return bool(along.min() - 0.5 <= line[1] <= along.max() + 0.5)


class _GramLOMO:
    """Leave-one-manoeuvre-out errors of the library's columns joined by a shape times the
    family's base columns, for many shapes at once, from per-manoeuvre Gram matrices.

    A candidate's columns are ``shape * columns[:, i]``; every inner product they enter is a
    sum over samples of products of the shape (or its square) with products of the base
    columns, the library's columns and the target, which are formed once: each manoeuvre's
    Gram matrices for all shapes are then a few matrix products (``sse``).
    """

    def __init__(self, problem, members, columns, rows):
        groups = np.empty(len(problem.target), dtype=int)
        for g, where in enumerate(members):
            groups[where] = g
        self.members = [np.flatnonzero(groups[rows] == g) for g in range(len(members))]
        B = problem.features[rows]
        scale = np.linalg.norm(B, axis=0)
        scale[~(scale > 0)] = 1.0
        B = B / scale  # unit columns, as the library's fit scales them
        y = problem.target[rows]
        m = np.asarray(columns, dtype=float)[rows]
        self.p, self.k = B.shape[1], m.shape[1]
        self.GBB = np.stack([B[g].T @ B[g] for g in self.members])
        self.GBy = np.stack([B[g].T @ y[g] for g in self.members])
        self.yy = np.array([y[g] @ y[g] for g in self.members])
        # per sample: base column x library column, base x base, base x target
        self.cross = (B[:, :, None] * m[:, None, :]).reshape(len(y), -1)
        self.square = (m[:, :, None] * m[:, None, :]).reshape(len(y), -1)
        self.target = m * y[:, None]
        self.base = self._solve(self.GBB[:, None], self.GBy[:, None])[0]  # the library alone

    def sse(self, shapes: np.ndarray) -> np.ndarray:
        """Per shape, per manoeuvre: the summed squared error of the manoeuvre left out,
        shape (n_shapes, n_groups), for shape values ``shapes`` (n_samples, n_shapes)."""
        n, p, k = shapes.shape[1], self.p, self.k
        G = len(self.members)
        A = np.zeros((G, n, p + k, p + k))
        b = np.zeros((G, n, p + k))
        for g, rows in enumerate(self.members):
            E = shapes[rows]
            cross = (self.cross[rows].T @ E).reshape(p, k, n).transpose(2, 1, 0)  # (n, k, p)
            A[g, :, :p, :p] = self.GBB[g]
            A[g, :, p:, :p] = cross
            A[g, :, :p, p:] = np.swapaxes(cross, 1, 2)
            A[g, :, p:, p:] = (self.square[rows].T @ (E * E)).reshape(k, k, n).transpose(2, 0, 1)
            b[g, :, :p] = self.GBy[g]
            b[g, :, p:] = (self.target[rows].T @ E).T
        # the candidate columns scaled to unit norm, as the library's
        norm = np.sqrt(np.einsum("gcjj->cj", A[:, :, p:, p:]))
        norm[~(norm > 0)] = 1.0
        scale = np.concatenate([np.ones((n, p)), norm], axis=1)
        A /= scale[None, :, :, None] * scale[None, :, None, :]
        b /= scale[None]
        return self._solve(A, b)

    def _solve(self, A, b):
        """Left-out errors from stacked Gram matrices ``A`` (G, C, P, P) and ``b`` (G, C, P)."""
        A_total, b_total = A.sum(axis=0), b.sum(axis=0)
        G, n, size = A.shape[0], A.shape[1], A.shape[2]
        out = np.empty((n, G))
        ridge = 1e-10 * np.eye(size)
        for g in range(G):
            w = np.linalg.solve(A_total - A[g] + ridge, (b_total - b[g])[..., None])[..., 0]
            out[:, g] = (self.yy[g] - 2.0 * np.einsum("ci,ci->c", w, b[g])
                         + np.einsum("ci,cij,cj->c", w, A[g], w))
        return np.maximum(out, 0.0)


def _scores(kind, lines, positions, lomo, L, rows):
    """Per line: per equation the (n_groups,) squared errors of the joint refit on the
    samples ``rows``."""
    shapes = [shape_name(kind, b, d, EDGE_WIDTH) for b, d in lines]
    x = np.concatenate([p[0] for p in positions])[rows]
    y = np.concatenate([p[1] for p in positions])[rows]
    out = {dof: [] for dof in DOFS}
    for start in range(0, len(shapes), CHUNK):
        values = np.column_stack([shape_values(parse_shape(s), x, y, L)
                                  for s in shapes[start:start + CHUNK]])
        for dof in DOFS:
            out[dof].append(lomo[dof].sse(values))
    return shapes, {dof: np.vstack(out[dof]) for dof in DOFS}


def _cost(sse, lomo, weights=None):
    """Mean over X, Y and N of the (weighted) error relative to the library's."""
    total = 0.0
    for dof in DOFS:
        w = np.ones(sse[dof].shape[1]) if weights is None else weights
        total = total + (sse[dof] @ w) / max(float(lomo[dof].base @ w), 1e-300)
    return total / len(DOFS)


def search_shape(kind: str, records: Sequence, ship, library, problems, rudder_signal: str,
                 *, n_boot: int = BOOTSTRAP) -> ShapeSearch | None:
    """The line of a ``kind`` shape whose family lowers the leave-one-manoeuvre-out error of
    ``library``'s refit the most (None when the records have no position to search, or lie
    too far from the origin: :func:`far_from_origin`)."""
    if far_from_origin(records, ship.L) is not None:
        return None
    groups = problems["X"].groups
    members = [np.flatnonzero(groups == g) for g in np.unique(groups)]
    positions = [(np.asarray(r["x"], dtype=float), np.asarray(r["y"], dtype=float))
                 for r in records]
    if not all(np.all(np.isfinite(x)) and np.all(np.isfinite(y)) for x, y in positions):
        return None
    coarse = _coarse_lines(kind, positions, ship.L)
    if not coarse:
        return None
    # the terms the shape multiplies, evaluated as any family's (the speed factor included)
    columns = family_columns(Family.of(kind, SHAPE_TERMS[kind]), records, library, ship,
                             rudder_signal)
    every = np.arange(len(groups))
    some = every[::COARSE_STRIDE]
    lomo = {dof: _GramLOMO(problems[dof], members, columns[dof], some) for dof in DOFS}
    _, sse = _scores(kind, coarse, positions, lomo, ship.L, some)
    best = coarse[int(np.argmin(_cost(sse, lomo)))]
    fine = _fine_lines(kind, best, positions, ship.L) or [best]
    some = every[::FINE_STRIDE]
    lomo = {dof: _GramLOMO(problems[dof], members, columns[dof], some) for dof in DOFS}
    names, sse = _scores(kind, fine, positions, lomo, ship.L, some)
    cost = _cost(sse, lomo)
    k = int(np.argmin(cost))
    named = np.array([(shape.bearing, shape.distance) for shape in map(parse_shape, names)])
    rng = np.random.default_rng(0)
    n_groups = len(members)
    draws = []
    for _ in range(n_boot):
        weights = np.bincount(rng.integers(0, n_groups, n_groups), minlength=n_groups)
        draws.append(named[int(np.argmin(_cost(sse, lomo, weights.astype(float))))])
    draws = np.array(draws)
    bearing_low, bearing_high = _circular_interval(draws[:, 0], named[k, 0])
    distance_low, distance_high = np.percentile(draws[:, 1], [2.5, 97.5])
    return ShapeSearch(kind, names[k], float(cost[k]),
                       {"bearing_deg": [bearing_low, bearing_high],
                        "distance_L": [float(distance_low), float(distance_high)]},
                       len(coarse) + len(fine))


def far_from_origin(records: Sequence, L: float) -> float | None:
    """The median distance of the tracks from the origin [ship lengths] when it exceeds
    :data:`FAR_ORIGIN` (projected coordinates such as UTM), else None."""
    x = np.concatenate([np.asarray(r["x"], dtype=float) for r in records])
    y = np.concatenate([np.asarray(r["y"], dtype=float) for r in records])
    distance = float(np.nanmedian(np.hypot(x, y))) / L if x.size else 0.0
    return distance if distance > FAR_ORIGIN else None


def _circular_interval(bearings: np.ndarray, centre: float) -> tuple[float, float]:
    """The 95 % interval of bearings [deg] about ``centre`` (differences wrapped to +-180)."""
    offsets = (bearings - centre + 180.0) % 360.0 - 180.0
    low, high = centre + np.percentile(offsets, [2.5, 97.5])
    if low >= 180.0:  # read from just below north: [-3, 15], not [357, 375]
        low, high = low - 360.0, high - 360.0
    return float(low), float(high)

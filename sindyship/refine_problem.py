"""The least-squares problem of a refinement (:mod:`sindyship.refine`): the residuals of the
multiple-shooting flights (:mod:`sindyship.shooting`) and of the fit's own objective (the
force error of paper eq. 16 and, for a ``prior`` fit, its prior), with their normal
equations, as functions of the relative changes of the model's active coefficients.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from .errors import SindyshipInputError
from .model import AbkowitzModel
from .optimizers import PriorRidge
from .shooting import (
    CHANNEL_SCALES,
    active_keys,
    fly_segments,
    make_segments,
    model_slots,
)
from .targets import DOFS

__all__ = ["DIVERGED_RESIDUAL", "ShootingProblem", "cost", "fly_batches", "penalty_rows"]

#: The residual of every channel at a sample after a segment diverged (non-dimensional: ten
#: ship lengths of position, ten times the design speed).
DIVERGED_RESIDUAL = 10.0
#: How the penalty is weighed: "fit" makes the fit's objective 1 at the fitted coefficients,
#: as the flights' mean squared error is; anything else weighs it over the forces' sum of
#: squares.
PENALTY_SCALE = "fit"


def cost(residuals: np.ndarray) -> float:
    """Half the sum of squared residuals."""
    return 0.5 * float(residuals @ residuals)


class ShootingProblem:
    """The least-squares problem of a refinement: the flight residuals of the segments and
    the penalty rows, as functions of the relative changes ``p`` of the active coefficients
    (coefficient = fitted x (1 + p))."""

    def __init__(self, model, records, segment_s, prior_weight, penalty, n_jobs):
        self.model = model
        self.keys = active_keys(model)
        self.fitted = np.array([model.coefficients[d][t] for d, t in self.keys])
        self.slots = model_slots(model)
        self.batches, self.segment_s = make_segments(model, records, segment_s), segment_s
        if not self.batches:
            raise SindyshipInputError("the records are too short to fly: each needs at least "
                                      "two samples from its flight start.")
        self.n_segments = sum(b.n_segments for b in self.batches)
        L, U0 = model.ship.L, model.ship.U0
        self.scales = np.array([L**a * U0**b for a, b in CHANNEL_SCALES])
        self.n_compared = sum(int(b.valid.sum()) * 6 for b in self.batches)
        self.penalty = penalty
        self.n_jobs = n_jobs
        self.flight_rms = math.nan
        self.reported_cost = None  # the cost the last progress line reported (report)
        self._last = None  # (p, flights) of the last flight without sensitivities
        # both parts relative to their values at the fitted coefficients: the flights' mean
        # squared error, and the fit's own objective, each 1 there
        self.flight_norm = self.penalty_norm = 1.0
        start = np.zeros(len(self.keys))
        flights, _, _ = self._flight_part(self._flights(start, False))
        self.flight_norm = 1.0 / math.sqrt(max(float(flights @ flights), 1e-300))
        self.weight = 1.0
        if penalty is not None and PENALTY_SCALE == "fit":  # the objective's value there
            rows, _ = self._penalty_part(start, False)
            value = float(rows @ rows) + sum(part[5] for part in penalty.values())
            self.weight = math.sqrt(prior_weight / max(value, 1e-12))
        elif penalty is not None:  # over the forces' sum of squares
            self.weight = math.sqrt(prior_weight)

    def coefficients(self, p: np.ndarray) -> dict:
        return dict(zip(self.keys, (self.fitted * (1.0 + p)).tolist(), strict=True))

    def weights(self, p: np.ndarray) -> np.ndarray:
        weights = self.model._weights.copy()
        weights[self.slots] = self.fitted * (1.0 + p)
        return weights

    def _flights(self, p: np.ndarray, sensitivities: bool):
        """The segments flown at ``p``; the last flight without sensitivities is kept, since
        a stage asks for the same point more than once in a row (its start, the search's first
        point, and the point the search ended at when its last trial was accepted)."""
        if not sensitivities and self._last is not None and np.array_equal(self._last[0], p):
            return self._last[1]
        flown = fly_batches(self.model, self.batches, self.weights(p), self.slots,
                             sensitivities, self.n_jobs)
        if not sensitivities:
            self._last = (np.array(p, dtype=float), flown)
        return flown

    def _flight_part(self, flown) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """The flights' residuals and, from their sensitivities, their part of J^T J and
        J^T r (with respect to the relative changes ``p``)."""
        norm = self.flight_norm / math.sqrt(max(self.n_compared, 1))
        residuals, gram, gradient = [], None, None
        for batch, (states, jac) in zip(self.batches, flown, strict=True):
            error = (states - batch.measured) * self.scales
            error = np.where(np.isfinite(error), error, DIVERGED_RESIDUAL)
            error[~batch.valid] = 0.0
            residuals.append(error[batch.valid].ravel() * norm)
            if jac is None:
                continue
            jac[~batch.valid] = 0.0
            jac *= (self.scales * norm)[None, None, :, None]
            flat = jac.reshape(-1, jac.shape[-1])
            part = flat.T @ flat
            step = flat.T @ (error.reshape(-1) * norm)
            gram = part if gram is None else gram + part
            gradient = step if gradient is None else gradient + step
        r = np.concatenate(residuals)
        unscaled = r / norm
        self.flight_rms = float(np.sqrt(np.sum(unscaled**2) / max(self.n_compared, 1)))
        if gram is None:
            return r, None, None
        outer = np.outer(self.fitted, self.fitted)  # d/dp = d/dtheta x fitted coefficient
        return r, gram * outer, gradient * self.fitted

    def _penalty_part(self, p: np.ndarray, with_jacobian: bool):
        if self.penalty is None:
            return np.empty(0), np.empty((0, len(self.keys)))
        values, jac = [], []
        theta = self.fitted * (1.0 + p)
        for lhs, rhs, norm, positions, fixed, _ in self.penalty.values():
            w = fixed.copy()
            for k, j in positions:
                w[j] = theta[k]
            values.append(self.weight * (lhs @ w - rhs) / norm)
            if with_jacobian:
                block = np.zeros((lhs.shape[0], len(self.keys)))
                for k, j in positions:
                    block[:, k] = self.weight * lhs[:, j] * self.fitted[k] / norm
                jac.append(block)
        return np.concatenate(values), (np.vstack(jac) if with_jacobian else None)

    def residuals(self, p: np.ndarray) -> np.ndarray:
        flights, _, _ = self._flight_part(self._flights(p, False))
        penalty, _ = self._penalty_part(p, False)
        return np.concatenate([flights, penalty])

    def normal(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """J^T J and J^T r of the residuals at ``p``: the flights' from their sensitivities,
        the penalty's from its rows."""
        _, gram, gradient = self._flight_part(self._flights(p, True))
        penalty, jac = self._penalty_part(p, True)
        return gram + jac.T @ jac, gradient + jac.T @ penalty

    def report(self, step: int, cost: float, label: str) -> None:
        """One line on stderr per accepted step of the search, beginning with ``label``: the
        cost, how much lower than the last step's (or the cost the search started from, set
        in ``reported_cost``) and the flights' error (the rms of their non-dimensional states'
        differences: u and v over U0, r over U0/L, x and y over L, psi in radians)."""
        stage = "whole flights" if self.segment_s is None else f"{self.segment_s:.4g} s segments"
        last, self.reported_cost = self.reported_cost, cost
        percent = 100.0 * (last - cost) / last if last else None
        fall = "" if percent is None else (f" ({percent:.2f} % lower)" if percent >= 0.01
                                            else f" ({percent:.1e} % lower)")
        print(f"{label} ({stage}): step {step}, cost {cost:.6g}{fall}, flight error "
              f"{self.flight_rms:.4g} (rms, non-dimensional)", file=sys.stderr, flush=True)


def fly_batches(model, batches, weights, slots, sensitivities, n_jobs):
    """Every batch of segments flown (split in chunks across joblib workers when asked)."""
    if n_jobs == 1:
        return [fly_segments(model, b, weights, slots, sensitivities=sensitivities)
                for b in batches]
    from joblib import Parallel, delayed

    payload = model.to_dict()  # JSON-ready: a worker rebuilds the model from it
    out = []
    for batch in batches:
        chunks = np.array_split(np.arange(batch.n_segments), max(2, min(batch.n_segments, 8)))
        parts = Parallel(n_jobs=n_jobs)(
            delayed(_fly_chunk)(payload, batch.take(idx), weights, slots, sensitivities)
            for idx in chunks if len(idx))
        states = np.concatenate([s for s, _ in parts])
        jac = np.concatenate([j for _, j in parts]) if sensitivities else None
        out.append((states, jac))
    return out


def _fly_chunk(payload, segments, weights, slots, sensitivities):
    return fly_segments(AbkowitzModel.from_dict(payload), segments, weights, slots,
                        sensitivities=sensitivities)



def penalty_rows(model, problems) -> dict:
    """Per degree of freedom, the fit's own objective as rows on its design ``problems``: the
    force error of eq. 16 and, for a ``prior`` fit, its prior; ``(lhs, rhs, ||y||, [(key
    index, column)], fixed coefficients, the objective's part no row reaches over ||y||^2)``."""
    info = model.info
    prior = model.optimizer.get("name") == "prior" and "prior" in info
    strength = info.get("straight_run", {}).get(
        "strength", model.optimizer["params"].get("strength")) if prior else 0.0
    keys = active_keys(model)
    out = {}
    for dof in DOFS:
        setting = info["prior"][dof] if prior else {"mean": None, "scale": None,
                                                    "relations": None}
        estimator = PriorRidge(strength=strength, mean=setting["mean"],
                               scale=None if setting["scale"] is None else
                               [np.nan if s is None else s for s in setting["scale"]],
                               relations=setting["relations"])
        lhs, rhs, norm2, offset = estimator.objective_rows(problems[dof].features,
                                                           problems[dof].target)
        terms = list(problems[dof].terms)
        positions = [(k, terms.index(t)) for k, (d, t) in enumerate(keys) if d == dof]
        fixed = np.array([model.coefficients[dof][t] for t in terms])
        out[dof] = (lhs, rhs, math.sqrt(max(norm2, 1e-300)), positions, fixed,
                    offset / max(norm2, 1e-300))
    return out

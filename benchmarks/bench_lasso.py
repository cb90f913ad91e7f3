"""Benchmark: sindyship's LassoCV against a naive scikit-learn LassoCV on a realistic problem.

The problem has the real shape (docs/protocol.md): 8 manoeuvres x 3200 samples = 25,600 samples;
the surge library of eq. 17a (16 terms) and the sway and yaw libraries of eq. 17b-c (22
terms), with the constant term; targets built from the paper's least-squares coefficients
(Tables 7-9, LS column) plus a deterministic fifth-order force that the library lacks, as the
MMG forces are not an exact Abkowitz polynomial.  The states come from a simple first-order
manoeuvring response (rudder servo, yaw rate following the rudder, drift following the yaw
rate, speed loss in turns) flown through the training manoeuvres: straight run, turning
circles +-35 deg, zig-zags 35/10, 20/20, 15/15 and the two spirals.  This is not the MMG
model; it only gives the library the real problem's scales and correlations.

Timed: ``sindyship.optimizers.LassoCV`` (leave one manoeuvre out) on the three equations, and
``sklearn.linear_model.LassoCV(alphas=100, cv=<leave-one-group-out splits>)`` with its
defaults on the sway equation (its call on three equations is estimated as three times that).
Also recorded: the smallest cross-validation MSE each reaches on the sway equation, and that of
least squares on the same folds.

Run from the repository root: ``python benchmarks/bench_lasso.py``.  Prints a summary and
writes ``benchmarks/results/lasso.json``.
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import sklearn
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import LassoCV as SklearnLassoCV
from sklearn.model_selection import LeaveOneGroupOut

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # benchmark the working tree this script belongs to

from sindyship.optimizers import LassoCV, LeastSquares  # noqa: E402

N_SAMPLES_PER_MANOEUVRE = 3200
DT = 1.0 / 18.63  # 1 s full scale in units of L / U0 (KCS)
DEG = np.pi / 180.0

# Term sets of eq. 17 and the paper's LS coefficients (Tables 7-9, x 1e-5, Prime I).
SURGE = {
    "1": 0.0, "du": -226.51, "du^2": -50.81, "v^2": 245.93, "r^2": -90.82,
    "delta^2": -186.48, "v delta": 123.22, "r delta": 197.15, "du^3": 81.99,
    "v^2 du": -167.28, "r^2 du": -3.071, "delta^2 du": -184.91, "du v r": -545.41,
    "du v delta": 13.61, "du r delta": 315.11, "v r delta": -116.27,
}  # fmt: skip
SWAY = {
    "1": 0.432, "du": -22.115, "v": -1257.569, "r": 263.464, "delta": -246.062,
    "du^2": -28.985, "du v": 8879.939, "du r": 3777.289, "du delta": -1020.67,
    "v^3": -199408.035, "r^3": -8212.779, "delta^3": 55.248, "du^2 v": 5048.682,
    "du^2 r": 6476.757, "du^2 delta": -2022.656, "v^2 r": -230252.527,
    "v^2 delta": 60670.839, "r^2 v": -85809.497, "r^2 delta": 6135.945,
    "delta^2 v": -4290.948, "delta^2 r": -894.971, "v r delta": 43061.015,
}  # fmt: skip
YAW = {
    "1": -0.205, "du": 12.766, "v": 292.766, "r": -215.66, "delta": 120.743,
    "du^2": 18.29, "du v": -1282.294, "du r": -1152.418, "du delta": 355.233,
    "v^3": 71409.415, "r^3": 2921.58, "delta^3": -37.988, "du^2 v": -2524.594,
    "du^2 r": -1919.395, "du^2 delta": 687.726, "v^2 r": 82913.891,
    "v^2 delta": -22771.822, "r^2 v": 30562.213, "r^2 delta": -2241.106,
    "delta^2 v": 1660.355, "delta^2 r": 343.875, "v r delta": -16052.721,
}  # fmt: skip
EQUATIONS = {"X": SURGE, "Y": SWAY, "N": YAW}


def _fly(command: str, n: int) -> np.ndarray:
    """States (du, v, r, delta) of one manoeuvre, sampled every DT (Euler, 4 substeps)."""
    t = np.arange(n)
    if command == "spiral_in":
        steps = (5 + 5 * (t // (n / 7))) * DEG
    elif command == "spiral_out":
        steps = (-35 + 5 * (t // (n / 7))) * DEG
    else:
        steps = None
    zigzag = {"zz35_10": (35, 10), "zz20_20": (20, 20), "zz15_15": (15, 15)}.get(command)
    fixed = {"straight": 0.0, "tc35_stbd": 35 * DEG, "tc35_port": -35 * DEG}.get(command)
    du = v = r = delta = psi = 0.0
    side = 1.0
    out = np.empty((n, 4))
    h = DT / 4
    for i in range(n):
        if zigzag is not None:
            rudder, check = zigzag
            if side > 0 and psi > check * DEG:
                side = -1.0
            elif side < 0 and psi < -check * DEG:
                side = 1.0
            command_angle = side * rudder * DEG
        elif steps is not None:
            command_angle = steps[i]
        else:
            command_angle = fixed
        out[i] = du, v, r, delta
        for _ in range(4):
            rate = np.clip(command_angle - delta, -5 * DEG / DT, 5 * DEG / DT)
            delta += h * rate
            r += h * (0.9 * np.tanh(delta / 0.5) * (1 + du) - r - 0.3 * r**3) / 3.0
            v += h * (-0.35 * r - 0.1 * delta - v - 2 * v**3) / 1.5
            du += h * (-(r**2 + 0.5 * v**2) - du) / 4.0
            psi += h * r
    return out


def _column(S: np.ndarray, term: str) -> np.ndarray:
    index = {"du": 0, "v": 1, "r": 2, "delta": 3}
    col = np.ones(S.shape[0])
    if term == "1":
        return col
    for factor in term.split():
        base, _, power = factor.partition("^")
        col = col * S[:, index[base]] ** int(power or 1)
    return col


def build_problem() -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], np.ndarray]:
    """{equation: (X, y)} and the manoeuvre label of every sample."""
    manoeuvres = [
        "straight", "tc35_stbd", "tc35_port", "zz35_10", "zz20_20", "zz15_15",
        "spiral_in", "spiral_out",
    ]  # fmt: skip
    S = np.vstack([_fly(m, N_SAMPLES_PER_MANOEUVRE) for m in manoeuvres])
    groups = np.repeat(np.arange(len(manoeuvres)), N_SAMPLES_PER_MANOEUVRE)
    misfit = S[:, 1] ** 5 + S[:, 2] ** 5 + 0.5 * S[:, 3] ** 5 + np.sin(3 * S[:, 2]) * S[:, 0]
    problems = {}
    for eq, coefficients in EQUATIONS.items():
        X = np.column_stack([_column(S, term) for term in coefficients])
        y = X @ (1e-5 * np.array(list(coefficients.values())))
        y = y + 0.02 * np.std(y) * misfit / np.std(misfit)
        problems[eq] = (X, y)
    return problems, groups


def _ls_cv_mse(X: np.ndarray, y: np.ndarray, splits: list) -> float:
    errors = []
    for train, test in splits:
        model = LeastSquares().fit(X[train], y[train])
        errors.append(np.mean((model.predict(X[test]) - y[test]) ** 2))
    return float(np.mean(errors))


def main() -> dict:
    t0 = time.perf_counter()
    problems, groups = build_problem()
    build_seconds = time.perf_counter() - t0

    ours = {}
    fitted = {}
    for eq, (X, y) in problems.items():
        start = time.perf_counter()
        fitted[eq] = LassoCV().fit(X, y, groups=groups)
        ours[eq] = time.perf_counter() - start
    ours_total = sum(ours.values())

    X, y = problems["Y"]
    splits = list(LeaveOneGroupOut().split(X, y, groups))
    naive = SklearnLassoCV(alphas=100, cv=splits)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        start = time.perf_counter()
        naive.fit(X, y)
        naive_seconds = time.perf_counter() - start
    naive_warnings = sum(issubclass(w.category, ConvergenceWarning) for w in caught)

    results = {
        "problem": {
            "n_samples": int(X.shape[0]),
            "n_groups": int(np.unique(groups).size),
            "n_features": {eq: int(p[0].shape[1]) for eq, p in problems.items()},
            "build_seconds": round(build_seconds, 3),
        },
        "sindyship_lassocv_seconds": {eq: round(s, 4) for eq, s in ours.items()},
        "sindyship_lassocv_seconds_total": round(ours_total, 4),
        "sklearn_lassocv_seconds_sway": round(naive_seconds, 4),
        "sklearn_lassocv_seconds_three_equations_estimate": round(3 * naive_seconds, 4),
        "ratio_sway": round(naive_seconds / ours["Y"], 2),
        "ratio_three_equations_estimate": round(3 * naive_seconds / ours_total, 2),
        "sklearn_lassocv_convergence_warnings_sway": int(naive_warnings),
        "sway_cv_mse_min": {
            "sindyship_lassocv": float(fitted["Y"].mse_path_[0].mean(axis=1).min()),
            "sklearn_lassocv": float(naive.mse_path_.mean(axis=1).min()),
            "least_squares": _ls_cv_mse(X, y, splits),
        },
        "sindyship_alpha_over_alpha_max": {
            eq: float(m.alpha_[0] / m.alphas_[0, 0]) for eq, m in fitted.items()
        },
        "environment": {
            "python": platform.python_version(),
            "numpy": np.__version__,
            "scikit-learn": sklearn.__version__,
            "cpu_count": os.cpu_count(),
        },
    }
    out = ROOT / "benchmarks" / "results" / "lasso.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")

    mse = results["sway_cv_mse_min"]
    print(f"problem: {X.shape[0]} samples, {results['problem']['n_features']} terms")
    print(
        "sindyship LassoCV (leave one manoeuvre out, 100 penalties): "
        + ", ".join(f"{eq} {s:.3f} s" for eq, s in ours.items())
        + f"; total {ours_total:.3f} s"
    )
    print(
        f"sklearn LassoCV (same folds, alphas=100), sway only: {naive_seconds:.3f} s "
        f"({naive_warnings} convergence warnings); ratio {results['ratio_sway']:.1f}x on sway, "
        f"{results['ratio_three_equations_estimate']:.1f}x estimated on three equations"
    )
    print(
        f"sway, smallest cross-validation MSE: sindyship {mse['sindyship_lassocv']:.3e}, "
        f"sklearn {mse['sklearn_lassocv']:.3e}, least squares {mse['least_squares']:.3e}"
    )
    print(f"written {out.relative_to(ROOT)}")
    return results


if __name__ == "__main__":
    main()

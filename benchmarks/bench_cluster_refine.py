"""A refinement of 26 records on a two-worker Dask ``LocalCluster`` against one process.

The records are the protocol's 11 manoeuvres (3200 s each) and two zig-zags started to port
(20/20 and 10/10), each flown by the KCS MMG once and recorded with two seeds of measurement
noise: 26 records, 83,200 samples.  The ``prior`` fit on ``abkowitz-vr`` is refined by its
flights (multiple shooting, ``max_evaluations=10``, no validation on halves: the refinement
alone is timed) in this process (``n_jobs=1``) and on the cluster (joblib's dask backend, the
segments split across the workers).  The script prints and saves the two times, their ratio
and how far apart the refined coefficients and flight costs are (relative to the largest
coefficient of each equation).

    python benchmarks/bench_cluster_refine.py

Saves ``benchmarks/results/cluster-refine.json``.  Needs the cluster extra
(``pip install "sindyship[cluster]"``).
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import joblib  # noqa: E402
import numpy as np  # noqa: E402

from sindyship.effects import add_noise  # noqa: E402
from sindyship.identify import fit  # noqa: E402
from sindyship.manoeuvres import Manoeuvre, fly, protocol_manoeuvres  # noqa: E402
from sindyship.mmg import MMGModel  # noqa: E402
from sindyship.refine import refine  # noqa: E402
from sindyship.ships import load_ship  # noqa: E402
from sindyship.trajectory import Trajectory  # noqa: E402

OUT = Path(__file__).parent / "results" / "cluster-refine.json"
#: Standard deviation of the measurement noise per channel (SI; psi in rad).
NOISE = {"u": 0.02, "v": 0.01, "r": 2e-5, "psi": 1e-3, "x": 0.5, "y": 0.5}
SEEDS = (1, 2)
EVALUATIONS = 10


def records(ship) -> list:
    plan = protocol_manoeuvres()
    manoeuvres = plan["train"] + plan["test"] + [
        Manoeuvre("zigzag", rudder=20, check=20, first_sign=-1, duration=3200.0),
        Manoeuvre("zigzag", rudder=10, check=10, first_sign=-1, duration=3200.0)]
    clean = fly(MMGModel(ship), manoeuvres)
    out = []
    for seed in SEEDS:
        for k, record in enumerate(clean):
            noisy = add_noise(record, NOISE, seed=1000 * seed + k)
            out.append(Trajectory(noisy.data, name=f"{record.name}_seed{seed}",
                                  meta=noisy.meta))
    return out


def largest_difference(a, b) -> float:
    """Largest coefficient difference, relative to the largest coefficient of its equation."""
    worst = 0.0
    for dof, terms in a.coefficients.items():
        scale = max(abs(v) for v in terms.values()) or 1.0
        worst = max(worst, max(abs(v - b.coefficients[dof][t]) for t, v in terms.items())
                    / scale)
    return worst


def main() -> None:
    from distributed import Client, LocalCluster

    ship = load_ship("kcs")
    runs = records(ship)
    prior = fit(runs, ship, library="abkowitz-vr", optimizer="prior")
    refine(prior, runs[:2], max_evaluations=1, validate=False)  # compile and warm up

    start = time.perf_counter()
    local = refine(prior, runs, max_evaluations=EVALUATIONS, n_jobs=1, validate=False)
    local_s = time.perf_counter() - start

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    with Client(cluster) as client:
        client.run(lambda: refine(prior, runs[:2], max_evaluations=1, validate=False)
                   and None)  # each worker compiles before the clock starts
        start = time.perf_counter()
        with joblib.parallel_config(backend="dask"):
            remote = refine(prior, runs, max_evaluations=EVALUATIONS, n_jobs=None,
                            validate=False)
        cluster_s = time.perf_counter() - start
        workers = len(client.scheduler_info()["workers"])
    cluster.close()

    result = {
        "records": len(runs), "samples": int(sum(r.n_samples for r in runs)),
        "max_evaluations": EVALUATIONS, "workers": workers, "cores": os.cpu_count(),
        "one_process_s": local_s, "cluster_s": cluster_s,
        "one_process_over_cluster": local_s / cluster_s,
        "coefficients_apart": largest_difference(local, remote),
        "cost_after": {"one_process": local.info["refined"]["cost_after"],
                       "cluster": remote.info["refined"]["cost_after"]},
        "cost_before": local.info["refined"]["cost_before"],
        "evaluations": {"one_process": local.info["refined"].get("evaluations"),
                        "cluster": remote.info["refined"].get("evaluations")},
    }
    result["costs_apart"] = abs(result["cost_after"]["one_process"]
                                - result["cost_after"]["cluster"]) / max(
        abs(result["cost_after"]["one_process"]), 1e-300)
    text = json.dumps(result, indent=2)
    print(text)
    OUT.write_text(text + "\n", encoding="utf-8")
    assert np.isfinite(cluster_s)


if __name__ == "__main__":
    main()

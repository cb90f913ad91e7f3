"""Fitting cost against the number of samples: 10^5 and 10^6 samples of long manoeuvres.

Eight long random-rudder manoeuvres of the KCS (rudder angles uniform in +-35 deg, each held
30 to 120 s, seeds 0 to 7) are flown by the MMG model at dt = 1 s: 12,500 s each for 10^5
samples and 125,000 s each for 10^6.  The number of manoeuvres, and so the number of
leave-one-manoeuvre-out folds, is the same at both sizes, so the work of every optimizer
should grow linearly with the samples.

Every (size, optimizer) case runs in a fresh process that loads the records, builds the
regression problems (:func:`sindyship.identify.design`) and fits them
(:func:`sindyship.identify.fit` with ``problems=``): the time of design + fit is reported, and
the process's peak resident memory (``resource.getrusage``, everything included: the Python
interpreter, the libraries, the records).  Prints a table and writes
``benchmarks/results/scale.json``, with t(10^6) / t(10^5) per optimizer (the claim: at most
12) and whether 10^6 samples fit in under 30 s and 2 GB.

Usage: ``python benchmarks/bench_scale.py [--sizes 100000 1000000] [--optimizers ls stlsq
lasso] [--cache DIR] [--n-jobs 2]``; ``--n-jobs`` goes to ``fit`` when it takes one.  The
flights are cached in ``--cache`` (default: a folder in the system's temporary directory); the
first run spends about a minute simulating.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sindyship._io import write_text_atomic  # noqa: E402
from sindyship.trajectory import Trajectory  # noqa: E402

OUT = Path(__file__).parent / "results" / "scale.json"
N_RECORDS = 8
TIME_LIMIT_S = 30.0
MEMORY_LIMIT_MB = 2048.0
RATIO_LIMIT = 12.0
COLUMNS = ("t", "u", "v", "r", "x", "y", "psi", "delta", "delta_c")


def records_file(cache: Path, n_samples: int) -> Path:
    """Simulate (once) and cache the records of one size as a compressed .npz."""
    path = cache / f"random-kcs-{N_RECORDS}x{n_samples // N_RECORDS}.npz"
    if path.exists():
        return path
    from sindyship.manoeuvres import Manoeuvre, fly
    from sindyship.mmg import MMGModel
    from sindyship.ships import load_ship

    ship = load_ship("kcs")
    duration = float(n_samples // N_RECORDS)
    plan = [Manoeuvre("random", rudder=35.0, duration=duration, seed=seed)
            for seed in range(N_RECORDS)]
    t0 = time.perf_counter()
    runs = fly(MMGModel(ship), plan)
    print(f"simulated {N_RECORDS} x {duration:.0f} s in {time.perf_counter() - t0:.0f} s",
          file=sys.stderr)
    bad = [r.name for r in runs if r.meta.get("diverged_at") is not None]
    if bad:
        raise RuntimeError(f"the MMG flights {bad} left the plausible range")
    arrays = {f"{k}:{c}": r[c] for k, r in enumerate(runs) for c in COLUMNS}
    cache.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, **arrays)
    tmp.replace(path)
    return path


def load_records(path: Path) -> list[Trajectory]:
    with np.load(path) as data:
        return [Trajectory(pd.DataFrame({c: data[f"{k}:{c}"] for c in COLUMNS}),
                           name=f"random{k}") for k in range(N_RECORDS)]


def child(path: Path, optimizer: str, n_jobs: int) -> None:
    """One case in this (fresh) process: load, design, fit; print a JSON line."""
    import inspect

    from sindyship.identify import design, fit, resolve_library
    from sindyship.ships import load_ship

    parallel = {"n_jobs": n_jobs} if "n_jobs" in inspect.signature(fit).parameters else {}

    ship = load_ship("kcs")
    library = resolve_library("abkowitz")
    records = load_records(path)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    t0 = time.perf_counter()
    problems = design(records, ship, library)
    t1 = time.perf_counter()
    model = fit(records, ship, library=library, optimizer=optimizer, problems=problems,
                **parallel)
    t2 = time.perf_counter()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({
        "n_samples": int(len(problems["X"].target)),
        "optimizer": optimizer,
        "design_s": t1 - t0,
        "fit_s": t2 - t1,
        "total_s": t2 - t0,
        "peak_rss_mb": peak,
        "rss_before_design_mb": before,
        "active_terms": model.n_active(),
        "fit_n_jobs": parallel.get("n_jobs"),
    }))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--optimizers", nargs="+", default=["ls", "stlsq", "lasso"])
    parser.add_argument("--cache", type=Path,
                        default=Path(tempfile.gettempdir()) / "sindyship-bench-scale")
    parser.add_argument("--repeat", type=int, default=1,
                        help="processes per case; the fastest is reported")
    parser.add_argument("--n-jobs", type=int, default=2,
                        help="workers for fit, when sindyship.identify.fit takes n_jobs")
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--child", nargs=3, metavar=("NPZ", "OPTIMIZER", "N_JOBS"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(Path(args.child[0]), args.child[1], int(args.child[2]))
        return

    files = {n: records_file(args.cache, n) for n in args.sizes}
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    cases = []
    for n in args.sizes:
        for opt in args.optimizers:
            runs = []
            for _ in range(args.repeat):
                proc = subprocess.run([sys.executable, __file__, "--child", str(files[n]), opt,
                                       str(args.n_jobs)],
                                      capture_output=True, text=True, env=env, check=False)
                if proc.returncode != 0:
                    raise RuntimeError(f"case {n} {opt} failed:\n{proc.stderr}")
                runs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
            best = min(runs, key=lambda r: r["total_s"])
            best["peak_rss_mb"] = max(r["peak_rss_mb"] for r in runs)
            cases.append(best)
            print(f"{best['n_samples']:>9d} {opt:6s} design {best['design_s']:6.2f} s  fit "
                  f"{best['fit_s']:6.2f} s  total {best['total_s']:6.2f} s  peak "
                  f"{best['peak_rss_mb']:7.0f} MB", file=sys.stderr)

    small, large = min(args.sizes), max(args.sizes)
    by = {(c["n_samples"] // N_RECORDS * N_RECORDS, c["optimizer"]): c for c in cases}
    ratios = {}
    verdict = {}
    for opt in args.optimizers:
        a, b = by.get((small, opt)), by.get((large, opt))
        if a and b and large != small:
            ratios[opt] = b["total_s"] / a["total_s"]
        if b:
            verdict[opt] = {"under_time": b["total_s"] < TIME_LIMIT_S,
                            "under_memory": b["peak_rss_mb"] < MEMORY_LIMIT_MB,
                            "ratio_ok": ratios.get(opt, 0.0) <= RATIO_LIMIT}
    lines = [f"{'samples':>9s} {'optimizer':9s} {'design s':>9s} {'fit s':>8s} {'total s':>8s} "
             f"{'peak MB':>8s}"]
    for c in cases:
        lines.append(f"{c['n_samples']:>9d} {c['optimizer']:9s} {c['design_s']:9.2f} "
                     f"{c['fit_s']:8.2f} {c['total_s']:8.2f} {c['peak_rss_mb']:8.0f}")
    lines.append("")
    for opt, r in ratios.items():
        v = verdict[opt]
        lines.append(f"{opt}: t({large:.0e})/t({small:.0e}) = {r:.2f} (limit {RATIO_LIMIT:g}); "
                     f"{large:.0e} samples under {TIME_LIMIT_S:g} s: {v['under_time']}, under "
                     f"{MEMORY_LIMIT_MB:g} MB: {v['under_memory']}")
    holds = bool(verdict) and all(all(v.values()) for v in verdict.values())
    lines.append(f"Claim (time, memory and ratio limits for every optimizer): "
                 f"{'HOLDS' if holds else 'DOES NOT HOLD'}")
    print("\n".join(lines))
    document = {
        "records": N_RECORDS,
        "manoeuvre": "random rudder +-35 deg, holds 30-120 s, seeds 0-7, dt 1 s",
        "cpu_count": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "cases": cases,
        "ratio_large_over_small": ratios,
        "limits": {"seconds": TIME_LIMIT_S, "memory_mb": MEMORY_LIMIT_MB, "ratio": RATIO_LIMIT},
        "verdict": verdict,
        "claim_holds": holds,
    }
    write_text_atomic(args.out, json.dumps(document, indent=2) + "\n")


if __name__ == "__main__":
    main()

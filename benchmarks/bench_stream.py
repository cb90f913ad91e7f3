"""Streamed fits of 10^6, 10^7 and 10^8 samples on one machine, through a two-worker Dask
LocalCluster.

Records: long random-rudder manoeuvres of the KCS (rudder angles uniform in +-35 deg, each held
30 to 120 s) flown by the MMG model at dt = 1 s, ``--record-seconds`` (default 100,000 s, so
10^5 samples) each, with the seeds 0, 1, ... in order (a seed whose MMG flight leaves the
plausible range is skipped, and named in the manifest): every record is its own simulation,
none is a copy.  They are flown in batches (the integrator flies the members of a batch
together) by ``--sim-processes`` processes and written to Parquet, one file per record, in
``--cache`` (kept between runs; ``manifest.json`` there says how they were made).  A size of
N samples fits the first N / 10^5 records: 10, 100 and 1000 records.

Every size runs in a fresh process: it starts a LocalCluster (``--workers`` single-threaded
worker processes; the scheduler runs in that process) and fits least squares with
:func:`sindyship.streaming.fit_files` (each record read, checked and reduced to its factors on
a worker, the factors merged as a tree on the cluster).  Reported: the wall time of the fit
with the cluster up and its workers' imports done (``fit_s``; the start-up, with those
imports, is ``startup_s``), the time per sample
relative to the smallest size (the claim: within 1.3 of linear), and the peak memory of the
whole process tree (the fitting process with the scheduler, the nannies and the workers),
sampled every 0.1 s from /proc: the largest sum of the processes' proportional set sizes
(PSS: shared library pages counted once) and of their resident set sizes (RSS: shared pages
counted in every process, an overestimate), and the sum of every process's own high-water
mark (VmHWM; an upper bound, the processes need not peak together).  A peak shorter than
0.1 s can be missed by the samples; VmHWM cannot miss it.

On the smallest size, the streamed coefficients of ``ls``, ``stlsq`` and ``lasso`` are
compared with :func:`sindyship.identify.fit` on the same records read into memory: the
largest difference relative to the largest coefficient of its equation.

Usage: ``python benchmarks/bench_stream.py [--sizes 1000000 10000000 100000000]
[--cache DIR] [--workers 2]``; prints a table and writes ``benchmarks/results/stream.json``.
Simulating the 1000 records of 10^8 samples took about 30 minutes on two cores shared with
other work (a batch of 100 records is 3 to 8 minutes on one core), the three fits 7 minutes.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import platform
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sindyship._io import write_text_atomic  # noqa: E402

OUT = Path(__file__).parent / "results" / "stream.json"
COLUMNS = ("t", "u", "v", "r", "x", "y", "psi", "delta", "delta_c")
RATIO_LIMIT = 1.3
MEMORY_LIMIT_MB = 2048.0
RUDDER_DEG = 35.0


def record_path(cache: Path, seed: int, seconds: int) -> Path:
    return cache / f"random-kcs-{seconds}s-seed{seed:05d}.parquet"


def skipped_path(cache: Path, seed: int, seconds: int) -> Path:
    """The marker of a seed whose MMG flight left the plausible range (no record)."""
    return cache / f"random-kcs-{seconds}s-seed{seed:05d}.diverged"


def simulate_batch(cache: str, seeds: list[int], seconds: int) -> float:
    """Fly one batch of records together and write each to Parquet (a flight that leaves the
    plausible range gets a marker instead); the seconds it took."""
    import pandas as pd

    from sindyship.manoeuvres import Manoeuvre, fly
    from sindyship.mmg import MMGModel
    from sindyship.ships import load_ship

    t0 = time.perf_counter()
    plan = [Manoeuvre("random", rudder=RUDDER_DEG, duration=float(seconds), seed=s)
            for s in seeds]
    runs = fly(MMGModel(load_ship("kcs")), plan)
    for seed, run in zip(seeds, runs, strict=True):
        if run.meta.get("diverged_at") is not None:
            skipped_path(Path(cache), seed, seconds).write_text(
                json.dumps({"diverged_at_s": float(run.meta["diverged_at"])}))
            continue
        path = record_path(Path(cache), seed, seconds)
        tmp = path.with_suffix(".tmp")
        pd.DataFrame({c: run[c] for c in COLUMNS}).to_parquet(tmp, index=False)
        tmp.replace(path)
    return time.perf_counter() - t0


def record_seeds(cache: Path, n_records: int, seconds: int) -> tuple[list[int], list[int]]:
    """The seeds of the first ``n_records`` records (seeds 0, 1, ... without those whose
    flight diverged), and the seeds skipped on the way; fewer when not yet simulated."""
    seeds, skipped, seed = [], [], 0
    while len(seeds) < n_records:
        if record_path(cache, seed, seconds).exists():
            seeds.append(seed)
        elif skipped_path(cache, seed, seconds).exists():
            skipped.append(seed)
        else:
            break
        seed += 1
    return seeds, skipped


def make_records(cache: Path, n_records: int, seconds: int, batch: int, processes: int) -> dict:
    """Simulate the records not yet in the cache; how they were made."""
    cache.mkdir(parents=True, exist_ok=True)
    t0, simulated = time.perf_counter(), 0
    while len(seeds := record_seeds(cache, n_records, seconds)[0]) < n_records:
        done = record_seeds(cache, 10**9, seconds)
        start = max(done[0] + done[1], default=-1) + 1
        missing = list(range(start, start + n_records - len(seeds)))
        size = min(batch, -(-len(missing) // processes))
        batches = [missing[i:i + size] for i in range(0, len(missing), size)]
        print(f"simulating {len(missing)} records of {seconds} s in {len(batches)} batches on "
              f"{processes} processes", file=sys.stderr)
        with multiprocessing.get_context("spawn").Pool(processes) as pool:
            jobs = [pool.apply_async(simulate_batch, (str(cache), b, seconds)) for b in batches]
            for k, job in enumerate(jobs):
                print(f"  batch {k + 1}/{len(jobs)}: {job.get():.0f} s", file=sys.stderr)
        simulated += len(missing)
    seeds, skipped = record_seeds(cache, n_records, seconds)
    manifest_path = cache / "manifest.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else {}
    manifest.update({
        "how": "each record simulated from scratch by the KCS MMG model (sindyship.manoeuvres."
               "fly), its own seed; no record is a copy or a resample of another",
        "manoeuvre": f"random rudder +-{RUDDER_DEG:g} deg, holds 30-120 s, start at U0",
        "records": len(seeds),
        "seeds": f"0 to {seeds[-1]}, without the skipped ones",
        "skipped_seeds": skipped,
        "skipped_why": "the MMG flight left the plausible range (sindyship's divergence check)",
        "seconds_per_record": seconds,
        "dt_s": 1.0,
        "format": "Parquet, one file per record, columns " + ", ".join(COLUMNS),
        "batch": batch,
    })
    if simulated:
        manifest["last_simulation_s"] = time.perf_counter() - t0
        manifest["last_simulated_records"] = simulated
    manifest_path.write_text(json.dumps(manifest, indent=2) + "\n")
    return manifest


# --------------------------------------------------------------------------------------------
# memory of a process tree, from /proc
# --------------------------------------------------------------------------------------------
def _children() -> dict[int, list[int]]:
    out: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as handle:
                ppid = int(handle.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        out.setdefault(ppid, []).append(int(entry))
    return out


def _tree(root: int) -> list[int]:
    children, todo, seen = _children(), [root], []
    while todo:
        pid = todo.pop()
        seen.append(pid)
        todo.extend(children.get(pid, []))
    return seen


def _status_kb(pid: int, key: str, file: str = "status") -> int:
    try:
        with open(f"/proc/{pid}/{file}") as handle:
            for line in handle:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


class TreeMemory:
    """Samples the memory of a process and its descendants every ``interval`` seconds."""

    def __init__(self, pid: int, interval: float = 0.1) -> None:
        self.pid, self.interval = pid, interval
        self.peak_pss = self.peak_rss = 0
        self.hwm: dict[int, int] = {}
        self.max_processes = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            pids = _tree(self.pid)
            self.max_processes = max(self.max_processes, len(pids))
            rss = pss = 0
            for pid in pids:
                rss += _status_kb(pid, "VmRSS")
                pss += _status_kb(pid, "Pss", "smaps_rollup")
                self.hwm[pid] = max(self.hwm.get(pid, 0), _status_kb(pid, "VmHWM"))
            self.peak_rss, self.peak_pss = max(self.peak_rss, rss), max(self.peak_pss, pss)
            self._stop.wait(self.interval)

    def __enter__(self) -> TreeMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()

    def summary(self) -> dict:
        return {"peak_pss_mb": self.peak_pss / 1024.0, "peak_rss_mb": self.peak_rss / 1024.0,
                "sum_of_process_hwm_mb": sum(self.hwm.values()) / 1024.0,
                "processes": self.max_processes}


# --------------------------------------------------------------------------------------------
# the cases, each in a fresh process
# --------------------------------------------------------------------------------------------
def _warm_up() -> None:
    import pyarrow.parquet  # noqa: F401

    import sindyship.streaming  # noqa: F401
    from sindyship.identify import design  # noqa: F401


def child_fit(cache: Path, n_records: int, seconds: int, workers: int) -> None:
    """One streamed least-squares fit: print a JSON line, save the model in the cache."""
    from sindyship.ships import load_ship
    from sindyship.streaming import connect, fit_files

    ship = load_ship("kcs")
    paths = [record_path(cache, k, seconds) for k in record_seeds(cache, n_records, seconds)[0]]
    t0 = time.perf_counter()
    with connect(n_workers=workers) as client:
        client.run(_warm_up)  # imports on every worker: start-up, not fitting
        t1 = time.perf_counter()
        model = fit_files(paths, ship, client=client)
        t2 = time.perf_counter()
    model.save(cache / f"model-stream-{n_records}x{seconds}.json")
    print(json.dumps({"n_samples": model.info["n_samples"], "records": n_records,
                      "workers": workers, "startup_s": t1 - t0, "fit_s": t2 - t1,
                      "total_s": time.perf_counter() - t0,
                      "load_average_1min_after": os.getloadavg()[0]}))


def _coefficient_gap(a, b) -> dict:
    out = {}
    for dof in ("X", "Y", "N"):
        x = np.array(list(a.coefficients[dof].values()))
        y = np.array(list(b.coefficients[dof].values()))
        scale = float(np.max(np.abs(x)))
        nonzero = x != 0
        out[dof] = {
            "max_abs_diff_over_max_coef": float(np.max(np.abs(x - y)) / scale),
            "max_rel_diff_per_nonzero_coef": float(np.max(np.abs(x - y)[nonzero]
                                                          / np.abs(x[nonzero]))),
            "same_zero_pattern": bool(np.array_equal(x == 0, y == 0)),
        }
    return out


def child_compare(cache: Path, n_records: int, seconds: int, workers: int) -> None:
    """Streamed against in-memory fits of ls, stlsq and lasso on the same records."""
    from sindyship.identify import fit
    from sindyship.ships import load_ship
    from sindyship.streaming import connect, fit_files, read_record

    ship = load_ship("kcs")
    paths = [record_path(cache, k, seconds) for k in record_seeds(cache, n_records, seconds)[0]]
    records = [read_record(p, ship=ship)[0] for p in paths]
    result = {}
    with connect(n_workers=workers) as client:
        for optimizer in ("ls", "stlsq", "lasso"):
            streamed = fit_files(paths, ship, optimizer=optimizer, client=client)
            direct = fit(records, ship, optimizer=optimizer)
            result[optimizer] = _coefficient_gap(direct, streamed)
            if optimizer == "ls":
                sv = direct.estimators_["Y"].singular_values_
                result["ls_condition_number_Y"] = float(sv[0] / sv[-1])
    print(json.dumps(result))


def run_child(args: list[str], env: dict) -> tuple[dict, dict]:
    """A child process under the memory sampler: its JSON line and the memory summary."""
    proc = subprocess.Popen([sys.executable, __file__, *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    with TreeMemory(proc.pid) as memory:
        out, err = proc.communicate()
    if proc.returncode != 0:
        raise RuntimeError(f"{args} failed:\n{err[-4000:]}")
    return json.loads(out.strip().splitlines()[-1]), memory.summary()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="+",
                        default=[1_000_000, 10_000_000, 100_000_000])
    parser.add_argument("--cache", type=Path,
                        default=Path(tempfile.gettempdir()) / "sindyship-bench-stream")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    parser.add_argument("--record-seconds", type=int, default=100_000,
                        help="length of every record [s] at dt = 1 s")
    parser.add_argument("--batch", type=int, default=100, help="records flown together")
    parser.add_argument("--sim-processes", type=int, default=2,
                        help="processes that simulate the records")
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--child", nargs=4, metavar=("KIND", "RECORDS", "SECONDS", "WORKERS"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        kind, n, seconds, workers = args.child
        task = child_fit if kind == "fit" else child_compare
        task(args.cache, int(n), int(seconds), int(workers))
        return

    seconds = args.record_seconds
    counts = {size: max(1, size // seconds) for size in sorted(args.sizes)}
    manifest = make_records(args.cache, max(counts.values()), seconds, args.batch,
                            args.sim_processes)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p])}
    cases = []
    for n in counts.values():
        load = os.getloadavg()[0]
        case, memory = run_child(["--cache", str(args.cache), "--child", "fit", str(n),
                                  str(seconds), str(args.workers)], env)
        case.update(memory, load_average_1min_before=load)
        cases.append(case)
        print(f"{case['n_samples']:>10d} samples ({n} records): fit {case['fit_s']:7.1f} s "
              f"(+ start-up {case['startup_s']:.1f} s), peak PSS {case['peak_pss_mb']:6.0f} MB "
              f"(RSS {case['peak_rss_mb']:.0f} MB, sum of HWM "
              f"{case['sum_of_process_hwm_mb']:.0f} MB)", file=sys.stderr)
    base = cases[0]
    for case in cases:
        case["time_per_sample_us"] = 1e6 * case["fit_s"] / case["n_samples"]
        case["time_per_sample_ratio"] = (case["time_per_sample_us"]
                                         / base["time_per_sample_us"])
    compare, _ = run_child(["--cache", str(args.cache), "--child", "compare",
                            str(counts[min(counts)]), str(seconds), str(args.workers)], env)
    largest = cases[-1]
    verdict = {
        "time_within_ratio": all(c["time_per_sample_ratio"] <= RATIO_LIMIT for c in cases),
        "largest_under_memory": largest["peak_pss_mb"] < MEMORY_LIMIT_MB,
        "largest_size": largest["n_samples"],
        "streamed_equals_in_memory_1e-10": all(
            g["max_abs_diff_over_max_coef"] <= 1e-10
            for opt in ("ls", "stlsq", "lasso") for g in compare[opt].values()),
    }
    lines = [f"{'samples':>10s} {'records':>7s} {'fit s':>8s} {'us/sample':>9s} {'ratio':>6s} "
             f"{'PSS MB':>7s} {'RSS MB':>7s} {'HWM MB':>7s}"]
    for c in cases:
        lines.append(f"{c['n_samples']:>10d} {c['records']:>7d} {c['fit_s']:8.1f} "
                     f"{c['time_per_sample_us']:9.2f} {c['time_per_sample_ratio']:6.2f} "
                     f"{c['peak_pss_mb']:7.0f} {c['peak_rss_mb']:7.0f} "
                     f"{c['sum_of_process_hwm_mb']:7.0f}")
    lines.append("")
    for opt in ("ls", "stlsq", "lasso"):
        worst = max(g["max_abs_diff_over_max_coef"] for g in compare[opt].values())
        lines.append(f"{opt}: streamed - in-memory, largest difference / largest coefficient "
                     f"= {worst:.2e} on {cases[0]['n_samples']} samples")
    lines.append(f"Claims: time per sample within {RATIO_LIMIT} of the smallest size: "
                 f"{verdict['time_within_ratio']}; {largest['n_samples']:.0e} samples under "
                 f"{MEMORY_LIMIT_MB:g} MB: {verdict['largest_under_memory']}")
    print("\n".join(lines))
    document = {
        "records": manifest,
        "cluster": f"dask.distributed LocalCluster, {args.workers} worker processes of one "
                   "thread, scheduler in the fitting process",
        "optimizer_scaled": "ls",
        "memory_measured": "the fitting process (client and scheduler), nannies and workers, "
                           "sampled every 0.1 s from /proc: peak of the summed PSS and RSS, "
                           "and the sum of every process's VmHWM",
        "cpu_count": os.cpu_count(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "cases": cases,
        "compare_with_in_memory": compare,
        "limits": {"time_per_sample_ratio": RATIO_LIMIT, "memory_mb": MEMORY_LIMIT_MB},
        "verdict": verdict,
    }
    write_text_atomic(args.out, json.dumps(document, indent=2) + "\n")


if __name__ == "__main__":
    main()

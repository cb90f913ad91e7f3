"""Time the steps users wait for, beside another checkout of sindyship in the same run.

The steps, each timed in a fresh process of the checkout (``PYTHONPATH``), best of
``--repeat``:

``protocol_flights``
    The 11 protocol manoeuvres (8 training, 3 held-out, 3200 s each) flown together by the KCS
    MMG model, after one warm-up flight in the same process (target below 0.3 s).
``diagnose_protocol``
    ``diagnose`` on the 8 training manoeuvres with its default settings (one process, no
    figures), after a warm-up diagnosis (target below 4 s).
``diagnose_10hz``
    ``diagnose`` on the six MARIN KVLCC2 free-running trials resampled at 10 Hz (about 65,700
    samples; the model-scale servo makes the integration step 1 s and every replayed rudder
    changes at every sample), default settings, one process, no figures (target below 30 s).
    Skipped when the shared data folder is absent.
``reproduce``
    ``sindyship reproduce`` end to end in a fresh process, figures and files included
    (target below 120 s: the refinement of the diagnosed model by its training flights takes
    about a minute of it; the fits, diagnosis and figures took 14 s before it was added).

The exported simulator's right-hand side is timed against the library's by
``benchmarks/bench_export.py`` (the plain module, which is what ``export`` wrote before
``--compile``, and the compiled one in the same run).

Prints and saves ``benchmarks/results/speed.json``.  These machines are noisy: compare the two
checkouts' figures of one run, not figures of different runs.

    git worktree add /tmp/sindyship-before COMMIT     # the version to compare with
    python benchmarks/bench_speed.py --against /tmp/sindyship-before [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sindyship.marin import default_marin_dir  # noqa: E402

OUT = Path(__file__).parent / "results" / "speed.json"
TARGETS = {"protocol_flights": 0.3, "diagnose_protocol": 4.0, "diagnose_10hz": 30.0,
           "reproduce": 120.0}

_BEST_OF = """
import json, sys, time
def best(f, repeat):
    f()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter(); f(); times.append(time.perf_counter() - t0)
    return times
"""

SNIPPETS = {
    "protocol_flights": _BEST_OF + """
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
plan = protocol_manoeuvres()
mmg = MMGModel(load_ship("kcs"))
print(json.dumps({"times": best(lambda: fly(mmg, plan["train"] + plan["test"]),
                                int(sys.argv[1]))}))
""",
    "diagnose_protocol": _BEST_OF + """
from sindyship.diagnose import diagnose
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
ship = load_ship("kcs")
train = fly(MMGModel(ship), protocol_manoeuvres()["train"])
print(json.dumps({"times": best(lambda: diagnose(train, ship), int(sys.argv[1])),
                  "samples": sum(r.n_samples for r in train)}))
""",
    "diagnose_10hz": _BEST_OF + """
from sindyship.diagnose import diagnose
from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
from sindyship.measurements import trajectory_from_frame
from sindyship.ships import load_ship
folder = default_marin_dir()
if folder is None:
    print(json.dumps({"skipped": "the shared data folder is absent"}))
    raise SystemExit
ship = load_ship("kvlcc2").scaled(45.7)
records = [trajectory_from_frame(read_marin(folder / name).data, key, resample=0.1)
           for key, name in MARIN_FILES.items()]
print(json.dumps({"times": best(lambda: diagnose(records, ship), int(sys.argv[1])),
                  "samples": sum(r.n_samples for r in records)}))
""",
}


def _run(checkout: Path, step: str, repeat: int) -> dict:
    """One step of ``checkout`` in a fresh process: its wall times [s] (and samples)."""
    env = {**os.environ, "PYTHONPATH": str(checkout), "MPLBACKEND": "Agg"}
    marin = default_marin_dir()  # the same data for a checkout in another folder
    if marin is not None:
        env["SINDYSHIP_MARIN_DIR"] = str(marin)
    if step == "reproduce":
        times = []
        for _ in range(repeat):
            with tempfile.TemporaryDirectory() as folder:
                start = time.perf_counter()
                subprocess.run([sys.executable, "-m", "sindyship.cli", "reproduce", "--out",
                                folder], env=env, check=True, cwd=checkout,
                               capture_output=True)
                times.append(time.perf_counter() - start)
        return {"seconds_all": times, "seconds": min(times)}
    done = subprocess.run([sys.executable, "-c", SNIPPETS[step], str(repeat)], env=env,
                          check=True, cwd=checkout, capture_output=True, text=True)
    found = json.loads(done.stdout.strip().splitlines()[-1])
    if "times" not in found:
        return found
    out = {"seconds_all": found["times"], "seconds": min(found["times"])}
    if "samples" in found:
        out["samples"] = found["samples"]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=3, help="timed runs of each (default 3)")
    parser.add_argument("--against", type=Path, default=None,
                        help="another checkout, timed in the same run")
    parser.add_argument("--steps", nargs="+", default=list(TARGETS), choices=list(TARGETS))
    args = parser.parse_args()
    result = {"cpu_count": os.cpu_count(), "against": None if args.against is None
              else str(args.against), "steps": {}}
    for step in args.steps:
        entry = {"target_seconds": TARGETS[step], "now": _run(ROOT, step, args.repeat)}
        if args.against is not None:
            entry["before"] = _run(args.against.resolve(), step, args.repeat)
        now, before = entry["now"], entry.get("before", {})
        if "seconds" in now:
            entry["meets_target"] = now["seconds"] < TARGETS[step]
            if "seconds" in before:
                entry["speed_up"] = before["seconds"] / now["seconds"]
        result["steps"][step] = entry
        print(step, json.dumps(entry), flush=True)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()

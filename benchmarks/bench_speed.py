"""Time the steps users wait for, beside another checkout of sindyship in the same run.

The steps, each timed in a fresh process of the checkout (``PYTHONPATH``), best of
``--repeat``:

``protocol_flights``
    The 11 protocol manoeuvres (8 training, 3 held-out, 3200 s each) flown together by the KCS
    MMG model, after one warm-up flight in the same process (target below 0.3 s).
``diagnose_protocol``
    ``diagnose`` on the 8 training manoeuvres with its default settings (one process, no
    figures), after a warm-up diagnosis.  It checks its verdict by making the ``fit`` command
    it names, the default fit refined by its flights, without and with the effect named
    (:attr:`sindyship.diagnose.Diagnosis.command`): target below 15 s, the diagnosis's own
    4 s (below) and two default fits, of which the one with the effect refines on (about 3
    and 8 s on two cores).
``diagnose_protocol_unchecked``
    The same without that check (``check_command=False``; the checkout compared with, which
    has no such check, runs its default): the diagnosis's own flights and fits, target below
    4 s.
``diagnose_10hz``
    ``diagnose`` on the six MARIN KVLCC2 free-running trials resampled at 10 Hz (about 65,700
    samples; the model-scale servo makes the integration step 1 s and every replayed rudder
    changes at every sample), default settings, one process, no figures (target below 30 s).
    Skipped when the shared data folder is absent.
``protocol_solve_ivp``
    The same 11 manoeuvres flown one by one by a scalar ``solve_ivp`` (RK45) reference of the
    same MMG (``benchmarks/scalar_reference.py``; this checkout only): ``protocol_flights``
    should be at least 7 times faster (``reference_over_flights``), and the JSON says how far
    apart the two flights end.
``fit_protocol``, ``fit_refine10_protocol``
    ``sindyship fit`` on the protocol's 8 training records in a fresh process: with its
    defaults, and with ``--refine 10`` (the command line is the same in both checkouts; what
    it fits is each checkout's default).
``fit_marin``, ``fit_refine10_marin``
    The same on the four MARIN zig-zags (measurement CSVs written from the shared data, 1 Hz,
    ``--derivative savgol --window 21``; skipped when the shared data folder is absent).
``reproduce``
    ``sindyship reproduce`` end to end in a fresh process, figures and files included
    (target below 15 s).

The exported simulator's right-hand side is timed against the library's by
``benchmarks/bench_export.py`` (the plain module, which is what ``export`` wrote before
``--compile``, and the compiled one in the same run).

Prints and saves ``benchmarks/results/speed.json``; ``--steps`` times the steps named and keeps
the others' saved figures.  These machines are noisy: compare the two checkouts' figures of one
step, which are always timed in one run, not figures of different runs.

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
TARGETS = {"protocol_flights": 0.3, "protocol_solve_ivp": None, "diagnose_protocol": 15.0,
           "diagnose_protocol_unchecked": 4.0, "diagnose_10hz": 30.0, "fit_protocol": None,
           "fit_refine10_protocol": None, "fit_marin": None, "fit_refine10_marin": None,
           "reproduce": 15.0}
#: The ``fit`` steps: which records, and the options after them.
FIT_STEPS = {"fit_protocol": ("protocol", []), "fit_refine10_protocol": ("protocol",
                                                                          ["--refine", "10"]),
             "fit_marin": ("marin", []), "fit_refine10_marin": ("marin", ["--refine", "10"])}
MARIN_ZIGZAGS = ("zz_10", "zz_-10", "zz_20", "zz_-20")
#: The MARIN measurements are full scale; the built-in ``kvlcc2`` is the model at 1:45.7.
MARIN_SCALE = 45.7

_BEST_OF = """
import json, sys, time
def best(f, repeat):
    f()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter(); f(); times.append(time.perf_counter() - t0)
    return times
"""

#: ``diagnose`` on the protocol's training records with OPTIONS (a checkout without an option
#: runs its default).
_DIAGNOSE_PROTOCOL = _BEST_OF + """
import inspect
from sindyship.diagnose import diagnose
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
ship = load_ship("kcs")
train = fly(MMGModel(ship), protocol_manoeuvres()["train"])
known = inspect.signature(diagnose).parameters
options = {key: value for key, value in OPTIONS.items() if key in known}
print(json.dumps({"times": best(lambda: diagnose(train, ship, **options), int(sys.argv[1])),
                  "samples": sum(r.n_samples for r in train), "options": options}))
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
    "protocol_solve_ivp": _BEST_OF + """
import numpy as np
sys.path.insert(0, "benchmarks")
from scalar_reference import RTOL, fly_scalar
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
plan = protocol_manoeuvres()
ship = load_ship("kcs")
mmg = MMGModel(ship)
manoeuvres = plan["train"] + plan["test"]
times = best(lambda: [fly_scalar(mmg, m) for m in manoeuvres], int(sys.argv[1]))
apart = max(float(np.nanmax(np.hypot(a["x"] - b["x"], a["y"] - b["y"]))) / ship.L
            for a, b in zip(fly(mmg, manoeuvres), [fly_scalar(mmg, m) for m in manoeuvres]))
print(json.dumps({"times": times, "rtol": RTOL, "largest_distance_L": apart}))
""",
    "diagnose_protocol": _DIAGNOSE_PROTOCOL.replace("OPTIONS", "{}"),
    "diagnose_protocol_unchecked": _DIAGNOSE_PROTOCOL.replace("OPTIONS",
                                                              '{"check_command": False}'),
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


def _records(kind: str, folder: Path) -> list[str] | None:
    """Measurement CSVs of the ``fit`` steps in ``folder``: the protocol's training records,
    or the four MARIN zig-zags (None without the shared data)."""
    from sindyship.manoeuvres import fly, protocol_manoeuvres
    from sindyship.measurements import write_csv
    from sindyship.mmg import MMGModel
    from sindyship.ships import load_ship

    if kind == "protocol":
        records = fly(MMGModel(load_ship("kcs")), protocol_manoeuvres()["train"])
    else:
        from sindyship.marin import MARIN_FILES, read_marin
        from sindyship.measurements import trajectory_from_frame

        marin = default_marin_dir()
        if marin is None:
            return None
        records = [_model_scale(trajectory_from_frame(read_marin(marin / MARIN_FILES[key]).data,
                                                      key, resample=1.0))
                   for key in MARIN_ZIGZAGS]
    paths = []
    for record in records:
        path = folder / f"{record.name}.csv"
        write_csv(record, path)
        paths.append(str(path))
    return paths


def _model_scale(record, scale: float = MARIN_SCALE):
    """A full-scale MARIN record Froude-scaled to the built-in ``kvlcc2`` model (lengths / scale,
    speeds and times / sqrt(scale), rates and revolutions x sqrt(scale))."""
    from sindyship.trajectory import Trajectory

    root = scale**0.5
    factors = {"t": 1 / root, "u": 1 / root, "v": 1 / root, "x": 1 / scale, "y": 1 / scale,
               "r": root, "p": root, "n": root}
    data = record.data.copy()
    for column, factor in factors.items():
        if column in data:
            data[column] = data[column] * factor
    return Trajectory(data, name=record.name)


def _fit_command(step: str, folder: Path) -> list[str] | None:
    """The ``sindyship fit`` arguments of a ``fit`` step (None: its data is absent)."""
    kind, options = FIT_STEPS[step]
    paths = _records(kind, folder / kind)
    if paths is None:
        return None
    window = f"{21.0 / MARIN_SCALE**0.5:.3f}"  # 21 s at full scale
    ship = ["--ship", "kcs"] if kind == "protocol" else [
        "--ship", "kvlcc2", "--derivative", "savgol", "--window", window]
    return ["fit", *paths, *ship, *options, "--out", str(folder / "model.json")]


def _run(checkout: Path, step: str, repeat: int) -> dict:
    """One step of ``checkout`` in a fresh process: its wall times [s] (and samples)."""
    env = {**os.environ, "PYTHONPATH": str(checkout), "MPLBACKEND": "Agg"}
    marin = default_marin_dir()  # the same data for a checkout in another folder
    if marin is not None:
        env["SINDYSHIP_MARIN_DIR"] = str(marin)
    if step in FIT_STEPS:
        times = []
        with tempfile.TemporaryDirectory() as name:
            folder = Path(name)
            (folder / "protocol").mkdir()
            (folder / "marin").mkdir()
            command = _fit_command(step, folder)
            if command is None:
                return {"skipped": "the shared data folder is absent"}
            for _ in range(repeat):
                start = time.perf_counter()
                subprocess.run([sys.executable, "-m", "sindyship.cli", *command], env=env,
                               check=True, cwd=checkout, capture_output=True)
                times.append(time.perf_counter() - start)
        return {"seconds_all": times, "seconds": min(times)}
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
    out.update({key: value for key, value in found.items() if key != "times"})
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
    if set(args.steps) != set(TARGETS) and OUT.exists():  # a subset: the others stay
        saved = json.loads(OUT.read_text())
        result["steps"] = {k: v for k, v in saved["steps"].items() if k in TARGETS}
    for step in args.steps:
        entry = {"target_seconds": TARGETS[step], "now": _run(ROOT, step, args.repeat)}
        if args.against is not None and step != "protocol_solve_ivp":
            entry["before"] = _run(args.against.resolve(), step, args.repeat)
        now, before = entry["now"], entry.get("before", {})
        if "seconds" in now and TARGETS[step] is not None:
            entry["meets_target"] = now["seconds"] < TARGETS[step]
        if "seconds" in now and "seconds" in before:
            entry["speed_up"] = before["seconds"] / now["seconds"]
        result["steps"][step] = entry
        print(step, json.dumps(entry), flush=True)
    steps = result["steps"]
    if "seconds" in steps.get("protocol_solve_ivp", {}).get("now", {}) \
            and "seconds" in steps.get("protocol_flights", {}).get("now", {}):
        result["reference_over_flights"] = (steps["protocol_solve_ivp"]["now"]["seconds"]
                                            / steps["protocol_flights"]["now"]["seconds"])
        print("solve_ivp reference / protocol flights:",
              f"{result['reference_over_flights']:.1f}", flush=True)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()

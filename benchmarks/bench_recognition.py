"""Zig-zags logged with the actual rudder alone: how often each is recognised right.

Most logs hold the rudder's actual angle and not its command.  A zig-zag is recognised from
the rudder's holds (:mod:`sindyship.rudder_holds`), and an actual rudder reaches each angle
through its steering gear: the KCS's full-scale servo approaches it so slowly that it never
settles within a leg, the KVLCC2 model's within a second.  This benchmark flies the five
zig-zags 35/10, 20/20, 15/15, 10/10 and 5/5 of both ships (40 L/U0 long), logs them at six
sampling steps (0.02 to 1 s for the KCS, the same in L/U0 for the model) with Gaussian noise
of 0, 0.1 and 0.3 deg on the actual rudder (no ``delta_c``), and counts for each ship

- ``right``: recognised with the nominal amplitude, check angle and first side, executed
  within a quarter of L/U0 of the first sample;
- ``wrong``: recognised as another zig-zag or from a later execute;
- ``missed``: not recognised (such a record is replayed open loop);

both as :func:`sindyship.trials.recognise_zigzag` reads it (in readings of about
:data:`sindyship.rudder_holds.READINGS_PER_LEG` to a leg when its holds are fragments) and
sample by sample.  Then it counts ``false`` recognitions: random rudder steps (10, 20 and
35 deg, holds of 1.6 to 6.4 L/U0, 64 L/U0 long, seeds 0 to 9, logged at two of the steps,
with and without 0.1 deg of noise), which are no zig-zag.

Prints the table and saves ``benchmarks/results/recognition.json``.  Run with
``python benchmarks/bench_recognition.py`` (about a minute).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from sindyship._io import clean_json, write_text_atomic
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
from sindyship.trajectory import Trajectory
from sindyship.trials import _recognise_rudder, recognise_zigzag

OUT = Path(__file__).parent / "results" / "recognition.json"
ZIGZAGS = ((35, 10), (20, 20), (15, 15), (10, 10), (5, 5))
#: Sampling steps [s] of the KCS; the KVLCC2 model's are the same in L/U0.
STEPS_KCS = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0)
NOISE_DEG = (0.0, 0.1, 0.3)
LENGTH = 40.0  # L/U0
SEED = 0
#: Random rudder steps: amplitudes [deg], seeds, the sampling steps (of STEPS_KCS), noise
#: [deg], hold times and length [L/U0].
RANDOM_RUDDER = (10, 20, 35)
RANDOM_SEEDS = range(10)
RANDOM_STEPS = (0.1, 0.5)
RANDOM_NOISE_DEG = (0.0, 0.1)
RANDOM_HOLD = (1.6, 6.4)
RANDOM_LENGTH = 64.0


def sample_by_sample(record: Trajectory):
    """The zig-zag recognised from every sample of the actual rudder (no readings)."""
    t = record.t
    return _recognise_rudder(t, record["psi"], record["r"], np.degrees(record.rudder), False,
                             t)[0]


def verdict(found, amplitude: float, check: float, latest: float) -> str:
    if found is None:
        return "missed"
    right = (found.amplitude_deg == amplitude and found.check_deg == check
             and found.first_sign == 1 and found.start_time <= latest)
    return "right" if right else "wrong"


def random_rudder(ship, rng) -> dict:
    """How many random-rudder records are recognised as a zig-zag (none is one)."""
    unit = ship.L / ship.U0
    kcs_time = (lambda s: s.L / s.U0)(load_ship("kcs"))
    counts = {"records": 0, "read": 0, "by_sample": 0}
    for seed in RANDOM_SEEDS:
        for step in RANDOM_STEPS:
            plan = [Manoeuvre("random", rudder=amplitude, seed=seed,
                              hold=(RANDOM_HOLD[0] * unit, RANDOM_HOLD[1] * unit),
                              duration=RANDOM_LENGTH * unit, dt=step * unit / kcs_time)
                    for amplitude in RANDOM_RUDDER]
            for flown in fly(MMGModel(ship), plan):
                actual = flown.data.drop(columns=["delta_c"])
                for noise in RANDOM_NOISE_DEG:
                    record = Trajectory(actual.assign(delta=actual["delta"] + np.radians(noise)
                                                      * rng.standard_normal(len(actual))), "r")
                    counts["records"] += 1
                    counts["read"] += recognise_zigzag(record) is not None
                    counts["by_sample"] += sample_by_sample(record) is not None
    return counts


def run() -> dict:
    start = time.perf_counter()
    rng = np.random.default_rng(SEED)
    kcs_time = (lambda s: s.L / s.U0)(load_ship("kcs"))
    out = {"zigzags": [f"{a}/{c}" for a, c in ZIGZAGS], "noise_deg": list(NOISE_DEG),
           "length_L_over_U0": LENGTH, "seed": SEED, "ships": {}}
    for name in ("kcs", "kvlcc2"):
        ship = load_ship(name)
        unit = ship.L / ship.U0
        steps = [s * unit / kcs_time for s in STEPS_KCS]
        counts = {way: {"right": 0, "wrong": 0, "missed": 0} for way in ("read", "by_sample")}
        cases = []
        for amplitude, check in ZIGZAGS:
            for step in steps:
                (flown,) = fly(MMGModel(ship), [Manoeuvre("zigzag", rudder=amplitude,
                                                          check=check, duration=LENGTH * unit,
                                                          dt=step)])
                actual = flown.data.drop(columns=["delta_c"])
                for noise in NOISE_DEG:
                    noisy = actual.assign(delta=actual["delta"] + np.radians(noise)
                                          * rng.standard_normal(len(actual)))
                    record = Trajectory(noisy, f"zz{amplitude}_{check}")
                    read = verdict(recognise_zigzag(record), amplitude, check, 0.25 * unit)
                    by_sample = verdict(sample_by_sample(record), amplitude, check, 0.25 * unit)
                    counts["read"][read] += 1
                    counts["by_sample"][by_sample] += 1
                    cases.append({"zigzag": f"{amplitude}/{check}", "step_s": step,
                                  "noise_deg": noise, "read": read, "by_sample": by_sample})
        false = random_rudder(ship, np.random.default_rng(SEED + 1))
        out["ships"][name] = {"steps_s": steps, "counts": counts, "cases": cases,
                              "random_rudder": false}
        print(f"{name}: read {counts['read']}, sample by sample {counts['by_sample']}; random "
              f"rudder recognised as a zig-zag: {false['read']} of {false['records']} read, "
              f"{false['by_sample']} sample by sample", flush=True)
    out["seconds"] = time.perf_counter() - start
    return out


def main() -> None:
    result = run()
    write_text_atomic(OUT, json.dumps(clean_json(result), indent=1) + "\n")
    print(f"wrote {OUT} ({result['seconds']:.0f} s)")


if __name__ == "__main__":
    main()

"""Measured wind and changing revolutions: does the diagnosis find them, and does the error fall?

Prints and saves ``benchmarks/results/measured-channels.json``.  The KCS flies the protocol's
8 training and 3 held-out manoeuvres (``sindyship.manoeuvres.protocol_manoeuvres``) in
conditions it logs as channels of its records (``simulate --effect``):

``wind``
    A gusty true wind of 15 m/s (gusts 20 % of it, the direction wandering by 10 deg) from a
    different mean direction in every record (137.5 deg apart, the golden angle), recorded as
    ``wind_speed`` and ``wind_dir``.
``propeller``
    Revolutions that differ between records (80, 90, 105 or 110 % of the design value) and step
    by -20 or +15 % in the middle of every other record, recorded as ``n``.
``environment``
    A steady earth-fixed load (Prime II 0.002 from 45 deg) on records with noise: 1 % of each
    channel's RMS on u, v, r and the rudder, 0.1 deg on the heading, 0.5 m on positions.

For each case: the diagnosis's ranking (the first effect, its share and whether it is
meaningful), then a plain Abkowitz fit against one with the effect (least squares, the same
training records), both flown on the held-out records with their recorded channels as time
series; the fall is the geometric mean over the held-out manoeuvres of the after/before mean
distance over the window both flights cover (``BeforeAfter.ratio``); a divergence is reported
and counts as a failure.

``python benchmarks/bench_measured_channels.py`` (about a minute on two cores).
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

from sindyship.diagnose import before_after, diagnose
from sindyship.effects import add_noise, parse_effects, simulate_with_effects
from sindyship.manoeuvres import protocol_manoeuvres
from sindyship.ships import load_ship

OUT = Path(__file__).parent / "results" / "measured-channels.json"
GOLDEN_ANGLE = 137.5


def wind_effects(index: int) -> list[str]:
    """The wind of record ``index``: 15 m/s with gusts, its own mean direction and seed."""
    direction = (30.0 + GOLDEN_ANGLE * index) % 360.0
    return ["wind=15", f"wind_dir={direction:.1f}", "gust=0.2", "wind_wander=10",
            f"seed={index + 1}"]


def propeller_effects(index: int) -> list[str]:
    """The revolutions of record ``index``: 80-110 % of design, a step in every other one."""
    level = (0.8, 0.9, 1.05, 1.1)[index % 4]
    step = ("rps_step=-0.2" if level > 0.9 else "rps_step=0.15") if index % 2 else "rps_step=0"
    return [f"rps={level}", step, f"seed={index + 1}"]


def load_effects(index: int) -> list[str]:
    """A steady earth-fixed load (Prime II 0.002 from the north-east) and 1 % noise on u, v, r
    and the rudder, every record with its own noise seed."""
    return ["load=0.002", "load_dir=45", "noise=0.01", f"seed={index + 1}"]


CASES = {"wind": wind_effects, "propeller": propeller_effects, "environment": load_effects}
NOISE = {"psi": math.radians(0.1), "x": 0.5, "y": 0.5}


def records_in(ship, conditions) -> tuple[list, list]:
    """The protocol's training and held-out records, each flown in its own conditions."""
    plan = protocol_manoeuvres()
    flown = {}
    for kind, manoeuvres in plan.items():
        offset = 0 if kind == "train" else len(plan["train"])
        flown[kind] = [simulate_with_effects(ship, [m], parse_effects(conditions(offset + i)))[0]
                       for i, m in enumerate(manoeuvres)]
        if conditions is load_effects:  # heading and positions get their own noise levels
            flown[kind] = [add_noise(r, NOISE, seed=100 + offset + i)
                           for i, r in enumerate(flown[kind])]
    return flown["train"], flown["test"]


def run_case(name: str, conditions) -> dict:
    kcs = load_ship("kcs")
    train, test = records_in(kcs, conditions)
    result = diagnose(train, kcs, fly_training=False, confirm=0)
    noise = result.noise_floor
    first = result.ranking[0]
    change = before_after(train, kcs, effects=[name], test=test, fly_training=False)
    rows = [
        {
            "manoeuvre": row["manoeuvre"],
            "before_mean_L": row["common"]["before_mean_L"],
            "after_mean_L": row["common"]["after_mean_L"],
            "common_window_s": row["common"]["window_s"],
            "before_diverged_at_s": row["before"]["diverged_at_s"],
            "after_diverged_at_s": row["after"]["diverged_at_s"],
        }
        for row in change.rows
    ]
    return {
        "ranked_first": first.effect.name,
        "first_share": first.explained_signal,
        "first_meaningful": bool(first.meaningful),
        "ranking": [s.effect.name for s in result.ranking],
        "noise_floor": noise,
        "held_out": rows,
        "geometric_mean_ratio": change.ratio("held-out"),
        "after_diverged": any(r["after_diverged_at_s"] is not None for r in rows),
    }


def main() -> dict:
    start = time.perf_counter()
    results = {name: run_case(name, conditions) for name, conditions in CASES.items()}
    results["seconds"] = time.perf_counter() - start
    for name in CASES:
        case = results[name]
        print(f"{name}: ranked first {case['ranked_first']} "
              f"({100 * case['first_share']:.1f} %, meaningful {case['first_meaningful']}); "
              f"held-out mean distance after/before {case['geometric_mean_ratio']:.3f} "
              "(geometric mean, common windows)")
        for row in case["held_out"]:
            print(f"  {row['manoeuvre']:10s} {row['before_mean_L']:.3f} -> "
                  f"{row['after_mean_L']:.3f} L over {row['common_window_s']:.0f} s")
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(results, indent=2, default=float) + "\n")
    return results


if __name__ == "__main__":
    main()

"""False alarms and detections of the diagnosis on noisy records; save the numbers.

Prints and saves ``benchmarks/results/significance.json``.  An effect is *meaningful* when it
explains at least 5 % of the force error above the noise floor, counting only the equations
whose gain holds when the manoeuvres are resampled (:func:`sindyship.diagnose.scoring.
significance`).  This script measures how often that rule fires for effects that are absent
and how often it finds one that is present:

``false_alarms``
    Records without the effect: the symmetric KCS (gamma_R = 0.415 to both sides; asymmetry
    and environment are absent from its physics) and data flown by the paper's own Abkowitz
    model (every catalogued effect absent), over noise levels (0, 0.5, 1 and 2 % of each
    channel's RMS on u, v, r; 0.1 deg on heading and rudder; 0.5 m on positions), seeds and
    manoeuvre sets.  The false-alarm rate is the share of (case, absent effect) pairs that are
    meaningful.
``detections``
    A steady earth-fixed load (Prime II 0.001 and 0.002, several directions) on the symmetric
    KCS with the same noise: whether ``environment`` ranks first and is meaningful.

``python benchmarks/bench_significance.py`` (about 5 minutes on two cores).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from sindyship.diagnose import diagnose
from sindyship.effects import parse_effects, sensor_noise, simulate_with_effects
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.model import paper_model
from sindyship.ships import load_ship

OUT = Path(__file__).parent / "results" / "significance.json"
NOISE_LEVELS = (0.0, 0.005, 0.01, 0.02)
SEEDS = (1, 2, 3)


def _case(records, ship, absent) -> dict:
    result = diagnose(records, ship, fly_training=False, confirm=0)
    scores = {s.effect.name: s for s in result.ranking}
    return {
        "false_alarms": sorted(name for name in absent if name in scores
                               and scores[name].meaningful),
        "explained_signal": {name: scores[name].explained_signal for name in absent
                             if name in scores},
        "noise_floor": result.noise_floor,
    }


def main() -> dict:
    start = time.perf_counter()
    kcs = load_ship("kcs")
    symmetric = kcs.with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)
    plan = protocol_manoeuvres()["train"]
    sets = {"protocol-8": plan, "turns-and-zigzags-6": plan[1:7]}
    sources = {
        "symmetric-mmg": (MMGModel(symmetric), symmetric, ("asymmetry", "environment")),
        "abkowitz-model": (paper_model(kcs).dynamics(), kcs,
                           ("asymmetry", "environment", "crossflow", "higher_order")),
    }
    cases = []
    for source, (dynamics, ship, absent) in sources.items():
        for set_name, manoeuvres in sets.items():
            clean = fly(dynamics, manoeuvres)
            for level in NOISE_LEVELS:
                for seed in SEEDS if level else (0,):
                    case = _case(sensor_noise(clean, level, seed), ship, absent)
                    cases.append({"source": source, "manoeuvres": set_name, "noise": level,
                                  "seed": seed, **case})
                    print(f"{source:15s} {set_name:20s} noise {level:.3f} seed {seed}: "
                          f"false alarms {case['false_alarms']}", flush=True)
    pairs = sum(len(c["explained_signal"]) for c in cases)
    alarms = sum(len(c["false_alarms"]) for c in cases)
    detections = []
    for magnitude in (0.001, 0.002):
        for direction in (45, 135, 270):
            effects = parse_effects([f"load={magnitude}", f"load_dir={direction}"])
            clean = simulate_with_effects(symmetric, plan, effects)
            for level in (0.0, 0.01):
                result = diagnose(sensor_noise(clean, level, 7), symmetric, fly_training=False,
                                  confirm=0)
                top = result.ranking[0]
                env = next(s for s in result.ranking if s.effect.name == "environment")
                detections.append({"load": magnitude, "load_dir": direction, "noise": level,
                                   "top": top.effect.name, "meaningful": env.meaningful,
                                   "explained": env.explained,
                                   "explained_signal": env.explained_signal})
                print(f"load {magnitude} from {direction} deg, noise {level}: top "
                      f"{top.effect.name}, environment {100 * env.explained:.1f} % "
                      f"({100 * env.explained_signal:.1f} % above noise)", flush=True)
    document = {
        "false_alarm_rate": alarms / pairs,
        "false_alarms": alarms,
        "absent_effect_cases": pairs,
        "cases": cases,
        "detections": detections,
        "detected": sum(d["top"] == "environment" and d["meaningful"] for d in detections),
        "detection_cases": len(detections),
        "seconds": time.perf_counter() - start,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(document, indent=2) + "\n")
    print(f"false alarms: {alarms} of {pairs} absent-effect scores "
          f"({100 * alarms / pairs:.1f} %); environment found in {document['detected']} of "
          f"{len(detections)} load cases; {document['seconds']:.0f} s")
    return document


if __name__ == "__main__":
    main()

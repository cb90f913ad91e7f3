"""Time the 11 protocol manoeuvres (8 training, 3 held-out, 3200 s each) with the MMG model.

Prints and saves ``benchmarks/results/simulate.json``: the wall time of one batch flight at
the default step (best of ``--repeat``), and the largest position change in ship lengths
when the step is halved (the accuracy claim: below 1e-4 L).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
from sindyship.simulation import default_step

OUT = Path(__file__).parent / "results" / "simulate.json"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    ship = load_ship("kcs")
    mmg = MMGModel(ship)
    plan = protocol_manoeuvres()
    manoeuvres = plan["train"] + plan["test"]
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        coarse = fly(mmg, manoeuvres)
        times.append(time.perf_counter() - t0)
    step = default_step(ship)
    fine = fly(mmg, manoeuvres, step=0.5 * step)
    moved = max(float(np.max(np.hypot(a["x"] - b["x"], a["y"] - b["y"]))) / ship.L
                for a, b in zip(coarse, fine, strict=True))
    result = {
        "manoeuvres": len(manoeuvres),
        "simulated_seconds_each": 3200,
        "step_s": step,
        "wall_seconds_best": min(times),
        "wall_seconds_all": times,
        "max_position_change_when_step_halved_L": moved,
        "target_wall_seconds": 1.0,
        "target_position_change_L": 1e-4,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

"""Time the 11 protocol manoeuvres (8 training, 3 held-out, 3200 s each) with the MMG model.

Flies them as one batch twice over: with the numpy accelerations of :mod:`sindyship.mmg`
(a model built under ``SINDYSHIP_NO_COMPILE=1``) and with the numba-compiled ones
(:mod:`sindyship._mmg_compiled`, after a warm-up flight that imports numba and loads or
compiles the code), each the best of ``--repeat``.  Prints and saves
``benchmarks/results/simulate.json``: both wall times, the warm-up flight, the largest
position difference between the two paths, and the largest position change in ship lengths
when the step is halved (the accuracy claim: below 1e-4 L).  The target is the compiled
flight under 0.3 s; without numba only the numpy path is timed and the target is not met.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import time
from pathlib import Path

import numpy as np

from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
from sindyship.simulation import default_step

OUT = Path(__file__).parent / "results" / "simulate.json"
TARGET_WALL_SECONDS = 0.3
TARGET_POSITION_CHANGE_L = 1e-4


def _numpy_model(ship) -> MMGModel:
    """The model with the numpy accelerations (built under SINDYSHIP_NO_COMPILE=1)."""
    before = os.environ.get("SINDYSHIP_NO_COMPILE")
    os.environ["SINDYSHIP_NO_COMPILE"] = "1"
    try:
        return MMGModel(ship)
    finally:
        if before is None:
            del os.environ["SINDYSHIP_NO_COMPILE"]
        else:
            os.environ["SINDYSHIP_NO_COMPILE"] = before


def _timed(model, manoeuvres, repeat: int) -> tuple[list, list[float]]:
    """The flights and the wall time of each of ``repeat`` flights."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        runs = fly(model, manoeuvres)
        times.append(time.perf_counter() - t0)
    return runs, times


def _moved(a_runs, b_runs, L: float) -> float:
    """Largest position difference between two sets of flights [ship lengths]."""
    return max(float(np.max(np.hypot(a["x"] - b["x"], a["y"] - b["y"]))) / L
               for a, b in zip(a_runs, b_runs, strict=True))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    ship = load_ship("kcs")
    plan = protocol_manoeuvres()
    manoeuvres = plan["train"] + plan["test"]
    numpy_runs, numpy_times = _timed(_numpy_model(ship), manoeuvres, args.repeat)
    compiled = MMGModel(ship)
    t0 = time.perf_counter()
    fly(compiled, manoeuvres)  # warm-up: imports numba, loads (or compiles) the code
    warm_up = time.perf_counter() - t0
    has_numba = compiled._compiled_parameters is not None
    result = {
        "manoeuvres": len(manoeuvres),
        "simulated_seconds_each": 3200,
        "step_s": default_step(ship),
        "numba": importlib.util.find_spec("numba") is not None,
        "load_average_1min": os.getloadavg()[0],  # other work on the machine slows both
        "numpy_wall_seconds_best": min(numpy_times),
        "numpy_wall_seconds_all": numpy_times,
    }
    best = min(numpy_times)
    if has_numba:
        compiled_runs, compiled_times = _timed(compiled, manoeuvres, args.repeat)
        best = min(compiled_times)
        result.update({
            "compiled_wall_seconds_best": best,
            "compiled_wall_seconds_all": compiled_times,
            "compiled_warm_up_flight_seconds": warm_up,
            "speed_up": min(numpy_times) / best,
            "max_position_difference_compiled_vs_numpy_L": _moved(compiled_runs, numpy_runs,
                                                                    ship.L),
        })
    fine = fly(compiled, manoeuvres, step=0.5 * default_step(ship))
    moved = _moved(numpy_runs, fine, ship.L)
    result.update({
        "wall_seconds_best": best,
        "max_position_change_when_step_halved_L": moved,
        "target_wall_seconds": TARGET_WALL_SECONDS,
        "target_position_change_L": TARGET_POSITION_CHANGE_L,
        "meets_target": bool(has_numba and best < TARGET_WALL_SECONDS
                             and moved < TARGET_POSITION_CHANGE_L),
    })
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

"""Regenerate the golden numbers the tests compare against (tests/golden/kcs.json).

Run after a deliberate change to the simulator or the identification, review the diff, and
commit it with the reason.  The tests allow the tolerances stated in the file.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from sindyship.effects import add_noise
from sindyship.evaluation import distance_errors, evaluate
from sindyship.flights import fly_like_batch
from sindyship.identify import fit
from sindyship.manoeuvres import fly, protocol_manoeuvres, turning_figures, zigzag_figures
from sindyship.mmg import MMGModel
from sindyship.model import paper_model
from sindyship.ships import load_ship
from sindyship.smoothing import smooth_records

OUT = Path(__file__).resolve().parents[1] / "tests" / "golden" / "kcs.json"


def noisy_records(records, seed: int):
    """The records with the README's 1 % noise: 1 % of each channel's RMS on u, v and r,
    0.1 deg on heading and rudder, 0.5 m on positions (seeded)."""
    out = []
    for k, record in enumerate(records):
        std = {c: 0.01 * float(np.sqrt(np.mean(record[c] ** 2))) for c in ("u", "v", "r")}
        std.update({"psi": math.radians(0.1), "delta": math.radians(0.1), "x": 0.5, "y": 0.5})
        out.append(add_noise(record, std, seed=1000 * seed + k))
    return out


def noise_ratios(ship, runs, test) -> dict:
    """Held-out mean distance of least squares fitted on the noisy training records smoothed
    with a 21 s Savitzky-Golay filter, over the distance on the clean ones (seed 1)."""
    train = [runs[n] for n in ("straight", "tc35_stbd", "tc35_port", "zz35_10", "zz20_20",
                               "zz15_15", "spiral_stbd", "spiral_port")]
    clean = evaluate(fit(train, ship), test)
    smoothed = smooth_records(noisy_records(train, seed=1), "savgol:21")
    noisy = evaluate(fit(smoothed, ship), test)
    return {name: noisy[name]["mean_distance_L"] / clean[name]["mean_distance_L"]
            for name in clean}


def main() -> None:
    ship = load_ship("kcs")
    mmg = MMGModel(ship)
    plan = protocol_manoeuvres()
    runs = {r.name: r for r in fly(mmg, plan["train"] + plan["test"])}
    golden = {"tolerance_rel": 1e-6, "turning": {}, "zigzag": {}}
    for name in ("tc35_stbd", "tc35_port", "tc15_stbd", "tc15_port"):
        golden["turning"][name] = turning_figures(runs[name], ship.L)
    for name in ("zz35_10", "zz20_20", "zz15_15", "zz10_10"):
        golden["zigzag"][name] = zigzag_figures(runs[name])
    test = [runs[n] for n in ("tc15_port", "tc15_stbd", "zz10_10")]
    flown = fly_like_batch(paper_model(ship, "LS").dynamics(), test)
    golden["paper_ls_flown"] = {r.name: distance_errors(f, r, ship.L)["mean_distance_L"]
                                for f, r in zip(flown, test, strict=True)}
    golden["noise_one_percent"] = noise_ratios(ship, runs, test)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(golden, indent=2) + "\n")
    print(json.dumps(golden, indent=2))


if __name__ == "__main__":
    main()

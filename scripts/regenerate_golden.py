"""Regenerate the golden numbers the tests compare against (tests/golden/kcs.json).

Run after a deliberate change to the simulator or the identification, review the diff, and
commit it with the reason.  The tests allow the tolerances stated in the file.
"""

from __future__ import annotations

import json
from pathlib import Path

from sindyship.evaluation import distance_errors, fly_like_batch
from sindyship.manoeuvres import fly, protocol_manoeuvres, turning_figures, zigzag_figures
from sindyship.mmg import MMGModel
from sindyship.model import paper_model
from sindyship.ships import load_ship

OUT = Path(__file__).resolve().parents[1] / "tests" / "golden" / "kcs.json"


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
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(golden, indent=2) + "\n")
    print(json.dumps(golden, indent=2))


if __name__ == "__main__":
    main()

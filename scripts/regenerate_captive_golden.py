"""Regenerate tests/golden/captive_forces.json: identified models against MMG captive tests.

Fits least squares and LASSO to the protocol's 8 KCS training manoeuvres and least squares to
its three zig-zags alone, and compares each model's forces with the MMG's virtual captive tests
(all four test types, 21 points per sweep).  tests/test_forces.py checks these numbers.
"""

from __future__ import annotations

import json
from pathlib import Path

from sindyship.captive import captive_tests
from sindyship.forces import compare_forces
from sindyship.identify import fit
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship

GOLDEN = Path(__file__).resolve().parents[1] / "tests" / "golden" / "captive_forces.json"


def golden_cases(train):
    """(name, records, optimizer) of the golden comparisons."""
    zigzags = [r for r in train if r.name.startswith("zz")]
    return [("ls_8", train, "ls"), ("lasso_8", train, "lasso"), ("ls_zigzags", zigzags, "ls")]


def compute(kcs, train) -> dict:
    captive = captive_tests(kcs, "all")
    out = {}
    for name, records, optimizer in golden_cases(train):
        model = fit(records, kcs, optimizer=optimizer)
        out[name] = compare_forces(model, captive, training_records=records).to_dict()
    return out


def main() -> None:
    kcs = load_ship("kcs")
    train = fly(MMGModel(kcs), protocol_manoeuvres()["train"])
    GOLDEN.write_text(json.dumps(compute(kcs, train), indent=2) + "\n")
    print("wrote", GOLDEN)


if __name__ == "__main__":
    main()

"""Time ``diagnose`` on the protocol and measure what it finds; save the numbers.

Prints and saves ``benchmarks/results/diagnose.json``:

``timing``
    ``diagnose`` on the 8 protocol training manoeuvres (3200 s each; the default settings:
    every catalogued effect scored, the best two confirmed by refitting and re-flying, every
    training manoeuvre flown) with ``n_jobs=2``, without and with the figures of
    ``--out`` (wall seconds, best of ``--repeat``; target below 60 s on two cores).  The MMG
    simulation of the data is not counted.
``kcs``
    The paper's data (asymmetric KCS rudder): rounds of :func:`diagnose_iteratively` with the
    held-out manoeuvres flown after each round, beside the paper's best Table-10 values.
``grid``, ``controls``, ``complete``, ``crossflow``
    Hidden simulator effects on the symmetric KCS (gamma_R = 0.415 to both sides, protocol
    manoeuvres shortened to 1000 s): the rank and share of the expected effect and the
    held-out mean distance before and after adding it, over a grid of magnitudes and
    directions wider than the tests'; the same ship without an effect; data made by an
    Abkowitz model; cross-flow drag.
``marin``
    The KVLCC2 measurements (identify on the zig-zags, fly the turning circles), when the
    shared folder is present.

``python benchmarks/bench_diagnose.py --quick`` runs the timing only.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from sindyship.diagnose import MEANINGFUL_SHARE, diagnose, diagnose_iteratively
from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.model import paper_model
from sindyship.ships import load_ship

OUT = Path(__file__).parent / "results" / "diagnose.json"
PAPER_BEST = {"tc15_port": 0.2953, "tc15_stbd": 0.1888, "zz10_10": 0.6252}


def _timing(repeat: int) -> dict:
    ship = load_ship("kcs")
    train = fly(MMGModel(ship), protocol_manoeuvres()["train"])
    plain, figures = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = diagnose(train, ship, n_jobs=2)
        plain.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        result = diagnose(train, ship, n_jobs=2)
        with tempfile.TemporaryDirectory() as folder:
            n_files = len(result.save_figures(folder))
        figures.append(time.perf_counter() - t0)
    return {
        "records": len(train),
        "seconds_each": 3200,
        "n_jobs": 2,
        "wall_seconds_best": min(plain),
        "wall_seconds_all": plain,
        "with_figures_wall_seconds_best": min(figures),
        "with_figures_wall_seconds_all": figures,
        "files_written": n_files,
        "target_wall_seconds": 60.0,
        "top_effect": result.ranking[0].effect.name,
        "ranking": {s.effect.name: s.explained for s in result.ranking},
    }


def _kcs() -> dict:
    ship = load_ship("kcs")
    plan = protocol_manoeuvres()
    mmg = MMGModel(ship)
    train, test = fly(mmg, plan["train"]), fly(mmg, plan["test"])
    t0 = time.perf_counter()
    rounds = diagnose_iteratively(train, ship, test=test, n_jobs=2, max_rounds=5)
    seconds = time.perf_counter() - t0
    held_out = rounds.table[rounds.table["set"] == "held-out"]
    by_round = {
        str(k): {row.manoeuvre: row.mean_distance_L for row in rows.itertuples()}
        for k, rows in held_out.groupby("round")
    }
    confirmations = {}
    for k, rnd in enumerate(rounds.rounds, 1):
        for score in rnd.diagnosis.ranking:
            if score.confirmation is not None:
                change = score.confirmation
                confirmations[f"round {k}: {score.effect.name}"] = {
                    "confirmed": change.confirmed,
                    "training_ratio": change.ratio("training"),
                    "held_out_ratio": change.ratio("held-out"),
                }
    return {
        "rounds": rounds.to_json()["rounds"],
        "added": rounds.added,
        "stopped": rounds.stopped,
        "held_out_mean_distance_by_round": by_round,
        "confirmations": confirmations,
        "paper_best_table_10": PAPER_BEST,
        "seconds": seconds,
        "report": rounds.report(),
    }


def _short(duration: float = 1000.0) -> dict:
    plan = protocol_manoeuvres()
    return {key: [replace(m, duration=duration) for m in plan[key]] for key in plan}


def _case(ship, hidden: list[str], library: str, expected: str | None) -> dict:
    plan = _short()
    effects = parse_effects(hidden)
    runs = {key: simulate_with_effects(ship, plan[key], effects) for key in plan}
    result = diagnose(
        runs["train"],
        ship,
        library=library,
        test=runs["test"],
        fly_training=False,
        confirm=0 if expected is None else 1,
    )
    out = {
        "hidden": hidden,
        "library": library,
        "expected": expected,
        "ranking": {s.effect.name: round(s.explained, 4) for s in result.ranking},
        "top": result.ranking[0].effect.name,
        "complete": result.complete,
    }
    if expected is None:
        return out
    out["rank_of_expected"] = result.rank(expected)
    top = result.ranking[0]
    if top.confirmation is not None:
        rows = [r for r in top.confirmation.rows if r["set"] == "held-out"]
        before = float(np.mean([r["before"]["mean_distance_L"] for r in rows]))
        after = float(np.mean([r["after"]["mean_distance_L"] for r in rows]))
        out.update(
            {
                "held_out_before_L": before,
                "held_out_after_L": after,
                "reduction": before / after if after > 0 else math.nan,
                "diverged_after": [
                    r["manoeuvre"] for r in rows if r["after"]["diverged_at_s"] is not None
                ],
            }
        )
    out["found"] = out["top"] == expected
    out["halved"] = (
        out["found"] and out.get("reduction", 0.0) >= 2.0 and not out.get("diverged_after")
    )
    return out


def _grid() -> dict:
    kcs = load_ship("kcs")
    symmetric = kcs.with_rudder(gamma_R_port=0.415, gamma_R_stbd=0.415)
    cases = []
    for magnitude in (0.0005, 0.001, 0.002, 0.004):
        for direction in (0, 90, 180, 270):
            cases.append(
                ([f"load={magnitude}", f"load_dir={direction}"], "abkowitz", "environment")
            )
    cases.append((["load=0.002", "load_dir=45", "load_arm=0.3"], "abkowitz", "environment"))
    for speed in (0.1, 0.25, 0.5, 1.0):
        for direction in (0, 120, 240):
            cases.append(
                ([f"current={speed}", f"current_dir={direction}"], "abkowitz", "environment")
            )
    for force in (-0.002, -0.001, -0.0005, 0.0005, 0.001, 0.002):
        cases.append(([f"prop_side_force={force}"], "abkowitz-noconst", "asymmetry"))
    for offset in (-2, -1, -0.5, 0.5, 1, 2):
        cases.append(([f"rudder_offset={offset}"], "abkowitz-noconst", "asymmetry"))
    grid = []
    for hidden, library, expected in cases:
        grid.append(_case(symmetric, hidden, library, expected))
        row = grid[-1]
        print(
            f"  {' '.join(hidden):38s} top {row['top']:12s} {expected} "
            f"{row['ranking'].get(expected, 0):.3f} x{row.get('reduction', math.nan):.1f}",
            flush=True,
        )
    controls = [_case(symmetric, [], library, None) for library in ("abkowitz", "abkowitz-noconst")]
    crossflow = [
        _case(symmetric, [f"crossflow={c}"], "abkowitz", "crossflow") for c in (0.1, 0.3, 1.0, 3.0)
    ]
    truth = paper_model(kcs)
    train = fly(truth.dynamics(), _short()["train"])
    complete = diagnose(train, kcs, fly_training=False)
    false_alarm = max(
        c["ranking"].get(name, 0.0) for c in controls for name in ("asymmetry", "environment")
    )
    return {
        "grid": grid,
        "grid_found": sum(c["found"] for c in grid),
        "grid_halved": sum(c["halved"] for c in grid),
        "grid_cases": len(grid),
        "smallest_share_when_found": min(c["ranking"][c["expected"]] for c in grid if c["found"]),
        "controls": controls,
        "false_alarm_share_in_controls": false_alarm,
        "crossflow": crossflow,
        "complete": {
            "ranking": {s.effect.name: s.explained for s in complete.ranking},
            "complete": complete.complete,
        },
        "threshold": MEANINGFUL_SHARE,
    }


def _marin() -> dict | None:
    from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
    from sindyship.measurements import trajectory_from_frame

    folder = default_marin_dir()
    if folder is None:
        return None
    ship = load_ship("kvlcc2").scaled(45.7)
    records = {
        key: trajectory_from_frame(read_marin(folder / name).data, key, resample=1.0)
        for key, name in MARIN_FILES.items()
    }
    train = [records[k] for k in ("zz_10", "zz_-10", "zz_20", "zz_-20")]
    test = [records["tc_35"], records["tc_-35"]]
    out = {}
    for label, settings in (
        ("savgol-21s", {"derivative": "savgol", "window": 21.0}),
        ("savgol-40s", {"derivative": "savgol", "window": 40.0}),
        ("five-point", {"derivative": "five-point"}),
    ):
        result = diagnose(train, ship, test=test, n_jobs=2, **settings)
        out[label] = {
            "ranking": {s.effect.name: s.explained for s in result.ranking},
            "explained_by_dof": {s.effect.name: s.explained_by_dof for s in result.ranking},
            "not_testable": {n.effect.name: list(n.needs) for n in result.not_testable},
            "force_residual_relative": {
                d: v["relative"] for d, v in result.residuals.summary().items()
            },
            "errors_before": result.errors(),
            "top": None if result.top is None else result.top.effect.name,
            "top_change": (
                None
                if result.top is None or result.top.confirmation is None
                else result.top.confirmation.to_json()
            ),
            "warnings": result.warnings,
            "report": result.report(),
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="timing only")
    args = parser.parse_args()
    result = {"timing": _timing(args.repeat)}
    print(json.dumps(result["timing"], indent=2), flush=True)
    if not args.quick:
        result["kcs"] = _kcs()
        print(result["kcs"]["report"], flush=True)
        result.update(_grid())
        result["marin"] = _marin()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2, default=float) + "\n")
    summary = {
        k: v
        for k, v in result.items()
        if k not in ("grid", "kcs", "marin", "controls", "crossflow")
    }
    print(json.dumps(summary, indent=2, default=float))


if __name__ == "__main__":
    main()

"""Compute every number the README states and write the README's generated blocks.

The README holds blocks between ``<!-- BEGIN name -->`` and ``<!-- END name -->`` lines; this
script computes the numbers behind them (the paper's experiment through
:func:`sindyship.reproduce.run`, the KVLCC2 turning circles, the MARIN measurements when the
shared data folder is present, and the benchmark results saved in ``benchmarks/results/``),
saves them to ``docs/readme-numbers.json`` and renders the blocks from that file.

    python scripts/make_readme.py            # recompute, save the numbers, rewrite the blocks
    python scripts/make_readme.py --render   # rewrite the blocks from the saved numbers only

``tests/test_readme.py`` checks that the README's blocks are what the saved numbers render to
and pins the saved numbers against fresh computations.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import re
import sys
import time
from pathlib import Path

from sindyship._io import clean_json

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
NUMBERS = ROOT / "docs" / "readme-numbers.json"
RESULTS = ROOT / "benchmarks" / "results"
TEST_NAMES = ("tc15_port", "tc15_stbd", "zz10_10")
METHOD_LABELS = {"ls": "least squares", "stlsq": "STLSQ", "lasso": "LASSO (CV)",
                 "svr": "linear SVR (CV)", "prior": "least squares with the ship's prior"}
#: The zig-zag fits of benchmarks/bench_captive.py whose prior means are the MMG's Taylor
#: coefficients (the yardstick), at the default strength and at 1e-4.
TAYLOR_FITS = ("prior 1e-05 taylor", "prior 1e-04 taylor")
#: The zig-zag fits of benchmarks/bench_captive.py with the even terms of ``asymmetry`` for the
#: rudder's side-dependent inflow, and fitted on the held-out records too (the reference).
INFLOW_FIT, REFERENCE_FIT = "+ asymmetry abs(v) abs(r)", "with the held-out records"
INSTANTANEOUS_FIT = "instantaneous + asymmetry abs(v) abs(r)"
#: The zig-zag fit of benchmarks/bench_captive.py with a small captive programme beside the
#: records (the hybrid fit, ``fit --captive``).
HYBRID_FIT = "+ captive programme"
#: The zig-zag fits of benchmarks/bench_captive.py refined with a stronger pull toward the
#: fit (``--refine-weight``): this, then the weight.
WEIGHTED_REFINEMENT = "refined, prior weight "
#: The lowest captive correlation, in X, Y and N of every test, that a model must keep to be
#: physically right (the recommended model keeps it on the protocol).
CAPTIVE_REQUIREMENT = 0.95
CAPTIVE_LABELS = {"static-drift": "static drift", "rudder": "rudder", "pure-yaw": "pure yaw",
                  "drift-yaw": "drift and yaw"}


# ------------------------------------------------------------------------------- numbers
def _kvlcc2_turns(revolutions: float | None = None) -> dict:
    from sindyship.manoeuvres import Manoeuvre, fly, turning_figures
    from sindyship.mmg import MMGModel
    from sindyship.ships import load_ship

    ship = load_ship("kvlcc2")
    if revolutions is not None:
        ship = dataclasses.replace(ship, propeller=dataclasses.replace(ship.propeller,
                                                                       n_P=revolutions))
    runs = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=35, duration=300, dt=0.1),
                                Manoeuvre("turning-circle", rudder=-35, duration=300, dt=0.1)])
    return {r.name: turning_figures(r, ship.L) for r in runs}


def _marin() -> dict | None:
    """The KVLCC2 measurements: identify on the zig-zags, fly the turns before and after the
    effect the diagnosis names, compared over the windows both flights cover."""
    from sindyship.diagnose import before_after, diagnose
    from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
    from sindyship.measurements import trajectory_from_frame
    from sindyship.ships import load_ship

    folder = default_marin_dir()
    if folder is None:
        return None
    raw = {key: read_marin(folder / name) for key, name in MARIN_FILES.items()}
    model_n = float(raw["tc_35"]["n"][0]) * 45.7**0.5
    ship = load_ship("kvlcc2").scaled(45.7)
    records = {key: trajectory_from_frame(rec.data, key, resample=1.0) for key, rec in raw.items()}
    train = [records[k] for k in ("zz_10", "zz_-10", "zz_20", "zz_-20")]
    test = [records["tc_35"], records["tc_-35"]]
    settings = {"derivative": "savgol", "window": 21.0}
    result = diagnose(train, ship, test=test, confirm=0, **settings)
    top = result.ranking[0]
    change = before_after(train, ship, effects=[top.effect.name], test=test, **settings)
    rows = {row["manoeuvre"]: row for row in change.rows}
    default_fit, measured = _marin_default(train, test, ship, settings)
    return {
        "default_fit": default_fit,
        "measured_turns": measured,
        "model_revolutions_rps": model_n,
        "ranking": {s.effect.name: {"explained": s.explained, "signal": s.explained_signal,
                                    "meaningful": s.meaningful} for s in result.ranking},
        "not_testable": sorted(n.effect.name for n in result.not_testable),
        "top": top.effect.name,
        "training_ratio": change.ratio("training"),
        "confirmed": change.confirmed,
        "turns": {name: {"before": rows[name]["before"], "after": rows[name]["after"],
                         "common": rows[name]["common"]} for name in ("tc_35", "tc_-35")},
    }


def _marin_default(train, test, ship, settings: dict) -> tuple[dict, dict]:
    """The default fit (``sindyship fit``: the prior on the recommended library of the ship's
    speed form, refined by the records' flights) on the MARIN zig-zags, and the same fit on
    ``abkowitz-vr`` (without the cross-flow drag the instantaneous form's library adds): the
    turns' figures (advance, tactical diameter, speed loss) as ``evaluate`` flies and reports
    them (from the rudder execute of the 1 s records ``python3 -m sindyship.marin`` writes),
    and what the refinement did, with the mean distance over the whole record; and the turns'
    recorded figures, as ``evaluate`` reports them, with ``pull_out_s``: how long each record
    goes on after its rudder last stood at half its largest angle or more."""
    import numpy as np

    from sindyship.evaluation import evaluate
    from sindyship.identify import fit, recommended_library
    from sindyship.refine import refine

    out, recorded = {}, {}
    for record in test:  # how long each turn goes on with the rudder back from hard over
        rudder = np.abs(record["delta"])
        last = int(np.flatnonzero(rudder >= 0.5 * rudder.max())[-1])
        recorded.setdefault("pull_out_s", {})[record.name] = float(record.t[-1] - record.t[last])
    for key, library in (("default", recommended_library(ship.speed_reference)),
                         ("abkowitz-vr", "abkowitz-vr")):
        model = refine(fit(train, ship, library=library, optimizer="prior",
                           speed=ship.speed_reference, **settings), train)
        turns = {}
        for name, errors in evaluate(model, test).items():
            flown = errors["turn"]["flown"] or {}
            turns[name] = {"diverged_at_s": errors["diverged_at_s"],
                           "mean_distance_L": errors["mean_distance_L"],
                           **{k: flown.get(k) for k in ("advance_L", "tactical_diameter_L",
                                                        "speed_loss")}}
            side = {"tc_35": "port", "tc_-35": "stbd"}[name]
            recorded[side] = {k: v for k, v in errors["turn"]["recorded"].items() if k != "side"}
        done = model.info["refined"]
        out[key] = {
            "library": model.library.name, "speed": model.library.speed, "turns": turns,
            "refined": done["largest_change"] is not None,
            "stopped": done["stopped"]}
    return out, recorded


def compute() -> dict:
    """Every number of the README (about a minute on two cores)."""
    from sindyship.reproduce import run

    start = time.perf_counter()
    output = run(None, figures=False, progress=lambda message: print(message, file=sys.stderr))
    numbers = {
        "table10": [{"method": r["method"], "effects": r["effects"], "errors": r["errors"],
                     "refined": bool(r.get("refined"))} for r in output["results"]],
        "paper_table_10": output["paper_table_10"],
        "paper_ls_flown": output["paper_ls_flown"],
        "paper_ls_agreement": output["paper_ls_agreement"],
        "diagnosis": output["diagnosis"]["rounds"],
        "diagnosis_stopped": output["diagnosis"]["stopped"],
        "linear_derivatives": output["linear_derivatives"],
        "captive": output["captive"],
        "kvlcc2_turns_yy": _kvlcc2_turns(),
        "marin": _marin(),
    }
    if numbers["marin"] is not None:
        numbers["kvlcc2_turns_marin_n"] = _kvlcc2_turns(numbers["marin"]["model_revolutions_rps"])
    for name in ("noise", "significance"):
        path = RESULTS / f"{name}.json"
        numbers[name] = json.loads(path.read_text()) if path.exists() else None
    numbers["captive_bench"] = _saved_captive_bench()
    numbers["campaign"] = _saved_campaign()
    numbers["speed"] = _saved_speed()
    numbers["pysindy"] = _saved_pysindy()
    numbers["seconds"] = time.perf_counter() - start
    return numbers


def _saved_captive_bench() -> dict | None:
    """The zig-zag fits of benchmarks/results/captive.json (least squares, the default
    prior, the yardstick: the prior with the MMG's own Taylor coefficients, least squares and
    the prior refined by their flights, the prior with the terms of ``asymmetry`` for the
    rudder's side-dependent inflow, alone and refined by segments or whole flights, and with
    the instantaneous speed, the hybrid fit with a small captive programme, alone and refined,
    and the reference: the prior fitted on the held-out records too), and the number of turns
    of each held-out turning circle."""
    path = RESULTS / "captive.json"
    if not path.exists():
        return None
    result = json.loads(path.read_text())
    default = f"prior {result['default_strength']:.0e}"
    fits = result["sets"]["zigzags"]["fits"]
    keys = ("ls", default, *TAYLOR_FITS, "ls refined", f"{default} refined",
            f"{default} {INFLOW_FIT}", f"{default} {INFLOW_FIT} refined",
            f"{default} {INFLOW_FIT} refined whole", f"{default} {INSTANTANEOUS_FIT}",
            f"{default} {INSTANTANEOUS_FIT} refined", f"{default} {REFERENCE_FIT}",
            f"{default} {HYBRID_FIT}", f"{default} {HYBRID_FIT} refined",
            f"{default} + {result['diagnosed_first']}",
            f"{default} + {result['diagnosed_first']} refined",
            *(k for k in fits if k.startswith(f"{default} {WEIGHTED_REFINEMENT}")))
    return {"default_strength": result["default_strength"],
            "diagnosed_first": result["diagnosed_first"],
            "held_out_turns": result["held_out_turns"],
            "sets": {"zigzags": {"fits": {k: fits[k] for k in keys}}}}


def _saved_speed() -> dict | None:
    """The timings of benchmarks/results/speed.json (each step of both checkouts timed in one
    run)."""
    path = RESULTS / "speed.json"
    if not path.exists():
        return None
    result = json.loads(path.read_text())
    return {"reference_over_flights": result.get("reference_over_flights"),
            "steps": {k: {"now": v["now"].get("seconds"),
                          "before": v.get("before", {}).get("seconds")}
                      for k, v in result["steps"].items()}}


def _saved_campaign() -> dict | None:
    """The workflows of benchmarks/results/campaign.json: what the diagnosis adds, and the
    held-out errors of each."""
    path = RESULTS / "campaign.json"
    if not path.exists():
        return None
    result = json.loads(path.read_text())
    return {"named": result["named"], "recommended": result["recommended"],
            "speed": result["diagnosis"]["speed"],
            "workflows": {k: {"errors": v["errors"], "geometric_mean_L": v["geometric_mean_L"]}
                          for k, v in result["workflows"].items() if k != "default before"}}


def _saved_pysindy() -> dict | None:
    """The held-out errors of every workflow of benchmarks/results/pysindy.json."""
    path = RESULTS / "pysindy.json"
    if not path.exists():
        return None
    result = json.loads(path.read_text())
    return {"recommended": result["recommended"],
            "workflows": {k: {"errors": v["errors"]} for k, v in result["workflows"].items()}}


# ------------------------------------------------------------------------------- blocks
def _cell(err: dict, paper: float | None = None) -> str:
    mean = err["mean_distance_L"]
    text = "n/a" if mean is None or not math.isfinite(mean) else f"{mean:.3f}"
    if err.get("diverged_at_s") is not None:
        text += f" (diverged at {err['diverged_at_s']:.0f} s)"
    return text + (f" ({paper:.3f})" if paper is not None else "")


def _table10(n: dict) -> str:
    lines = ["| method | port turn 15 deg | starboard turn 15 deg | zig-zag 10/10 |",
             "|---|---|---|---|"]
    best = {name: min(r["errors"][name]["mean_distance_L"] for r in n["table10"])
            for name in TEST_NAMES}
    for row in n["table10"]:
        label = METHOD_LABELS.get(row["method"], row["method"])
        if row["effects"]:
            label += " + " + " + ".join(f"`{e}`" for e in row["effects"]) + " (diagnosed)"
        if row.get("refined"):
            label = (label + ", refined by its training flights: the default `fit` with the "
                     "diagnosed effect (recommended)")
        paper = {} if row["effects"] else n["paper_table_10"].get(row["method"], {})
        cells = []
        for name in TEST_NAMES:
            text = _cell(row["errors"][name], paper.get(name))
            if row["errors"][name]["mean_distance_L"] == best[name]:
                text = f"**{text}**"
            cells.append(text)
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _agreement(n: dict) -> str:
    a, flown = n["paper_ls_agreement"], n["paper_ls_flown"]
    return (
        f"Least squares reproduces the paper's LS coefficients (Tables 7-9) with a median "
        f"relative deviation of {a['median_rel_dev']:.3f} and the same sign for "
        f"{100 * a['sign_agreement']:.1f} % of the {a['n_coefficients']} non-zero coefficients. "
        f"The paper's own LS coefficients flown by our simulator give "
        f"{flown['tc15_port']['mean_distance_L']:.3f}, "
        f"{flown['tc15_stbd']['mean_distance_L']:.3f} and "
        f"{flown['zz10_10']['mean_distance_L']:.3f} ship lengths: the turning circles match its "
        "Table 10; its zig-zag figure (1.499) could not be reproduced under any protocol tried "
        "([docs/protocol.md](docs/protocol.md)), and neither could its LASSO and SVR figures "
        "with its own LASSO and SVR coefficients."
    )


def _shares(ranking: list[dict], count: int = 4) -> str:
    return ", ".join(f"`{s['effect']}` {100 * s['explained']:.1f} %"
                     + ("" if s.get("meaningful", True) else " (not meaningful)")
                     for s in ranking[:count])


def _diagnosis(n: dict) -> str:
    rounds = n["diagnosis"]
    first, second = rounds[0], rounds[1] if len(rounds) > 1 else None
    text = (f"On the paper's training set the diagnosis ranks {_shares(first['ranking'])} "
            f"(share of the leave-one-manoeuvre-out force error) and adds "
            f"`{first['added']}`.")
    if second is not None:
        text += (f" Diagnosing again ranks {_shares(second['ranking'], 3)} and adds "
                 f"`{second['added']}`.")
    if len(rounds) > 2:
        last = rounds[-1]
        text += (f" Then it stops: {_shares(last['ranking'], 2)}; "
                 f"{n['diagnosis_stopped']} (a gain that holds only on one or two manoeuvres, "
                 "as cross-flow's on the 35/10 zig-zag, does not count).")
    return text


def _linear(n: dict) -> str:
    row = next(r for r in n["linear_derivatives"] if r["name"] == "N_v")
    keys = [k for k in row if k.startswith("ls+")]
    after = ", ".join(f"{row[k]:.0f} with {k[3:].replace('+', ' and ')}" for k in keys)
    refined = next((k for k in row if k.endswith("+refined")), None)
    default = ("" if refined is None else
               f" The default `fit` with {refined[6:-8].replace('+', ' and ')} (the prior, "
               f"refined by the training flights) has {row[refined]:.0f}, the `prior` fit "
               f"alone {row['prior']:.0f}.")
    return (f"N'_v (x 1e-5) is {row['MMG_Taylor']:.0f} in the MMG's own Taylor expansion, "
            f"{row['paper_LS']:.0f} in the paper's LS, {row['ls']:.0f} in our least squares, "
            f"and moves to {after}.{default}")


def _marin_text(n: dict) -> str:
    m = n["marin"]
    if m is None:
        return "(The MARIN numbers need the shared data folder; run scripts/make_readme.py there.)"
    rank = m["ranking"]
    top = m["top"]
    second = [k for k in rank if k != top][0]
    port, stbd = m["turns"]["tc_35"], m["turns"]["tc_-35"]

    def turn(row, side):
        b, a, c = row["before"], row["after"], row["common"]
        parts = []
        for when, err in (("without", b), ("with", a)):
            parts.append(f"{when} it {_cell(err)}")
        return (f"{side} turn {parts[0]}, {parts[1]}; over the {c['window_s']:.0f} s both "
                f"flights cover {c['before_mean_L']:.3f} -> {c['after_mean_L']:.3f} L, and the "
                f"{'flight with it' if c['worse'] == 'after' else 'flight without it'} is the "
                "worse")

    return (
        "Identified by least squares on the paper's library in the design speed form "
        "(`sindyship diagnose marin/zz_*.csv --test marin/tc_35.csv marin/tc_-35.csv --ship "
        "marin/kvlcc2-full-scale.toml --derivative savgol --window 21 --speed design "
        "--confirm 0`) on the four MARIN zig-zags (21 s Savitzky-Golay derivatives) and tested on "
        f"the 35 deg turns, `{top}` explains {100 * rank[top]['explained']:.1f} % of the "
        f"force error ({100 * rank[top]['signal']:.1f} % of the part above the noise floor) "
        f"and `{second}` {100 * rank[second]['explained']:.1f} %; "
        f"{', '.join(f'`{e}`' for e in m['not_testable'])} are not testable (no channels). "
        f"Adding `{top}` improves the re-flown zig-zags (x {m['training_ratio']:.2f}) but not "
        f"the turns: {turn(port, 'the port')}; {turn(stbd, 'the starboard')}. Under the rule "
        "that a flight diverging where the other does not is the worse one, the effect does not "
        "carry over from zig-zags to turns: the zig-zags sweep about 70 deg of heading, over "
        "which heading terms can stand in for slow drift (the report says so)."
        + _marin_default_text(m)
    )


MARIN_TURNS = (("tc_35", "port"), ("tc_-35", "stbd"))


def marin_misses(variant: dict, measured: dict) -> dict:
    """The default fit's largest misses on the MARIN turns: the relative error of advance and
    tactical diameter, the difference in speed loss (None when a turn diverged)."""
    figures, losses = [], []
    for name, side in MARIN_TURNS:
        flown, truth = variant["turns"][name], measured[side]
        if flown["diverged_at_s"] is not None:
            return {"figures": None, "speed_loss": None}
        figures += [abs(flown[k] / truth[k] - 1) for k in ("advance_L", "tactical_diameter_L")]
        losses.append(abs(flown["speed_loss"] - truth["speed_loss"]))
    return {"figures": max(figures), "speed_loss": max(losses)}


def _marin_default_text(m: dict) -> str:
    default = m.get("default_fit")
    if default is None:
        return ""
    measured = m["measured_turns"]

    def turns(variant):
        parts = []
        for name, side in MARIN_TURNS:
            flown, truth = variant["turns"][name], measured[side]
            label = "port" if side == "port" else "starboard"
            if flown["diverged_at_s"] is not None:
                parts.append(f"the {label} turn diverges at {flown['diverged_at_s']:.0f} s")
                continue
            parts.append(f"the {label} turn {flown['advance_L']:.2f} / "
                         f"{flown['tactical_diameter_L']:.2f} / {flown['speed_loss']:.2f} "
                         f"(measured {truth['advance_L']:.2f} / "
                         f"{truth['tactical_diameter_L']:.2f} / {truth['speed_loss']:.2f})")
        miss = marin_misses(variant, measured)
        if miss["figures"] is not None:  # bounds rounded up, so that they hold
            parts[-1] += (f": advance and tactical diameter within "
                          f"{math.ceil(100 * miss['figures']):.0f} %, speed loss within "
                          f"{math.ceil(100 * miss['speed_loss']) / 100:.2f}")
        return " and ".join(parts)

    chosen, polynomial = default["default"], default["abkowitz-vr"]
    kept = ("" if chosen["refined"] else
            f" Its refinement by the zig-zags' flights is refused: {chosen['stopped']}.")
    flown = [chosen["turns"][name] for name, _ in MARIN_TURNS]
    if all(turn.get("mean_distance_L") is not None for turn in flown):
        pull_out = " and ".join(f"{measured['pull_out_s'][name]:.0f}"
                                for name, _ in MARIN_TURNS)
        kept += (f" Over the whole records, which end with {pull_out} s of pull-out (the "
                 "rudder back amidships), the flights lie a mean " + " and ".join(
                     f"{turn['mean_distance_L']:.2f} L" for turn in flown)
                 + " from the measured tracks (port, starboard; `sindyship evaluate` prints "
                 "it).")
    return (" The default fit (`sindyship fit --derivative savgol --window 21`: the prior on "
            f"`{chosen['library']}`, the recommended library in the {chosen['speed']} speed "
            "form the `kvlcc2` ship file names, with cross-flow drag) flies, as advance / tactical "
            f"diameter in ship lengths / speed loss, {turns(chosen)}.{kept} Without the "
            f"cross-flow drag (`--library abkowitz-vr`) it flies {turns(polynomial)}.")


def _kvlcc2_table(n: dict) -> str:
    yy = n["kvlcc2_turns_yy"]
    lines = ["| | starboard | port |", "|---|---|---|"]
    m = n.get("marin")
    if m is not None:
        mt = m["measured_turns"]
        lines.append(f"| MARIN measurement | {mt['stbd']['advance_L']:.2f} / "
                     f"{mt['stbd']['tactical_diameter_L']:.2f} | {mt['port']['advance_L']:.2f} / "
                     f"{mt['port']['tactical_diameter_L']:.2f} |")
    stbd, port = yy["tc35_stbd"], yy["tc35_port"]
    lines.append(f"| MMG, Yasukawa & Yoshimura condition (17.95 rps) | "
                 f"{stbd['advance_L']:.2f} / {stbd['tactical_diameter_L']:.2f} | "
                 f"{port['advance_L']:.2f} / {port['tactical_diameter_L']:.2f} |")
    mn = n.get("kvlcc2_turns_marin_n")
    if mn is not None:
        lines.append(f"| MMG at MARIN's revolutions (Froude-scaled, "
                     f"{m['model_revolutions_rps']:.2f} rps) | "
                     f"{mn['tc35_stbd']['advance_L']:.2f} / "
                     f"{mn['tc35_stbd']['tactical_diameter_L']:.2f} | "
                     f"{mn['tc35_port']['advance_L']:.2f} / "
                     f"{mn['tc35_port']['tactical_diameter_L']:.2f} |")
    return "\n".join(lines)


def _noise(n: dict) -> str:
    noise, sig = n.get("noise"), n.get("significance")
    parts = []
    if noise is not None:
        ratios = noise["one_percent_over_clean"]
        parts.append(
            "With 1 % Gaussian noise on u, v and r (0.1 deg on heading, 0.5 m on positions), "
            f"mean over {noise['seeds']} seeds, the held-out errors stay within "
            + " and ".join(f"{max(v['ratios'].values()):.2f}x for {METHOD_LABELS.get(k, k)}"
                           for k, v in ratios.items())
            + " of the clean-data values (`benchmarks/bench_noise.py`, with `--smoothing auto`).")
    if sig is not None:
        parts.append(
            f"Over {len(sig['cases'])} records without the effect (noise 0 to 2 %, seeds, two "
            f"manoeuvre sets) {sig['false_alarms']} of {sig['absent_effect_cases']} absent-effect "
            f"scores were meaningful; a steady load was found in {sig['detected']} of "
            f"{sig['detection_cases']} cases with and without noise "
            "(`benchmarks/bench_significance.py`).")
    return " ".join(parts)


def _correlations(by_test: dict) -> list[str]:
    def cell(value):
        return "n/a" if value is None else f"{value:+.2f}"

    return [" / ".join(cell(by_test[t][f]["correlation"]) for f in "XYN")
            for t in CAPTIVE_LABELS]


def _captive(n: dict) -> str:
    captive = n["captive"]
    diagnosed = [k for k in captive if k.startswith("ls+")][-1]
    rows = {"least squares": captive["ls"], "`prior`": captive["prior"],
            diagnosed: captive[diagnosed]}
    for key in captive:
        if key.endswith("+refined"):
            rows[f"{key[:-len('+refined')]}, refined (the default `fit` with the diagnosed "
                 "effect)"] = captive[key]
    lines = ["| model | " + " | ".join(CAPTIVE_LABELS.values()) + " |",
             "|---|" + "---|" * len(CAPTIVE_LABELS)]
    lines += [f"| {label} | " + " | ".join(_correlations(row)) + " |"
              for label, row in rows.items()]
    bench = n.get("captive_bench")
    if bench is not None:
        zz = bench["sets"]["zigzags"]["fits"]
        ls, prior = zz["ls"], zz[f"prior {bench['default_strength']:.0e}"]
        ls_refined = zz["ls refined"]
        prior_refined = zz[f"prior {bench['default_strength']:.0e} refined"]
        sweeps = ("static-drift", "pure-yaw", "drift-yaw")

        def low(row, forces="YN"):
            return min(row["captive"][t][f]["correlation"] for t in sweeps for f in forces)

        def flights(row):
            return " / ".join(f"{e['mean_distance_L']:.3f}" for e in row["held_out"].values())

        taylor = [zz[k] for k in TAYLOR_FITS]
        strength = f"{bench['default_strength']:.0e}".replace("e-0", "e-")
        ls_kept = ls_refined.get("refinement", {}).get("largest_change") is not None
        lines += ["", "Identified on the three zig-zags alone (`benchmarks/bench_captive.py`; "
                  "held-out mean distances tc15_port / tc15_stbd / zz10_10 in ship lengths, and "
                  "the lowest correlation over static drift, pure yaw and drift and yaw), least "
                  f"squares (on the paper's library `abkowitz`) flies {flights(ls)} with a lowest "
                  f"Y or N correlation of {low(ls):+.2f}, and the `prior` fit (on "
                  f"`abkowitz-vr`) {flights(prior)} with {low(prior):+.2f} in Y and N "
                  f"({low(prior, 'XYN'):+.2f} with X). With the MMG's own Taylor coefficients "
                  "as the prior's means (the same fit otherwise; a yardstick that uses the "
                  f"simulator's coefficients) it flies {flights(taylor[0])} at the default "
                  f"prior strength, {strength}, and {flights(taylor[1])} at 1e-4 (lowest X, Y or "
                  f"N correlation {low(taylor[0], 'XYN'):+.2f} and "
                  f"{low(taylor[1], 'XYN'):+.2f}): exact means leave the turns far off too, so "
                  "better estimates from main dimensions alone do not fix them. "
                  + _refined_on_zigzags(prior_refined, flights(prior_refined),
                                        low(prior_refined, "XYN"))
                  + _ways_out_on_zigzags(zz, f"prior {bench['default_strength']:.0e}",
                                         bench["diagnosed_first"], flights, low)
                  + " Least squares refined the same way "
                  + ("keeps the refinement and" if ls_kept else "keeps its fitted coefficients and")
                  + f" flies {flights(ls_refined)} (fitted: {flights(ls)}; lowest Y or N "
                  f"correlation {low(ls_refined):+.2f})."
                  + _what_limits_the_turns(zz, f"prior {bench['default_strength']:.0e}",
                                           bench["held_out_turns"], flights, low)]
    return "\n".join(lines)


def _what_limits_the_turns(zz: dict, key: str, turns: dict, flights, low) -> str:
    """Why the zig-zags alone fly the held-out turns as they do: the steady yaw rate, the
    reference fitted on the turns too, and the rudder's side-dependent inflow."""
    def steady(row):
        port, starboard = (row["steady_yaw_rate_error_pct"][f"tc15_{side}"]
                           for side in ("port", "stbd"))
        return f"port {port:+.2f} %, starboard {starboard:+.2f} %"

    reference, inflow = zz[f"{key} {REFERENCE_FIT}"], zz[f"{key} {INFLOW_FIT}"]
    refined = zz[f"{key} {INFLOW_FIT} refined"]
    per_cent = [row["held_out"][name]["mean_distance_L"] / abs(error)
                for row in zz.values()
                for name, error in row["steady_yaw_rate_error_pct"].items()
                if error is not None]
    return (f" A held-out turning circle lasts 3200 s, {min(turns.values()):.1f} to "
            f"{max(turns.values()):.1f} turns, so its mean distance grows with the error of its "
            "steady yaw rate (flown / recorded - 1 of the mean yaw rate over its last "
            "quarter; negative where the model turns too slowly): "
            f"{steady(zz[key])} for the `prior` fit; over these fits the mean distance is "
            f"{min(per_cent):.1f} to {max(per_cent):.1f} L per per cent of that error. The same "
            "`prior` fit made on the zig-zags and the held-out records together (a check of "
            f"what the library can express, not a workflow) flies {flights(reference)} "
            f"({steady(reference)}; lowest X, Y or N correlation "
            f"{low(reference, 'XYN'):+.2f}): the three zig-zags, which never hold a steady "
            "turn, leave the yaw rate a few per cent free. With two terms more in each of the sway "
            "force and the yaw moment, `abs(v)` and `abs(r)` from the catalogue's `asymmetry` (the "
            "even terms of a rudder whose inflow is straightened differently on the two sides, "
            "as the KCS's is: its gamma_R is 0.492 or 0.338 by the sign of the drift angle at "
            "the rudder, which the Abkowitz series, odd in v and r, cannot express), the "
            f"`prior` fit flies {flights(inflow)} ({steady(inflow)}), and refined by its "
            f"zig-zag flights {flights(refined)} ({steady(refined)}; lowest X, Y or N "
            f"correlation {low(refined, 'XYN'):+.2f}). "
            + _closest_to_the_turns(zz, key, flights, low))


def _closest_to_the_turns(zz: dict, key: str, flights, low) -> str:
    """How close the zig-zags alone come to the turns with the rudder-inflow terms: refined by
    whole flights, and with the forces scaled by the instantaneous speed."""
    whole = zz[f"{key} {INFLOW_FIT} refined whole"]
    fitted, refined = zz[f"{key} {INSTANTANEOUS_FIT}"], zz[f"{key} {INSTANTANEOUS_FIT} refined"]
    # workflows only: not the reference (fitted on the turns) nor the Taylor yardstick (the
    # simulator's own coefficients)
    kept = [row["held_out"]["tc15_stbd"]["mean_distance_L"] for name, row in zz.items()
            if REFERENCE_FIT not in name and name not in TAYLOR_FITS
            and low(row, "XYN") >= CAPTIVE_REQUIREMENT]
    best = (f"fly the starboard turn {min(kept):.3f} L off at best" if kept else
            "do not exist")
    hybrid, hybrid_refined = zz[f"{key} {HYBRID_FIT}"], zz[f"{key} {HYBRID_FIT} refined"]
    done = hybrid_refined.get("refinement", {})
    refinement = (f"its refinement by the zig-zag flights is refused ({done.get('stopped')})"
                  if done.get("largest_change") is None else
                  f"refined by its zig-zag flights it flies {flights(hybrid_refined)} (lowest "
                  f"X, Y or N correlation {low(hybrid_refined, 'XYN'):+.2f})")
    return ("Refined by whole closed-loop zig-zag flights instead of shooting segments, that fit "
            f"flies {flights(whole)} (lowest X, Y or N correlation {low(whole, 'XYN'):+.2f}); "
            "with its forces scaled by the instantaneous speed (`--speed instantaneous`) it "
            f"flies {flights(fitted)} fitted and {flights(refined)} refined, while the surge "
            "force's lowest correlation falls to "
            f"{min(low(fitted, 'X'), low(refined, 'X')):+.2f}. Given a small towing-tank "
            "programme beside the zig-zags (`fit --captive`: the MMG's static drift, rudder and "
            "pure yaw, five conditions each, as `sindyship captive` makes them), the `prior` "
            f"fit flies {flights(hybrid)} with its lowest X, Y or N correlation "
            f"{low(hybrid, 'XYN'):+.2f} (drift and yaw combined, which the programme does not "
            f"hold, among them); {refinement}. Of all these zig-zag fits, those "
            f"whose lowest X, Y or N correlation is {CAPTIVE_REQUIREMENT} or more (the default "
            f"fit's requirement on the protocol) {best}.")


def _ways_out_on_zigzags(zz: dict, key: str, first: str, flights, low) -> str:
    """The refused refinement's ways out on the zig-zags: the effect the diagnosis ranks first
    added (the recommended workflow), and a stronger pull toward the fit inside the
    refinement."""
    fitted, refined = zz[f"{key} + {first}"], zz[f"{key} + {first} refined"]
    sweeps = ("static-drift", "pure-yaw", "drift-yaw")
    value, force, test = min((refined["captive"][t][f]["correlation"], f, t)
                             for t in sweeps for f in "XYN")

    def outcome(row) -> str:
        done = row.get("refinement", {})
        if done.get("largest_change") is None:
            return f"is refused ({done.get('stopped')}) and flies {flights(row)}"
        return (f"is kept and flies {flights(row)} (lowest X, Y or N correlation "
                f"{low(row, 'XYN'):+.2f})")

    marker = f"{key} {WEIGHTED_REFINEMENT}"
    weights = [(name[len(marker):], row) for name, row in zz.items() if name.startswith(marker)]
    kept = refined.get("refinement", {}).get("largest_change") is not None
    return (f" With the effect `sindyship diagnose` ranks first on the same records, `{first}`, "
            f"added (the recommended workflow), the `prior` fit flies {flights(fitted)}; "
            + (f"refined by its zig-zag flights (the refinement kept) it flies "
               f"{flights(refined)}, with Y and N correlating {low(refined):+.2f} or more and "
               f"{force} in {CAPTIVE_LABELS[test]} {value:+.2f} (the effect's surge terms odd "
               "in v, r and delta, which the zig-zags do not pin down, take part of the surge "
               "force)." if kept else f"its refinement by the zig-zag flights {outcome(refined)}.")
            + " Held closer to the fit inside the refinement "
            "(`--refine-weight`, default 0.01), the default fit's refinement "
            + "; ".join(f"at {w} {outcome(row)}" for w, row in weights) + ".")


def _refined_on_zigzags(row: dict, flown: str, lowest: float) -> str:
    """What refining the prior fit by its zig-zag flights did (kept, or refused and why)."""
    done = row.get("refinement", {})
    if done.get("largest_change") is None:
        return (f"Refining the `prior` fit by its zig-zag flights (the default `fit`) is "
                f"refused: {done.get('stopped', 'no step lowered the error')}; it flies "
                f"{flown} (lowest X, Y or N correlation {lowest:+.2f}).")
    return (f"Refined by the error of its zig-zag flights (the default `fit`), the `prior` fit "
            f"flies {flown} and keeps its forces (lowest X, Y or N correlation "
            f"{lowest:+.2f}).")


def _pysindy(n: dict) -> str:
    result = n.get("pysindy")
    if result is None:
        return "(run benchmarks/bench_pysindy.py)"
    work = result["workflows"]

    def errors(key):
        return " / ".join(f"{e['mean_distance_L']:.3f}" for e in work[key]["errors"].values())

    names = list(work["pysindy"]["errors"])
    recommended = result["recommended"]
    wins = [name for name in names if work[recommended]["errors"][name][
        "mean_distance_L"] < work["pysindy"]["errors"][name]["mean_distance_L"]]
    prior = (f", sindyship with the ship's prior {errors('sindyship_prior')}"
             if "sindyship_prior" in work else "")
    return (f"Held-out mean distance ({' / '.join(names)}): pysindy {errors('pysindy')}, "
            f"sindyship least squares {errors('sindyship_ls')}, sindyship least squares "
            f"diagnosed {errors('sindyship_diagnosed')}{prior}, and the default `fit` with "
            f"the first diagnosed effect (the prior, refined by its training flights) "
            f"{errors('sindyship_refined')} ship lengths: the recommended workflow is better "
            f"than pysindy on {len(wins)} of {len(names)} ({', '.join(wins)}).")


def _campaign(n: dict) -> str:
    result = n.get("campaign")
    if result is None:
        return "(run benchmarks/bench_campaign.py)"
    work = result["workflows"]
    names = list(work["default"]["errors"])
    named = result["named"]

    def flights(key):
        return " / ".join(_cell(e) for e in work[key]["errors"].values())

    def listed(effects):
        return " and ".join(f"`{e}`" for e in effects)

    low, high = result["speed"]["range"]
    text = (f"`benchmarks/bench_campaign.py` flies a campaign like that in the simulator "
            "(`sindyship.campaign`): the KVLCC2 model from rest, 120-180 s of course keeping by "
            "hand before each execute, revolutions 70-85 % of the design condition, a gusty "
            "wind 3-6 times the ship's speed, 1 % sensor noise; trained on 10/10 and 20/20 "
            "zig-zags and 35 deg turns to both sides, held out a 15/15 zig-zag and 25 deg "
            f"turns. Its speed runs from {low:.2f} to {high:.2f} U0, and `diagnose --rounds 3` "
            f"recommends the {result['speed']['recommended']} speed form and adds "
            + (", ".join(f"`{e}`" for e in named) or "nothing")
            + f". Held out ({' / '.join(names)}), the default fit flies {flights('default')} "
            "ship lengths without an effect")
    if named:
        def added(effects) -> str:  # the campaign's key of the default fit with effects
            return " + ".join(["default", *effects])

        alone = [f"{flights(added([e]))} with `{e}` alone" for e in named if added([e]) in work]
        steps = [f"{flights(added(named[:k]))} with {listed(named[:k])}"  # one by one
                 for k in range(2, len(named)) if added(named[:k]) in work]
        recommended = work[result["recommended"]]
        text += (", " + ", ".join(alone) + ("; added in the order named, " + ", ".join(steps)
                                           if steps else "")
                 + f", and {flights(result['recommended'])} with all of them (geometric mean "
                 f"{recommended['geometric_mean_L']:.3f} L).")
        order = [("default", "without an effect")] + [
            (added(named[:k]), f"with {listed(named[:k])}")
            for k in range(1, len(named) + 1) if added(named[:k]) in work]
        text += (" In the order named the geometric mean goes "
                 + ", ".join(f"{work[key]['geometric_mean_L']:.3f} L {words}"
                             for key, words in order) + ".")
        first, everything = f"abkowitz-vr + {named[0]}", f"abkowitz-vr + {' + '.join(named)}"
        if {"abkowitz-vr", first, everything} <= set(work):
            text += (" An effect added alone can lose the turns to the cross-flow drag of the "
                     "default library, whose terms then absorb the effects still missing (the "
                     "campaign's hull is the MMG's cubic polynomial, with no cross-flow drag for "
                     "them to model): without it (`--library abkowitz-vr`) the default fit "
                     f"flies {flights('abkowitz-vr')} without an effect, {flights(first)} with "
                     f"`{named[0]}` alone and {flights(everything)} with all of them "
                     f"(geometric mean {work[everything]['geometric_mean_L']:.3f} L).")
    else:
        text += "."
    return text


def _speed(n: dict) -> str:
    speed = n.get("speed")
    if speed is None:
        return "(run benchmarks/bench_speed.py)"
    steps = speed["steps"]

    def pair(step):
        return f"{steps[step]['now']:.0f} s ({steps[step]['before']:.0f} s before)"

    return ("`benchmarks/bench_speed.py`, on two cores, beside the release before multiple "
            "shooting in the same run: the 11 protocol manoeuvres fly together in "
            f"{steps['protocol_flights']['now']:.2f} s, "
            f"{speed['reference_over_flights']:.1f} times as fast as a scalar `solve_ivp` "
            f"(RK45) of the same MMG; `fit --refine 10` on the eight training records takes "
            f"{pair('fit_refine10_protocol')}, the default `fit` "
            f"{steps['fit_protocol']['now']:.0f} s, and `sindyship reproduce` end to end "
            f"{pair('reproduce')}.")


BLOCKS = {
    "table10": _table10,
    "captive": _captive,
    "pysindy": _pysindy,
    "agreement": _agreement,
    "diagnosis": _diagnosis,
    "linear": _linear,
    "marin": _marin_text,
    "kvlcc2": _kvlcc2_table,
    "noise": _noise,
    "campaign": _campaign,
    "speed": _speed,
}


def render(readme: str, numbers: dict) -> str:
    """The README with every generated block rendered from ``numbers``."""
    for name, make in BLOCKS.items():
        pattern = re.compile(rf"(<!-- BEGIN {name} -->\n)(.*?)(<!-- END {name} -->)", re.S)
        if not pattern.search(readme):
            raise SystemExit(f"README.md has no block {name!r}")
        readme = pattern.sub(lambda m, make=make: m.group(1) + make(numbers) + "\n" + m.group(3),
                             readme)
    return readme


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--render", action="store_true",
                        help="rewrite the blocks from docs/readme-numbers.json only")
    args = parser.parse_args()
    if args.render:
        numbers = json.loads(NUMBERS.read_text())
    else:
        numbers = compute()
        NUMBERS.write_text(json.dumps(clean_json(numbers), indent=1) + "\n")
        print(f"wrote {NUMBERS.relative_to(ROOT)} in {numbers['seconds']:.0f} s", file=sys.stderr)
    README.write_text(render(README.read_text(), numbers))
    print("README.md blocks rewritten", file=sys.stderr)


if __name__ == "__main__":
    main()

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
    from sindyship.manoeuvres import turning_figures
    from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
    from sindyship.measurements import trajectory_from_frame
    from sindyship.ships import load_ship

    folder = default_marin_dir()
    if folder is None:
        return None
    raw = {key: read_marin(folder / name) for key, name in MARIN_FILES.items()}
    measured = {"port": turning_figures(raw["tc_35"], 320.0),
                "stbd": turning_figures(raw["tc_-35"], 320.0)}
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
    return {
        "refined": _marin_refined(train, test, ship, settings),
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


def _marin_refined(train, test, ship, settings: dict) -> dict:
    """Least squares and the prior fit on the MARIN zig-zags, before and after refining by
    their flights: the held-out turns and the mean over the training zig-zags."""
    from sindyship.evaluation import evaluate
    from sindyship.identify import fit
    from sindyship.refine import refine
    from sindyship.reproduce import REFINE_EVALUATIONS

    def flights(model) -> dict:
        held_out = evaluate(model, test)
        training = evaluate(model, train)
        return {"turns": {k: {"mean_distance_L": v["mean_distance_L"],
                              "diverged_at_s": v["diverged_at_s"]} for k, v in held_out.items()},
                "training_mean_L": sum(v["mean_distance_L"] for v in training.values())
                / len(training)}

    out = {}
    for key, options in (("ls", {}), ("prior", {"optimizer": "prior",
                                                 "library": "abkowitz-vr"})):
        model = fit(train, ship, **options, **settings)
        refined = refine(model, train, max_evaluations=REFINE_EVALUATIONS)
        out[key] = {"before": flights(model), "after": flights(refined),
                    "straight_run_stable": refined.info["refined"]["straight_run_stable"],
                    "kept_stable": refined.info["refined"]["refused_unstable"]}
    return out


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
    numbers["pysindy"] = _saved_pysindy()
    numbers["seconds"] = time.perf_counter() - start
    return numbers


def _saved_captive_bench() -> dict | None:
    """The zig-zag fits of benchmarks/results/captive.json (least squares, the default
    prior, the yardstick: the prior with the MMG's own Taylor coefficients, and least squares
    and the prior refined by their flights)."""
    path = RESULTS / "captive.json"
    if not path.exists():
        return None
    result = json.loads(path.read_text())
    default = f"prior {result['default_strength']:.0e}"
    fits = result["sets"]["zigzags"]["fits"]
    keys = ("ls", default, *TAYLOR_FITS, "ls refined", f"{default} refined")
    return {"default_strength": result["default_strength"],
            "sets": {"zigzags": {"fits": {k: fits[k] for k in keys}}}}


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
            label += ", refined by its training flights (recommended for flights)"
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
        "(PROTOCOL.md), and neither could its LASSO and SVR figures with its own LASSO and SVR "
        "coefficients."
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
    keys = [k for k in row if k.startswith("ls+") and not k.endswith("+refined")]
    after = ", ".join(f"{row[k]:.0f} with {k[3:].replace('+', ' and ')}" for k in keys)
    refined = next((row[k] for k in row if k.endswith("+refined")), None)
    if refined is not None:
        after += f", and {refined:.0f} once refined by the training flights"
    return (f"N'_v (x 1e-5) is {row['MMG_Taylor']:.0f} in the MMG's own Taylor expansion, "
            f"{row['paper_LS']:.0f} in the paper's LS, {row['ls']:.0f} in ours, and moves to "
            f"{after}.")


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
        f"Identified on the four MARIN zig-zags (21 s Savitzky-Golay derivatives) and tested on "
        f"the 35 deg turns, `{top}` explains {100 * rank[top]['explained']:.1f} % of the "
        f"force error ({100 * rank[top]['signal']:.1f} % of the part above the noise floor) "
        f"and `{second}` {100 * rank[second]['explained']:.1f} %; "
        f"{', '.join(f'`{e}`' for e in m['not_testable'])} are not testable (no channels). "
        f"Adding `{top}` improves the re-flown zig-zags (x {m['training_ratio']:.2f}) but not "
        f"the turns: {turn(port, 'the port')}; {turn(stbd, 'the starboard')}. Under the rule "
        "that a flight diverging where the other does not is the worse one, the effect does not "
        "carry over from zig-zags to turns: the zig-zags sweep about 70 deg of heading, over "
        "which heading terms can stand in for slow drift (the report says so)."
        + _marin_refined_text(m.get("refined"))
    )


def _marin_refined_text(refined: dict | None) -> str:
    if refined is None:
        return ""

    def turns(row):
        return " / ".join(_cell(row["turns"][k]) for k in ("tc_35", "tc_-35"))

    parts = []
    for key, label in (("ls", "least squares"), ("prior", "the `prior` fit")):
        r = refined[key]
        if r.get("kept_stable"):
            parts.append(f"{label} is kept as fitted (turns {turns(r['before'])}): refined, "
                         "it was unstable in straight running, which the prior's stability "
                         "requirement refuses")
            continue
        unstable = ("" if r["straight_run_stable"]
                    else ", and the refined model is unstable in straight running")
        parts.append(f"{label} goes from {r['before']['training_mean_L']:.3f} to "
                     f"{r['after']['training_mean_L']:.3f} L on the zig-zags and flies the "
                     f"turns (port / starboard) {turns(r['before'])} before and "
                     f"{turns(r['after'])} after{unstable}")
    return (" Refining by the zig-zags' flights (`fit --refine 10`) does not carry over to the "
            f"turns either: {parts[0]}; {parts[1]}. A refinement fits the manoeuvres it "
            "flies and extrapolates no better than they span.")


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
    diagnosed = [k for k in captive if k.startswith("ls+") and not k.endswith("+refined")][-1]
    refined = f"{diagnosed}+refined"
    rows = {"least squares": captive["ls"], "`prior`": captive["prior"],
            diagnosed: captive[diagnosed]}
    if refined in captive:
        rows[f"{diagnosed}, refined (recommended for flights)"] = captive[refined]
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

        lines += ["", "Identified on the three zig-zags alone (`benchmarks/bench_captive.py`), "
                  f"the lowest Y or N correlation over static drift, pure yaw and drift and yaw "
                  f"is {low(ls):+.2f} for least squares and {low(prior):+.2f} for `prior`; "
                  f"their held-out flights are {flights(ls)} and {flights(prior)} ship lengths. "
                  "With the MMG's own Taylor coefficients in place of the estimates (the same "
                  "fit otherwise; a yardstick that uses the simulator's coefficients) it flies "
                  f"{flights(zz[TAYLOR_FITS[0]])} at the same strength and "
                  f"{flights(zz[TAYLOR_FITS[1]])} at 1e-4 (lowest X, Y or N correlation "
                  f"{min(low(zz[k], 'XYN') for k in TAYLOR_FITS):+.2f}): the estimates from "
                  "main dimensions are not accurate enough for the turns by themselves. "
                  "Refined by the error of its zig-zag flights (`fit --refine`), the `prior` "
                  f"fit flies {flights(prior_refined)} and keeps its forces (lowest X, Y or N "
                  f"correlation {low(prior_refined, 'XYN'):+.2f}); least squares refined the "
                  f"same way flies {flights(ls_refined)} (lowest Y or N correlation "
                  f"{low(ls_refined):+.2f}): it fits the zig-zags closer and the turns worse."]
    return "\n".join(lines)


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
            f"sindyship least squares {errors('sindyship_ls')}, sindyship diagnosed "
            f"{errors('sindyship_diagnosed')}, the diagnosed model refined by its training "
            f"flights {errors('sindyship_refined')}{prior} ship lengths; the recommended "
            f"workflow (refined) is better than pysindy on {len(wins)} of {len(names)} "
            f"({', '.join(wins)}).")


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

"""The paper's experiment end to end (the reproduction protocol).

Generates the eight training and three held-out KCS manoeuvres with the MMG simulator, fits
every optimizer on the training set, flies the held-out manoeuvres with each identified model
(the zig-zag closed loop) and compares the Table-10 distances with the paper's.  Writes the
coefficient tables, the saved models, trajectory figures in the style of the paper's Figures
2-5 and a JSON of all results to an output folder.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import pandas as pd

from .evaluation import distance_errors, fly_like_batch
from .identify import design, fit, resolve_library
from .manoeuvres import fly, protocol_manoeuvres
from .mmg import MMGModel
from .model import paper_model, write_text_atomic
from .paper import TABLE_10, ls_agreement, paper_coefficients
from .ships import load_ship

METHODS = ("ls", "stlsq", "lasso", "svr")
TEST_NAMES = ("tc15_port", "tc15_stbd", "zz10_10")


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def run(out_dir: str | Path | None = "reproduce-output", *, methods=METHODS,
        figures: bool = True, diagnose_rounds: int = 3, progress=_progress) -> dict:
    """Run the protocol; return the JSON-ready results (and write files when ``out_dir``).

    Returns
    -------
    dict
        ``{"results": [...], "paper_ls_agreement": {...}, "paper_ls_flown": {...},
        "seconds": ...}`` as documented for ``sindyship reproduce --json``.
    """
    start = time.perf_counter()
    ship = load_ship("kcs")
    plan = protocol_manoeuvres()
    progress("simulating the 8 training and 3 held-out KCS manoeuvres (MMG)")
    mmg = MMGModel(ship)
    train = fly(mmg, plan["train"])
    test = fly(mmg, plan["test"])
    library = resolve_library("abkowitz")
    problems = design(train, ship, library)
    results = []
    models = {}
    flights = {}
    for method in methods:
        t0 = time.perf_counter()
        model = fit(train, ship, library=library, optimizer=method, problems=problems)
        flown = fly_like_batch(model.dynamics(), test)
        errors = {rec.name: distance_errors(f, rec, ship.L) for f, rec in zip(flown, test,
                                                                              strict=True)}
        models[method] = model
        flights[method] = flown
        results.append({"method": method, "library": library.name, "effects": [],
                         "errors": errors, "active_terms": model.n_active(),
                         "selected": model.info.get("selected", {})})
        progress(f"  {method:6s} fitted and flown in {time.perf_counter() - t0:5.1f} s: "
                 + ", ".join(f"{k} {v['mean_distance_L']:.3f} L" for k, v in errors.items()))
    diagnosis = None
    if diagnose_rounds:
        from .diagnose import diagnose_iteratively

        progress("diagnosing missing effects, adding the best one, diagnosing again")
        t0 = time.perf_counter()
        iterative = diagnose_iteratively(train, ship, test=test, max_rounds=diagnose_rounds)
        diagnosis = {"rounds": [], "stopped": iterative.stopped,
                     "report": iterative.report()}
        for k, rnd in enumerate(iterative.rounds):
            d = rnd.diagnosis
            diagnosis["rounds"].append({
                "library": d.library.name,
                "ranking": [{"effect": sc.effect.name, "explained": sc.explained}
                            for sc in d.ranking],
                "added": rnd.added,
            })
            if k == 0:
                continue  # the plain library: the "ls" row above
            effects = list(d.library.effects)
            errors = d.errors("held-out")
            results.append({"method": "ls", "library": d.library.name, "effects": effects,
                            "errors": errors, "active_terms": d.model.n_active(),
                            "selected": {}})
            key = "ls+" + "+".join(effects)
            models[key] = d.model
            flights[key] = fly_like_batch(d.model.dynamics(), test)
        if out_dir is not None and figures:
            import matplotlib.pyplot as plt

            Path(out_dir).mkdir(parents=True, exist_ok=True)
            fig = iterative.figure()
            fig.savefig(Path(out_dir) / "diagnosis-rounds.png", dpi=110)
            plt.close(fig)
        progress(f"  diagnosis in {time.perf_counter() - t0:5.1f} s: " + " -> ".join(
            r["library"] for r in diagnosis["rounds"]))
    agreement = ls_agreement(models["ls"].coefficients) if "ls" in models else None
    paper_ls = paper_model(ship, "LS")
    paper_flown = fly_like_batch(paper_ls.dynamics(), test)
    paper_errors = {rec.name: distance_errors(f, rec, ship.L)
                    for f, rec in zip(paper_flown, test, strict=True)}
    table = coefficient_table(models, ship)
    linear_terms = {("X", "du"), ("Y", "v"), ("Y", "r"), ("Y", "delta"), ("N", "v"),
                    ("N", "r"), ("N", "delta")}
    linear = [
        {"name": row["paper_name"].replace("'", ""), "MMG_Taylor": row["MMG_Taylor"],
         "paper_LS": row["paper_LS"], **{m: row[m.upper()] for m in models}}
        for _, row in table.iterrows() if (row["equation"], row["term"]) in linear_terms
    ]
    output = {
        "linear_derivatives": linear,
        "results": results,
        "diagnosis": diagnosis,
        "paper_ls_agreement": agreement,
        "paper_ls_flown": paper_errors,
        "paper_table_10": TABLE_10,
    }
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        from .export import generate_python, latex_document_part

        for method, model in models.items():
            model.save(out / f"model-{method}.json")
            write_text_atomic(out / f"equations-{method}.tex", latex_document_part(model))
            write_text_atomic(out / f"simulator-{method}.py", generate_python(
                model, source_note="sindyship reproduce: the paper's KCS training set"))
        table.to_csv(out / "coefficients.csv", index=False)
        if figures:
            from .plots import trajectory_overlay

            for k, rec in enumerate(test):
                fig = trajectory_overlay(rec, {m.upper(): flights[m][k] for m in flights},
                                         L=ship.L, title=f"Held-out {rec.name}")
                fig.savefig(out / f"trajectory-{rec.name}.png", dpi=110)
                import matplotlib.pyplot as plt

                plt.close(fig)
    output["seconds"] = time.perf_counter() - start
    if out_dir is not None:
        write_text_atomic(Path(out_dir) / "results.json", json.dumps(output, indent=2) + "\n")
    return output


def coefficient_table(models: dict, ship=None) -> pd.DataFrame:
    """Identified coefficients (x 1e-5) beside the paper's Tables 7-9 and, with ``ship``, the
    Taylor reference the MMG implies (expanded with the mean gamma_R)."""
    paper = paper_coefficients()
    table = paper[["equation", "term", "paper_name", "LS_1e-5", "Lasso_1e-5", "SVR_1e-5"]]
    table = table.rename(columns={"LS_1e-5": "paper_LS", "Lasso_1e-5": "paper_LASSO",
                                  "SVR_1e-5": "paper_SVR"})
    if ship is not None:
        from .taylor import taylor_reference

        reference = taylor_reference(ship)
        table.insert(3, "MMG_Taylor", [reference[d].get(t, float("nan")) * 1e5
                                       for d, t in zip(table["equation"], table["term"],
                                                       strict=True)])
    for method, model in models.items():
        values = [model.coefficients[d].get(t, float("nan")) * 1e5
                  for d, t in zip(table["equation"], table["term"], strict=True)]
        table[method.upper()] = values
    return table


def format_report(output: dict) -> str:
    """Plain-text report: Table 10 beside the paper, and the LS agreement check."""
    lines = ["Held-out mean distance [ship lengths] (paper Table 10 in brackets; +effect: the",
             "least-squares model with the terms of effects the diagnosis found missing)", ""]
    header = f"{'method':30s}" + "".join(f"{n:>22s}" for n in TEST_NAMES)
    lines.append(header)
    for res in output["results"]:
        cells = []
        for name in TEST_NAMES:
            err = res["errors"][name]
            value = f"{err['mean_distance_L']:.4f}"
            if err["diverged_at_s"] is not None:
                value += f" (div {err['diverged_at_s']:.0f}s)"
            paper = None if res["effects"] else TABLE_10.get(res["method"], {}).get(name)
            cells.append(f"{value} [{paper:.4f}]" if paper is not None else value)
        label = res["method"] + "".join(f"+{e}" for e in res["effects"])
        lines.append(f"{label:30s}" + "".join(f"{c:>22s}" for c in cells))
    if output.get("diagnosis"):
        lines.append("")
        lines.append("Missing-effect diagnosis (share of the force error each effect explains on "
                     "manoeuvres left out):")
        lines.extend("  " + line for line in output["diagnosis"]["report"].splitlines()[:4])
    paper_flown = output.get("paper_ls_flown")
    if paper_flown:
        lines.append("")
        lines.append("The paper's own LS coefficients flown here: " + ", ".join(
            f"{k} {v['mean_distance_L']:.3f} L" for k, v in paper_flown.items()))
    agreement = output.get("paper_ls_agreement")
    if agreement:
        lines.append(
            f"LS coefficients vs paper Tables 7-9: median relative deviation "
            f"{agreement['median_rel_dev']:.3f}, "
            f"same sign {100 * agreement['sign_agreement']:.1f} %"
            f" ({agreement['n_coefficients']} non-zero coefficients)")
    linear = output.get("linear_derivatives")
    if linear:
        lines.append("")
        lines.append("Linear derivatives x 1e-5: the MMG's Taylor reference beside the fits")
        methods = [k for k in linear[0] if k not in ("name", "MMG_Taylor", "paper_LS")]
        widths = [max(10, len(m) + 2) for m in methods]
        lines.append(f"{'':8s}{'MMG':>10s}{'paper LS':>10s}" + "".join(
            f"{m.upper():>{w}s}" for m, w in zip(methods, widths, strict=True)))
        for row in linear:
            lines.append(f"{row['name']:8s}{row['MMG_Taylor']:10.1f}{row['paper_LS']:10.1f}"
                         + "".join(f"{row[m]:{w}.1f}"
                                   for m, w in zip(methods, widths, strict=True)))
        lines.append("(all coefficients: coefficients.csv in the output folder)")
    lines.append(f"Finished in {output['seconds']:.1f} s.")
    return "\n".join(lines)

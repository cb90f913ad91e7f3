"""The paper's experiment end to end (the reproduction protocol).

Generates the eight training and three held-out KCS manoeuvres with the MMG simulator, fits
every optimizer on the training set, flies the held-out manoeuvres with each identified model
(the zig-zag closed loop) and compares the Table-10 distances with the paper's.  Writes the
coefficient tables, the saved models, trajectory figures in the style of the paper's Figures
2-5 and a JSON of all results to an output folder.
"""

from __future__ import annotations

import json
import re
import sys
import time
from pathlib import Path

import pandas as pd

from ._compile_notice import compiles_first
from ._io import save_figure, write_text_atomic
from .evaluation import distance_errors
from .flight_reports import reproduce_report
from .flights import fly_like_batch
from .identify import RECOMMENDED_LIBRARIES, design, fit, resolve_library
from .manoeuvres import fly, protocol_manoeuvres
from .mmg import MMGModel
from .model import paper_model
from .paper import TABLE_10, ls_agreement, paper_coefficients
from .ships import load_ship

METHODS = ("ls", "stlsq", "lasso", "svr", "prior")
#: The library of every method: the paper's, but the physics-consistent fit takes the surge
#: term ``v r`` that its prior has an estimate of (:mod:`sindyship.priors`).
METHOD_LIBRARIES = {"prior": RECOMMENDED_LIBRARIES["design"]}
#: The captive tests the models' forces are compared with (:func:`captive_agreement`).
CAPTIVE_TESTS = ("static-drift", "rudder", "pure-yaw", "drift-yaw")
TEST_NAMES = ("tc15_port", "tc15_stbd", "zz10_10")
#: Most evaluations of the recommended model's refinement (``max_evaluations`` of
#: :func:`sindyship.refine.refine`; the default of ``sindyship fit``).
REFINE_EVALUATIONS = 60


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _distances(flown, test, ship) -> dict:
    """The Table-10 distances of flights of the held-out records, by record name."""
    return {rec.name: distance_errors(f, rec, ship.L) for f, rec in zip(flown, test,
                                                                        strict=True)}


def _fit_and_fly(train, test, ship, methods, progress) -> tuple[list, dict, dict]:
    """Fit every method on the training set and fly the held-out manoeuvres."""
    libraries, problems = {}, {}
    results, models, flights = [], {}, {}
    for method in methods:
        t0 = time.perf_counter()
        name = METHOD_LIBRARIES.get(method, "abkowitz")
        if name not in libraries:
            libraries[name] = resolve_library(name)
            problems[name] = design(train, ship, libraries[name])
        library = libraries[name]
        model = fit(train, ship, library=library, optimizer=method, problems=problems[name])
        flown = fly_like_batch(model.dynamics(), test)
        errors = _distances(flown, test, ship)
        models[method] = model
        flights[method] = flown
        results.append({"method": method, "library": library.name, "effects": [],
                        "errors": errors, "active_terms": model.n_active(),
                        "selected": model.info.get("selected", {})})
        progress(f"  {method:6s} fitted and flown in {time.perf_counter() - t0:5.1f} s: "
                 + ", ".join(f"{k} {v['mean_distance_L']:.3f} L" for k, v in errors.items()))
    return results, models, flights


def _diagnosis_rounds(train, test, ship, rounds, progress):
    """Diagnose, add the best effect, diagnose again: the JSON summary, one result row per
    added effect, the diagnosed models and the iteration itself."""
    from .diagnose import diagnose_iteratively

    progress("diagnosing missing effects, adding the best one, diagnosing again")
    t0 = time.perf_counter()
    # the recommended row below fits and flies the command's model of the first effect
    iterative = diagnose_iteratively(train, ship, test=test, max_rounds=rounds,
                                     search_beyond=False, check_command=False)
    diagnosis = {"rounds": [], "stopped": iterative.stopped, "report": iterative.report()}
    results, models = [], {}
    for k, rnd in enumerate(iterative.rounds):
        d = rnd.diagnosis
        diagnosis["rounds"].append({
            "library": d.library.name,
            "ranking": [{"effect": sc.effect.name, "explained": sc.explained,
                         "explained_signal": sc.explained_signal, "meaningful": sc.meaningful}
                        for sc in d.ranking],
            "added": rnd.added,
        })
        if k == 0:
            continue  # the plain library: the "ls" row of the fits
        effects = list(d.library.effects)
        results.append({"method": "ls", "library": d.library.name, "effects": effects,
                        "errors": d.errors("held-out"), "active_terms": d.model.n_active(),
                        "selected": {}})
        models["ls+" + "+".join(effects)] = d.model
    progress(f"  diagnosis in {time.perf_counter() - t0:5.1f} s: " + " -> ".join(
        r["library"] for r in diagnosis["rounds"]))
    return diagnosis, results, models, iterative


def _recommended_row(iterative, train, test, ship, evaluations, progress):
    """The recommended workflow: the default fit of ``sindyship fit`` (``prior`` on
    ``abkowitz-vr``, refined by its training flights, :func:`sindyship.refine.refine`) with the
    first effect the diagnosis names; its result row, key, model and held-out flights."""
    from .refine import refine

    added = [rnd.added for rnd in iterative.rounds if rnd.added]
    effects = added[:1]
    progress(f"the recommended fit: prior on {METHOD_LIBRARIES['prior']} with "
             f"{', '.join(effects) or 'no effect'}, refined by its training flights (at most "
             f"{evaluations} evaluations)")
    t0 = time.perf_counter()
    fitted = fit(train, ship, library=METHOD_LIBRARIES["prior"], effects=effects,
                 optimizer="prior")
    model = refine(fitted, train, max_evaluations=evaluations, progress=sys.stderr.isatty())
    flown = fly_like_batch(model, test)
    errors = _distances(flown, test, ship)
    progress(f"  fitted and refined in {time.perf_counter() - t0:5.1f} s: "
             + ", ".join(f"{k} {v['mean_distance_L']:.3f} L" for k, v in errors.items()))
    row = {"method": "prior", "library": model.library.name, "effects": effects,
           "refined": True, "recommended": True, "errors": errors,
           "active_terms": model.n_active(), "selected": {},
           "refinement": model.info["refined"]}
    return row, "+".join(["prior", *effects, "refined"]), model, flown


def _held_out_flights(iterative, test) -> dict:
    """The held-out flights of every diagnosed model (after the plain round), keyed as the
    models of :func:`_diagnosis_rounds`, in the order of ``test``."""
    out = {}
    for rnd in iterative.rounds[1:]:
        d = rnd.diagnosis
        flown = {c.name: c.flown for c in d.comparisons if c.set == "held-out"}
        out["ls+" + "+".join(d.library.effects)] = [flown[r.name] for r in test]
    return out


def _write_outputs(out: Path, output: dict, models: dict, flights: dict, test, ship,
                   table: pd.DataFrame, figures: list) -> None:
    """Models, equations, simulators, the coefficient table, figures and results.json."""
    from .export import generate_python, latex_document_part

    for method, model in models.items():
        model.save(out / f"model-{method}.json")
        write_text_atomic(out / f"equations-{method}.tex", latex_document_part(model))
        module = "simulator_" + re.sub(r"\W", "_", method)  # a name import takes
        write_text_atomic(out / f"{module}.py", generate_python(
            model, source_note="sindyship reproduce: the paper's KCS training set"))
    labels = {c: c if c in ("equation", "term", "paper_name") else f"{c} [x 1e-5, Prime I]"
              for c in table.columns}
    write_text_atomic(out / "coefficients.csv", table.rename(columns=labels).to_csv(index=False))
    for name, fig in figures:
        save_figure(fig, out / name)
    write_text_atomic(out / "results.json", json.dumps(output, indent=2) + "\n")


def _trajectory_figures(test, flights: dict, ship) -> list:
    """Per held-out record: the track overlay, and the standard figure of its manoeuvre (a
    zig-zag's heading and rudder with its overshoots, a turn with advance and tactical
    diameter), each beside the IMO criteria."""
    from .flights import recognised_zigzag
    from .plotting import plot_turning_circle, plot_zigzag, trajectory_overlay

    out = []
    for k, rec in enumerate(test):
        flown = {m.upper(): flights[m][k] for m in flights}
        out.append((f"trajectory-{rec.name}.png",
                    trajectory_overlay(rec, flown, L=ship.L, title=f"Held-out {rec.name}")))
        if recognised_zigzag(rec) is not None:
            out.append((f"zigzag-{rec.name}.png",
                        plot_zigzag(rec, flights=flown, L=ship.L, U=ship.U0)))
        else:
            out.append((f"turning-{rec.name}.png",
                        plot_turning_circle(rec, L=ship.L, flights=flown)))
    return out


def run(out_dir: str | Path | None = "reproduce-output", *, methods=METHODS,
        figures: bool = True, diagnose_rounds: int = 3,
        refine_evaluations: int = REFINE_EVALUATIONS, progress=_progress) -> dict:
    """Run the protocol; return the JSON-ready results (and write files when ``out_dir``).

    Last comes the recommended workflow: the default fit (``prior``) with the first effect
    the diagnosis names, refined by the error of its training flights (:mod:`sindyship.refine`,
    at most ``refine_evaluations`` evaluations; 0 skips it).

    Returns
    -------
    dict
        ``{"results": [...], "paper_ls_agreement": {...}, "paper_ls_flown": {...},
        "seconds": ...}`` as documented for ``sindyship reproduce --json``.
    """
    start = time.perf_counter()
    ship = load_ship("kcs")
    plan = protocol_manoeuvres()
    if compiles_first():
        progress("numba compiles the flight loops in this first run after an installation "
                 "(about a minute more on two cores; later runs reuse them)")
    progress("simulating the 8 training and 3 held-out KCS manoeuvres (MMG)")
    mmg = MMGModel(ship)
    flown = fly(mmg, plan["train"] + plan["test"])  # one batch: every manoeuvre is 3200 s
    train, test = flown[: len(plan["train"])], flown[len(plan["train"]):]
    results, models, flights = _fit_and_fly(train, test, ship, methods, progress)
    diagnosis, drawn = None, []
    if diagnose_rounds:
        diagnosis, rows, diagnosed, iterative = _diagnosis_rounds(
            train, test, ship, diagnose_rounds, progress)
        results += rows
        models.update(diagnosed)
        for key, round_flights in _held_out_flights(iterative, test).items():
            flights[key] = round_flights  # flown by the diagnosis, not again
        if figures:
            drawn.append(("diagnosis-rounds.png", iterative.figure()))
        if refine_evaluations:
            row, key, model, flights[key] = _recommended_row(iterative, train, test, ship,
                                                             refine_evaluations, progress)
            results.append(row)
            models[key] = model
    agreement = ls_agreement(models["ls"].coefficients) if "ls" in models else None
    paper_ls = paper_model(ship, "LS")
    paper_flown = fly_like_batch(paper_ls.dynamics(), test)
    paper_errors = _distances(paper_flown, test, ship)
    table = coefficient_table(models, ship)
    progress("comparing every model's forces with the MMG's virtual captive tests")
    output = {
        "linear_derivatives": _linear_derivatives(table, models),
        "results": results,
        "captive": captive_agreement(models, ship),
        "diagnosis": diagnosis,
        "paper_ls_agreement": agreement,
        "paper_ls_flown": paper_errors,
        "paper_table_10": TABLE_10,
    }
    if out_dir is not None:
        if figures:
            drawn += _trajectory_figures(test, flights, ship)
        output["seconds"] = time.perf_counter() - start
        _write_outputs(Path(out_dir), output, models, flights, test, ship, table, drawn)
    output["seconds"] = time.perf_counter() - start
    return output


def captive_agreement(models: dict, ship) -> dict:
    """Every model's forces against the MMG's virtual captive tests of the ship.

    Returns
    -------
    dict
        ``{model: {test: {"X": {"correlation", "relative_rms"}, "Y": ..., "N": ...}}}`` for
        the tests of :data:`CAPTIVE_TESTS` (:func:`sindyship.forces.compare_forces`).
    """
    from .captive import captive_tests
    from .forces import compare_forces

    captive = captive_tests(ship, "all")
    out = {}
    for key, model in models.items():
        by_test = compare_forces(model, captive).to_dict()["by_test"]
        out[key] = {test: {dof: {k: by_test[test][dof][k]
                                 for k in ("correlation", "relative_rms")} for dof in "XYN"}
                    for test in CAPTIVE_TESTS}
    return out


def _linear_derivatives(table: pd.DataFrame, models: dict) -> list[dict]:
    """The linear derivatives (x 1e-5): MMG Taylor reference, paper LS and every fit."""
    linear_terms = {("X", "du"), ("Y", "v"), ("Y", "r"), ("Y", "delta"), ("N", "v"),
                    ("N", "r"), ("N", "delta")}
    return [
        {"name": row["paper_name"].replace("'", ""), "MMG_Taylor": row["MMG_Taylor"],
         "paper_LS": row["paper_LS"], **{m: row[m.upper()] for m in models}}
        for _, row in table.iterrows() if (row["equation"], row["term"]) in linear_terms
    ]


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
    """Plain-text report (:func:`sindyship.flight_reports.reproduce_report`)."""
    return reproduce_report(output)

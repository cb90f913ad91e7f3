"""Coefficients against captive tests: least squares beside the physics-consistent fit.

Identifies the KCS on the paper's training set (8 manoeuvres) and on its three zig-zags alone,
with least squares (``ls``, the paper's library ``abkowitz``) and with ``prior`` at a range of
strengths (its default 1e-5 among them) on the library ``abkowitz-vr`` that ``reproduce`` gives
it, and at its default strength on the paper's library (``prior 1e-05 abkowitz``: without the
surge term ``v r``), and for every model reports

- the agreement of its forces with the MMG's virtual captive tests
  (:func:`sindyship.captive.captive_tests`: static drift to 20 deg, rudder to 35 deg, pure yaw
  to r' = 0.6, drift and yaw combined): correlation and relative RMS error of X, Y and N per
  test (:func:`sindyship.forces.compare_forces`);
- the held-out flights of the protocol (tc15_port, tc15_stbd, zz10_10; mean distance in
  ship lengths, a diverged flight as such);
- its straight-run stability.

A yardstick for the semi-empirical estimates: ``prior 1e-05 taylor`` (and ``1e-04``) is the
same fit (terms, widths, speed relations, stability requirement) with the means of the
estimated derivatives replaced by the MMG's own Taylor coefficients
(:func:`sindyship.taylor.taylor_reference`): what the prior would give if the regressions on
main dimensions were exact for this hull.  It uses the simulator's coefficients, so it is a
yardstick, never a workflow.

On the zig-zags, ``ls refined`` and ``prior 1e-05 refined`` are those fits refined by the
error of their training flights (:func:`sindyship.refine.refine`, the zig-zags flown closed
loop; at most ``reproduce.REFINE_EVALUATIONS`` flights): whether a refinement keeps the
prior's forces while it fixes its flights.  Two more fits there say what limits the turns:

- ``prior 1e-05 + asymmetry abs(v) abs(r)`` (and ``... refined``): the library with the even
  sway and yaw terms ``abs(v)`` and ``abs(r)`` of the catalogue's ``asymmetry`` alone, those of
  a rudder whose inflow is straightened differently on the two sides (the KCS's gamma_R is
  0.492 turning to starboard and 0.338 to port; the Abkowitz series is odd in v and r and
  cannot express it);
- ``prior 1e-05 with the held-out records``: the prior fit on the zig-zags *and the held-out
  records*, a reference for what the library's forces fitted on the turns fly, never a
  workflow.

``prior 1e-05 + <effect>`` (and ``... refined``) is the workflow the README recommends on
those records: the effect ``sindyship diagnose`` ranks first on the zig-zags (all of its
terms) added to the default fit.  ``prior 1e-05 refined, prior weight W`` refines the default
fit with a stronger pull toward the fit's own objective (``fit --refine-weight W``, default
0.01; :data:`PRIOR_WEIGHTS`): whether the refinement it refuses for losing a hard-over turn
is kept, and flies better, when it is held closer to the fit.

And ``prior 1e-05 + captive programme`` (and ``... refined``) is the hybrid fit (``fit
--captive``, :func:`sindyship.hybrid.fit_hybrid`) of the zig-zags and a small towing-tank
programme of the MMG's virtual captive tests (:data:`CAPTIVE_PROGRAMME`: static drift, rudder
and pure yaw, :data:`PROGRAMME_POINTS` conditions each; no drift and yaw combined, which the
captive agreement still judges) at the default captive share.

Two more say how close the zig-zags alone come to the turns with those terms: ``... refined
whole`` (refined by whole closed-loop zig-zag flights, as ``evaluate`` flies them, instead of
the default shooting segments) and ``prior 1e-05 instantaneous + asymmetry abs(v) abs(r)``
(and ``... refined``: the library's forces scaled with the instantaneous speed, ``fit --speed
instantaneous``).

A turning circle of the protocol lasts 3200 s, about eight turns (``held_out_turns``), so its
mean distance grows with the error of its steady yaw rate: every row reports that error (the
mean yaw rate over the last quarter of each held-out turn, flown against recorded, in per
cent).

With ``--against CHECKOUT``, the ``prior`` fit on the zig-zags refined by another checkout of
sindyship (``sindyship fit --optimizer prior --library abkowitz-vr --refine N`` of that
checkout on the same records, written as measurement CSVs, for each N of
:data:`AGAINST_EVALUATIONS`), its saved models flown and compared here as every other row
(``prior 1e-05 refined before, N evaluations``): how the flights and forces of that
refinement move with the length of its search.

Prints the tables and saves ``benchmarks/results/captive.json``.  Run with
``python benchmarks/bench_captive.py`` (about fifteen seconds once numba has compiled), or::

    git worktree add /tmp/sindyship-before COMMIT
    python benchmarks/bench_captive.py --against /tmp/sindyship-before
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from bench_campaign import checkout_cli, checkout_commit

from sindyship._io import clean_json, write_text_atomic
from sindyship.captive import captive_tests
from sindyship.diagnose import diagnose
from sindyship.evaluation import distance_errors
from sindyship.flights import fly_like_batch
from sindyship.hybrid import fit_hybrid
from sindyship.identify import (
    design,
    fit,
    fitted_model,
    resolve_library,
    straight_run_stable,
)
from sindyship.library import Effect, load_effect
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.measurements import write_csv
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel
from sindyship.optimizers import PriorRidge
from sindyship.priors import prior_means, prior_parameters
from sindyship.refine import refine
from sindyship.reproduce import (
    CAPTIVE_TESTS,
    METHOD_LIBRARIES,
    REFINE_EVALUATIONS,
    captive_agreement,
)
from sindyship.ships import load_ship
from sindyship.stability import straight_run_stability
from sindyship.taylor import taylor_reference
from sindyship.terms import Term

OUT = Path(__file__).parent / "results" / "captive.json"
STRENGTHS = (1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3)
#: The strengths of the fits with the MMG's Taylor coefficients as the prior (the yardstick).
TAYLOR_STRENGTHS = (1e-5, 1e-4)
#: The terms of the catalogue's ``asymmetry`` of a rudder whose inflow is straightened
#: differently on the two sides: even in v and r, in sway and yaw.
RUDDER_INFLOW = ("abs(v)", "abs(r)")
#: The share of a held-out turn, from its end, over which its steady yaw rate is taken.
STEADY_SHARE = 0.25
#: The towing-tank programme of the hybrid fit on the zig-zags, and its conditions per test.
CAPTIVE_PROGRAMME = ("static-drift", "rudder", "pure-yaw")
PROGRAMME_POINTS = 5
#: The stronger pulls toward the fit's objective inside the refinement of the default fit on
#: the zig-zags (the default is 0.01).
PRIOR_WEIGHTS = (0.1, 1.0)
#: The most trial steps (``--refine N``) another checkout's refinement is given (--against).
AGAINST_EVALUATIONS = (10, 20, 40, 60, 90)


def taylor_prior_fit(ship, library, problems, strength: float):
    """The ``prior`` fit with the MMG's own Taylor coefficients in place of the semi-empirical
    estimates: the same terms, widths, speed relations and stability requirement."""
    reference = taylor_reference(ship, library)
    estimated = prior_means(ship)

    def fitted_with(chosen: float):
        fitted = {}
        for dof, problem in problems.items():
            params = prior_parameters(ship, dof, problem.terms)
            mean = [reference[dof][term] if Term(term).canonical() in estimated[dof] else m
                    for term, m in zip(problem.terms, params["mean"], strict=True)]
            fitted[dof] = PriorRidge(strength=chosen, mean=mean, scale=params["scale"],
                                     relations=params["relations"]).fit(problem.features,
                                                                        problem.target)
        return fitted_model(ship, library, fitted, {d: p.terms for d, p in problems.items()},
                            optimizer="prior", rudder_signal="actual", info={})

    return straight_run_stable(fitted_with(strength), fitted_with)


def rudder_inflow() -> Effect:
    """The catalogue's ``asymmetry`` with its :data:`RUDDER_INFLOW` terms alone."""
    asymmetry = load_effect("asymmetry")
    return Effect(f"{asymmetry.name}-rudder-inflow", asymmetry.title, asymmetry.physics, (),
                  {dof: [t for t in asymmetry.terms[dof] if t.text in RUDDER_INFLOW]
                   for dof in ("Y", "N")})


def captive_programme(ship) -> pd.DataFrame:
    """The MMG's virtual captive tests of :data:`CAPTIVE_PROGRAMME`, one table."""
    return pd.concat([captive_tests(ship, test, points=PROGRAMME_POINTS)
                      for test in CAPTIVE_PROGRAMME], ignore_index=True)


def is_turning_circle(record) -> bool:
    return record.meta.get("manoeuvre") == "turning-circle"


def steady_yaw_rate_error(flown, record) -> float | None:
    """Per cent by which a flown turning circle's steady yaw rate r (its mean over the last
    :data:`STEADY_SHARE` of the record) misses the recorded one; None for another manoeuvre
    or a diverged flight."""
    if not is_turning_circle(record) or flown.meta.get("diverged_at") is not None:
        return None
    start = int((1.0 - STEADY_SHARE) * len(record.t))
    return 100.0 * (float(np.mean(flown["r"][start:])) / float(np.mean(record["r"][start:]))
                    - 1.0)


def evaluate(model, test, ship) -> dict:
    """Captive agreement per test, held-out flights and stability of one model."""
    flown = fly_like_batch(model.dynamics(), test)
    return {
        "captive": captive_agreement({"model": model}, ship)["model"],
        "held_out": {r.name: distance_errors(f, r, ship.L) for f, r in zip(flown, test,
                                                                            strict=True)},
        "steady_yaw_rate_error_pct": {r.name: steady_yaw_rate_error(f, r)
                                      for f, r in zip(flown, test, strict=True)
                                      if is_turning_circle(r)},
        "straight_run": model.info.get("straight_run"),
        "straight_run_stable": straight_run_stability(model).stable,
        "strength": model.optimizer["params"].get("strength"),
    }


def refined_by(checkout: Path, records, ship) -> dict:
    """The ``prior`` fit on ``records`` refined by the ``sindyship fit`` of another checkout
    with each number of trial steps of :data:`AGAINST_EVALUATIONS`: the saved models, loaded
    here, by that number."""
    models = {}
    with tempfile.TemporaryDirectory() as folder:
        paths = []
        for record in records:
            paths.append(str(Path(folder) / f"{record.name}.csv"))
            write_csv(record, paths[-1])
        for evaluations in AGAINST_EVALUATIONS:
            out = Path(folder) / f"refined-{evaluations}.json"
            checkout_cli(checkout, "fit", *paths, "--ship", "kcs", "--optimizer", "prior",
                         "--library", METHOD_LIBRARIES["prior"], "--refine", str(evaluations),
                         "--out", str(out))
            models[evaluations] = AbkowitzModel.load(out, ship=ship)
    return models


def run(against: Path | None = None) -> dict:
    """Every fit of every training set (and, with ``against``, the refinements of another
    checkout on the zig-zags)."""
    start = time.perf_counter()
    ship = load_ship("kcs")
    plan = protocol_manoeuvres()
    flown = fly(MMGModel(ship), plan["train"] + plan["test"])
    train, test = flown[: len(plan["train"])], flown[len(plan["train"]):]
    paper = resolve_library("abkowitz")
    library = resolve_library(METHOD_LIBRARIES["prior"])
    default = PriorRidge().strength
    sets = {"protocol": train, "zigzags": [r for r in train if r.name.startswith("zz")]}
    out = {"libraries": {"ls": paper.name, "prior": library.name}, "tests": list(CAPTIVE_TESTS),
           "strengths": list(STRENGTHS), "default_strength": default, "sets": {}}
    for name, records in sets.items():
        problems = design(records, ship, library)
        paper_problems = design(records, ship, paper)
        fitted = {"ls": fit(records, ship, library=paper, problems=paper_problems)}
        rows = {"ls": evaluate(fitted["ls"], test, ship)}
        for strength in STRENGTHS:
            model = fit(records, ship, library=library, optimizer="prior",
                        params={"strength": strength}, problems=problems)
            fitted[f"prior {strength:.0e}"] = model
            rows[f"prior {strength:.0e}"] = evaluate(model, test, ship)
        model = fit(records, ship, library=paper, optimizer="prior",
                    params={"strength": default}, problems=paper_problems)
        rows[f"prior {default:.0e} {paper.name}"] = evaluate(model, test, ship)
        for strength in TAYLOR_STRENGTHS:
            rows[f"prior {strength:.0e} taylor"] = evaluate(
                taylor_prior_fit(ship, library, problems, strength), test, ship)
        if name == "zigzags":
            prior, inflow = f"prior {default:.0e}", f"prior {default:.0e} + asymmetry abs(v) abs(r)"
            fitted[inflow] = fit(records, ship, library=library.extended(rudder_inflow()),
                                 optimizer="prior")
            rows[inflow] = evaluate(fitted[inflow], test, ship)
            rows[f"{prior} with the held-out records"] = evaluate(
                fit(records + test, ship, library=library, optimizer="prior"), test, ship)
            hybrid = f"prior {default:.0e} + captive programme"
            fitted[hybrid] = fit_hybrid(records, ship, captive_programme(ship), library=library,
                                        optimizer="prior")
            rows[hybrid] = evaluate(fitted[hybrid], test, ship)
            instantaneous = f"prior {default:.0e} instantaneous + asymmetry abs(v) abs(r)"
            fitted[instantaneous] = fit(records, ship, library=library.extended(rudder_inflow()),
                                        optimizer="prior", speed="instantaneous")
            rows[instantaneous] = evaluate(fitted[instantaneous], test, ship)
            out["held_out_turns"] = {r.name: float(abs(r["psi"][-1] - r["psi"][0]) / (2 * np.pi))
                                     for r in test if is_turning_circle(r)}
            first = diagnose(records, ship).ranking[0].effect.name
            diagnosed = f"{prior} + {first}"
            fitted[diagnosed] = fit(records, ship, library=library, effects=[first],
                                    optimizer="prior")
            rows[diagnosed] = {**evaluate(fitted[diagnosed], test, ship),
                               "ranked_first": first}
            out["diagnosed_first"] = first
            # each fit refined by the error of its training flights
            for key in ("ls", prior, inflow, instantaneous, hybrid, diagnosed):
                refined = refine(fitted[key], records, max_evaluations=REFINE_EVALUATIONS)
                rows[f"{key} refined"] = {**evaluate(refined, test, ship),
                                          "refinement": refined.info["refined"]}
            for weight in PRIOR_WEIGHTS:
                refined = refine(fitted[prior], records, max_evaluations=REFINE_EVALUATIONS,
                                 prior_weight=weight)
                rows[f"{prior} refined, prior weight {weight:g}"] = {
                    **evaluate(refined, test, ship), "refinement": refined.info["refined"]}
            refined = refine(fitted[inflow], records, max_evaluations=REFINE_EVALUATIONS,
                             segment_s="whole")
            rows[f"{inflow} refined whole"] = {**evaluate(refined, test, ship),
                                               "refinement": refined.info["refined"]}
            if against is not None:
                for evaluations, model in refined_by(against.resolve(), records, ship).items():
                    rows[f"{prior} refined before, {evaluations} evaluations"] = {
                        **evaluate(model, test, ship), "evaluations": evaluations}
                out["against"] = str(against)
                out["against_commit"] = checkout_commit(against)
        out["sets"][name] = {"training": [r.name for r in records], "fits": rows}
    out["seconds"] = time.perf_counter() - start
    return out


def format_table(result: dict) -> str:
    """Correlations per test and force, and held-out mean distances, per fit."""
    lines = []
    for name, data in result["sets"].items():
        lines.append(f"Identified on {name} ({', '.join(data['training'])}); captive "
                     "correlation X Y N per test; held-out mean distance [L]")
        head = "  ".join(f"{t:>16s}" for t in result["tests"])
        lines.append(f"{'fit':64s}{head}   tc15_port tc15_stbd  zz10_10  steady r [%]")
        for fit_name, row in data["fits"].items():
            cells = "  ".join(" ".join(f"{row['captive'][t][f]['correlation']:+.2f}"
                                       for f in "XYN") + " " for t in result["tests"])
            flights = "  ".join(
                f"{'diverged':>9s}" if e["diverged_at_s"] is not None
                else f"{e['mean_distance_L']:9.3f}" for e in row["held_out"].values())
            steady = " ".join("-" if e is None else f"{e:+.2f}"
                              for e in row["steady_yaw_rate_error_pct"].values())
            lines.append(f"{fit_name:64s}{cells}  {flights}  {steady}")
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, default=None,
                        help="another checkout of sindyship whose refinement of the prior fit "
                        "on the zig-zags is compared")
    result = run(parser.parse_args().against)
    print(format_table(result))
    write_text_atomic(OUT, json.dumps(clean_json(result), indent=1) + "\n")
    print(f"saved {OUT} ({result['seconds']:.0f} s)")


if __name__ == "__main__":
    main()

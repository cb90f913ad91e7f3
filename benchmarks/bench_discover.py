"""Discovering effects outside the catalogue: found, estimated, and never invented.

Prints and saves ``benchmarks/results/discover.json``.  All cases fly the protocol's 8 training
and 3 held-out manoeuvres (``sindyship.manoeuvres.protocol_manoeuvres``) with the symmetric KCS
(gamma_R = 0.415 to both sides), and run :func:`sindyship.diagnose.discover` on the training
records:

``lag``
    The recorded rudder angle late by 2, 4 and 6 s (the commanded angle exact; ``simulate
    --effect rudder_lag``), library ``abkowitz``.  Reported: what was discovered and the delay
    estimate; the held-out flights of the plain fit, of the fit with the discovered effect
    (``fit --effects effect.toml``) and of a fit on the same manoeuvres without the lag.
``stall``, ``bank``
    The rudder stalling at 15 deg of angle of attack, and a bank 8 ship lengths to the west
    (Prime II 0.005 at one length), with the library the diagnosis reaches on the clean
    symmetric KCS (``abkowitz+higher_order+crossflow``): what was discovered, the catalogued
    effects that are meaningful there (the best finding competes with the first of them in
    left-out flights, ``contests``), and the fall of
    the held-out error with the discovery (geometric mean over the held-out manoeuvres of the
    mean distance over the window both flights cover; a divergence counts as a failure).
``false_alarms``
    Records without any missing effect: the symmetric KCS with ``abkowitz+higher_order+
    crossflow``, and records flown by the paper's own Abkowitz model (LS, Tables 7-9) with
    ``abkowitz``; two manoeuvre sets, noise 0, 1 and 2 % of each channel's RMS on u, v, r
    (0.1 deg on heading and rudder, 0.5 m on positions), two seeds: 20 cases.  The false-alarm
    rate is the share of cases where anything meaningful is discovered.
``seconds_protocol``
    Wall time of ``discover`` on the 8 protocol manoeuvres (the lag of 4 s).

``python benchmarks/bench_discover.py`` (a few minutes on two cores).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from sindyship.diagnose import before_after, discover
from sindyship.effects import parse_effects, sensor_noise, simulate_with_effects
from sindyship.flights import fly_like
from sindyship.identify import fit
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.model import paper_model
from sindyship.ships import load_ship

OUT = Path(__file__).parent / "results" / "discover.json"
CATALOGUED = ["higher_order", "crossflow"]


def symmetric_kcs():
    return load_ship("kcs").with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)


def flights(model, records, ship) -> list[dict]:
    out = []
    for flown, record in zip(fly_like(model, records), records, strict=True):
        distance = np.hypot(flown["x"] - record["x"], flown["y"] - record["y"]) / ship.L
        out.append({"manoeuvre": record.name, "mean_L": float(np.nanmean(distance)),
                    "diverged_at_s": flown.meta.get("diverged_at")})
    return out


def lag_case(lag: float, ship, clean_test_errors) -> dict:
    plan = protocol_manoeuvres()
    effects = parse_effects([f"rudder_lag={lag}"])
    train = simulate_with_effects(ship, plan["train"], effects)
    test = simulate_with_effects(ship, plan["test"], effects)
    start = time.perf_counter()
    found = discover(train, ship)
    seconds = time.perf_counter() - start
    plain = flights(fit(train, ship), test, ship)
    result = {"lag_s": lag, "discovered": [f.family for f in found.accepted],
              "delay_s": found.best.delays.get("delta") if found.best else None,
              "share": found.best.explained_signal if found.best else 0.0,
              "seconds": seconds, "plain": plain}
    if found.accepted:
        model = fit(train, ship, library=found.library.extended(found.effect()))
        result["with_discovery"] = flights(model, test, ship)
        result["ratio_to_clean"] = [
            w["mean_L"] / c["mean_L"] for w, c in zip(result["with_discovery"],
                                                      clean_test_errors, strict=True)]
    return result


def outside_case(name: str, spec: list[str], ship) -> dict:
    plan = protocol_manoeuvres()
    effects = parse_effects(spec)
    train = simulate_with_effects(ship, plan["train"], effects)
    test = simulate_with_effects(ship, plan["test"], effects)
    found = discover(train, ship, effects=CATALOGUED)
    result = {"effect": name, "spec": spec, "discovered": [f.family for f in found.accepted],
              "catalogue_meaningful": found.catalogue,
              "contests": [c.to_json() for c in found.contests],
              "findings": [f.to_json() for f in found.accepted],
              "first_round": [{"family": f.family, "share": f.explained_signal,
                               "meaningful": f.meaningful} for f in found.findings]}
    if found.accepted:
        change = before_after(train, ship, library=found.library, effects=[found.effect()],
                              test=test, fly_training=False)
        result["held_out"] = [{"manoeuvre": r["manoeuvre"], **r["common"]} for r in change.rows]
        result["ratio"] = change.ratio("held-out")
    return result


def false_alarms(ship) -> dict:
    kcs = load_ship("kcs")
    plan = protocol_manoeuvres()["train"]
    sets = {"protocol-8": plan, "turns-and-zigzags-6": plan[1:7]}
    sources = {"symmetric-mmg": (None, ship, CATALOGUED),
               "abkowitz-model": (paper_model(kcs).dynamics(), kcs, [])}
    cases = []
    for source, (dynamics, own_ship, effects) in sources.items():
        for set_name, manoeuvres in sets.items():
            clean = (simulate_with_effects(own_ship, manoeuvres) if dynamics is None
                     else fly(dynamics, manoeuvres))
            for level, seed in ((0.0, 0), (0.01, 1), (0.01, 2), (0.02, 1), (0.02, 2)):
                found = discover(sensor_noise(clean, level, seed), own_ship, effects=effects)
                top = found.findings[0] if found.findings else None
                cases.append({"source": source, "set": set_name, "noise": level, "seed": seed,
                              "discovered": [f.family for f in found.accepted],
                              "top": None if top is None else top.family,
                              "top_share": 0.0 if top is None else top.explained_signal})
    alarms = sum(bool(c["discovered"]) for c in cases)
    return {"cases": cases, "n_cases": len(cases), "false_alarms": alarms,
            "false_alarm_rate": alarms / len(cases)}


def main() -> dict:
    start = time.perf_counter()
    ship = symmetric_kcs()
    plan = protocol_manoeuvres()
    clean_train = simulate_with_effects(ship, plan["train"])
    clean_test = simulate_with_effects(ship, plan["test"])
    clean_errors = flights(fit(clean_train, ship), clean_test, ship)
    results = {"clean_fit": clean_errors,
               "lag": [lag_case(lag, ship, clean_errors) for lag in (2.0, 4.0, 6.0)],
               "outside": [outside_case("stall", ["rudder_stall=15"], ship),
                           outside_case("bank", ["bank=0.005", "bank_distance=-8"], ship)],
               "false_alarms": false_alarms(ship)}
    results["seconds_protocol"] = results["lag"][1]["seconds"]
    results["seconds"] = time.perf_counter() - start
    for case in results["lag"]:
        diverged = sum(f["diverged_at_s"] is not None for f in case["plain"])
        print(f"lag {case['lag_s']:.0f} s: discovered {case['discovered']}, delay "
              f"{case['delay_s']}, plain fit diverged on {diverged}/3 held-out flights, with the "
              f"discovery {[round(f['mean_L'], 3) for f in case.get('with_discovery', [])]} L "
              f"(x{[round(r, 2) for r in case.get('ratio_to_clean', [])]} of the lag-free fit)")
    for case in results["outside"]:
        print(f"{case['effect']}: discovered {case['discovered']}, held-out after/before "
              f"{case.get('ratio')}; catalogued effects meaningful: {case['catalogue_meaningful']}"
              + "".join(f"; flights: finding {c['finding']} {c['finding_L']:.3g} L, catalogued "
                        f"{c['catalogued']} {c['catalogued_L']:.3g} L, {c['winner']} wins"
                        for c in case["contests"]))
    fa = results["false_alarms"]
    print(f"false alarms: {fa['false_alarms']} of {fa['n_cases']} cases; discover on the protocol "
          f"took {results['seconds_protocol']:.1f} s")
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(results, indent=2, default=float) + "\n")
    return results


if __name__ == "__main__":
    main()

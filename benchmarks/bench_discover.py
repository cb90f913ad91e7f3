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
``stall``, ``bank``, ``patch``, ``patch_diagonal``
    The rudder stalling at 15 deg of angle of attack; a bank 8 ship lengths to the west
    (Prime II 0.005 at one length); shallow water beyond a straight edge, where the linear
    hull derivatives are 1.8 times their deep-water values, 2 L north of the start, and
    3 L from it toward 045 deg (``simulate --effect shallow_patch``; no depth channel).  The
    library is the one the diagnosis reaches on the clean symmetric KCS
    (``abkowitz+higher_order+crossflow``).  Reported: what was discovered; for a shape of the
    position, its line (bearing and distance) against the true one and the intervals; the
    catalogued effects that are meaningful there and the left-out flights that decide
    (``contests``); the held-out flights of the plain fit against a fit on the same
    manoeuvres without the effect (``plain_over_clean``), and the fall of the held-out error
    with the discovery (``ratio``: geometric mean over the held-out manoeuvres of after/before
    mean distance over the window both flights cover; a divergence counts as a failure).
``asymmetric_lag``
    The 4 s lag on the default KCS, whose asymmetry the library misses: the delay's estimate
    and 95 % interval.
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
from sindyship.terms import parse_shape

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
              "interval_s": found.best.intervals.get("delta") if found.best else None,
              "share": found.best.explained_signal if found.best else 0.0,
              "seconds": seconds, "plain": plain}
    if found.accepted:
        model = fit(train, ship, library=found.library.extended(found.effect()))
        result["with_discovery"] = flights(model, test, ship)
        result["ratio_to_clean"] = [
            w["mean_L"] / c["mean_L"] for w, c in zip(result["with_discovery"],
                                                      clean_test_errors, strict=True)]
    return result


def line_error(found: str, true_line: tuple[float, float]) -> dict:
    """How far a discovered shape's line lies from the true one: bearing difference [deg] and
    distance difference along the bearing [L] (a line and its reverse are the same line)."""
    shape = parse_shape(found)
    bearing, distance = shape.bearing, shape.distance
    turn = (bearing - true_line[0] + 180.0) % 360.0 - 180.0
    if abs(turn) > 90.0:  # the reverse normal: the same line read from the other side
        bearing, distance = (bearing + 180.0) % 360.0, -distance
        turn = (bearing - true_line[0] + 180.0) % 360.0 - 180.0
    return {"bearing_error_deg": abs(turn), "distance_error_L": abs(distance - true_line[1])}


def outside_case(name: str, spec: list[str], ship, clean_errors=None, true_line=None) -> dict:
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
        result["held_out"] = [{"manoeuvre": r["manoeuvre"], **r["common"],
                               "before_diverged_at_s": r["before"]["diverged_at_s"],
                               "after_diverged_at_s": r["after"]["diverged_at_s"]}
                              for r in change.rows if r["set"] == "held-out"]
        result["ratio"] = change.ratio("held-out")
    shapes = [v for f in found.accepted for v in f.variables if parse_shape(v)]
    if shapes and true_line is not None:
        result["line"] = {"found": shapes[0], "true_bearing_deg": true_line[0],
                          "true_distance_L": true_line[1], **line_error(shapes[0], true_line),
                          "intervals": found.accepted[0].intervals}
    if clean_errors is not None:
        plain = flights(fit(train, ship, effects=CATALOGUED), test, ship)
        result["plain"] = plain
        result["plain_over_clean"] = float(np.exp(np.mean(
            [np.log(p["mean_L"] / c["mean_L"]) for p, c in zip(plain, clean_errors, strict=True)])))
    return result


def asymmetric_lag(lag: float) -> dict:
    """The rudder lag on the default (asymmetric) KCS, whose asymmetry the library misses:
    the delay finding's estimate and interval, accepted or not."""
    ship = load_ship("kcs")
    train = simulate_with_effects(ship, protocol_manoeuvres()["train"],
                                  parse_effects([f"rudder_lag={lag}"]))
    found = discover(train, ship)
    delay = next((f for f in found.findings if f.family == "delay:delta"), None)
    return {"lag_s": lag, "discovered": [f.family for f in found.accepted],
            "catalogue_meaningful": found.catalogue,
            "delay_s": None if delay is None else delay.delays["delta"],
            "interval_s": None if delay is None else delay.intervals.get("delta")}


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
    clean_catalogued = flights(fit(clean_train, ship, effects=CATALOGUED), clean_test, ship)
    results = {"clean_fit": clean_errors,
               "clean_fit_catalogued": clean_catalogued,
               "lag": [lag_case(lag, ship, clean_errors) for lag in (2.0, 4.0, 6.0)],
               "asymmetric_lag": asymmetric_lag(4.0),
               "outside": [outside_case("stall", ["rudder_stall=15"], ship),
                           outside_case("bank", ["bank=0.005", "bank_distance=-8"], ship,
                                        clean_catalogued, (90.0, -8.0)),
                           outside_case("patch", ["shallow_patch=0.8", "patch_distance=2"],
                                        ship, clean_catalogued, (0.0, 2.0)),
                           outside_case("patch_diagonal", ["shallow_patch=0.8",
                                                           "patch_distance=3", "patch_dir=45"],
                                        ship, clean_catalogued, (45.0, 3.0))],
               "false_alarms": false_alarms(ship)}
    results["seconds_protocol"] = results["lag"][1]["seconds"]
    results["seconds"] = time.perf_counter() - start
    for case in results["lag"]:
        diverged = sum(f["diverged_at_s"] is not None for f in case["plain"])
        print(f"lag {case['lag_s']:.0f} s: discovered {case['discovered']}, delay "
              f"{case['delay_s']} (interval {case['interval_s']}), plain fit diverged on "
              f"{diverged}/3 held-out flights, with the "
              f"discovery {[round(f['mean_L'], 3) for f in case.get('with_discovery', [])]} L "
              f"(x{[round(r, 2) for r in case.get('ratio_to_clean', [])]} of the lag-free fit)")
    for case in results["outside"]:
        line = case.get("line")
        print(f"{case['effect']}: discovered {case['discovered']}, held-out after/before "
              f"{case.get('ratio')}"
              + (f", plain fit x{case['plain_over_clean']:.1f} of the fit without the effect"
                 if "plain_over_clean" in case else "")
              + (f", line {line['found']} off by {line['bearing_error_deg']:.1f} deg and "
                 f"{line['distance_error_L']:.2f} L" if line else "")
              + f"; catalogued effects meaningful: {case['catalogue_meaningful']}"
              + "".join(f"; flights: finding {c['finding']} {c['finding_L']:.3g} L, catalogued "
                        f"{c['catalogued']} {c['catalogued_L']:.3g} L, {c['winner']} wins"
                        for c in case["contests"]))
    asym = results["asymmetric_lag"]
    print(f"lag 4 s on the asymmetric KCS: delay {asym['delay_s']}, interval "
          f"{asym['interval_s']}, discovered {asym['discovered']}")
    fa = results["false_alarms"]
    print(f"false alarms: {fa['false_alarms']} of {fa['n_cases']} cases; discover on the protocol "
          f"took {results['seconds_protocol']:.1f} s")
    OUT.parent.mkdir(exist_ok=True)
    OUT.write_text(json.dumps(results, indent=2, default=float) + "\n")
    return results


if __name__ == "__main__":
    main()

"""False refusals and detections of the plausibility checks on load; save the numbers.

Prints and saves ``benchmarks/results/plausibility.json``:

``good``
    Records that must load: the 11 protocol manoeuvres of the KCS (with ``ship="kcs"``, so
    every check runs) over seeds x noise levels (noise level k: k % Gaussian noise of each
    channel's RMS on u, v, r, and k x 0.1 deg on psi and delta, k x 0.5 m on x, y), the same
    with a 1 m/s current from four directions, the protocol of the KVLCC2 model (7 m, flown in
    its own time scale as ``simulate --protocol --ship kvlcc2`` flies it),
    and the six MARIN records when the shared folder is present.  For each group: the count of
    records, of false refusals (by check), and the worst heading gain deviation |g - 1| and
    frame misfit (thresholds 0.25 and 0.1).
``bad``
    The same KCS records (noise level 1) spoiled one way each (psi in degrees under a bare
    header, psi negated, earth-fixed u and v, time in milliseconds, knots under a m/s header,
    v negated): how many are refused, by which check, and the statistic's range.
``jumps``
    The ``jumps`` note (a note, never a refusal): the good records above it would name
    (``false_notes``, each group with its ship), with the protocol also sampled every 0.25, 0.5
    and 0.95 L/U0 and the simulated campaign of trials from rest
    (:func:`sindyship.campaign.campaign_trials`, ``counted``); the MARIN records it names with
    the full-scale ship of :func:`sindyship.marin.full_scale_ship`, on their own grid and on
    the README's 1 s grid (``tc_-35`` ends with v changing 2.4 m/s in 2 s); and how many of the KCS
    records at noise level 1 it finds spoilt with one sample of v moved by 0.3 U0 (``spike``)
    or with v ramped by 0.3 U0 over 0.05 L/U0 from the middle on (``ramp``).

``python benchmarks/bench_plausibility.py --quick`` runs one seed and two noise levels.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

from sindyship.campaign import campaign_trials, fly_trials
from sindyship.effects import add_noise, parse_effects, simulate_with_effects
from sindyship.errors import SindyshipInputError
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.marin import MARIN_FILES, default_marin_dir, full_scale_ship, read_marin
from sindyship.measurements import trajectory_from_frame
from sindyship.mmg import MMGModel
from sindyship.plausibility import CHECKS, frame_misfit, heading_gain, sample_jumps
from sindyship.ships import load_ship
from sindyship.trajectory import Trajectory

RESULTS = Path(__file__).resolve().parent / "results" / "plausibility.json"
#: The coarser grids [L/U0] the protocol is sampled on for the ``jumps`` note.
COARSE = (0.25, 0.5, 0.95)


def noisy(record: Trajectory, level: float, seed: int) -> Trajectory:
    """Noise level ``level`` (1 = 1 % RMS on u, v, r; 0.1 deg on psi, delta; 0.5 m on x, y)."""
    if level == 0:
        return record
    data = record.data
    std = {c: 0.01 * level * float(np.sqrt(np.mean(data[c] ** 2))) for c in ("u", "v", "r")}
    std.update({"psi": math.radians(0.1) * level, "delta": math.radians(0.1) * level,
                "x": 0.5 * level, "y": 0.5 * level})
    return add_noise(record, std, seed=seed)


def outcome(frame, ship) -> str | None:
    """The refusing check's name, or None when the record loads."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            trajectory_from_frame(frame, "bench", ship=ship)
    except SindyshipInputError as error:
        text = str(error)
        for name in CHECKS:
            if f"the {name} check" in text:
                return name
        return "other: " + text
    return None


def statistics(data) -> tuple[float, float]:
    gain, span = heading_gain(data["t"].to_numpy(), data["r"].to_numpy(),
                              data["psi"].to_numpy())
    deviation = abs(gain - 1.0) if span >= 0.1 else math.nan
    return deviation, frame_misfit({c: data[c].to_numpy() for c in data.columns})


def summarise(name: str, records, ship) -> dict:
    refusals: Counter[str] = Counter()
    deviations, misfits = [], []
    for record in records:
        result = outcome(record.data, ship)
        if result is not None:
            refusals[result] += 1
        deviation, misfit = statistics(record.data)
        deviations.append(deviation)
        misfits.append(misfit)
    out = {
        "records": len(records),
        "false_refusals": sum(refusals.values()),
        "by_check": dict(refusals),
        "max_heading_gain_deviation": float(np.nanmax(deviations)) if records else None,
        "max_frame_misfit": float(np.nanmax(misfits)) if records else None,
    }
    print(f"{name:>22}: {out}")
    return out


def noted(records, ship) -> list[str]:
    """The names of the records the ``jumps`` note would name samples of."""
    return [record.name for record in records if sample_jumps(record.data, ship)]


def glitched(record: Trajectory, ship, kind: str) -> Trajectory:
    """The record with one sample of v moved by 0.3 U0 (``spike``), or v ramped by 0.3 U0
    over 0.05 L/U0 from the middle on (``ramp``)."""
    t, v = record.t, record["v"].copy()
    middle = len(t) // 2
    if kind == "spike":
        v[middle] += 0.3 * ship.U0
    else:
        v[middle:] += 0.3 * ship.U0 * np.clip((t[middle:] - t[middle])
                                              / (0.05 * ship.time_scale), 0.0, 1.0)
    return Trajectory(record.data.assign(v=v), record.name)


def spoilt(record: Trajectory) -> dict[str, object]:
    """The spoiled copies of a record, each as a frame with the headers a user would write."""
    data = record.data
    psi, u, v = data["psi"], data["u"], data["v"]
    earth = data.copy()
    earth["u"] = u * np.cos(psi) - v * np.sin(psi)
    earth["v"] = u * np.sin(psi) + v * np.cos(psi)
    return {
        "psi_degrees_bare": data.assign(psi=np.degrees(psi)),
        "psi_negated": data.assign(psi=-psi),
        "earth_fixed_uv": earth,
        "time_ms_bare": data.assign(t=data["t"] * 1000.0),
        "knots_as_m_s": data.assign(u=u * 3600 / 1852, v=v * 3600 / 1852),
        "v_to_port": data.assign(v=-v),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    seeds = [0] if args.quick else [0, 1, 2, 3, 4]
    levels = [0.0, 1.0] if args.quick else [0.0, 1.0, 2.0, 5.0]
    began = time.perf_counter()
    kcs = load_ship("kcs")
    plan = protocol_manoeuvres()
    clean = fly(MMGModel(kcs), plan["train"] + plan["test"])
    good = {}
    grid = [noisy(r, level, seed) for r in clean for level in levels for seed in seeds]
    good["kcs_protocol_noise"] = summarise("kcs_protocol_noise", grid, kcs)
    current = []
    for direction in (0, 90, 180, 270):
        effects = parse_effects(["current=1", f"current_dir={direction}"])
        current += [noisy(r, 1.0, 0) for r in
                    simulate_with_effects(kcs, plan["train"] + plan["test"], effects)]
    good["kcs_current_1m_s"] = summarise("kcs_current_1m_s", current, kcs)
    kvlcc2 = load_ship("kvlcc2")
    model_plan = protocol_manoeuvres(ship=kvlcc2)
    model = fly(MMGModel(kvlcc2), model_plan["train"] + model_plan["test"])
    good["kvlcc2_model"] = summarise("kvlcc2_model", model, kvlcc2)
    folder = default_marin_dir()
    if folder is not None:
        marin = [read_marin(folder / name) for name in MARIN_FILES.values()]
        good["marin_full_scale"] = summarise("marin_full_scale", marin, None)
    coarse = [Trajectory(r.data.iloc[::max(1, int(share * kcs.time_scale // r.dt))]
                         .reset_index(drop=True), f"{r.name} every {share} L/U0")
              for r in clean for share in COARSE]
    trials = fly_trials(kvlcc2, [trial for runs in campaign_trials(0).values() for trial in runs])
    jumps = {"false_notes": {
        "kcs_protocol_noise": noted(grid, kcs), "kcs_current_1m_s": noted(current, kcs),
        "kcs_protocol_coarse": noted(coarse, kcs), "kvlcc2_model": noted(model, kvlcc2),
        "kvlcc2_campaign": noted(trials, kvlcc2)},
        "counted": {"kcs_protocol_coarse": len(coarse), "kvlcc2_campaign": len(trials)}}
    if folder is not None:
        full_scale = full_scale_ship()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the reader's notes: counted here
            by_second = [trajectory_from_frame(r.data, r.name, resample=1.0) for r in marin]
        jumps["marin_noted"] = {"own_grid": noted(marin, full_scale),
                                "1_s_grid": noted(by_second, full_scale)}
    base = [noisy(r, 1.0, seed) for r in clean for seed in seeds]
    jumps["found"] = {kind: sum(bool(sample_jumps(glitched(r, kcs, kind).data, kcs))
                                for r in base) for kind in ("spike", "ramp")}
    jumps["records"] = len(base)
    print(f"{'jumps':>22}: {jumps}")
    bad: dict[str, dict] = {}
    for kind in spoilt(base[0]):
        caught: Counter[str] = Counter()
        missed, deviations, misfits = [], [], []
        for record in base:
            frame = spoilt(record)[kind]
            result = outcome(frame, kcs)
            caught[result or "loaded"] += 1
            if result is None:
                missed.append(record.name)
            if record.name != "straight":  # heading north without turning: nothing to see
                deviation, misfit = statistics(frame)
                deviations.append(deviation)
                misfits.append(misfit)
        bad[kind] = {"records": len(base), "outcomes": dict(caught),
                     "loaded": sorted(set(missed)),
                     "turning_records_min_heading_gain_deviation": float(np.nanmin(deviations))
                     if not np.all(np.isnan(deviations)) else None,
                     "turning_records_min_frame_misfit": float(np.nanmin(misfits))}
        print(f"{kind:>22}: {bad[kind]}")
    result = {"good": good, "bad": bad, "jumps": jumps, "seeds": seeds, "noise_levels": levels,
              "seconds": round(time.perf_counter() - began, 1)}
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {RESULTS} in {result['seconds']} s")


if __name__ == "__main__":
    main()

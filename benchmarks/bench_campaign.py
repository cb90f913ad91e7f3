"""Free-running trials as they are run outdoors: the simulated campaign, identified and flown.

The campaign of :func:`sindyship.campaign.campaign_trials` (seed 0): the KVLCC2 model from
rest, a helmsman keeping the course by hand for 120-180 s, then the manoeuvre; revolutions
70-85 % of the design condition, a gusty wind of 4-6 m/s (3-6 times the ship's speed),
logged with 1 % sensor noise.  Training: zig-zags 10/10 and 20/20 to both sides and 35 deg
turns; held out: a 15/15 zig-zag and 25 deg turns to both sides.

Every workflow runs as a user would run it, through the command line on the records' CSV
files: ``sindyship diagnose`` on the training records (which effects it names), then
``sindyship fit`` with its defaults, with each named effect alone and with the named effects
added one by one in the order named (the last: all of them), each flown on the held-out
records by ``sindyship evaluate --json``; and on the library ``abkowitz-vr`` (``--library
abkowitz-vr``: without the cross-flow drag the default library of the instantaneous form
adds) without an effect, with the first named effect and with all of them.  With
``--against CHECKOUT``, the same
``fit`` (its defaults) and ``evaluate`` of another checkout of sindyship run on the same files
in the same run (``default before``).  The score of a workflow is the geometric mean of the held-out
mean distances in ship lengths; a diverged flight is listed as such and makes the workflow
fail (docs/protocol.md).

Prints a table and saves ``benchmarks/results/campaign.json``::

    git worktree add /tmp/sindyship-before COMMIT
    python benchmarks/bench_campaign.py [--against /tmp/sindyship-before]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(__file__).parent / "results" / "campaign.json"
SHIP = "kvlcc2"
SEED = 0


def write_campaign(folder: Path, seed: int = SEED) -> dict[str, list[str]]:
    """Fly the campaign and write its records as measurement CSVs: the paths by set."""
    from sindyship.campaign import campaign_trials, fly_trials
    from sindyship.measurements import write_csv
    from sindyship.ships import load_ship

    ship = load_ship(SHIP)
    out = {}
    for part, trials in campaign_trials(seed=seed).items():
        (folder / part).mkdir(parents=True, exist_ok=True)
        out[part] = []
        for record in fly_trials(ship, trials):
            path = folder / part / f"{record.name}.csv"
            write_csv(record, path)
            out[part].append(str(path))
    return out


def checkout_cli(checkout: Path, *arguments: str) -> str:
    """``sindyship ARGUMENTS`` of ``checkout`` in a fresh process: its stdout (also the
    ``--against`` runs of bench_captive.py)."""
    env = {**os.environ, "PYTHONPATH": str(checkout), "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, "-m", "sindyship.cli", *arguments], env=env,
                          cwd=checkout, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"sindyship {' '.join(arguments[:2])} failed:\n{done.stderr[-2000:]}")
    return done.stdout


def workflow(checkout: Path, paths: dict, folder: Path, label: str,
             options: list[str]) -> dict:
    """``fit`` on the training records with ``options`` and ``evaluate`` on the held-out ones:
    the held-out errors, their geometric mean and the fit's time."""
    model = folder / f"{label}.json"
    start = time.perf_counter()
    checkout_cli(checkout, "fit", *paths["train"], "--ship", SHIP, *options, "--out", str(model))
    fit_s = time.perf_counter() - start
    flown = json.loads(checkout_cli(checkout, "evaluate", str(model), *paths["test"], "--json"))
    errors = flown["errors"]
    errors = {name: {"mean_distance_L": row["mean_distance_L"],
                     "diverged_at_s": row.get("diverged_at_s")} for name, row in errors.items()}
    diverged = [name for name, row in errors.items() if row["diverged_at_s"] is not None]
    means = [row["mean_distance_L"] for row in errors.values()]
    score = math.exp(sum(math.log(m) for m in means) / len(means))
    return {"options": options, "fit_s": fit_s, "errors": errors, "diverged": diverged,
            "geometric_mean_L": score}


def diagnosis(paths: dict) -> dict:
    """``sindyship diagnose --rounds 3`` on the training records, with the held-out records
    flown: the effects it adds round by round, and its first ranking."""
    found = json.loads(checkout_cli(ROOT, "diagnose", *paths["train"], "--ship", SHIP, "--test",
                            *paths["test"], "--rounds", "3", "--json"))
    return {"added": found["added"], "stopped": found["stopped"], "speed": found["speed"],
            "ranking": [{"effect": row["effect"], "explained": row["explained"],
                         "meaningful": row.get("meaningful")} for row in found["ranking"]]}


def checkout_commit(checkout: Path) -> str | None:
    """The short commit hash of a checkout (None when it is not a git work tree)."""
    done = subprocess.run(["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True)
    return done.stdout.strip() or None


def run(against: Path | None) -> dict:
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        paths = write_campaign(folder / "records")
        found = diagnosis(paths)
        named = found["added"]
        workflows = {"default": workflow(ROOT, paths, folder, "default", [])}
        for effect in named:
            workflows[f"default + {effect}"] = workflow(ROOT, paths, folder, effect,
                                                        ["--effects", effect])
        for k in range(2, len(named) + 1):  # the named effects added in the order named
            workflows[f"default + {' + '.join(named[:k])}"] = workflow(
                ROOT, paths, folder, f"named{k}", ["--effects", ",".join(named[:k])])
        # the same without the cross-flow drag of the instantaneous form's default library
        polynomial = ["--library", "abkowitz-vr"]
        workflows["abkowitz-vr"] = workflow(ROOT, paths, folder, "vr", polynomial)
        for k in sorted({1, len(named)}) if named else ():
            workflows[f"abkowitz-vr + {' + '.join(named[:k])}"] = workflow(
                ROOT, paths, folder, f"vr{k}", [*polynomial, "--effects", ",".join(named[:k])])
        if against is not None:
            workflows["default before"] = workflow(against.resolve(), paths, folder, "before",
                                                   [])
    recommended = workflows[f"default + {' + '.join(named)}" if named else "default"]
    out = {"ship": SHIP, "seed": SEED, "diagnosis": found, "named": named,
           "workflows": workflows, "recommended": f"default + {' + '.join(named)}" if named
           else "default", "against": None if against is None else str(against),
           "against_commit": None if against is None else checkout_commit(against)}
    if "default before" in workflows:
        out["before_over_recommended"] = (workflows["default before"]["geometric_mean_L"]
                                          / recommended["geometric_mean_L"])
    out["seconds"] = time.perf_counter() - start
    return out


def format_table(result: dict) -> str:
    names = list(next(iter(result["workflows"].values()))["errors"])
    lines = [f"diagnosis: {', '.join(result['named'])} named first",
             f"{'workflow':34s} " + " ".join(f"{n:>12s}" for n in names)
             + f" {'geo mean':>9s} {'fit s':>6s}"]
    for label, row in result["workflows"].items():
        cells = []
        for name in names:
            err = row["errors"][name]
            cells.append(f"{err['mean_distance_L']:12.3f}" if err["diverged_at_s"] is None
                         else f"{'div ' + format(err['diverged_at_s'], '.0f'):>12s}")
        lines.append(f"{label:34s} " + " ".join(cells)
                     + f" {row['geometric_mean_L']:9.3f} {row['fit_s']:6.1f}")
    if "before_over_recommended" in result:
        lines.append(f"geometric mean, the default before ({result['against_commit']}) over "
                     f"the recommended: {result['before_over_recommended']:.2f}x (a diverged "
                     "flight counts its distance before it diverged)")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--against", type=Path, default=None,
                        help="another checkout, whose default fit runs on the same records")
    args = parser.parse_args()
    result = run(args.against)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(format_table(result))
    print(f"\n{result['seconds']:.0f} s; saved {OUT}")


if __name__ == "__main__":
    main()

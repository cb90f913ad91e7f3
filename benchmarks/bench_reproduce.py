"""Time ``sindyship reproduce`` (the paper's experiment end to end), optionally beside another
checkout of sindyship in the same run.

Prints and saves ``benchmarks/results/reproduce.json`` with the best wall time of the whole run
(figures and files included) over ``--repeat`` runs, each in a fresh process.  With
``--against PATH`` (a checkout of another version, e.g. ``git worktree add /tmp/old COMMIT``)
the two are run alternately on the same machine and the ratio is reported; these machines are
noisy, so only a ratio measured in one run means anything.

    python benchmarks/bench_reproduce.py [--repeat 2] [--against /tmp/old]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(__file__).parent / "results" / "reproduce.json"
CODE = ("import sys; from sindyship.reproduce import run; "
        "run(sys.argv[1], progress=lambda message: None)")


def _wall(checkout: Path) -> float:
    """Seconds of one ``reproduce`` run of ``checkout`` in a fresh process."""
    env = {**os.environ, "PYTHONPATH": str(checkout), "MPLBACKEND": "Agg"}
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", CODE, folder], env=env, check=True, cwd=checkout)
        return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=2, help="runs of each (default 2)")
    parser.add_argument("--against", type=Path, default=None,
                        help="another checkout to time alternately in the same run")
    args = parser.parse_args()
    ours, theirs = [], []
    for _ in range(args.repeat):
        ours.append(_wall(ROOT))
        if args.against is not None:
            theirs.append(_wall(args.against.resolve()))
    result = {"wall_seconds": min(ours), "wall_seconds_all": ours, "target_seconds": 15.0}
    if theirs:
        result.update({"against": str(args.against), "against_wall_seconds": min(theirs),
                       "against_wall_seconds_all": theirs,
                       "ratio_to_against": min(ours) / min(theirs)})
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

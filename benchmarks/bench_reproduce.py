"""Time ``sindyship reproduce`` (the paper's experiment end to end) in one process.

Prints and saves ``benchmarks/results/reproduce.json`` with the wall time of the whole run and
of its parts as the run reports them; the target is under 60 s on 2 cores.
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

from sindyship.reproduce import run

OUT = Path(__file__).parent / "results" / "reproduce.json"


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        output = run(folder, progress=lambda message: print(message, flush=True))
        wall = time.perf_counter() - start
    result = {
        "wall_seconds": wall,
        "target_seconds": 60.0,
        "held_out_mean_distance_L": {
            r["method"]: {k: v["mean_distance_L"] for k, v in r["errors"].items()}
            for r in output["results"]
        },
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()

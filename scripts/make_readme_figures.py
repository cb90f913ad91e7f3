"""Regenerate the figures the README shows (docs/figures/) from a fresh reproduce run."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from sindyship.reproduce import run

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "figures"


def main() -> None:
    FIGURES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        run(folder)
        for name in ("trajectory-tc15_port.png", "trajectory-zz10_10.png", "diagnosis-rounds.png"):
            shutil.copy(Path(folder) / name, FIGURES / name)
            print("wrote", FIGURES / name)


if __name__ == "__main__":
    main()

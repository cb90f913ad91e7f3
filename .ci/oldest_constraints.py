"""Print pip constraints that pin every dependency to the oldest version pyproject.toml allows.

Run by .ci/run for its second test environment: the runtime dependencies and the optional
ones whose versions shape numbers or file handling (numba, dask, pyarrow) at their lower
bounds; the test tools resolve freely.
"""

from __future__ import annotations

import re
import sys
import tomllib
from pathlib import Path

#: Optional dependencies pinned too (the test tools are not).
PINNED_EXTRAS = ("numba", "dask", "pyarrow")


def oldest(requirement: str) -> str | None:
    """``name==lowest`` of a requirement with a lower bound, else None."""
    match = re.match(r"^\s*([A-Za-z0-9_.\-]+)(\[[^\]]*\])?\s*(.*)$", requirement)
    if match is None:
        return None
    name, _, spec = match.groups()
    low = re.search(r">=\s*([0-9][0-9A-Za-z.]*)", spec)
    return f"{name}=={low.group(1)}" if low else None


def main() -> int:
    project = tomllib.loads(Path(sys.argv[1] if len(sys.argv) > 1 else "pyproject.toml")
                            .read_text(encoding="utf-8"))["project"]
    requirements = list(project["dependencies"]) + [
        r for extra in project["optional-dependencies"].values() for r in extra
        if r.split("[")[0].split(">")[0].strip() in PINNED_EXTRAS]
    pins = sorted({pin for r in requirements if (pin := oldest(r)) is not None})
    print("\n".join(pins))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

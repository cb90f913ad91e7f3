"""The one place that writes files: atomic text and figure writes, and JSON-ready values.

Every output goes through a temporary file in the target's folder and a rename, so a failure
or an interrupted run never leaves a half-written file (the command-line contract in
``docs/command-line.md``).

Examples
--------
>>> import json, math, tempfile
>>> import numpy as np
>>> from pathlib import Path
>>> json.dumps(clean_json({"a": np.float64(1.5), "b": [math.nan, np.int64(2)]}))
'{"a": 1.5, "b": [null, 2]}'
>>> with tempfile.TemporaryDirectory() as folder:
...     path = Path(folder) / "note.txt"
...     write_text_atomic(path, "hello\\n")
...     path.read_text()
'hello\\n'
"""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

__all__ = ["clean_json", "save_figure", "write_text_atomic"]


def clean_json(value):
    """A JSON-ready copy of ``value``.

    Mappings get string keys, tuples and arrays become lists, numpy scalars become Python
    numbers, non-finite floats become None (JSON has no NaN), and any other object its
    ``str``.

    Parameters
    ----------
    value : object

    Returns
    -------
    object
        Made of dict, list, str, int, float, bool and None only.
    """
    if isinstance(value, Mapping):
        return {str(k): clean_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [clean_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return clean_json(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, str | int | float | bool):
        return value
    return str(value)


def _temporary_sibling(path: Path) -> tuple[int, str]:
    return tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)


def _publish(tmp: str, path: Path) -> None:
    """Give the temporary file the permissions ``umask`` allows and rename it into place."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write text to ``path`` through a temporary file in the same folder and a rename.

    Parameters
    ----------
    path : str or Path
        The file; its folder is created when missing.
    text : str
        Written as UTF-8.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = _temporary_sibling(path)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        _publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def save_figure(fig, path: str | Path, *, dpi: int = 110) -> Path:
    """Save a matplotlib figure through a temporary file and a rename.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        The image file; its suffix gives the format (PNG by default).
    dpi : int

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = _temporary_sibling(path)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png")
        _publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path

"""Whether numba is about to compile sindyship's flight loops, so a long first run can say so.

numba keeps the machine code it compiles in a cache (the package's ``__pycache__``, or the
folder ``NUMBA_CACHE_DIR`` names), so only the first process after an installation, or after
a change of a compiled module, compiles.  On two cores that first compilation of the
identified models' whole flights (:mod:`sindyship._flights_compiled`) and of the refinement's
segments (:mod:`sindyship._shooting_compiled`) takes about a minute, during which nothing else
moves.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path

__all__ = ["compiles_first"]


def compiles_first() -> bool:
    """Whether numba is installed, compiling is on (``SINDYSHIP_NO_COMPILE`` is not ``1``)
    and the loops of the whole flights or of the refinement's segments have no cached machine
    code as new as their source.

    Imports numba (about half a second) when it is installed; compiles nothing.  Says False
    where numba keeps its cache in a way this does not know.
    """
    if os.environ.get("SINDYSHIP_NO_COMPILE") == "1" or importlib.util.find_spec("numba") is None:
        return False
    from . import _flights_compiled, _shooting_compiled

    if not _flights_compiled.COMPILED:
        return False
    return not all(_cached(loop) for loop in (_flights_compiled._run, _shooting_compiled._fly))


def _cached(dispatcher) -> bool:
    """Whether numba's cache index of ``dispatcher`` exists and is no older than its source
    (numba itself compares the source's time and size stamped in the index)."""
    try:
        index = Path(dispatcher._cache._cache_file._index_path)
        source = Path(dispatcher.py_func.__code__.co_filename)
    except AttributeError:  # another layout of numba's cache: say nothing
        return True
    if not index.is_file():
        return False
    try:
        return index.stat().st_mtime >= source.stat().st_mtime
    except OSError:  # no source to compare with
        return True

"""The one place that writes files: the output policy, atomic writes, and JSON-ready values.

Every output goes through a temporary file in the target's folder and a rename, so a failure
or an interrupted run never leaves a half-written file.  Folder outputs are written into a
temporary sibling folder that replaces the target only at the end (:func:`output_folder`).
Before any work starts, every verb of the command line checks its outputs with
:func:`check_output`: symbolic links, devices, FIFOs, sockets, a folder where a file is
expected (and a file where a folder is), an output that is one of the inputs, and a folder
that cannot be written are refused.  Missing folders on the way to an output are created.

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

import contextlib
import math
import os
import shutil
import stat
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

import numpy as np

from .errors import SindyshipInputError

__all__ = ["check_output", "clean_json", "output_folder", "physical_memory", "save_figure",
           "write_text_atomic"]

#: What ``stat`` says a path is, for the messages that refuse it.
_FILE_KINDS = (
    (stat.S_ISLNK, "a symbolic link"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISREG, "a regular file"),
)


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


#: Longest file name most file systems allow [bytes].
NAME_MAX = 255


def _temporary_prefix(name: str) -> str:
    """The prefix of a hidden temporary sibling of ``name``: its name, shortened (with a
    digest) so that the temporary name stays within :data:`NAME_MAX` bytes."""
    encoded = os.fsencode(name)
    if len(encoded) <= NAME_MAX - 32:
        return f".{name}."
    import hashlib

    return f".{hashlib.sha256(encoded).hexdigest()[:16]}."


def _temporary_sibling(path: Path) -> tuple[int, str]:
    return tempfile.mkstemp(prefix=_temporary_prefix(path.name), suffix=".tmp",
                            dir=path.parent)


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


def physical_memory() -> int:
    """Bytes of physical memory of this machine (0 when the system does not say)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 0


def _kind_of(mode: int) -> str:
    return next((name for test, name in _FILE_KINDS if test(mode)), "not a regular file")


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return a.resolve() == b.resolve()


def _is_inside(inner: Path, outer: Path) -> bool:
    """Whether ``inner`` is ``outer`` or lies somewhere inside it (after resolving links)."""
    inner, outer = inner.resolve(), outer.resolve()
    return inner == outer or outer in inner.parents


def _check_writable_folder(path: Path, label: str) -> None:
    """The nearest existing folder above ``path`` is a folder this process can write in."""
    ancestor = path.parent
    while not os.path.lexists(ancestor) and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise SindyshipInputError(
            f"{label}: {ancestor} is not a folder, so nothing can be written below it; give a "
            "path whose folders are folders."
        )
    try:
        fd, probe = tempfile.mkstemp(prefix=".sindyship-probe.", dir=ancestor)
    except OSError as exc:
        raise SindyshipInputError(
            f"{label}: cannot write in the folder {ancestor} ({exc.strerror or exc}); choose "
            "a folder you can write to."
        ) from None
    os.close(fd)
    os.unlink(probe)


#: Suffixes of the kinds of file sindyship reads and writes, and what each names.
DATA_SUFFIXES = {".csv": "a CSV table", ".parquet": "a Parquet table", ".pq": "a Parquet table",
                 ".json": "a JSON document", ".py": "a Python module", ".tex": "a LaTeX file",
                 ".toml": "a TOML file", ".png": "an image", ".pdf": "a PDF document"}


def check_output(path: str | os.PathLike, *, inputs: Iterable = (), kind: str = "file",
                 label: str | None = None, replaceable: str | None = None,
                 suffixes: tuple[str, ...] = ()) -> Path:
    """Refuse an output before any work starts; return it as a :class:`Path`.

    Refused (:class:`SindyshipInputError`, one sentence): an empty name; a symbolic link, a
    device, a FIFO or a socket; a folder where a file is expected, or anything but a folder
    where a folder is expected; an output that is one of ``inputs`` (the same file after
    resolving links, hard links included), or a folder output that holds an input or the
    current folder; a place whose nearest existing folder cannot be written.  Missing
    folders are not refused: the writers create them.

    Parameters
    ----------
    path : str or os.PathLike
        The output.
    inputs : iterable of str or os.PathLike
        The files the command reads (missing ones are skipped: their reader reports them).
    kind : {"file", "folder"}
        What the output is.
    label : str, optional
        How the message names the output (default: the path).
    replaceable : str, optional
        For a folder: an existing non-empty folder is replaced at the end only when it holds
        this file (the verb's own result file, so it is a previous output); otherwise refused.
    suffixes : tuple of str, optional
        For a file: the suffixes that fit what is written (the first is the usual one).  A name
        ending in the suffix of another kind of file (:data:`DATA_SUFFIXES`: a model written
        to ``run.csv``, a simulator to ``data.json``) is refused; other names are taken.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     check_output(Path(folder) / "new" / "run.csv").name
    'run.csv'
    """
    if kind not in ("file", "folder"):
        raise ValueError(f"kind must be 'file' or 'folder', not {kind!r}")
    text = os.fspath(path)
    label = label or text
    if not text.strip():
        raise SindyshipInputError(f"the output name {text!r} is empty; give a file or folder name.")
    target = Path(text)
    long = [part for part in target.parts if len(os.fsencode(part)) > NAME_MAX]
    if long:
        raise SindyshipInputError(
            f"{label}: the name {long[0][:40]!r}... is {len(os.fsencode(long[0]))} bytes long, "
            f"more than the {NAME_MAX} a file system allows; give a shorter name."
        )
    if kind == "file" and text.endswith(("/", os.sep)):
        raise SindyshipInputError(
            f"{label}: ends with '/', which names a folder; give the name of a file to write."
        )
    if os.path.lexists(target):
        mode = os.lstat(target).st_mode
        if stat.S_ISDIR(mode) and kind == "file":
            raise SindyshipInputError(
                f"{label}: is a folder; give the name of a file to write (e.g. "
                f"{text}/out{suffixes[0] if suffixes else '.csv'})."
            )
        if stat.S_ISREG(mode) and kind == "folder":
            raise SindyshipInputError(
                f"{label}: is a file, and this output is a folder; give a folder name."
            )
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
            raise SindyshipInputError(
                f"{label}: is {_kind_of(mode)}, which sindyship never writes through; give "
                f"the name of a regular {'file' if kind == 'file' else 'folder'}."
            )
    _check_inputs(target, [Path(os.fspath(p)) for p in inputs if p], kind, label)
    if kind == "folder" and target.is_dir():
        _check_replaceable(target, label, replaceable)
    _check_writable_folder(target.absolute(), label)
    suffix = target.suffix.lower()
    if kind == "file" and suffixes and suffix in DATA_SUFFIXES and suffix not in suffixes:
        raise SindyshipInputError(
            f"{label}: the name ends in {suffix}, the suffix of {DATA_SUFFIXES[suffix]}, but "
            f"this output is {DATA_SUFFIXES[suffixes[0]]}; give a name ending in "
            f"{suffixes[0]}."
        )
    return target


def _check_inputs(target: Path, inputs: list[Path], kind: str, label: str) -> None:
    for source in inputs:
        if not source.exists():
            continue
        if kind == "file" and target.exists() and _same_file(target, source):
            raise SindyshipInputError(
                f"{label}: is also an input ({source}); write the output to another file."
            )
        if kind == "folder" and _is_inside(source, target):
            raise SindyshipInputError(
                f"{label}: the output folder holds the input {source}, which replacing the "
                "folder would delete; choose another folder."
            )
    if kind == "folder" and _is_inside(Path.cwd(), target):
        raise SindyshipInputError(
            f"{label}: the output folder holds the current folder, which replacing it would "
            "delete; choose a new folder."
        )


#: The file an output folder lists the names it wrote in (:func:`output_folder`).
MANIFEST = ".sindyship-output"


def _check_replaceable(target: Path, label: str, marker: str | None) -> None:
    """A folder may be replaced only when it is empty, or an output folder of the same verb
    (``marker`` among its files) holding nothing but what that output wrote (its manifest
    lists them): never a file of the user's."""
    try:
        entries = {entry.name for entry in os.scandir(target)}
    except OSError as exc:
        raise SindyshipInputError(
            f"{label}: cannot read the folder ({exc.strerror or exc}); choose another folder."
        ) from None
    if not entries:
        return
    written = _manifest(target)
    if marker is None or marker not in entries or written is None:
        hint = f" (it has no {marker})" if marker else ""
        raise SindyshipInputError(
            f"{label}: is a folder that holds other files{hint} and would be replaced; give a "
            "new or empty folder, or a previous output folder of the same command."
        )
    foreign = sorted(entries - written - {MANIFEST})
    if foreign:
        raise SindyshipInputError(
            f"{label}: the previous output folder also holds {foreign[0]!r}, which this "
            "command did not write and replacing the folder would delete; move it away or "
            "give another folder."
        )


def _manifest(folder: Path) -> set[str] | None:
    """The names an output folder's manifest lists, or None without a readable one."""
    try:
        text = (folder / MANIFEST).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    return {line for line in text.splitlines() if line}


@contextlib.contextmanager
def output_folder(path: str | os.PathLike) -> Iterator[Path]:
    """Write a folder output into a temporary sibling folder; put it in place at the end.

    Inside the ``with`` block everything is written to the temporary folder (yielded).  When
    the block ends normally the temporary folder takes the name ``path``, replacing a
    previous folder of that name only then; when it raises (or the run is killed) the
    previous folder stays whole and the temporary one is removed (a killed run may leave a
    hidden ``.NAME.*.tmp`` folder beside it).  The folder gets the permissions ``umask``
    allows.  Check ``path`` with :func:`check_output` first.

    Examples
    --------
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     with output_folder(Path(folder) / "out") as tmp:
    ...         _ = (tmp / "a.txt").write_text("a")
    ...     sorted(p.name for p in Path(folder).iterdir()), (Path(folder) / "out").is_dir()
    (['out'], True)

    The folder lists what it holds in a hidden manifest (:data:`MANIFEST`), so that a later
    run replaces it only while it holds nothing else.
    """
    target = Path(path).absolute()
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=_temporary_prefix(target.name), suffix=".tmp",
                                dir=target.parent))
    try:
        yield tmp
        names = sorted(entry.name for entry in os.scandir(tmp))
        (tmp / MANIFEST).write_text("".join(f"{name}\n" for name in names), encoding="utf-8")
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)
        _swap_in(tmp, target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _swap_in(tmp: Path, target: Path) -> None:
    """Rename ``tmp`` to ``target``; a previous ``target`` is moved aside first, then removed."""
    if not os.path.lexists(target):
        os.replace(tmp, target)
        return
    old = Path(tempfile.mkdtemp(prefix=_temporary_prefix(target.name), suffix=".old",
                                dir=target.parent))
    os.rmdir(old)
    os.replace(target, old)
    try:
        os.replace(tmp, target)
    except BaseException:
        os.replace(old, target)
        raise
    shutil.rmtree(old, ignore_errors=True)

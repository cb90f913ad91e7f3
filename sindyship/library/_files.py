"""Built-in and user library and effect files: where they are, reading them."""

from __future__ import annotations

import importlib.resources
import tomllib
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import sindyship
from sindyship.errors import SindyshipInputError

from ._checks import (
    _EFFECT_KEYS,
    _LIBRARY_KEYS,
    _MAX_FILE_BYTES,
    _NAME_RE,
    _check_keys,
    _name,
    _read_delays,
    _read_terms,
    _text,
    _where,
)
from ._objects import Effect, TermLibrary

if TYPE_CHECKING:
    pass


# ---------------------------------------------------------------------------- files
def builtin_library_dir() -> Traversable:
    """The folder of the built-in libraries (effects are in its ``effects`` subfolder).

    An installed wheel carries it as ``sindyship/libraries``; an editable install or a
    source checkout uses the ``libraries`` folder at the top of the repository.
    """
    packaged = importlib.resources.files("sindyship") / "libraries"
    if packaged.is_dir():
        return packaged
    return Path(sindyship.__file__).resolve().parents[1] / "libraries"


def _builtin_names(folder: Traversable) -> tuple[str, ...]:
    if not folder.is_dir():
        return ()
    names = [f.name[: -len(".toml")] for f in folder.iterdir() if f.name.endswith(".toml")]
    return tuple(sorted(name for name in names if _NAME_RE.fullmatch(name)))


def available_libraries() -> tuple[str, ...]:
    """Names of the built-in term libraries.

    Examples
    --------
    >>> {"abkowitz", "abkowitz-noconst"} <= set(available_libraries())
    True
    """
    return _builtin_names(builtin_library_dir())


#: The paper's library (eq. 15 / 17): the default of least squares and of ``diagnose``, which
#: ``fit`` without ``--library`` replaces by its recommended one.
PAPER_LIBRARY = "abkowitz"


def read_from_builtin(library: TermLibrary, name: str = PAPER_LIBRARY) -> bool:
    """Whether ``library`` was read from the built-in library file ``name`` (extended by
    effects or not), the test by which a command names it by ``name`` rather than by a path.

    Examples
    --------
    >>> read_from_builtin(load_library("abkowitz").extended(load_effect("wind")))
    True
    >>> read_from_builtin(load_library("abkowitz-vr"))
    False
    """
    if library.source is None:
        return False
    builtin = Path(str(builtin_library_dir())) / f"{name}.toml"
    return Path(library.source).resolve() == builtin.resolve()


def available_effects() -> tuple[str, ...]:
    """Names of the built-in effects (``libraries/effects/*.toml``)."""
    return _builtin_names(builtin_library_dir() / "effects")


def names_a_file(name_or_path: str | Path) -> bool:
    """Whether a library or effect is given by its file (a path, a name ending in ``.toml`` or
    holding a slash) rather than by a built-in name.

    Examples
    --------
    >>> names_a_file("asymmetry"), names_a_file("heel.toml"), names_a_file("found/lag")
    (False, True, True)
    """
    text = str(name_or_path)
    return (isinstance(name_or_path, Path) or text.endswith(".toml") or "/" in text
            or "\\" in text)


def _locate(name_or_path: str | Path, kind: str) -> Traversable:
    """The file of a built-in library/effect name, or the given path."""
    text = str(name_or_path)
    if names_a_file(name_or_path):
        path = Path(name_or_path)
        if not path.is_file():
            raise SindyshipInputError(f"{path}: there is no such {kind} file.")
        return path
    folder = builtin_library_dir()
    if kind == "effect":
        folder = folder / "effects"
    names = _builtin_names(folder)
    if text not in names:
        raise SindyshipInputError(
            f'there is no built-in {kind} named "{text[:40]}"; the built-in ones are '
            f"{', '.join(names) or 'none'}, or give the path of a .toml file."
        )
    return folder / f"{text}.toml"


def _read_toml(file: Traversable) -> tuple[dict[str, Any], str]:
    data = file.read_bytes()
    if len(data) > _MAX_FILE_BYTES:
        raise SindyshipInputError(f"{file}: the file is larger than {_MAX_FILE_BYTES} bytes.")
    try:
        raw = data.decode("utf-8")
    except UnicodeDecodeError:
        raise SindyshipInputError(f"{file}: the file is not UTF-8 text.") from None
    try:
        return tomllib.loads(raw), raw
    except tomllib.TOMLDecodeError as error:
        raise SindyshipInputError(f"{file}: not valid TOML ({error}).") from None
    except ValueError as error:  # an integer of thousands of digits
        raise SindyshipInputError(f"{file}: holds a number too long to read ({error}); write "
                                  "it with fewer digits.") from None


def load_library(name_or_path: str | Path) -> TermLibrary:
    """Read a term library: a built-in one by name, or a TOML file by path.

    Parameters
    ----------
    name_or_path : str or Path
        A name from :func:`available_libraries` (``"abkowitz"``), or the path of a file
        (anything containing a slash or ending in ``.toml``).

    Returns
    -------
    TermLibrary

    Raises
    ------
    SindyshipInputError
        If the file is missing, is not valid TOML, or breaks the library format (unknown
        keys, wrong types, no ``[terms]``, an unknown degree of freedom, an empty or
        repeated term, a term that breaks the grammar); the message names the file, and
        the line and term where there is one.

    Examples
    --------
    >>> library = load_library("abkowitz")
    >>> library.system, [t.text for t in library.terms["X"][:4]]
    ('prime-I', ['1', 'du', 'du^2', 'v^2'])
    """
    file = _locate(name_or_path, "library")
    data, raw = _read_toml(file)
    _check_keys(data, _LIBRARY_KEYS, file)
    source = Path(str(file))
    return TermLibrary(
        name=_name(data, file),
        system=_text(data, "system", file),
        description=_text(data, "description", file).strip(),
        terms=_read_terms(data["terms"], file, raw, all_dofs=True),
        source=source,
        delays=_read_delays(data.get("delays"), file),
        speed=_speed_form(data, file),
    )


def load_effect(name_or_path: str | Path) -> Effect:
    """Read an effect: a built-in one by name, or a TOML file by path.

    The file has ``name``, ``title``, ``physics``, ``channels`` (optional, default none),
    a ``[terms]`` table with the degrees of freedom the effect touches and a ``[delays]``
    table of channels that lag the force (at least one of the two).

    Raises
    ------
    SindyshipInputError
        As :func:`load_library`, and if a term uses a channel missing from ``channels``.
    """
    file = _locate(name_or_path, "effect")
    data, raw = _read_toml(file)
    _check_keys(data, _EFFECT_KEYS, file)
    channels = data.get("channels", [])
    if not isinstance(channels, list) or not all(isinstance(c, str) for c in channels):
        raise SindyshipInputError(f'{_where(file)}channels must be a list such as ["psi"].')
    return Effect(
        name=_name(data, file),
        title=_text(data, "title", file).strip(),
        physics=_text(data, "physics", file).strip(),
        channels=tuple(channels),
        terms=(_read_terms(data["terms"], file, raw, all_dofs=False) if "terms" in data
               else {}),
        source=Path(str(file)),
        delays=_read_delays(data.get("delays"), file),
    )


def _speed_form(data, label) -> str:
    """A library's ``speed`` key: ``design`` (the default) or ``instantaneous``."""
    value = data.get("speed", "design")
    if value not in ("design", "instantaneous"):
        raise SindyshipInputError(
            f'{_where(label)}speed must be "design" or "instantaneous", not {value!r}.'
        )
    return value

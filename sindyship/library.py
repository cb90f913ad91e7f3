"""Term libraries and effects: their TOML files, the library variables, and the pysindy library.

A *term library* (``libraries/<name>.toml``) declares the terms of the surge force X, sway
force Y and yaw moment N of a manoeuvring model; the built-in ``abkowitz`` library holds the
paper's eq. 15 / 17 (16 surge, 22 sway and 22 yaw terms) and ``abkowitz-noconst`` the same
without the constant terms.  An *effect* (``libraries/effects/<name>.toml``) is a catalogued
physical effect: a paragraph on its physics, the data channels it needs, and the extra terms
per degree of freedom that model it; :meth:`TermLibrary.extended` adds effects to a library.
Every term is declared once, in these files, and its column, name, LaTeX and generated code
all come from that declaration (:class:`sindyship.terms.Term`).  The files are untrusted
input: their terms are read by the whitelist parser of :mod:`sindyship.terms`.

Using the library with pysindy
------------------------------
:class:`AbkowitzFeatureLibrary` is a pysindy feature library.  pysindy fits one term set for
all the columns of ``x_dot``, whereas eq. 15 gives each degree of freedom its own term set
(surge is even in v, r and delta; sway and yaw are not).  ``GeneralizedLibrary`` with
``inputs_per_library`` does not help: it chooses the *inputs* each sub-library sees, not the
*equations* that use it, and fitting X, Y and N together on the union of their terms would
put terms into equations that eq. 15 leaves out.  The recommended way is therefore one
``SINDy`` per degree of freedom, each with that equation's terms, the motion state
``x = [du, v, r]``, the rudder (and any further channels) as control input
``u = [delta, ...]`` in the order of ``input_names``, and the regression target of that
equation (paper eq. 16) as a one-column ``x_dot``.  pysindy accepts an ``x_dot`` with fewer
columns than ``x`` in ``fit`` and ``predict``; give the left-hand side to ``print`` with
``lhs=["X'"]``.  (``SINDy.simulate`` needs one equation per state and is not meant for this
use; sindyship simulates fitted models with its own equations of motion, eq. 14.)

>>> import numpy as np
>>> import pysindy as ps
>>> library = load_library("abkowitz")
>>> rng = np.random.default_rng(0)
>>> x = rng.uniform(-0.2, 0.2, size=(300, 3))  # du, v, r
>>> u = rng.uniform(-0.6, 0.6, size=(300, 1))  # delta [rad]
>>> values = dict(zip(library.input_names, np.hstack([x, u]).T))
>>> models = {}
>>> for dof in DOFS:
...     terms = library.terms[dof]
...     true_coef = rng.normal(size=len(terms))
...     target = feature_matrix(terms, values) @ true_coef  # here: exactly in the library
...     models[dof] = ps.SINDy(
...         feature_library=AbkowitzFeatureLibrary.for_dof(library, dof),
...         optimizer=ps.STLSQ(threshold=0.0, alpha=0.0),
...     ).fit(x, t=1.0, x_dot=target[:, None], u=u, feature_names=list(library.input_names))
...     assert np.allclose(models[dof].coefficients()[0], true_coef)
>>> models["Y"].predict(x, u=u).shape
(300, 1)
>>> models["X"].get_feature_names()[:4]
['1', 'du', 'du^2', 'v^2']
"""

from __future__ import annotations

import importlib.resources
import re
import tomllib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib.resources.abc import Traversable
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np
from pysindy.feature_library.base import BaseFeatureLibrary, x_sequence_or_item
from pysindy.utils import AxesArray, comprehend_axes
from sklearn.utils.validation import check_is_fitted

import sindyship
from sindyship.errors import SindyshipInputError
from sindyship.terms import CORE_VARIABLES, Term, describe_variable, parse_term

if TYPE_CHECKING:
    from sindyship.trajectory import Trajectory

__all__ = [
    "DOFS",
    "AbkowitzFeatureLibrary",
    "Effect",
    "TermLibrary",
    "available_effects",
    "available_libraries",
    "builtin_library_dir",
    "feature_matrix",
    "load_effect",
    "load_library",
    "nondimensional_variables",
]

#: The degrees of freedom of the manoeuvring model: surge force, sway force, yaw moment.
DOFS = ("X", "Y", "N")
_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
_CHANNEL_RE = re.compile(r"[a-z][a-z0-9]*(?:_[a-z0-9]+)*")
_MAX_FILE_BYTES = 1_000_000
_LIBRARY_KEYS = {"name": True, "system": True, "description": False, "terms": True}
_EFFECT_KEYS = {"name": True, "title": True, "physics": True, "channels": False, "terms": True}


# ---------------------------------------------------------------------------- validation
def _where(source: str | Path | None, line: int | None = None) -> str:
    if source is None:
        return ""
    return f"{source}, line {line}: " if line is not None else f"{source}: "


def _check_keys(data: Mapping[str, Any], keys: Mapping[str, bool], source: str | Path) -> None:
    """Unknown or missing top-level keys are errors."""
    unknown = sorted(set(data) - set(keys))
    if unknown:
        raise SindyshipInputError(
            f'{_where(source)}unknown key "{unknown[0]}" (the keys are {", ".join(keys)}).'
        )
    for key, required in keys.items():
        if required and key not in data:
            what = "a [terms] table" if key == "terms" else f'the key "{key}"'
            raise SindyshipInputError(f"{_where(source)}{what} is missing.")


def _text(data: Mapping[str, Any], key: str, source: str | Path, default: str = "") -> str:
    value = data.get(key, default)
    if not isinstance(value, str):
        raise SindyshipInputError(
            f'{_where(source)}"{key}" must be a text string, not {type(value).__name__}.'
        )
    return value


def _name(data: Mapping[str, Any], source: str | Path, *, extended: bool = False) -> str:
    """The library or effect name; ``extended`` allows ``base+effect+...`` names."""
    name = _text(data, "name", source)
    parts = name.split("+") if extended else [name]
    if not all(_NAME_RE.fullmatch(part) for part in parts):
        raise SindyshipInputError(
            f'{_where(source)}the name "{name[:40]}" is not valid: use up to 64 letters, '
            "digits, '_', '-' or '.', starting with a letter or digit."
        )
    return name


def _term_lines(raw: str | None, dof: str, texts: Sequence[str]) -> list[int | None]:
    """The line of each term in the raw file text, found by searching after its key."""
    if raw is None:
        return [None] * len(texts)
    key = re.search(
        rf"""^[ \t]*(?:terms[ \t]*\.[ \t]*)?(?:{dof}|"{dof}"|'{dof}')[ \t]*=""",
        raw,
        re.MULTILINE,
    )
    offset = key.end() if key else 0
    lines: list[int | None] = []
    for text in texts:
        found = [
            i for i in (raw.find(f'"{text}"', offset), raw.find(f"'{text}'", offset)) if i >= 0
        ]
        if not found:
            lines.append(None)
            continue
        index = min(found)
        lines.append(raw.count("\n", 0, index) + 1)
        offset = index + len(text) + 2
    return lines


def _check_unique(
    dof: str,
    terms: Sequence[Term],
    source: str | Path,
    lines: Sequence[int | None] | None = None,
) -> None:
    """No two terms of a degree of freedom may be the same up to scale, or share a name."""
    lines = lines if lines is not None else [None] * len(terms)
    seen: dict[str, int] = {}
    names: dict[str, int] = {}
    for i, term in enumerate(terms):
        key = term.canonical(scale=False)
        if key in seen:
            first = terms[seen[key]]
            again = "" if first.text == term.text else f' (the same as "{first.text}")'
            earlier = f" on line {lines[seen[key]]}" if lines[seen[key]] is not None else ""
            raise SindyshipInputError(
                f'{_where(source, lines[i])}the term "{term.text}" of {dof} repeats a term '
                f"given earlier{earlier}{again}; remove one of them."
            )
        seen[key] = i
        name = term.identifier(dof)
        if name in names:
            raise SindyshipInputError(
                f'{_where(source, lines[i])}the terms "{terms[names[name]].text}" and '
                f'"{term.text}" of {dof} would both be named {name}; rename a channel.'
            )
        names[name] = i


def _read_terms(
    table: object, source: str | Path, raw: str | None, *, all_dofs: bool
) -> dict[str, tuple[Term, ...]]:
    """Parse and validate a ``[terms]`` table (DOF -> list of term texts)."""
    if not isinstance(table, Mapping):
        raise SindyshipInputError(
            f"{_where(source)}terms must be a table of term lists per degree of freedom "
            f"({', '.join(DOFS)})."
        )
    for dof in table:
        if dof not in DOFS:
            raise SindyshipInputError(
                f'{_where(source)}unknown degree of freedom "{dof}" in [terms] '
                f"(use {', '.join(DOFS)})."
            )
    missing = [dof for dof in DOFS if dof not in table]
    if all_dofs and missing:
        raise SindyshipInputError(
            f"{_where(source)}[terms] gives no {missing[0]} terms; a library lists terms for "
            f"each of {', '.join(DOFS)}."
        )
    if not table:
        raise SindyshipInputError(f"{_where(source)}[terms] is empty.")
    out: dict[str, tuple[Term, ...]] = {}
    for dof in DOFS:
        texts = table.get(dof, [])
        if not isinstance(texts, list) or not all(isinstance(t, str) for t in texts):
            raise SindyshipInputError(
                f'{_where(source)}{dof} must be a list of term strings such as ["v", "v^3"].'
            )
        if dof in table and not texts:
            raise SindyshipInputError(f"{_where(source)}the list of {dof} terms is empty.")
        lines = _term_lines(raw, dof, texts)
        terms = tuple(
            parse_term(text, source=source, line=line)
            for text, line in zip(texts, lines, strict=True)
        )
        _check_unique(dof, terms, source, lines)
        out[dof] = terms
    return out


def _frozen_terms(
    terms: Mapping[str, Iterable[Term | str]], source: str | Path, *, all_dofs: bool
) -> Mapping[str, tuple[Term, ...]]:
    """Terms per DOF as an immutable mapping in DOF order, checked for repeats."""
    unknown = [dof for dof in terms if dof not in DOFS]
    if unknown:
        raise SindyshipInputError(f'{_where(source)}unknown degree of freedom "{unknown[0]}".')
    if all_dofs and any(not tuple(terms.get(dof, ())) for dof in DOFS):
        raise SindyshipInputError(f"{_where(source)}a library needs terms for each of X, Y, N.")
    out = {}
    for dof in DOFS:
        if isinstance(terms.get(dof), str):
            raise SindyshipInputError(f"{_where(source)}the {dof} terms must be a list of terms.")
        items = tuple(
            t if isinstance(t, Term) else parse_term(t, source=source) for t in terms.get(dof, ())
        )
        _check_unique(dof, items, source)
        out[dof] = items
    return MappingProxyType(out)


def _variables(terms: Mapping[str, tuple[Term, ...]]) -> frozenset[str]:
    return frozenset().union(*(t.variables for dof_terms in terms.values() for t in dof_terms))


# ---------------------------------------------------------------------------- the objects
@dataclass(frozen=True)
class TermLibrary:
    """The terms of X, Y and N of a manoeuvring model, read from a library file.

    Parameters
    ----------
    name : str
        Stable identifier, e.g. ``"abkowitz"``; ``"abkowitz+asymmetry"`` once extended.
    system : str
        The non-dimensional system of the variables and coefficients, e.g. ``"prime-I"``.
    description : str
        What the library is, for people (cite the equation it comes from).
    terms : mapping of str to tuple of Term
        The terms per degree of freedom, keyed by ``"X"``, ``"Y"``, ``"N"`` in that order
        (term texts are parsed).  Within a degree of freedom no two terms may be equal up
        to a constant factor.
    source : Path, optional
        The file the library was read from.
    effects : tuple of str
        Names of the effects added by :meth:`extended`, in order.

    Examples
    --------
    >>> library = load_library("abkowitz")
    >>> {dof: len(terms) for dof, terms in library.terms.items()}
    {'X': 16, 'Y': 22, 'N': 22}
    >>> sorted(library.variables), sorted(library.channels)
    (['delta', 'du', 'r', 'v'], [])
    >>> TermLibrary("toy", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["r", "r v^0"]})
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: library "toy": the term "r v^0" is not valid: \
"^" is followed by one digit 1-9; found "0" at character 5.
    """

    name: str
    system: str
    description: str
    terms: Mapping[str, tuple[Term, ...]]
    source: Path | None = field(default=None, compare=False)
    effects: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        label = self.source if self.source is not None else f'library "{self.name}"'
        frozen = _frozen_terms(self.terms, label, all_dofs=True)
        object.__setattr__(self, "terms", frozen)
        object.__setattr__(self, "effects", tuple(self.effects))

    def __hash__(self) -> int:
        return hash((self.name, self.system, self.description, *self.terms.items(), self.effects))

    @property
    def variables(self) -> frozenset[str]:
        """All variables the terms use."""
        return _variables(self.terms)

    @property
    def channels(self) -> frozenset[str]:
        """The variables beyond du, v, r and delta: data channels the library needs."""
        return self.variables - set(CORE_VARIABLES)

    @property
    def input_names(self) -> tuple[str, ...]:
        """The input columns for :class:`AbkowitzFeatureLibrary`: du, v, r, delta, channels.

        The state of a pysindy fit is ``[du, v, r]``; the rest is its control input ``u``.
        """
        return (*CORE_VARIABLES, *sorted(self.channels))

    def extended(self, *effects: Effect) -> TermLibrary:
        """This library with the terms of ``effects`` added.

        Each effect's terms are appended per degree of freedom, skipping those the library
        already has (by :meth:`Term.canonical`, up to a constant factor).

        Examples
        --------
        >>> base = TermLibrary("toy", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["r"]})
        >>> drift = Effect("drift", "Drift", "A made-up effect.", ("psi",),
        ...                {"Y": ["sin(psi)", "v"], "N": ["cos(psi)"]})
        >>> bigger = base.extended(drift)
        >>> bigger.name, [t.text for t in bigger.terms["Y"]], sorted(bigger.channels)
        ('toy+drift', ['v', 'sin(psi)'], ['psi'])
        """
        terms = {dof: list(self.terms[dof]) for dof in DOFS}
        names = list(self.effects)
        for effect in effects:
            if effect.name in names:
                continue
            names.append(effect.name)
            for dof in DOFS:
                present = {t.canonical(scale=False) for t in terms[dof]}
                terms[dof] += [
                    t for t in effect.terms[dof] if t.canonical(scale=False) not in present
                ]
        added = names[len(self.effects) :]
        return TermLibrary(
            name="+".join([self.name, *added]),
            system=self.system,
            description=self.description,
            terms=terms,
            source=self.source,
            effects=tuple(names),
        )

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready description (name, system, description, effects, term texts).

        Examples
        --------
        >>> library = load_library("abkowitz-noconst")
        >>> TermLibrary.from_dict(library.to_dict()) == library
        True
        """
        return {
            "name": self.name,
            "system": self.system,
            "description": self.description,
            "effects": list(self.effects),
            "terms": {dof: [t.text for t in self.terms[dof]] for dof in DOFS},
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str | Path | None = None) -> TermLibrary:
        """The library saved by :meth:`to_dict` (e.g. inside a model JSON), validated.

        Parameters
        ----------
        data : mapping
            As made by :meth:`to_dict`.
        source : str or Path, optional
            Where ``data`` comes from, for error messages.
        """
        label = source if source is not None else "saved library"
        if not isinstance(data, Mapping):
            raise SindyshipInputError(f"{_where(label)}a library must be a JSON object.")
        _check_keys(data, {**_LIBRARY_KEYS, "effects": False}, label)
        effects = data.get("effects", [])
        if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
            raise SindyshipInputError(f"{_where(label)}effects must be a list of effect names.")
        return cls(
            name=_name(data, label, extended=True),
            system=_text(data, "system", label),
            description=_text(data, "description", label),
            terms=_read_terms(data["terms"], label, None, all_dofs=True),
            source=Path(source) if source is not None else None,
            effects=tuple(effects),
        )


@dataclass(frozen=True)
class Effect:
    """A catalogued physical effect: its physics, the channels it needs, its terms.

    Parameters
    ----------
    name : str
        Stable identifier (``"asymmetry"``, ``"crossflow"``, ...).
    title : str
        A short title for reports.
    physics : str
        One paragraph: what the effect is, how it shows in the residuals, what to measure.
    channels : tuple of str
        Data channels the effect needs beyond u, v, r and delta; every such variable its
        terms use must be listed here.
    terms : mapping of str to tuple of Term
        Extra terms per degree of freedom; a degree of freedom the effect does not touch
        has an empty tuple.
    source : Path, optional
        The file the effect was read from.

    Examples
    --------
    >>> Effect("e", "E", "Text.", (), {"Y": ["abs(v) v"], "N": ["abs(r) r"]}).terms["X"]
    ()
    """

    name: str
    title: str
    physics: str
    channels: tuple[str, ...]
    terms: Mapping[str, tuple[Term, ...]]
    source: Path | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        label = self.source if self.source is not None else f'effect "{self.name}"'
        frozen = _frozen_terms(self.terms, label, all_dofs=False)
        if not any(frozen.values()):
            raise SindyshipInputError(f"{_where(label)}the effect has no terms.")
        channels = tuple(self.channels)
        for channel in channels:
            if not isinstance(channel, str) or not _CHANNEL_RE.fullmatch(channel):
                raise SindyshipInputError(f"{_where(label)}{channel!r} is not a channel name.")
            if channel in CORE_VARIABLES:
                raise SindyshipInputError(
                    f'{_where(label)}"{channel}" is always available; list only the channels '
                    "beyond du, v, r and delta."
                )
        undeclared = sorted(_variables(frozen) - set(CORE_VARIABLES) - set(channels))
        if undeclared:
            raise SindyshipInputError(
                f'{_where(label)}the terms use the channel "{undeclared[0]}"; add it to channels.'
            )
        object.__setattr__(self, "terms", frozen)
        object.__setattr__(self, "channels", channels)

    def __hash__(self) -> int:
        return hash((self.name, self.title, self.physics, self.channels, *self.terms.items()))

    @property
    def variables(self) -> frozenset[str]:
        """All variables the effect's terms use."""
        return _variables(self.terms)


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


def available_effects() -> tuple[str, ...]:
    """Names of the built-in effects (``libraries/effects/*.toml``)."""
    return _builtin_names(builtin_library_dir() / "effects")


def _locate(name_or_path: str | Path, kind: str) -> Traversable:
    """The file of a built-in library/effect name, or the given path."""
    text = str(name_or_path)
    is_path = (
        isinstance(name_or_path, Path) or text.endswith(".toml") or "/" in text or "\\" in text
    )
    if is_path:
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
    )


def load_effect(name_or_path: str | Path) -> Effect:
    """Read an effect: a built-in one by name, or a TOML file by path.

    The file has ``name``, ``title``, ``physics``, ``channels`` (optional, default none)
    and a ``[terms]`` table with the degrees of freedom the effect touches.

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
        terms=_read_terms(data["terms"], file, raw, all_dofs=False),
        source=Path(str(file)),
    )


# ---------------------------------------------------------------------------- numbers
_SCALINGS = {
    "surge": lambda x, L, U0: x / U0 - 1.0,
    "speed": lambda x, L, U0: x / U0,
    "rate": lambda x, L, U0: x * L / U0,
    "none": lambda x, L, U0: x,
}


def nondimensional_variables(
    trajectory: Trajectory,
    L: float,
    U0: float,
    *,
    needed: Iterable[str] | TermLibrary | Effect | None = None,
    rudder: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The library variables of a record, non-dimensional in the Prime-I system (eq. 14).

    With the ship length ``L`` and the design speed ``U0`` (constant, not the instantaneous
    speed): ``du = u/U0 - 1``, ``v = v/U0``, ``r = r L/U0``, ``delta`` the rudder angle
    [rad], ``psi`` the heading [rad], ``n = n L/U0`` (n in rps), ``wind_speed`` over U0,
    ``wind_dir`` [rad].  Any other channel is passed through as recorded (SI units).

    Parameters
    ----------
    trajectory : Trajectory
        The record, in SI units.
    L, U0 : float
        Ship length [m] and design speed [m/s].
    needed : iterable of str, TermLibrary or Effect, optional
        The variables to compute; a library or effect stands for the variables its terms
        use.  Default: du, v, r and delta.
    rudder : numpy.ndarray, optional
        The rudder angle [rad] to use for ``delta`` (e.g. the commanded one); default the
        record's actual rudder angle, else its commanded one.

    Returns
    -------
    dict of str to numpy.ndarray
        One array per needed variable, du, v, r, delta first.

    Raises
    ------
    SindyshipInputError
        If the record lacks a channel that is needed (the message names the channel and
        the library or effect), or ``L``, ``U0`` or ``rudder`` are not valid.

    Examples
    --------
    >>> import pandas as pd
    >>> from sindyship.trajectory import Trajectory
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": [10.0, 5.0], "v": [0.0, 2.5],
    ...                       "r": [0.0, 0.05], "x": [0.0, 1.0], "y": [0.0, 0.0],
    ...                       "psi": [0.0, 0.1], "delta": [0.0, 0.2]})
    >>> values = nondimensional_variables(Trajectory(frame, "demo"), L=100.0, U0=10.0)
    >>> {name: value.tolist() for name, value in values.items()}
    {'du': [0.0, -0.5], 'v': [0.0, 0.25], 'r': [0.0, 0.5], 'delta': [0.0, 0.2]}
    """
    for label, value in (("L", L), ("U0", U0)):
        if not (np.isfinite(value) and value > 0):
            raise SindyshipInputError(f"{label} must be a positive number, not {value!r}.")
    if needed is None:
        names, requester = set(CORE_VARIABLES), "the model"
    elif isinstance(needed, TermLibrary | Effect):
        kind = "library" if isinstance(needed, TermLibrary) else "effect"
        names, requester = set(needed.variables), f'{kind} "{needed.name}"'
    else:
        names, requester = set(needed), "the terms"
    record = f'record "{trajectory.name}"' if trajectory.name else "the record"
    order = sorted(names, key=lambda n: (n not in CORE_VARIABLES, _core_rank(n), n))
    out: dict[str, np.ndarray] = {}
    for name in order:
        variable = describe_variable(name)
        if variable.column == "rudder":
            if rudder is not None:
                column = np.asarray(rudder, dtype=float)
                if column.shape != (trajectory.n_samples,):
                    raise SindyshipInputError(
                        f"the rudder angle given for {record} has shape {column.shape}, "
                        f"not ({trajectory.n_samples},)."
                    )
            elif trajectory.has("delta") or trajectory.has("delta_c"):
                column = trajectory.rudder
            else:
                raise SindyshipInputError(
                    f'{requester} needs the rudder angle ("delta" or "delta_c"), which '
                    f"{record} does not have."
                )
        elif trajectory.has(variable.column):
            column = trajectory[variable.column]
        else:
            raise SindyshipInputError(
                f'{requester} needs the channel "{variable.column}", which {record} does not have.'
            )
        out[name] = _SCALINGS[variable.scaling](column, float(L), float(U0))
    return out


def _core_rank(name: str) -> int:
    return CORE_VARIABLES.index(name) if name in CORE_VARIABLES else len(CORE_VARIABLES)


def feature_matrix(terms: Sequence[Term | str], values: Mapping[str, np.ndarray]) -> np.ndarray:
    """The regressor matrix: one column per term (paper eq. 17), one row per sample.

    Parameters
    ----------
    terms : sequence of Term (or term text)
        The terms of one degree of freedom, in order.
    values : mapping of str to numpy.ndarray
        The variables, e.g. from :func:`nondimensional_variables`.

    Returns
    -------
    numpy.ndarray
        Shape (n_samples, n_terms); for arrays of more dimensions, the terms are the last
        axis.

    Examples
    --------
    >>> import numpy as np
    >>> feature_matrix(["1", "v", "v^2 r"], {"v": np.array([1.0, 2.0]), "r": np.array([3.0, 4.0])})
    array([[ 1.,  1.,  3.],
           [ 1.,  2., 16.]])
    """
    parsed = [t if isinstance(t, Term) else Term(t) for t in terms]
    columns = [term.evaluate(values) for term in parsed]
    shapes = [c.shape for c in columns] or [np.shape(next(iter(values.values()), []))]
    shape = np.broadcast_shapes(*shapes)
    if not columns:
        return np.empty((*shape, 0))
    return np.stack([np.broadcast_to(c, shape) for c in columns], axis=-1)


# ---------------------------------------------------------------------------- pysindy
class AbkowitzFeatureLibrary(BaseFeatureLibrary):
    """A pysindy feature library made of library terms (see the module docstring for use).

    Parameters
    ----------
    terms : sequence of str
        The term texts, e.g. ``library_terms = [t.text for t in library.terms["Y"]]``;
        ``Term`` objects are accepted too.  Parsed in :meth:`fit`.
    input_names : sequence of str
        The variable each input column holds, in order.  pysindy hands the library the
        state columns followed by the control columns, so for ``x = [du, v, r]`` and
        ``u = [delta]`` this is ``("du", "v", "r", "delta")``.

    Attributes
    ----------
    terms_ : tuple of Term
        The parsed terms (machine-readable through ``Term.factors``).
    n_features_in_ : int
        Number of input columns.
    n_output_features_ : int
        Number of terms.

    Examples
    --------
    >>> import numpy as np
    >>> lib = AbkowitzFeatureLibrary(terms=("v", "abs(v) v"), input_names=("v",))
    >>> lib.fit_transform(np.array([[-2.0], [3.0]]))
    AxesArray([[-2., -4.],
               [ 3.,  9.]])
    >>> lib.get_feature_names()
    ['v', 'abs(v) v']
    >>> (lib + AbkowitzFeatureLibrary(terms=("v^3",), input_names=("v",))).fit(
    ...     np.ones((2, 1))).get_feature_names()
    ['v', 'abs(v) v', 'v^3']
    """

    def __init__(
        self,
        terms: Sequence[str | Term],
        input_names: Sequence[str] = CORE_VARIABLES,
    ) -> None:
        self.terms = terms
        self.input_names = input_names

    @classmethod
    def for_dof(cls, library: TermLibrary, dof: str) -> AbkowitzFeatureLibrary:
        """The feature library of one degree of freedom of ``library``.

        Its inputs are ``library.input_names``: the state ``[du, v, r]``, then the control
        ``[delta, *sorted(channels)]``.
        """
        return cls(terms=tuple(t.text for t in library.terms[dof]), input_names=library.input_names)

    @x_sequence_or_item
    def fit(self, x_full: list[AxesArray], y: object = None) -> AbkowitzFeatureLibrary:
        """Parse the terms and check them against the inputs.

        Parameters
        ----------
        x_full : array_like, shape (n_samples, n_inputs), or a list of them
            The input data (state then control columns).
        y : ignored

        Returns
        -------
        self
        """
        n_features = x_full[0].shape[x_full[0].ax_coord]
        names = tuple(self.input_names)
        if len(names) != n_features or len(set(names)) != len(names):
            raise ValueError(
                f"input_names {names} must name each of the {n_features} input columns once."
            )
        terms = tuple(
            t if isinstance(t, Term) else parse_term(t, source="AbkowitzFeatureLibrary")
            for t in self.terms
        )
        if not terms:
            raise ValueError("AbkowitzFeatureLibrary needs at least one term.")
        for term in terms:
            missing = sorted(term.variables - set(names))
            if missing:
                raise SindyshipInputError(
                    f'the term "{term.text}" uses "{missing[0]}", which is not among the '
                    f"inputs {', '.join(names)}."
                )
        self.terms_ = terms
        self.n_features_in_ = n_features
        self.n_output_features_ = len(terms)
        return self

    @x_sequence_or_item
    def transform(self, x_full: list[AxesArray]) -> list[AxesArray]:
        """Evaluate the terms.

        Parameters
        ----------
        x_full : array_like, shape (n_samples, n_inputs), or a list of them

        Returns
        -------
        AxesArray, shape (n_samples, n_terms), or a list of them
        """
        check_is_fitted(self)
        out = []
        for x in x_full:
            if x.shape[-1] != self.n_features_in_:
                raise ValueError(
                    f"x has {x.shape[-1]} input columns; the library was fitted with "
                    f"{self.n_features_in_}."
                )
            data = np.asarray(x, dtype=float)
            values = {name: data[..., i] for i, name in enumerate(self.input_names)}
            xp = feature_matrix(self.terms_, values)
            out.append(AxesArray(xp, comprehend_axes(xp)))
        return out

    def get_feature_names(self, input_features: Sequence[str] | None = None) -> list[str]:
        """The term texts (the coefficient keys), checked against pysindy's input names.

        The library binds its input columns by ``input_names``; pysindy passes the names it
        gives the same columns (``SINDy.fit(..., feature_names=...)``) as ``input_features``.
        When they disagree the library would label its terms with the wrong variables, so it
        refuses (pysindy's default names ``x0, x1, ..., u0, ...`` name no variable and pass).

        Raises
        ------
        sklearn.exceptions.NotFittedError
            Before :meth:`fit`.
        ValueError
            When ``input_features`` are not ``input_names`` in the same order.
        """
        check_is_fitted(self)
        if input_features is not None:
            given, expected = [str(n) for n in input_features], [str(n) for n in self.input_names]
            if given != expected and not all(re.fullmatch(r"[xu]\d+", n) for n in given):
                missing = sorted(set(expected) - set(given))
                extra = sorted(set(given) - set(expected))
                what = (f"missing {missing}" if missing else "") + (
                    f"{'; ' if missing else ''}unknown {extra}" if extra else "")
                raise ValueError(
                    f"the input columns are named {given} but the library binds them as "
                    f"{expected} ({what or 'another order'}); pass input_names in the order of "
                    "the columns (state, then control) or the same feature_names to SINDy."
                )
        return [str(t) for t in self.terms_]

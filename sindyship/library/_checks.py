"""Checks of library and effect files: keys, names, terms, line numbers in messages."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from sindyship.errors import SindyshipInputError
from sindyship.targets import DOFS
from sindyship.terms import Term, is_variable_name, parse_term

if TYPE_CHECKING:
    pass


#: The degrees of freedom of the manoeuvring model: surge force, sway force, yaw moment.
_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")
_MAX_FILE_BYTES = 1_000_000
_LIBRARY_KEYS = {"name": True, "system": True, "description": False, "terms": True,
                 "delays": False, "speed": False}
_EFFECT_KEYS = {"name": True, "title": True, "physics": True, "channels": False, "terms": False,
                "delays": False}
#: Channels a library may not delay: time, the motion state and the positions it integrates.
UNDELAYABLE = ("t", "u", "v", "r", "x", "y", "psi", "du")
#: Largest delay of a channel [s].
MAX_DELAY = 3600.0


# ---------------------------------------------------------------------------- validation
def _read_delays(raw: Any, source: str | Path | None) -> dict[str, float]:
    """A ``[delays]`` table: recorded channel -> seconds by which it lags the physics.

    Raises
    ------
    SindyshipInputError
        For a table that is not channel = number, a channel of the motion state, time or
        position, or a delay that is not finite, zero, or beyond :data:`MAX_DELAY`.
    """
    if raw is None:
        return {}
    if not isinstance(raw, Mapping):
        raise SindyshipInputError(
            f"{_where(source)}delays must be a table such as {{delta = 4.0}} (seconds)."
        )
    out = {}
    for channel, value in raw.items():
        if not is_variable_name(channel):
            raise SindyshipInputError(
                f"{_where(source)}{channel!r} is not a channel name: use lower-case letters, "
                "digits and single underscores, as in the measurement CSV (e.g. delta)."
            )
        if channel in UNDELAYABLE:
            raise SindyshipInputError(
                f'{_where(source)}the channel "{channel}" cannot be delayed: only input '
                "channels such as delta, delta_c, n or wind_speed can."
            )
        if (isinstance(value, bool) or not isinstance(value, int | float)
                or not math.isfinite(value) or value == 0 or abs(value) > MAX_DELAY):
            raise SindyshipInputError(
                f"{_where(source)}the delay of {channel} must be a non-zero number of seconds "
                f"between -{MAX_DELAY:g} and {MAX_DELAY:g}, not {value!r}."
            )
        out[channel] = float(value)
    return out


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

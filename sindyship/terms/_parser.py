"""The whitelist parser of the term grammar (never eval or sympify of file text)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import NamedTuple

from ..errors import SindyshipInputError
from ._shapes import shape_name_error
from ._variables import (
    _DIGITS,
    _LOWER,
    _MAX_NAME_LENGTH,
    _MAX_NUMBER_LENGTH,
    _NAME_RE,
    _RESERVED,
    FUNCTIONS,
    MAX_DEGREE,
    MAX_FACTORS,
    MAX_TERM_LENGTH,
)


class Factor(NamedTuple):
    """One factor of a term: ``function(base)^power``.

    ``function`` is one of :data:`FUNCTIONS` or None; ``base`` is a variable name (str) or a
    number (float); ``power`` is 1-9.
    """

    function: str | None
    base: str | float
    power: int


class _TermError(SindyshipInputError):
    """A term that breaks the grammar; ``reason`` says how, without the location."""

    def __init__(self, text: object, reason: str) -> None:
        self.text = text
        self.reason = reason
        super().__init__(_message(text, reason, None, None))


def _quote(text: object) -> str:
    """The term as it appears in a one-line message (escaped, shortened)."""
    shown = text if isinstance(text, str) else repr(text)
    if len(shown) > 60:
        shown = shown[:57] + "..."
    return json.dumps(shown, ensure_ascii=False)


def _message(text: object, reason: str, source: str | Path | None, line: int | None) -> str:
    where = ""
    if source is not None:
        where = f"{source}, line {line}: " if line is not None else f"{source}: "
    elif line is not None:
        where = f"line {line}: "
    return f"{where}the term {_quote(text)} is not valid: {reason}."


class _Scanner:
    """Reads one term text left to right; every method either consumes input or raises."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.pos = 0

    def fail(self, reason: str) -> _TermError:
        return _TermError(self.text, reason)

    def peek(self) -> str:
        return self.text[self.pos] if self.pos < len(self.text) else ""

    def where(self) -> str:
        char = self.peek()
        if not char:
            return "at the end"
        return f"{json.dumps(char, ensure_ascii=False)} at character {self.pos + 1}"

    def take(self, allowed: str) -> str:
        start = self.pos
        while self.pos < len(self.text) and self.text[self.pos] in allowed:
            self.pos += 1
        return self.text[start : self.pos]

    def factors(self) -> tuple[Factor, ...]:
        out = [self.factor()]
        while self.pos < len(self.text):
            if self.peek() != " ":
                raise self.fail(f"unexpected {self.where()}")
            self.pos += 1
            if self.peek() in ("", " "):
                raise self.fail("factors are separated by single spaces, with none at the ends")
            out.append(self.factor())
            if len(out) > MAX_FACTORS:
                raise self.fail(f"a term has at most {MAX_FACTORS} factors")
        return tuple(out)

    def factor(self) -> Factor:
        char = self.peek()
        function: str | None = None
        if char and char in _DIGITS:
            base: str | float = self.number()
        elif char and char in _LOWER:
            start = self.pos
            word = self.take(_LOWER + _DIGITS + "_")
            if self.peek() == "(":
                if word not in FUNCTIONS:
                    raise self.fail(
                        f'"{word}" is not a known function (use one of {", ".join(FUNCTIONS)})'
                    )
                self.pos += 1
                function = word
                if not self.peek() or self.peek() not in _LOWER:
                    raise self.fail(f"{word}() applies to a variable; found {self.where()}")
                base = self.variable(self.pos, self.take(_LOWER + _DIGITS + "_"))
                if self.peek() != ")":
                    raise self.fail(f'expected ")" to close {word}(, found {self.where()}')
                self.pos += 1
            else:
                base = self.variable(start, word)
        elif char == "":
            raise self.fail("a factor is missing at the end")
        else:
            raise self.fail(f"unexpected {self.where()}")
        power = 1
        if self.peek() == "^":
            self.pos += 1
            digit = self.peek()
            if not digit or digit not in "123456789":
                raise self.fail(f'"^" is followed by one digit 1-9; found {self.where()}')
            self.pos += 1
            if self.peek() and self.peek() in _DIGITS:
                raise self.fail("an exponent is a single digit 1-9")
            power = int(digit)
        return Factor(function, base, power)

    def variable(self, start: int, name: str) -> str:
        if name in _RESERVED:
            hint = f"; write {name}(v)" if name in FUNCTIONS else ""
            raise self.fail(f'"{name}" cannot be a variable: {_RESERVED[name]}{hint}')
        if len(name) > _MAX_NAME_LENGTH:
            raise self.fail(f"a variable name has at most {_MAX_NAME_LENGTH} characters")
        if not _NAME_RE.fullmatch(name):
            raise self.fail(
                f'"{name}" (character {start + 1}) is not a variable name: lower-case letters, '
                "digits and single underscores between them, starting with a letter"
            )
        malformed = shape_name_error(name)
        if malformed:
            raise self.fail(f'"{name}" is named like a shape but is not one: {malformed}')
        return name

    def number(self) -> float:
        digits = self.take(_DIGITS)
        if self.peek() == ".":
            self.pos += 1
            decimals = self.take(_DIGITS)
            if not decimals:
                raise self.fail(f"a digit must follow the decimal point at character {self.pos}")
            digits += "." + decimals
        if self.peek() and self.peek() not in " ^":
            raise self.fail(f"a number stands alone as a factor; unexpected {self.where()}")
        if len(digits) > _MAX_NUMBER_LENGTH:
            raise self.fail(f"a number has at most {_MAX_NUMBER_LENGTH} characters")
        value = float(digits)
        if value == 0.0:
            raise self.fail("a zero factor makes the whole column zero")
        return value


def _parse(text: object) -> tuple[Factor, ...]:
    """The factors of ``text``; raises :class:`_TermError` if it breaks the grammar."""
    if not isinstance(text, str):
        raise _TermError(text, f"a term is text, not {type(text).__name__}")
    if not text.strip():
        raise _TermError(text, "it is empty")
    if len(text) > MAX_TERM_LENGTH:
        raise _TermError(text, f"a term has at most {MAX_TERM_LENGTH} characters")
    if text == "1":
        return ()
    factors = _Scanner(text).factors()
    degree = sum(f.power for f in factors)
    if degree > MAX_DEGREE:
        raise _TermError(text, f"its exponents add up to {degree}, more than {MAX_DEGREE}")
    return factors

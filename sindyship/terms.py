"""Terms of a manoeuvring model: a whitelist parser and the :class:`Term` object.

A term is one monomial of the Abkowitz Taylor series (paper eq. 15), written in the small
language of the term-library files (``libraries/*.toml``)::

    term   := "1" | factor (" " factor)*
    factor := atom ("^" digit)?
    atom   := variable | number | ("abs" | "sin" | "cos" | "sign") "(" variable ")"

Variables are the non-dimensional motion variables ``du`` (= u' - 1), ``v``, ``r``, ``delta``
and named data channels (``psi``, ``n``, ``wind_speed``, ``wind_dir``, ...).  Library files are
untrusted input, so the text is read by a hand-written tokenizer that accepts exactly this
grammar and nothing else: it is never handed to ``eval``, ``sympify`` or a parser of Python
or sympy syntax.  A bad term raises :class:`~sindyship.errors.SindyshipInputError` with one
sentence naming the file, the line and the term.

A :class:`Term` is made once from its text, and everything else comes from it: the numeric
column (:meth:`Term.evaluate`), the sympy expression (:meth:`Term.sympy`), the coefficient's
printed name (:attr:`Term.subscript`, :meth:`Term.latex`), a Python identifier for generated
code (:meth:`Term.identifier`) and the LaTeX of the monomial (:meth:`Term.latex_term`).

Examples
--------
>>> import numpy as np
>>> term = parse_term("v^2 r")
>>> term.factors
(Factor(function=None, base='v', power=2), Factor(function=None, base='r', power=1))
>>> term.evaluate({"v": np.array([0.1, 0.2]), "r": np.array([1.0, -1.0])})
array([ 0.01, -0.04])
>>> term.latex("Y"), term.identifier("Y"), term.latex_term()
("Y'_{vvr}", 'Y_vvr', "v'^{2} r'")
>>> parse_term("r v v").canonical()
'v^2 r'
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from decimal import Decimal, localcontext
from fractions import Fraction
from pathlib import Path
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import sympy

from sindyship.errors import SindyshipInputError

__all__ = [
    "CORE_VARIABLES",
    "FUNCTIONS",
    "Factor",
    "MAX_DEGREE",
    "MAX_FACTORS",
    "MAX_TERM_LENGTH",
    "Term",
    "VARIABLES",
    "Variable",
    "describe_variable",
    "parse_term",
]

#: Functions a factor may apply to a variable.
FUNCTIONS = ("abs", "sign", "sin", "cos")
#: The motion variables of the Abkowitz expansion (paper eq. 15), in the paper's order.
CORE_VARIABLES = ("du", "v", "r", "delta")
#: Longest term text accepted [characters].
MAX_TERM_LENGTH = 120
#: Most factors in one term.
MAX_FACTORS = 8
#: Largest sum of the exponents in one term (keeps every column finite for finite data).
MAX_DEGREE = 9
_MAX_NAME_LENGTH = 32
_MAX_NUMBER_LENGTH = 10
_DIGITS = "0123456789"
_LOWER = "abcdefghijklmnopqrstuvwxyz"
_NAME_RE = re.compile(r"[a-z][a-z0-9]*(?:_[a-z0-9]+)*")
_ATOMIC_LATEX_RE = re.compile(r"[A-Za-z]|\\[A-Za-z]+")
#: Names that cannot be variables, with the reason shown to the user.
_RESERVED = {
    "u": 'the library variable for surge is "du" (= u/U0 - 1)',
    **{name: "it is a function name" for name in FUNCTIONS},
}

_NUMPY_FUNCTIONS = {"abs": np.abs, "sign": np.sign, "sin": np.sin, "cos": np.cos}
_SYMPY_FUNCTIONS = {"abs": sympy.Abs, "sign": sympy.sign, "sin": sympy.sin, "cos": sympy.cos}
_LATEX_FUNCTIONS = {"sign": r"\operatorname{sgn}", "sin": r"\sin", "cos": r"\cos"}
_TEXT_FUNCTIONS = {"sign": "sgn", "sin": "sin", "cos": "cos"}


@dataclass(frozen=True)
class Variable:
    """How one library variable is made from SI data and how it is printed.

    Parameters
    ----------
    name : str
        The name used in term text (``"du"``, ``"v"``, ``"psi"``, ...).
    column : str
        The trajectory channel it is computed from (``"rudder"`` means the actual rudder angle
        if recorded, else the commanded one).
    scaling : str
        Prime-I non-dimensionalisation (paper section 2.2) with the design speed U0 and
        length L: ``"surge"`` u/U0 - 1, ``"speed"`` value/U0, ``"rate"`` value L/U0,
        ``"none"`` the SI value unchanged (angles in rad, other channels as recorded).
    symbol : str
        LaTeX of the variable in a term (a prime marks a non-dimensional value).
    subscript : str
        Plain text of the variable in a coefficient name (``"d"`` for delta, as ``X'_vd``).
    subscript_latex : str
        LaTeX of the variable in a coefficient subscript (``\\delta`` for delta).
    description : str
        One line for people: what the variable is.
    """

    name: str
    column: str
    scaling: str
    symbol: str
    subscript: str
    subscript_latex: str
    description: str


#: The variables with a known meaning; any other channel is used as recorded (SI, unscaled).
VARIABLES: Mapping[str, Variable] = MappingProxyType(
    {
        v.name: v
        for v in (
            Variable("du", "u", "surge", r"\Delta u'", "u", "u", "surge speed change u/U0 - 1"),
            Variable("v", "v", "speed", "v'", "v", "v", "sway speed v/U0"),
            Variable("r", "r", "rate", "r'", "r", "r", "yaw rate r L/U0"),
            Variable("delta", "rudder", "none", r"\delta", "d", r"\delta", "rudder angle [rad]"),
            Variable("psi", "psi", "none", r"\psi", "psi", r"\psi", "heading [rad]"),
            Variable("n", "n", "rate", "n'", "n", "n", "propeller revolutions n L/U0"),
            Variable(
                "wind_speed",
                "wind_speed",
                "speed",
                "V_{w}'",
                "wind_speed",
                "V_{w}",
                "wind speed over U0",
            ),
            Variable(
                "wind_dir",
                "wind_dir",
                "none",
                r"\psi_{w}",
                "wind_dir",
                r"\psi_{w}",
                "direction the wind comes from, clockwise from north [rad]",
            ),
        )
    }
)


def describe_variable(name: str) -> Variable:
    """The :class:`Variable` record of ``name``; a channel without one is used as recorded.

    Examples
    --------
    >>> describe_variable("r").scaling
    'rate'
    >>> describe_variable("depth").symbol
    '\\\\mathrm{depth}'
    """
    known = VARIABLES.get(name)
    if known is not None:
        return known
    latex = r"\mathrm{" + name.replace("_", r"\_") + "}"
    return Variable(name, name, "none", latex, name, latex, f"channel {name} as recorded")


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


def parse_term(text: str, *, source: str | Path | None = None, line: int | None = None) -> Term:
    """Read one term, naming ``source`` and ``line`` in the error if it is not valid.

    Parameters
    ----------
    text : str
        The term as written, e.g. ``"v^2 r"`` or ``"abs(v) v"``.
    source : str or Path, optional
        The file the term comes from, for the error message.
    line : int, optional
        The line of ``source`` where the term is written, for the error message.

    Returns
    -------
    Term

    Raises
    ------
    SindyshipInputError
        If ``text`` does not follow the term grammar (see the module docstring).

    Examples
    --------
    >>> parse_term("du v delta").variables == {"du", "v", "delta"}
    True
    >>> parse_term("v^^2", source="my.toml", line=7)
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: my.toml, line 7: the term "v^^2" is not valid: "^" is \
followed by one digit 1-9; found "^" at character 3.
    """
    try:
        return Term(text)
    except _TermError as error:
        raise SindyshipInputError(_message(text, error.reason, source, line)) from None


def _number_text(value: float | Fraction) -> str:
    """A number as short decimal text: 2.0 -> "2", 0.5 -> "0.5"."""
    fraction = Fraction(repr(value)) if isinstance(value, float) else value
    with localcontext() as context:
        context.prec = 400
        decimal = Decimal(fraction.numerator) / Decimal(fraction.denominator)
    text = format(decimal.normalize(), "f")
    return text


def _variable_rank(name: str) -> tuple[int, str]:
    if name in CORE_VARIABLES:
        return (CORE_VARIABLES.index(name), "")
    return (len(CORE_VARIABLES), name)


def _join_subscript(tokens: list[tuple[str, bool]], separator: str) -> str:
    """Concatenate subscript tokens; ``separator`` goes next to any token that is not compact.

    Compact tokens (runs of one-letter variables, ``|v|``) are written together as in the
    paper's ``vvr`` and ``|v|v``; names, numbers and functions are set apart.  In LaTeX, a
    control word followed by a letter gets a space (``\\delta\\delta v``).
    """
    out = ""
    previous_compact = True
    for token, compact in tokens:
        if out and not (compact and previous_compact):
            out += separator
        elif out and re.search(r"\\[A-Za-z]+$", out) and token[0].isalpha():
            out += " "
        out += token
        previous_compact = compact
    return out


@dataclass(frozen=True)
class Term:
    """One term of a manoeuvring model, made once from its text.

    Parameters
    ----------
    text : str
        The term as written in the library file; it is also the coefficient's key.

    Attributes
    ----------
    factors : tuple of Factor
        The machine-readable form: ``(function or None, variable or number, power)`` per
        factor, in the written order; empty for the constant ``"1"``.

    Raises
    ------
    SindyshipInputError
        If ``text`` does not follow the term grammar. Use :func:`parse_term` to name the
        file and line in the message.

    Notes
    -----
    Equivalent spellings (``"v^2 r"``, ``"r v^2"``, ``"v v r"``) are different terms, since
    coefficients are keyed by the text as written; :meth:`canonical` tells them apart from
    genuinely different terms.

    Examples
    --------
    >>> term = Term("abs(v) v")
    >>> term.subscript, term.identifier("N"), term.latex("N")
    ('|v|v', 'N_absv_v', "N'_{|v|v}")
    >>> Term("1").evaluate({"v": [0.1, 0.2, 0.3]})
    array([1., 1., 1.])
    >>> Term("delta^2 v").latex("N")
    "N'_{\\\\delta\\\\delta v}"
    """

    text: str
    factors: tuple[Factor, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "factors", _parse(self.text))

    def __str__(self) -> str:
        return self.text

    # ------------------------------------------------------------------ structure
    @property
    def variables(self) -> frozenset[str]:
        """The variables the term uses (empty for a constant)."""
        return frozenset(f.base for f in self.factors if isinstance(f.base, str))

    @property
    def degree(self) -> int:
        """The sum of the exponents of the variables (0 for a constant)."""
        return sum(f.power for f in self.factors if isinstance(f.base, str))

    @property
    def is_constant(self) -> bool:
        """Whether the term uses no variable (``"1"``, or a number)."""
        return not self.variables

    def _combined(self) -> tuple[Fraction, list[Factor]]:
        """The product of the numbers, and the variable factors merged and sorted."""
        scale = Fraction(1)
        powers: dict[tuple[str | None, str], int] = {}
        for function, base, power in self.factors:
            if isinstance(base, str):
                powers[function, base] = powers.get((function, base), 0) + power
            else:
                scale *= Fraction(repr(base)) ** power
        order = {None: 0, **{name: i + 1 for i, name in enumerate(FUNCTIONS)}}
        keys = sorted(powers, key=lambda key: (_variable_rank(key[1]), order[key[0]]))
        return scale, [Factor(function, base, powers[function, base]) for function, base in keys]

    def canonical(self, *, scale: bool = True) -> str:
        """A canonical spelling: equal for equivalent terms, different for different ones.

        Like factors are merged, variables are ordered du, v, r, delta, then channels by
        name (a plain factor before functions of the same variable), and numbers are
        multiplied into one leading factor.

        Parameters
        ----------
        scale : bool
            If False, leave numbers out: terms with equal ``canonical(scale=False)`` give
            proportional columns, which a regression cannot tell apart.

        Examples
        --------
        >>> Term("r v^2").canonical(), Term("v v r").canonical(), Term("1").canonical()
        ('v^2 r', 'v^2 r', '1')
        >>> Term("2 v 0.5").canonical(), Term("3 v").canonical(scale=False)
        ('v', 'v')
        """
        number, factors = self._combined()
        words = []
        if scale and number != 1:
            words.append(_number_text(number))
        for function, base, power in factors:
            word = f"{function}({base})" if function else str(base)
            words.append(word + (f"^{power}" if power > 1 else ""))
        return " ".join(words) or "1"

    # ------------------------------------------------------------------ numbers
    def evaluate(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """The term's numeric column, evaluated element-wise.

        Parameters
        ----------
        values : mapping of str to array_like
            An array per variable (non-dimensional, as made by
            :func:`sindyship.library.nondimensional_variables`); arrays broadcast together.

        Returns
        -------
        numpy.ndarray
            The product of the factors, with the broadcast shape of the variables used; a
            constant term takes the broadcast shape of all the given arrays.

        Raises
        ------
        SindyshipInputError
            If a variable the term uses is not in ``values``.

        Examples
        --------
        >>> import numpy as np
        >>> Term("abs(v) v").evaluate({"v": np.array([-2.0, 3.0])})
        array([-4.,  9.])
        """
        arrays = {}
        for name in sorted(self.variables):
            if name not in values:
                raise SindyshipInputError(
                    f'the term {_quote(self.text)} needs the variable "{name}", '
                    f"which the data do not provide (given: {', '.join(sorted(values)) or 'none'})."
                )
            arrays[name] = np.asarray(values[name], dtype=float)
        given = arrays.values() if arrays else (np.asarray(a, dtype=float) for a in values.values())
        out = np.ones(np.broadcast_shapes(*(a.shape for a in given)))
        for function, base, power in self.factors:
            column = arrays[base] if isinstance(base, str) else base
            if function is not None:
                column = _NUMPY_FUNCTIONS[function](column)
            out = out * column**power
        return out

    def sympy(self) -> sympy.Expr:
        """The term as a sympy expression over real symbols named as the variables.

        ``abs`` becomes :class:`sympy.Abs`, ``sign`` :class:`sympy.sign`; numbers are exact
        rationals.

        Examples
        --------
        >>> Term("abs(v) v^2 0.5").sympy()
        v**2*Abs(v)/2
        """
        expr: sympy.Expr = sympy.Integer(1)
        for function, base, power in self.factors:
            if isinstance(base, str):
                atom = sympy.Symbol(base, real=True)
                if function is not None:
                    atom = _SYMPY_FUNCTIONS[function](atom)
            else:
                number = Fraction(repr(base))
                atom = sympy.Rational(number.numerator, number.denominator)
            expr = expr * atom**power
        return expr

    # ------------------------------------------------------------------ names
    def _subscript_tokens(self) -> list[tuple[tuple[str, bool], tuple[str, bool]]]:
        """Per factor: (plain text, compact) and (LaTeX, compact), see `_join_subscript`."""
        tokens = []
        for function, base, power in self.factors:
            sup_text = f"^{power}" if power > 1 else ""
            sup_latex = f"^{{{power}}}" if power > 1 else ""
            if not isinstance(base, str):
                text = _number_text(base)
                tokens.append(((text + sup_text, False), (text + sup_latex, False)))
                continue
            var = describe_variable(base)
            plain, latex = var.subscript, var.subscript_latex
            if function == "abs":
                tokens.append(((f"|{plain}|{sup_text}", True), (f"|{latex}|{sup_latex}", True)))
                continue
            if function is not None:
                name, latex_name = _TEXT_FUNCTIONS[function], _LATEX_FUNCTIONS[function]
                tokens.append(
                    (
                        (f"{name}({plain}){sup_text}", False),
                        (f"{latex_name}{sup_latex}({latex})", False),
                    )
                )
                continue
            if len(plain) == 1:
                plain_token = (plain * power, True)
            else:
                plain_token = (plain + sup_text, False)
            if _ATOMIC_LATEX_RE.fullmatch(latex):
                latex_token = (_join_subscript([(latex, True)] * power, ""), True)
            else:
                latex_token = (("{" + latex + "}" if power > 1 else latex) + sup_latex, False)
            tokens.append((plain_token, latex_token))
        return tokens

    @property
    def subscript(self) -> str:
        """The coefficient's subscript as plain text, in the paper's style.

        Variables repeat as often as their power, in the written order; ``du`` is ``u``,
        ``delta`` is ``d``; the constant is ``0``.

        Examples
        --------
        >>> [Term(t).subscript for t in ("v^2 r", "du v", "delta", "1", "sin(psi) v")]
        ['vvr', 'uv', 'd', '0', 'sin(psi) v']
        """
        if not self.factors:
            return "0"
        return _join_subscript([plain for plain, _ in self._subscript_tokens()], " ")

    def latex(self, dof: str) -> str:
        """The coefficient's name in LaTeX, as in the paper's Tables 7-9.

        Examples
        --------
        >>> Term("v r delta").latex("Y"), Term("1").latex("X")
        ("Y'_{vr\\\\delta}", "X'_{0}")
        """
        _check_dof(dof)
        if not self.factors:
            return f"{dof}'_{{0}}"
        subscript = _join_subscript([latex for _, latex in self._subscript_tokens()], r"\,")
        return f"{dof}'_{{{subscript}}}"

    def identifier(self, dof: str) -> str:
        """A Python identifier for the coefficient, e.g. ``Y_vvr``, ``N_absv_v``, ``X_0``.

        Plain products of du, v, r and delta read as in the paper (``Y_vvr``, ``X_uvd``);
        other factors are separated by underscores (``N_absv_v``, ``N_sinpsi``, ``N_psi2``,
        ``X_0p5_v``).  Terms with different :meth:`canonical` forms get different
        identifiers unless channel names are chosen to mimic them (channels named
        ``absv`` or ``psi2``); :class:`sindyship.library.TermLibrary` checks this per
        degree of freedom.

        Examples
        --------
        >>> [Term(t).identifier("N") for t in ("v^2 r", "abs(v) v", "1", "psi^2 v")]
        ['N_vvr', 'N_absv_v', 'N_0', 'N_psi2_v']
        """
        _check_dof(dof)
        if not self.factors:
            return f"{dof}_0"
        items: list[str] = []
        run = ""
        for function, base, power in self.factors:
            core = isinstance(base, str) and base in CORE_VARIABLES
            if core and function is None:
                run += VARIABLES[base].subscript * power
                continue
            if run:
                items.append(run)
                run = ""
            suffix = str(power) if power > 1 else ""
            if isinstance(base, str):
                name = VARIABLES[base].subscript if core else base
                items.append(f"{function or ''}{name}{suffix}")
            else:
                number = _number_text(base).replace(".", "p")
                items.append(number + (f"pow{suffix}" if suffix else ""))
        if run:
            items.append(run)
        return f"{dof}_" + "_".join(items)

    def latex_term(self) -> str:
        """The LaTeX of the monomial, e.g. ``v'^{2} r'`` or ``\\Delta u'``.

        Examples
        --------
        >>> Term("du^2 v").latex_term()
        "\\\\Delta u'^{2} v'"
        >>> Term("abs(r) r sin(psi)").latex_term()
        "|r'| r' \\\\sin(\\\\psi)"
        """
        if not self.factors:
            return "1"
        words = []
        for function, base, power in self.factors:
            sup = f"^{{{power}}}" if power > 1 else ""
            if not isinstance(base, str):
                words.append(_number_text(base) + sup)
                continue
            symbol = describe_variable(base).symbol
            if function is None:
                words.append(symbol + sup)
            elif function == "abs":
                words.append(f"|{symbol}|{sup}")
            else:
                words.append(f"{_LATEX_FUNCTIONS[function]}{sup}({symbol})")
        return " ".join(words)


def _check_dof(dof: str) -> None:
    if not (isinstance(dof, str) and re.fullmatch(r"[A-Z][A-Za-z0-9]*", dof)):
        raise ValueError(f"a degree of freedom is a capitalised name such as X or N, not {dof!r}")

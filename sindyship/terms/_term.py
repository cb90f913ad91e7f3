"""A term: its parsed factors, its numbers, its printed, LaTeX and sympy forms."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from decimal import Decimal, localcontext
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import SindyshipInputError
from ._parser import Factor, _message, _parse, _quote, _TermError
from ._variables import (
    _ATOMIC_LATEX_RE,
    _LATEX_FUNCTIONS,
    _NUMPY_FUNCTIONS,
    _SYMPY_FUNCTIONS,
    _TEXT_FUNCTIONS,
    CORE_VARIABLES,
    FUNCTIONS,
    VARIABLES,
    describe_variable,
)

if TYPE_CHECKING:
    import sympy


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


def evaluate_factor(factor: Factor, values: Mapping[str, np.ndarray]):
    """One factor ``(function, base, power)`` of a term, evaluated on the variables: the one
    place a term's numbers are made (:meth:`Term.evaluate` and a fitted model's forces).

    Examples
    --------
    >>> evaluate_factor(Factor("abs", "v", 2), {"v": np.array([-2.0, 3.0])})
    array([4., 9.])
    """
    function, base, power = factor
    if isinstance(base, str):
        if base not in values:
            raise SindyshipInputError(
                f"the model needs the variable {base!r}, which the data do not provide."
            )
        column = np.asarray(values[base], dtype=float)
    else:
        column = float(base)
    if function is not None:
        column = _NUMPY_FUNCTIONS[function](column)
    return column**power if power != 1 else column


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
        for factor in self.factors:
            out = out * evaluate_factor(factor, arrays)
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
        import sympy

        expr: sympy.Expr = sympy.Integer(1)
        for function, base, power in self.factors:
            if isinstance(base, str):
                atom = sympy.Symbol(base, real=True)
                if function is not None:
                    atom = getattr(sympy, _SYMPY_FUNCTIONS[function])(atom)
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

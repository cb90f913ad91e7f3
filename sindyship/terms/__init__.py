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

from ._parser import Factor
from ._shapes import (
    BANK_NEAREST,
    SHAPE_KINDS,
    Shape,
    describe_shape,
    is_shape_name,
    parse_shape,
    shape_name,
    shape_values,
)
from ._term import Term, evaluate_factor, parse_term
from ._variables import (
    ANGLE_CHANNELS,
    CORE_VARIABLES,
    DERIVED_SOURCES,
    FUNCTIONS,
    MAX_DEGREE,
    MAX_FACTORS,
    MAX_TERM_LENGTH,
    SPEED_FLOOR,
    VARIABLES,
    Variable,
    channel_scaling,
    describe_variable,
    is_variable_name,
    read_over_speed,
    sources_of,
)

__all__ = [
    "BANK_NEAREST",
    "CORE_VARIABLES",
    "DERIVED_SOURCES",
    "SPEED_FLOOR",
    "FUNCTIONS",
    "Factor",
    "MAX_DEGREE",
    "MAX_FACTORS",
    "MAX_TERM_LENGTH",
    "SHAPE_KINDS",
    "Shape",
    "Term",
    "VARIABLES",
    "Variable",
    "ANGLE_CHANNELS",
    "channel_scaling",
    "describe_shape",
    "describe_variable",
    "evaluate_factor",
    "is_shape_name",
    "is_variable_name",
    "parse_shape",
    "parse_term",
    "read_over_speed",
    "shape_name",
    "shape_values",
    "sources_of",
]

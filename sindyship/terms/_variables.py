"""The variables a term may use, their non-dimensionalisation and printed names."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from ._shapes import describe_shape, is_shape_name, parse_shape

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


def is_variable_name(name) -> bool:
    """Whether ``name`` can be a variable of the term grammar: lower-case letters, digits and
    single underscores, starting with a letter (the form of a measurement CSV's channels).

    Examples
    --------
    >>> is_variable_name("wave_height"), is_variable_name("Heel"), is_variable_name("a__b")
    (True, False, False)
    """
    return isinstance(name, str) and _NAME_RE.fullmatch(name) is not None


_NUMPY_FUNCTIONS = {"abs": np.abs, "sign": np.sign, "sin": np.sin, "cos": np.cos}
#: The sympy function of each of the grammar's functions, by name (sympy is imported only
#: where an expression is made: it costs every command a fifth of a second).
_SYMPY_FUNCTIONS = {"abs": "Abs", "sign": "sign", "sin": "sin", "cos": "cos"}
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
        if recorded, else the commanded one; ``"rudder_rate"`` its rate of change, by central
        differences in a record and from the servo in a flight).
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
            Variable("delta_rate", "rudder_rate", "rate", r"\dot{\delta}'", "ddot",
                     r"\dot{\delta}", "rudder rate d(delta)/dt L/U0"),
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
            Variable("wind_app_speed", "apparent_wind", "speed", "V_{A}'", "VA", "V_{A}",
                     "apparent wind speed over U0, from the true wind and the ship's motion"),
            Variable("wind_app_angle", "apparent_wind", "none", r"\gamma_{A}", "gA",
                     r"\gamma_{A}", "angle off the bow the apparent wind comes from, "
                     "positive from starboard [rad]"),
        )
    }
)

#: The least speed U/U0 of the ``instantaneous`` speed form (variables over the speed U): a
#: ship at rest has no U to divide by.
SPEED_FLOOR = 0.05

#: Variables made from the ship's motion and recorded channels, with the channels they need:
#: in a flight they follow the flown motion, never the recorded one.
DERIVED_SOURCES: Mapping[str, tuple[str, ...]] = MappingProxyType({
    "wind_app_speed": ("wind_speed", "wind_dir"),
    "wind_app_angle": ("wind_speed", "wind_dir"),
})


def sources_of(name: str) -> tuple[str, ...]:
    """The recorded channels a variable is made from: itself, or a derived variable's sources.

    Examples
    --------
    >>> sources_of("wind_app_angle"), sources_of("n")
    (('wind_speed', 'wind_dir'), ('n',))
    """
    if is_shape_name(name):
        return ("x", "y")
    return DERIVED_SOURCES.get(name, (name,))


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
    shape = parse_shape(name)
    if shape is not None:
        latex = r"\mathrm{" + name.replace("_", r"\_") + "}"
        return Variable(name, "position", "none", latex, name, latex, describe_shape(shape))
    latex = r"\mathrm{" + name.replace("_", r"\_") + "}"
    return Variable(name, name, "none", latex, name, latex, f"channel {name} as recorded")


def read_over_speed(name: str) -> bool:
    """Whether the ``instantaneous`` speed form reads a variable over the speed U: those
    made non-dimensional with U0 (the ``speed`` and ``rate`` scalings, e.g. n L/U0).

    Examples
    --------
    >>> read_over_speed("n"), read_over_speed("psi")
    (True, False)
    """
    return describe_variable(name).scaling in ("speed", "rate")


#: Recorded channels that are angles: a delay reads them unwrapped
#: (:meth:`sindyship.library.TermLibrary.aligned`).
ANGLE_CHANNELS = ("delta", "delta_c", "wind_dir", "phi")


def channel_scaling(name: str, L: float, U0: float) -> tuple[float, float]:
    """``(factor, offset)`` that turn a channel in SI into the library's scaling,
    ``value * factor + offset`` (the scalings of :func:`nondimensional_variables`).

    Examples
    --------
    >>> channel_scaling("n", 230.0, 12.348)[0] == 230.0 / 12.348
    True
    """
    kind = describe_variable(name).scaling
    return {"surge": (1.0 / U0, -1.0), "speed": (1.0 / U0, 0.0), "rate": (L / U0, 0.0),
            "none": (1.0, 0.0)}[kind]

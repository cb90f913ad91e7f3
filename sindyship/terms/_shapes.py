"""Shape variables: smooth functions of the ship's position that name their own parameters.

A bank, a canal wall or the edge of a shallow patch changes the forces where the ship is.
A shape variable is such a function of the position (x north, y east [m]), and its name
carries its parameters, so that a term such as ``edge_b000_p020_w05 v`` is read, flown and
saved like any other (docs/term-grammar.md).  Every shape is measured across a straight line
whose normal points to the bearing ``b`` (whole degrees clockwise from north) and which lies
``p`` (ahead) or ``m`` (behind) the origin along that bearing, in tenths of a ship length:

``edge_bBBB_{p|m}DDD_wWW``
    A smooth step from 0 to 1 across the line, ``WW`` tenths of a ship length wide:
    ``0.5 (1 + tanh(s / w))`` with ``s`` the signed distance beyond the line.  Multiplying a
    hull term (``edge_... v``) makes a derivative that changes across the line: a shallow
    patch, a channel, a change of water.
``bank_bBBB_{p|m}DDD``
    The pull toward the line of a bank: ``sign(d) (L / max(|d|, L/2))^2`` with ``d`` the
    signed distance from the ship to the line along the bearing (positive when the line is
    ahead).  With ``sin(psi)`` and ``cos(psi)`` it makes an earth-fixed force toward the
    bank that grows as the ship comes close (bank suction falls off with the square of the
    distance, Norrbin 1974).

Examples
--------
>>> shape = parse_shape("edge_b000_p020_w05")
>>> shape.kind, shape.bearing, shape.distance, shape.width
('edge', 0.0, 2.0, 0.5)
>>> shape_name("bank", 90.0, -8.0)
'bank_b090_m080'
>>> import numpy as np
>>> shape_values(shape, np.array([0.0, 2.0, 10.0]) * 100.0, np.zeros(3), L=100.0).round(3)
array([0. , 0.5, 1. ])
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

#: The kinds of shape, with the parameters their names carry.
SHAPE_KINDS = ("edge", "bank")
_SHAPE_RE = re.compile(r"(edge|bank)_b(\d{3})_([pm])(\d{3,})(?:_w(\d{2,}))?")
#: The start of every shape name: a variable that starts so and is not a shape is refused.
SHAPE_PREFIX = re.compile(r"(edge|bank)_b\d")
#: The least distance to a bank's line [ship lengths]: nearer, the pull is held.
BANK_NEAREST = 0.5


@dataclass(frozen=True)
class Shape:
    """A shape variable's parameters (see the module docstring).

    Attributes
    ----------
    kind : {"edge", "bank"}
    bearing : float
        Direction of the line's normal [deg clockwise from north], whole degrees.
    distance : float
        Where the line lies along the bearing from the origin [ship lengths], in tenths.
    width : float
        The width of an edge's step [ship lengths] (0 for a bank).
    """

    kind: str
    bearing: float
    distance: float
    width: float = 0.0

    @property
    def name(self) -> str:
        return shape_name(self.kind, self.bearing, self.distance, self.width)


def parse_shape(name: str) -> Shape | None:
    """The :class:`Shape` a variable name stands for, or None when it is not a shape.

    Examples
    --------
    >>> parse_shape("bank_b270_p080"), parse_shape("edge_b000_p020") is None
    (Shape(kind='bank', bearing=270.0, distance=8.0, width=0.0), True)
    """
    if not isinstance(name, str):
        return None
    match = _SHAPE_RE.fullmatch(name)
    if match is None:
        return None
    kind, bearing, sign, distance, width = match.groups()
    if (kind == "edge") != (width is not None) or int(bearing) >= 360:
        return None
    if kind == "edge" and int(width) == 0:
        return None
    shape = Shape(kind, float(bearing), (1 if sign == "p" else -1) * int(distance) / 10.0,
                  int(width) / 10.0 if width is not None else 0.0)
    return shape if shape.name == name else None  # one name for one shape


def is_shape_name(name) -> bool:
    """Whether ``name`` is a shape variable (:func:`parse_shape`)."""
    return parse_shape(name) is not None


def shape_name_error(name: str) -> str | None:
    """Why a variable named like a shape (``edge_b...``, ``bank_b...``) is not one, or None.

    Examples
    --------
    >>> shape_name_error("edge_b000_p20_w5")
    'a shape name is edge_bBBB_pDDD_wWW or bank_bBBB_pDDD (bearing in whole degrees 000-359, \
distance in tenths of a ship length with at least three digits, p ahead or m behind, width in \
tenths with at least two digits, not 00), e.g. edge_b000_p020_w05'
    >>> shape_name_error("depth") is None
    True
    """
    if not isinstance(name, str) or not SHAPE_PREFIX.match(name) or is_shape_name(name):
        return None
    return ("a shape name is edge_bBBB_pDDD_wWW or bank_bBBB_pDDD (bearing in whole degrees "
            "000-359, distance in tenths of a ship length with at least three digits, p ahead "
            "or m behind, width in tenths with at least two digits, not 00), e.g. "
            "edge_b000_p020_w05")


def shape_name(kind: str, bearing: float, distance: float, width: float = 0.0) -> str:
    """The variable name of a shape: bearing rounded to whole degrees (modulo 360), distance
    and width to tenths of a ship length.

    Examples
    --------
    >>> shape_name("edge", -15.2, 2.04, 0.5)
    'edge_b345_p020_w05'
    """
    if kind not in SHAPE_KINDS:
        raise ValueError(f"a shape is one of {', '.join(SHAPE_KINDS)}, not {kind!r}")
    if not (math.isfinite(bearing) and math.isfinite(distance) and math.isfinite(width)):
        raise ValueError("a shape's bearing, distance and width must be finite numbers")
    tenths = int(round(distance * 10.0))
    name = f"{kind}_b{int(round(bearing)) % 360:03d}_{'p' if tenths >= 0 else 'm'}{abs(tenths):03d}"
    if kind == "edge":
        name += f"_w{max(int(round(width * 10.0)), 1):02d}"
    return name


def shape_values(shape: Shape, x, y, L: float) -> np.ndarray:
    """The shape at positions ``x`` (north), ``y`` (east) [m] of a ship of length ``L`` [m]."""
    bearing = math.radians(shape.bearing)
    across = (np.asarray(x, dtype=float) * math.cos(bearing)
              + np.asarray(y, dtype=float) * math.sin(bearing)) / L - shape.distance
    if shape.kind == "edge":
        return 0.5 * (1.0 + np.tanh(across / shape.width))
    ahead = -across
    return np.sign(ahead) / np.maximum(np.abs(ahead), BANK_NEAREST) ** 2


def describe_shape(shape: Shape) -> str:
    """One line for people: what the shape is."""
    where = (f"a line at {shape.distance:+.1f} L from the origin along the bearing "
             f"{shape.bearing:03.0f} deg")
    if shape.kind == "edge":
        return f"a smooth step from 0 to 1 across {where}, {shape.width:.1f} L wide"
    return f"the pull of a bank along {where}, (L / distance)^2"

"""Units of measurement-CSV headers: ``name [unit]`` parsed into a name and a factor to SI.

A header may carry its unit in brackets, ``psi [deg]`` (docs/measurement-csv.md).
:data:`UNITS` lists the recognised spellings; the channels the contract names must carry a unit
of their quantity (``psi`` an angle, ``u`` a speed, ...), other channels accept any recognised
unit.  Used by :mod:`sindyship.measurements`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from sindyship.errors import SindyshipInputError

__all__ = ["COMMON_NAMES", "UNITS", "Column", "parse_headers", "renaming_hint", "unit_factor"]

_DEG = math.pi / 180.0

#: Recognised units: spelling -> (quantity, factor to the SI unit of that quantity).  Spaces in
#: a unit are ignored; the case must match unless only one entry matches case-insensitively
#: (``KN`` is refused because it could be knots ``kn`` or kilonewtons ``kN``).
UNITS: dict[str, tuple[str, float]] = {
    "-": ("dimensionless", 1.0),
    "1": ("dimensionless", 1.0),
    "rad": ("angle", 1.0),
    "deg": ("angle", _DEG),
    "degree": ("angle", _DEG),
    "degrees": ("angle", _DEG),
    "\u00b0": ("angle", _DEG),
    "rad/s": ("angular rate", 1.0),
    "deg/s": ("angular rate", _DEG),
    "\u00b0/s": ("angular rate", _DEG),
    "deg/min": ("angular rate", _DEG / 60.0),
    "m/s": ("speed", 1.0),
    "kn": ("speed", 1852.0 / 3600.0),
    "kt": ("speed", 1852.0 / 3600.0),
    "kts": ("speed", 1852.0 / 3600.0),
    "knot": ("speed", 1852.0 / 3600.0),
    "knots": ("speed", 1852.0 / 3600.0),
    "km/h": ("speed", 1.0 / 3.6),
    "m": ("length", 1.0),
    "km": ("length", 1000.0),
    "cm": ("length", 0.01),
    "mm": ("length", 0.001),
    "nmi": ("length", 1852.0),
    "s": ("time", 1.0),
    "ms": ("time", 0.001),
    "min": ("time", 60.0),
    "h": ("time", 3600.0),
    "rps": ("revolutions", 1.0),
    "rev/s": ("revolutions", 1.0),
    "1/s": ("revolutions", 1.0),
    "Hz": ("revolutions", 1.0),
    "rpm": ("revolutions", 1.0 / 60.0),
    "rev/min": ("revolutions", 1.0 / 60.0),
    "N": ("force", 1.0),
    "kN": ("force", 1000.0),
    "MN": ("force", 1.0e6),
    "Nm": ("moment", 1.0),
    "N*m": ("moment", 1.0),
    "kNm": ("moment", 1000.0),
    "kN*m": ("moment", 1000.0),
    "kN.m": ("moment", 1000.0),
    "MNm": ("moment", 1.0e6),
    "MN*m": ("moment", 1.0e6),
    "N.m": ("moment", 1.0),
}

_SI_UNIT = {
    "dimensionless": "-",
    "angle": "rad",
    "angular rate": "rad/s",
    "speed": "m/s",
    "length": "m",
    "time": "s",
    "revolutions": "rps",
    "force": "N",
    "moment": "Nm",
}

# The quantity of the channels the contract names; other channels accept any recognised unit.
_QUANTITY = {
    "t": "time",
    "u": "speed",
    "v": "speed",
    "r": "angular rate",
    "p": "angular rate",
    "x": "length",
    "y": "length",
    "psi": "angle",
    "phi": "angle",
    "delta": "angle",
    "delta_c": "angle",
    "n": "revolutions",
    "wind_speed": "speed",
    "wind_dir": "angle",
    "depth": "length",
}

_HEADER = re.compile(r"^(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?$")

@dataclass(frozen=True)
class Column:
    header: str  # as written, e.g. "psi [deg]"
    name: str  # bare name, e.g. "psi"
    unit: str | None  # as written, e.g. "deg", or None when the header has no unit
    factor: float  # multiplies the values to give SI


def parse_headers(headers: list[str], source: str) -> list[Column]:
    columns: list[Column] = []
    seen: dict[str, str] = {}
    for position, text in enumerate(headers, start=1):
        header = text.strip()
        match = _HEADER.match(header)
        if match is None:
            raise SindyshipInputError(
                f"{source}: column {position} has the malformed header '{header}'; write a "
                "name optionally followed by one unit in brackets, e.g. 'psi [deg]'."
            )
        name = match["name"].strip()
        unit = match["unit"]
        if not name:
            raise SindyshipInputError(
                f"{source}: column {position} has no name; give every column a name in the "
                "header row."
            )
        if name in seen:
            raise SindyshipInputError(
                f"{source}: the columns '{seen[name]}' and '{header}' are both '{name}'; "
                "keep one of them or rename the other."
            )
        seen[name] = header
        factor = 1.0
        if unit is not None:
            unit = unit.strip()
            factor = unit_factor(name, header, unit, source)
        columns.append(Column(header=header, name=name, unit=unit, factor=factor))
    return columns


def unit_factor(name: str, header: str, unit: str, source: str) -> float:
    """The factor to SI of ``unit`` in the column ``header`` of channel ``name`` (refused in one
    sentence naming ``source`` when unknown, ambiguous or of another quantity)."""
    key = unit.replace(" ", "")
    if key not in UNITS:
        matches = [spelling for spelling in UNITS if spelling.lower() == key.lower()]
        if len(matches) > 1:
            raise SindyshipInputError(
                f"{source}: column '{header}' has the ambiguous unit '{unit}' (it could be "
                f"{' or '.join(matches)}); write the unit with the right upper and lower case."
            )
        key = matches[0] if matches else ""
    if not key:
        known = _units_for(_QUANTITY.get(name))
        raise SindyshipInputError(
            f"{source}: column '{header}' has the unknown unit '{unit}'; use one of {known}."
        )
    quantity, factor = UNITS[key]
    expected = _QUANTITY.get(name)
    if expected is not None and quantity != expected:
        raise SindyshipInputError(
            f"{source}: column '{header}' gives a unit of {quantity} but '{name}' is "
            f"{_article(expected)} {expected}; use one of {_units_for(expected)}."
        )
    return factor


def _units_for(quantity: str | None) -> str:
    spellings = [key for key, (kind, _) in UNITS.items() if quantity in (None, kind)]
    return ", ".join(spellings)


def _article(word: str) -> str:
    return "an" if word[0] in "aeiou" else "a"


#: Names other logs give the required channels (lower case), by the name sindyship reads.
COMMON_NAMES = {
    "t": ("time", "time_s", "timestamp"),
    "u": ("surge", "surge_speed", "u_body"),
    "v": ("sway", "sway_speed", "v_body"),
    "r": ("yaw_rate", "yawrate", "rot"),
    "x": ("x0", "north", "x_earth"),
    "y": ("y0", "east", "y_earth"),
    "psi": ("heading", "hdg", "yaw", "heading_rad"),
    "delta": ("rudder", "rudder_angle", "rudder_deg"),
}


def renaming_hint(wanted: list[str], present: list[str]) -> str:
    """The hint to rename a present column that is a common name (:data:`COMMON_NAMES`) of
    the first missing channel it can be, else "".

    Examples
    --------
    >>> renaming_hint(["psi"], ["t", "u", "Heading"])
    " (is 'Heading' the channel psi? rename the column psi)"
    """
    for name in wanted:
        for column in present:
            if column.lower() in COMMON_NAMES.get(name, ()):
                return f" (is '{column}' the channel {name}? rename the column {name})"
    return ""

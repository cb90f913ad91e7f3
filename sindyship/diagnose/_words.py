"""The words of :func:`sindyship.diagnose.discover`: what a finding usually means, its title
and physics paragraph in the effect file it writes, and TOML strings."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence

from ..library import DOFS
from ..terms import SHAPE_KINDS, describe_shape, parse_shape

__all__ = ["_hint", "_physics", "_title", "_toml_string", "shape_words"]


def shape_words(variables, intervals) -> str:
    """The shape of the position among ``variables`` in words, with the 95 % intervals of its
    line's bearing and distance when given (empty when there is none).

    Examples
    --------
    >>> shape_words(["v", "edge_b000_p020_w05"], {"distance_L": [1.9, 2.1]})
    'Shape: a smooth step from 0 to 1 across a line at +2.0 L from the origin along the \
bearing 000 deg, 0.5 L wide (95 % intervals when the manoeuvres are resampled: distance 1.9 \
to 2.1 L)'
    """
    shape = next((parse_shape(v) for v in sorted(variables) if parse_shape(v)), None)
    if shape is None:
        return ""
    ranges = []
    if "bearing_deg" in intervals:
        low, high = intervals["bearing_deg"]
        ranges.append(f"bearing {low:.1f} to {high:.1f} deg")
    if "distance_L" in intervals:
        low, high = intervals["distance_L"]
        ranges.append(f"distance {low:.1f} to {high:.1f} L")
    return (f"Shape: {describe_shape(shape)}"
            + (f" (95 % intervals when the manoeuvres are resampled: {', '.join(ranges)})"
               if ranges else ""))


def _toml_string(text: str) -> str:
    r"""A TOML basic string of ``text``; a byte of a file name that was not UTF-8 (held as a
    lone surrogate, which TOML cannot carry) is written as ``\xff``.

    Characters beyond U+FFFF are written as they are (JSON's surrogate-pair escapes are not
    TOML), control characters as ``\uXXXX``.

    Examples
    --------
    >>> import tomllib
    >>> text = "run\udcff \U0001f600\x7f"
    >>> tomllib.loads("a = " + _toml_string(text))["a"] == "run\\xff \U0001f600\x7f"
    True
    """
    try:
        readable = text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate that no byte gave
        readable = text.encode("utf-8", "backslashreplace").decode("utf-8")
    return json.dumps(readable, ensure_ascii=False).replace("\x7f", "\\u007f")


# ------------------------------------------------------------------------------- words
_HINTS = {
    "heading": "forces that follow the heading: a load fixed to the earth (an unlogged wind, "
               "a current, a towline); log the wind and use the catalogued wind or environment",
    "position": "forces that depend on where the ship is: a spatial field such as a bank, a "
                "shallow patch or a current that varies in space (with sin or cos of psi, a "
                "force fixed to the earth that grows toward one side)",
    "rudder": "a rudder force that departs from the cubic at large angles: the rudder stalls "
              "or saturates",
    "motion": "hull forces beyond the third order in v and r: large drift angles or yaw rates "
              "(cross-flow drag, vortex shedding)",
    "rate": "a rudder force that follows the rudder's rate of change: the recorded angle leads "
            "or lags the force it causes (the delay search says by how much)",
    "edge": "hull or rudder forces that change across a line: shallow water or a channel "
            "beyond an edge (log the depth and refit with it as a channel), a change of "
            "current",
    "bank": "an earth-fixed pull toward a line the ship does not cross that grows as the ship "
            "comes close: the suction of a bank or a quay wall",
}


def _hint(family: str, delays: Mapping[str, float], terms: Mapping[str, Sequence[str]],
          logged_wind: bool = False) -> str:
    if delays:
        channel, tau = next(iter(delays.items()))
        side = "lags" if tau > 0 else "leads"
        return (f"the recorded {channel} {side} the force it causes by {abs(tau):.1f} s: a slow "
                "or filtered sensor, or a logging delay between the channels")
    if family == "heading" and logged_wind:
        return ("forces that follow the heading although the records log the wind: a load "
                "fixed to the earth that the wind channels do not carry (a current, a towline), "
                "or a wind the catalogued wind effect models poorly")
    if family.startswith("channel:"):
        channel = family.split(":", 1)[1]
        return f"the forces follow the recorded channel {channel}, which the library ignores"
    if family == "rudder":
        used = {t for dof in DOFS for t in terms.get(dof, [])}
        if used and all("abs(" in t or "^4" in t or "^5" in t for t in used):
            return _HINTS["rudder"] + " (only the large rudder angles carry it)"
    return _HINTS.get(family, "")


def _title(finding) -> str:
    if finding.delays:
        channel, tau = next(iter(finding.delays.items()))
        return f"{channel} late by {tau:.1f} s (discovered)"
    if finding.family in SHAPE_KINDS:
        what = "Forces that change across" if finding.family == "edge" else "The pull of a bank on"
        shape = next(parse_shape(v) for v in finding.variables if parse_shape(v))
        return (f"{what} a line {shape.distance:+.1f} L along the bearing "
                f"{shape.bearing:03.0f} deg (discovered)")
    return f"Missing {finding.family} terms (discovered)"


def _physics(finding, records: Sequence[str]) -> str:
    shares = ", ".join(f"{dof} {finding.signal_by_dof[dof]:.0%}" for dof in DOFS
                       if finding.significant.get(dof))
    what = (", ".join(f"{c} read {d:+.2f} s later" for c, d in finding.delays.items())
            if finding.delays else
            "; ".join(f"{dof}: {', '.join(ts)}" for dof, ts in finding.terms.items() if ts))
    line = shape_words(finding.variables, finding.intervals)
    if line:
        what = f"{line}. {what}"
    return (f"Discovered by sindyship discover from {len(records)} records "
            f"({', '.join(records)}); not in the catalogue. {what}. It explains "
            f"{finding.explained_signal:.0%} of the cross-validated force error above the noise "
            f"floor ({shares}). What it usually means: {finding.hint}. Check it with "
            "sindyship diagnose --effects on records it was not found on.")

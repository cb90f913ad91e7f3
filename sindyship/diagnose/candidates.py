"""Candidate terms beyond the catalogue, built with pysindy feature libraries.

Every family is a pysindy feature library (its public API: ``PolynomialLibrary``,
``FourierLibrary``, ``CustomLibrary`` and their tensor products) over variables of the records,
non-dimensional as the term grammar defines them (docs/term-grammar.md), and every feature name
is rewritten into a term of that grammar, so that a discovered term can be written into an
effect file, parsed by the whitelist parser and flown:

``heading``
    ``sin(psi)``, ``cos(psi)``: forces fixed to the earth.
``position``
    Polynomials up to degree 2 in the position ``x``, ``y`` [m] times ``sin(psi)`` and
    ``cos(psi)`` (the tensor product of a polynomial and a Fourier library): an earth-fixed
    force whose size depends on where the ship is, such as the suction of a bank or a current
    that varies in space.
``rudder``
    Rudder terms beyond the cubic: ``delta^5``, ``abs(delta) delta``, ``abs(delta)^3 delta``
    in sway and yaw, ``delta^4``, ``abs(delta)^3`` in surge (a rudder force that saturates or
    stalls at large angles).
``rate``
    The rudder rate ``delta_rate`` in sway and yaw (an angle signal that leads or lags the
    force it causes; a flight takes the rate its servo moves at).
``motion``
    Fifth-order terms in v' and r' in sway and yaw, fourth-order ones in surge.
``channel:NAME``
    A recorded channel the library does not use: the channel, its square and its products with
    v', r' and delta.

The delays of channels (a sensor that lags) are searched separately
(:mod:`sindyship.diagnose.discovery`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..library import DOFS, SPEED_FACTOR, nondimensional_variables
from ..terms import CORE_VARIABLES, Term, is_variable_name

#: Channels that are never candidates of their own (time, motion, positions, heading, rudder).
NOT_CHANNELS = frozenset({"t", "u", "v", "r", "x", "y", "psi", "delta", "delta_c"})

def unnamed_channels(records: Sequence) -> list[str]:
    """Columns every record has that no term can name (``"Heel"``, ``"wave height"``): the
    search leaves them out and the report says how to search them (rename the column).

    Parameters
    ----------
    records : sequence of Trajectory

    Returns
    -------
    list of str
        The columns, sorted; term variables are lower-case letters, digits and single
        underscores (docs/term-grammar.md).

    Examples
    --------
    >>> import pandas as pd
    >>> from sindyship.trajectory import Trajectory
    >>> frame = pd.DataFrame({"t": [0.0], "u": [1.0], "Heel": [0.0], "depth": [9.0]})
    >>> unnamed_channels([Trajectory(frame, name="run")])
    ['Heel']
    """
    shared = set.intersection(*(set(r.data.columns) for r in records)) if records else set()
    return sorted(c for c in shared - NOT_CHANNELS if not is_variable_name(c))


@dataclass(frozen=True)
class Family:
    """A family of candidate terms.

    Attributes
    ----------
    name : str
        ``heading``, ``position``, ``rudder``, ``motion`` or ``channel:NAME``.
    terms : dict of str to tuple of str
        The candidate terms per degree of freedom, in the term grammar.
    variables : tuple of str
        The variables the family's terms use.
    """

    name: str
    terms: Mapping[str, tuple[str, ...]]
    variables: tuple[str, ...]

    @classmethod
    def of(cls, name: str, terms: Mapping[str, Sequence[str]]) -> Family:
        """The family of ``terms``, with the variables they use."""
        variables = {v for texts in terms.values() for t in texts for v in Term(t).variables}
        return cls(name, {dof: tuple(terms.get(dof, ())) for dof in DOFS},
                   tuple(sorted(variables)))


def _grammar(name: str) -> str:
    """A pysindy feature name as a term: ``sin(1 psi)`` -> ``sin(psi)``, ``1 cos(1 psi)`` ->
    ``cos(psi)``.

    Examples
    --------
    >>> _grammar("1 sin(1 psi)"), _grammar("x y cos(1 psi)"), _grammar("v^4 r")
    ('sin(psi)', 'x y cos(psi)', 'v^4 r')
    """
    text = re.sub(r"(sin|cos)\(1 ", r"\1(", name)
    parts = [p for p in text.split(" ") if p != "1"]
    return " ".join(parts) or "1"


def _feature_names(library, inputs: Sequence[str], sample: np.ndarray) -> list[str]:
    library.fit(sample)
    return [_grammar(n) for n in library.get_feature_names(list(inputs))]


def families(records: Sequence, library, ship) -> list[Family]:
    """The candidate families the records can test, terms the library lacks removed.

    Parameters
    ----------
    records : sequence of Trajectory
    library : TermLibrary
        The fitted library: candidates it already has (up to a constant factor) are left out.
    ship : Ship
    """
    import pysindy as ps

    sample = np.linspace(-1.0, 1.0, 12).reshape(4, 3)
    present = {dof: {t.canonical(scale=False) for t in library.terms[dof]} for dof in DOFS}
    out = []

    def add(name: str, by_dof: Mapping[str, Sequence[str]], variables: Sequence[str]) -> None:
        terms = {dof: tuple(t for t in by_dof.get(dof, ())
                            if Term(t).canonical(scale=False) not in present[dof])
                 for dof in DOFS}
        if any(terms.values()):
            out.append(Family(name, terms, tuple(variables)))

    heading = _feature_names(ps.FourierLibrary(n_frequencies=1), ["psi"], sample[:, :1])
    add("heading", dict.fromkeys(DOFS, heading), ["psi"])

    earth = ps.TensoredLibrary([ps.PolynomialLibrary(degree=2, include_bias=False),
                                ps.FourierLibrary(n_frequencies=1)],
                               inputs_per_library=[[0, 1], [2]])
    position = _feature_names(earth, ["x", "y", "psi"], sample)
    add("position", dict.fromkeys(DOFS, position), ["x", "y", "psi"])

    odd = ps.CustomLibrary(
        library_functions=[lambda a: a**5, lambda a: np.abs(a) * a, lambda a: np.abs(a) ** 3 * a],
        function_names=[lambda a: f"{a}^5", lambda a: f"abs({a}) {a}",
                        lambda a: f"abs({a})^3 {a}"])
    even = ps.CustomLibrary(library_functions=[lambda a: a**4, lambda a: np.abs(a) ** 3],
                            function_names=[lambda a: f"{a}^4", lambda a: f"abs({a})^3"])
    odd_rudder = _feature_names(odd, ["delta"], sample[:, :1])
    add("rudder", {"X": _feature_names(even, ["delta"], sample[:, :1]), "Y": odd_rudder,
                   "N": odd_rudder}, ["delta"])

    rate = _feature_names(ps.PolynomialLibrary(degree=1, include_bias=False), ["delta_rate"],
                          sample[:, :1])
    add("rate", {"Y": rate, "N": rate}, ["delta_rate"])

    hull = [Term(t) for t in _feature_names(ps.PolynomialLibrary(degree=5, include_bias=False),
                                            ["v", "r"], sample[:, :2])]
    add("motion", {"X": [t.text for t in hull if t.degree == 4],
                   "Y": [t.text for t in hull if t.degree == 5],
                   "N": [t.text for t in hull if t.degree == 5]}, ["v", "r"])

    shared = set.intersection(*(set(r.data.columns) for r in records)) if records else set()
    for channel in sorted(shared - NOT_CHANNELS - set(library.variables)
                          - set(unnamed_channels(records))):
        values = np.concatenate([r[channel] for r in records])
        finite = values[np.isfinite(values)]
        if finite.size == 0 or np.ptp(finite) <= 1e-12 * max(1.0, float(np.abs(finite).max())):
            continue
        terms = _feature_names(ps.PolynomialLibrary(degree=2, include_bias=False),
                               [channel, *CORE_VARIABLES[1:]], np.tile(sample[:, :1], (1, 4)))
        with_channel = [t for t in terms if channel in Term(t).variables
                        and Term(t).degree <= 2 and "du" not in Term(t).variables]
        add(f"channel:{channel}", dict.fromkeys(DOFS, with_channel), [channel])
    return out


def family_columns(family: Family, records: Sequence, library, ship, rudder_signal: str
                   ) -> dict[str, np.ndarray]:
    """The candidate columns of a family on the records (stacked), per degree of freedom,
    evaluated by the term grammar on the records as the library reads them (its delays
    applied)."""
    from ..library import record_variables

    blocks = {dof: [] for dof in DOFS}
    for record in records:
        aligned = library.aligned(record)
        values = record_variables(aligned, library, ship.L, ship.U0, rudder_signal)
        extra = set(family.variables) - set(values)
        if extra:
            values.update(nondimensional_variables(aligned, ship.L, ship.U0, needed=extra))
        factor = values.get(SPEED_FACTOR, 1.0)  # (U/U0)^2 of the instantaneous form
        for dof in DOFS:
            blocks[dof].append(np.column_stack(  # a constant term broadcast to the samples
                [np.broadcast_to(Term(t).evaluate(values) * factor, (record.n_samples,))
                 for t in family.terms[dof]])
                if family.terms[dof] else np.empty((record.n_samples, 0)))
    return {dof: np.vstack(blocks[dof]) for dof in DOFS}

"""Term libraries and effects (paper eq. 15, 17): the objects."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sindyship.errors import SindyshipInputError
from sindyship.terms import ANGLE_CHANNELS, CORE_VARIABLES, Term, is_variable_name, sources_of

from ._checks import (
    _LIBRARY_KEYS,
    DOFS,
    _check_keys,
    _frozen_terms,
    _name,
    _read_delays,
    _read_terms,
    _text,
    _variables,
    _where,
)

if TYPE_CHECKING:
    pass


# ---------------------------------------------------------------------------- the objects
@dataclass(frozen=True)
class TermLibrary:
    """The terms of X, Y and N of a manoeuvring model, read from a library file.

    Parameters
    ----------
    name : str
        Stable identifier, e.g. ``"abkowitz"``; ``"abkowitz+asymmetry"`` once extended.
    system : str
        The non-dimensional system of the variables and coefficients, e.g. ``"prime-I"``.
    description : str
        What the library is, for people (cite the equation it comes from).
    terms : mapping of str to tuple of Term
        The terms per degree of freedom, keyed by ``"X"``, ``"Y"``, ``"N"`` in that order
        (term texts are parsed).  Within a degree of freedom no two terms may be equal up
        to a constant factor.
    source : Path, optional
        The file the library was read from.
    effects : tuple of str
        Names of the effects added by :meth:`extended`, in order.
    delays : mapping of str to float
        Recorded channels that lag the physics, and by how many seconds (a rudder-angle
        sensor late by 4 s: ``{"delta": 4.0}``).  Every term reads such a channel at
        ``t + delay`` (:meth:`aligned`); see docs/effects.md.
    speed : {"design", "instantaneous"}
        The speed the forces and the variables are made non-dimensional with: the constant
        design speed U0 (the paper's Prime I), or the instantaneous speed U = sqrt(u^2 + v^2),
        so that ``v`` is v/U, ``r`` r L/U, ``n`` n L/U and every term carries (U/U0)^2 (forces
        that scale with the square of the speed, valid as a ship slows in a turn; Yasukawa &
        Yoshimura 2015).  ``du`` stays u/U0 - 1 in both.

    Examples
    --------
    >>> from sindyship.library import load_library
    >>> library = load_library("abkowitz")
    >>> {dof: len(terms) for dof, terms in library.terms.items()}
    {'X': 16, 'Y': 22, 'N': 22}
    >>> sorted(library.variables), sorted(library.channels)
    (['delta', 'du', 'r', 'v'], [])
    >>> TermLibrary("toy", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["r", "r v^0"]})
    Traceback (most recent call last):
    ...
    sindyship.errors.SindyshipInputError: library "toy": the term "r v^0" is not valid: \
"^" is followed by one digit 1-9; found "0" at character 5.
    """

    name: str
    system: str
    description: str
    terms: Mapping[str, tuple[Term, ...]]
    source: Path | None = field(default=None, compare=False)
    effects: tuple[str, ...] = ()
    delays: Mapping[str, float] = field(default_factory=dict)
    speed: str = "design"

    def __post_init__(self) -> None:
        label = self.source if self.source is not None else f'library "{self.name}"'
        if self.speed not in ("design", "instantaneous"):
            raise SindyshipInputError(
                f'{_where(label)}speed must be "design" or "instantaneous", not {self.speed!r}.'
            )
        frozen = _frozen_terms(self.terms, label, all_dofs=True)
        object.__setattr__(self, "terms", frozen)
        object.__setattr__(self, "effects", tuple(self.effects))
        object.__setattr__(self, "delays", _read_delays(dict(self.delays), label))

    def __hash__(self) -> int:
        return hash((self.name, self.system, self.description, *self.terms.items(), self.effects,
                     *sorted(self.delays.items()), self.speed))

    def __reduce__(self):
        """Rebuilt from its fields (its term mapping is read-only): a library, and a model
        that holds it, go to joblib's and Dask's workers and through ``copy.deepcopy``."""
        texts = {dof: [term.text for term in terms] for dof, terms in self.terms.items()}
        return type(self), (self.name, self.system, self.description, texts, self.source,
                            self.effects, dict(self.delays), self.speed)

    def aligned(self, record):
        """The record with every delayed channel read ``delay`` seconds later.

        A channel that lags the physics by ``tau`` (:attr:`delays`) is replaced by its value
        at ``t + tau`` (linear interpolation, angles unwrapped first; held at the record's
        first or last value beyond its ends).  Time, the motion and the positions are
        untouched.  A record this library has already aligned is returned as it is.

        Examples
        --------
        >>> import pandas as pd
        >>> from sindyship.trajectory import Trajectory
        >>> lib = TermLibrary("toy", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["r"]},
        ...                   delays={"delta": 2.0})
        >>> frame = pd.DataFrame({"t": [0.0, 1.0, 2.0, 3.0], "delta": [0.0, 0.0, 0.1, 0.2]})
        >>> lib.aligned(Trajectory(frame, name="run"))["delta"].tolist()
        [0.1, 0.2, 0.2, 0.2]
        """
        import numpy as np

        from sindyship.trajectory import Trajectory

        done = record.meta.get("aligned", {})
        if dict(done) == dict(self.delays):
            return record
        t = np.asarray(record.t, dtype=float)
        data = record.data.copy()
        for channel in sorted(set(self.delays) | set(done)):
            shift = self.delays.get(channel, 0.0) - done.get(channel, 0.0)
            if shift == 0.0 or channel not in data.columns:
                continue
            values = data[channel].to_numpy(dtype=float)
            angle = channel in ANGLE_CHANNELS
            base = np.unwrap(values) if angle and np.all(np.isfinite(values)) else values
            moved = np.interp(t + shift, t, base)
            data[channel] = np.mod(moved, 2 * np.pi) if channel == "wind_dir" else moved
        return Trajectory(data, name=record.name,
                          meta={**record.meta, "aligned": dict(self.delays)})

    @cached_property
    def variables(self) -> frozenset[str]:
        """All variables the terms use (computed once: the library is immutable)."""
        return _variables(self.terms)

    @property
    def channels(self) -> frozenset[str]:
        """The variables beyond du, v, r and delta: data channels the library needs."""
        return self.variables - set(CORE_VARIABLES)

    @cached_property
    def sources(self) -> frozenset[str]:
        """What the variables are made from: each variable itself, or a derived variable's
        sources (``x`` and ``y`` for a shape of the position, the true wind for the apparent
        wind; :func:`sindyship.terms.sources_of`)."""
        return frozenset(source for name in self.variables for source in sources_of(name))

    @property
    def input_names(self) -> tuple[str, ...]:
        """The input columns for :class:`AbkowitzFeatureLibrary`: du, v, r, delta, channels.

        The state of a pysindy fit is ``[du, v, r]``; the rest is its control input ``u``.
        """
        return (*CORE_VARIABLES, *sorted(self.channels))

    def extended(self, *effects: Effect) -> TermLibrary:
        """This library with the terms of ``effects`` added.

        Each effect's terms are appended per degree of freedom, skipping those the library
        already has (by :meth:`Term.canonical`, up to a constant factor).

        Examples
        --------
        >>> base = TermLibrary("toy", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["r"]})
        >>> drift = Effect("drift", "Drift", "A made-up effect.", ("psi",),
        ...                {"Y": ["sin(psi)", "v"], "N": ["cos(psi)"]})
        >>> bigger = base.extended(drift)
        >>> bigger.name, [t.text for t in bigger.terms["Y"]], sorted(bigger.channels)
        ('toy+drift', ['v', 'sin(psi)'], ['psi'])
        """
        terms = {dof: list(self.terms[dof]) for dof in DOFS}
        names = list(self.effects)
        delays = dict(self.delays)
        for effect in effects:
            if effect.name in names:
                continue
            names.append(effect.name)
            for channel, delay in effect.delays.items():
                if delays.setdefault(channel, delay) != delay:
                    raise SindyshipInputError(
                        f'effect "{effect.name}" delays {channel} by {delay:g} s but the library '
                        f"already delays it by {delays[channel]:g} s; use one of them."
                    )
            for dof in DOFS:
                present = {t.canonical(scale=False) for t in terms[dof]}
                terms[dof] += [
                    t for t in effect.terms[dof] if t.canonical(scale=False) not in present
                ]
        added = names[len(self.effects) :]
        return TermLibrary(
            name="+".join([self.name, *added]),
            system=self.system,
            description=self.description,
            terms=terms,
            source=self.source,
            effects=tuple(names),
            delays=delays,
            speed=self.speed,
        )

    def rebased(self, original: TermLibrary, base: TermLibrary) -> TermLibrary:
        """The terms and delays this library adds to ``original`` (the library it extends, such
        as the file it was read from), added to ``base`` instead, in this library's speed form.

        Examples
        --------
        >>> original = TermLibrary("toy", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["r"]})
        >>> drift = Effect("drift", "Drift", "A made-up effect.", ("psi",),
        ...                {"Y": ["sin(psi)"], "N": ["cos(psi)"]})
        >>> base = TermLibrary("big", "prime-I", "", {"X": ["du"], "Y": ["v", "r"], "N": ["r"]})
        >>> moved = original.extended(drift).rebased(original, base)
        >>> moved.name, [t.text for t in moved.terms["Y"]], moved.effects
        ('big+drift', ['v', 'r', 'sin(psi)'], ('drift',))
        """
        terms = {}
        for dof in DOFS:
            present = {t.canonical(scale=False)
                       for t in (*original.terms[dof], *base.terms[dof])}
            terms[dof] = [*base.terms[dof],
                          *(t for t in self.terms[dof] if t.canonical(scale=False) not in present)]
        delays = {**base.delays, **{channel: delay for channel, delay in self.delays.items()
                                    if original.delays.get(channel) != delay}}
        return TermLibrary(name="+".join([base.name, *self.effects]), system=base.system,
                           description=base.description, terms=terms, source=base.source,
                           effects=self.effects, delays=delays, speed=self.speed)

    def with_speed(self, speed: str) -> TermLibrary:
        """The same terms made non-dimensional with another speed (:attr:`speed`).

        Examples
        --------
        >>> from sindyship.library import load_library
        >>> load_library("abkowitz").with_speed("instantaneous").speed
        'instantaneous'
        """
        if speed == self.speed:
            return self
        return TermLibrary(self.name, self.system, self.description, self.terms, self.source,
                           self.effects, self.delays, speed)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready description (name, system, description, effects, term texts).

        Examples
        --------
        >>> from sindyship.library import load_library
        >>> library = load_library("abkowitz-noconst")
        >>> TermLibrary.from_dict(library.to_dict()) == library
        True
        """
        out = {
            "name": self.name,
            "system": self.system,
            "description": self.description,
            "effects": list(self.effects),
            "terms": {dof: [t.text for t in self.terms[dof]] for dof in DOFS},
        }
        if self.delays:
            out["delays"] = dict(self.delays)
        if self.speed != "design":
            out["speed"] = self.speed
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], *, source: str | Path | None = None) -> TermLibrary:
        """The library saved by :meth:`to_dict` (e.g. inside a model JSON), validated.

        Parameters
        ----------
        data : mapping
            As made by :meth:`to_dict`.
        source : str or Path, optional
            Where ``data`` comes from, for error messages.
        """
        label = source if source is not None else "saved library"
        if not isinstance(data, Mapping):
            raise SindyshipInputError(f"{_where(label)}a library must be a JSON object.")
        _check_keys(data, {**_LIBRARY_KEYS, "effects": False}, label)
        effects = data.get("effects", [])
        if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
            raise SindyshipInputError(f"{_where(label)}effects must be a list of effect names.")
        return cls(
            name=_name(data, label, extended=True),
            system=_text(data, "system", label),
            description=_text(data, "description", label),
            terms=_read_terms(data["terms"], label, None, all_dofs=True),
            source=Path(source) if source is not None else None,
            effects=tuple(effects),
            delays=_read_delays(data.get("delays"), label),
            speed=data.get("speed", "design"),
        )


@dataclass(frozen=True)
class Effect:
    """A catalogued physical effect: its physics, the channels it needs, its terms.

    Parameters
    ----------
    name : str
        Stable identifier (``"asymmetry"``, ``"crossflow"``, ...).
    title : str
        A short title for reports.
    physics : str
        One paragraph: what the effect is, how it shows in the residuals, what to measure.
    channels : tuple of str
        Data channels the effect needs beyond u, v, r and delta; every such variable its
        terms use must be listed here.
    terms : mapping of str to tuple of Term
        Extra terms per degree of freedom; a degree of freedom the effect does not touch
        has an empty tuple.
    source : Path, optional
        The file the effect was read from.
    delays : mapping of str to float
        Recorded channels that lag the physics [s] (:attr:`TermLibrary.delays`); an effect
        needs terms, delays or both.

    Examples
    --------
    >>> Effect("e", "E", "Text.", (), {"Y": ["abs(v) v"], "N": ["abs(r) r"]}).terms["X"]
    ()
    """

    name: str
    title: str
    physics: str
    channels: tuple[str, ...]
    terms: Mapping[str, tuple[Term, ...]]
    source: Path | None = field(default=None, compare=False)
    delays: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        label = self.source if self.source is not None else f'effect "{self.name}"'
        frozen = _frozen_terms(self.terms, label, all_dofs=False)
        delays = _read_delays(dict(self.delays), label)
        if not any(frozen.values()) and not delays:
            raise SindyshipInputError(f"{_where(label)}the effect has no terms and no delays.")
        object.__setattr__(self, "delays", delays)
        channels = tuple(self.channels)
        for channel in channels:
            if not is_variable_name(channel):
                raise SindyshipInputError(f"{_where(label)}{channel!r} is not a channel name.")
            if channel in CORE_VARIABLES:
                raise SindyshipInputError(
                    f'{_where(label)}"{channel}" is always available; list only the channels '
                    "beyond du, v, r and delta."
                )
        made_from = {name: sources_of(name) for name in sorted(_variables(frozen))}
        used = {source for sources in made_from.values() for source in sources}
        undeclared = sorted(used - set(CORE_VARIABLES) - set(channels))
        if undeclared:
            derived = next((name for name, sources in made_from.items()
                            if undeclared[0] in sources and sources != (name,)), None)
            if derived is None:
                raise SindyshipInputError(f'{_where(label)}the terms use the channel '
                                          f'"{undeclared[0]}"; add it to channels.')
            missing = [s for s in made_from[derived] if s in undeclared]
            listed = " and ".join(f'"{s}"' for s in missing)
            raise SindyshipInputError(
                f'{_where(label)}the term variable "{derived}" is made from the '
                f'channel{"s" if len(missing) > 1 else ""} {listed}; add '
                f'{"them" if len(missing) > 1 else "it"} to channels.'
            )
        object.__setattr__(self, "terms", frozen)
        object.__setattr__(self, "channels", channels)

    def __hash__(self) -> int:
        return hash((self.name, self.title, self.physics, self.channels, *self.terms.items(),
                     *sorted(self.delays.items())))

    @property
    def variables(self) -> frozenset[str]:
        """All variables the effect's terms use."""
        return _variables(self.terms)

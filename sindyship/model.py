"""The fitted Abkowitz model: coefficients, force prediction, simulation and saving.

An :class:`AbkowitzModel` holds the ship (for L, U0, the Prime I inertia of Table 6 and the
rudder servo), the term library and one coefficient per term and degree of freedom (Prime I,
keyed by the term as written).  It predicts the hydrodynamic forces of eq. 15 term by term and
flies eq. 14 with the same integrator, servo and closed-loop manoeuvre logic as the MMG
simulator.  Saved models are JSON text (never pickle).
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from . import __version__
from ._io import write_text_atomic
from ._saved_checks import (
    FORMAT_VERSION,
    MAX_COEFFICIENT,
    _check_format,
    _check_nondim,
    _coefficients_of,
    _jsonable,
    _no_duplicate_keys,
    _optimizer_of,
    _ship_of,
)
from .errors import SindyshipInputError
from .library import (
    SPEED_FACTOR,
    TermLibrary,
    derived_variables,
    motion_variables,
    nondimensional_variables,
    record_variables,
    rescaled_to_speed,
)
from .ships import Ship, ship_digest, ship_to_dict
from .simulation.kernels import ChannelSeries
from .targets import DOFS, abkowitz_mass_matrix, coriolis, coriolis_factors
from .terms import CORE_VARIABLES, DERIVED_SOURCES, Factor, evaluate_factor, is_shape_name
from .trajectory import Trajectory

#: The variables :func:`motion_variables` makes (not rescaled again to the speed).
_MOTION = ("du", "v", "r", "delta", "psi", SPEED_FACTOR)


def channel_series(records, names, L: float, U0: float) -> ChannelSeries:
    """The channels ``names`` of records that share their sample times, in the library's
    scaling (:func:`sindyship.library.nondimensional_variables`), one row per record."""
    values = [nondimensional_variables(r, L, U0, needed=names) for r in records]
    return ChannelSeries(np.asarray(records[0].t, dtype=float),
                         {name: np.vstack([v[name] for v in values]) for name in names})


def coriolis_of_values(ship: Ship, values: Mapping) -> tuple:
    """Coriolis terms (Prime I) of paper eq. 14 at a library's variables: they take the motion
    over U0, so the instantaneous form's v/U and r L/U are turned back with the speed factor
    (:data:`sindyship.library.SPEED_FACTOR`)."""
    ratio = np.sqrt(values[SPEED_FACTOR]) if SPEED_FACTOR in values else 1.0
    return coriolis(ship, values["du"] + 1.0, values["v"] * ratio, values["r"] * ratio)


@dataclass(frozen=True)
class AbkowitzDynamics:
    """Simulator dynamics of an identified model (paper eq. 14) from its forces of eq. 15.

    Parameters
    ----------
    model : AbkowitzModel
    channels : dict, optional
        Values of the library's extra channels (e.g. ``n``) held constant during a flight, in
        the library's non-dimensional form.
    """

    model: AbkowitzModel
    channels: Mapping[str, float] = field(default_factory=dict)
    series: ChannelSeries | None = None

    @property
    def time_varying(self) -> bool:
        """Whether recorded channels vary in the flight (the integrator then passes the time)."""
        return self.series is not None

    @cached_property
    def uses_rudder_rate(self) -> bool:
        """Whether terms use the rudder's rate (delta_rate): the integrator then passes the
        rate the flight's servo moves at."""
        return "delta_rate" in self.model.library.variables

    @cached_property
    def uses_position(self) -> bool:
        """Whether terms depend on where the ship is (x, y): the integrator then passes the
        flight's own position, never the recorded one."""
        return self.model._uses_position

    @property
    def ship(self) -> Ship:
        return self.model.ship

    @property
    def rudder_input(self) -> str:
        return "commanded" if self.model.rudder_signal == "commanded" else "actual"

    def accelerations(self, u, v, r, delta, psi, branch=None, t=None, members=None,
                      position=None, rudder_rate=None):
        """Accelerations (du/dt, dv/dt, dr/dt) in SI from SI state values; the recorded
        channels at time ``t`` of the flights ``members`` when the dynamics has a series, the
        flight's ``position`` (x, y) [m] and ``rudder_rate`` [rad/s] when terms use them
        (the origin and a still rudder when not given, as for a stability analysis)."""
        model = self.model
        if model._compiled_accelerations:
            a = model._run_compiled(self, u, v, r, delta, psi, t, members, position,
                                    rudder_rate)
            if a is not None:
                return a
        values = self.variables_at(u, v, r, delta, psi, t, members, position, rudder_rate)
        return self.accelerations_from(model.forces_from_values(values), values)

    def fly_compiled(self, integ, commands, t, state0, step, check_divergence, on_step):
        """The kernel's flights of this model through the compiled loop
        (:func:`sindyship._flights_compiled.fly`), or None where it has no form for them."""
        if not self.model._compiled_flights:
            return None
        from ._flights_compiled import fly

        return fly([(self, 0, len(commands))], integ, commands, t, state0, step,
                   check_divergence, on_step)

    def variables_at(self, u, v, r, delta, psi, t=None, members=None, position=None,
                     rudder_rate=None) -> dict:
        """The library's non-dimensional variables at SI states (as :meth:`accelerations`)."""
        channels = dict(self.channels)
        if self.series is not None:
            channels.update(self.series.at(t, members))
        return self.model.flight_variables(u, v, r, delta, psi, channels, position,
                                           rudder_rate)

    def accelerations_from(self, forces: Mapping[str, np.ndarray], values: Mapping) -> tuple:
        """Accelerations (SI) of eq. 14 from the hydrodynamic forces of eq. 15 (Prime I):
        the Coriolis terms added, the mass matrix inverted.  The Coriolis terms take the
        motion over U0 (``values`` of the instantaneous form hold v/U and r L/U, so they are
        turned back with the speed factor)."""
        ship = self.ship
        U0, L = ship.U0, ship.L
        X_C, Y_C, N_C = coriolis_of_values(ship, values)
        Minv = self.model.inverse_mass
        X = forces["X"] + X_C
        Y = forces["Y"] + Y_C
        N = forces["N"] + N_C
        a_u = Minv[0, 0] * X
        a_v = Minv[1, 1] * Y + Minv[1, 2] * N
        a_r = Minv[2, 1] * Y + Minv[2, 2] * N
        scale = U0 * U0 / L
        return a_u * scale, a_v * scale, a_r * scale / L


def _compiled_tables(bases, factors, slots):
    """The compiled path's tables (:func:`sindyship._forces_compiled.tables`), or None when
    numba is not there or compiling is switched off (``SINDYSHIP_NO_COMPILE=1``)."""
    if os.environ.get("SINDYSHIP_NO_COMPILE") == "1" or importlib.util.find_spec("numba") is None:
        return None
    from ._forces_compiled import COMPILED, tables

    return tables(bases, factors, slots) if COMPILED else None  # numba there but broken


@dataclass
class AbkowitzModel:
    """An identified Abkowitz model (paper eq. 14-15).

    Parameters
    ----------
    ship : Ship
        The ship the data belongs to.
    library : TermLibrary
        The terms per degree of freedom.
    coefficients : dict
        ``{"X": {term: value}, "Y": ..., "N": ...}`` in Prime I.
    optimizer : dict
        ``{"name": ..., "params": {...}}`` as used in the fit.
    rudder_signal : {"actual", "commanded"}
        The rudder angle in the features.
    info : dict
        Free facts about the fit (training records, derivative method, ...).
    """

    ship: Ship
    library: TermLibrary
    coefficients: dict[str, dict[str, float]]
    optimizer: dict = field(default_factory=lambda: {"name": "given", "params": {}})
    rudder_signal: str = "actual"
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        for dof in DOFS:
            terms = [t.text for t in self.library.terms[dof]]
            given = self.coefficients.get(dof, {})
            unknown = sorted(set(given) - set(terms))
            if unknown:
                raise SindyshipInputError(
                    f"coefficient {dof}[{unknown[0]!r}] has no term in library "
                    f"{self.library.name!r}; use the library's term strings."
                )
            self.coefficients[dof] = {t: float(given.get(t, 0.0)) for t in terms}
        if self.rudder_signal not in ("actual", "commanded"):
            raise SindyshipInputError(
                f"rudder_signal must be 'actual' or 'commanded', not {self.rudder_signal!r}."
            )
        self.inverse_mass = np.linalg.inv(abkowitz_mass_matrix(self.ship))
        self._compile()

    def _compile(self) -> None:
        """Index the non-zero terms of all equations by their distinct factors, so a call of
        :meth:`forces_from_values` evaluates each factor once and forms every term's column
        and every force with a few whole-array products (no loop over terms)."""
        unique: dict[str, object] = {}
        for dof in DOFS:
            for term in self.library.terms[dof]:
                if self.coefficients[dof][term.text] != 0.0:
                    unique.setdefault(term.canonical(scale=False) + "|" + term.text, term)
        terms = list(unique.values())
        factors = list(dict.fromkeys(f for term in terms for f in term.factors))
        self._factors = factors
        # the factors by base (a variable or a function of one): each base is evaluated once
        # and raised to all its powers in one operation
        bases: dict[Factor, tuple[list[int], list[int]]] = {}
        for k, factor in enumerate(factors):
            rows, powers = bases.setdefault(Factor(factor.function, factor.base, 1), ([], []))
            rows.append(k)
            powers.append(factor.power)
        self._bases = [(base, np.array(rows), np.array(powers, dtype=float)[:, None])
                       for base, (rows, powers) in bases.items()]
        width = max((len(term.factors) for term in terms), default=1) or 1  # "1" has none
        # factor indices of each term, padded with the index of a row of ones
        slots = np.full((width, len(terms)), len(factors), dtype=np.intp)
        for k, term in enumerate(terms):
            slots[: len(term.factors), k] = [factors.index(f) for f in term.factors]
        self._slots = slots
        index = {t.text: k for k, t in enumerate(terms)}
        weights = np.zeros((len(DOFS), len(terms)))
        for row, dof in enumerate(DOFS):
            for term in self.library.terms[dof]:
                c = self.coefficients[dof][term.text]
                if c != 0.0:
                    weights[row, index[term.text]] += c
        self._weights = weights
        self._weight_slots = {(dof, term.text): (row, index[term.text])
                              for row, dof in enumerate(DOFS)
                              for term in self.library.terms[dof]
                              if self.coefficients[dof][term.text] != 0.0}
        self._compiled = _compiled_tables(self._bases, factors, slots)
        # the compiled flights make the motion's variables from the state themselves, in
        # either speed form; the compiled accelerations of states make the design form's
        self._compiled_flights = self._compiled is not None \
            and not (set(DERIVED_SOURCES) & set(self.library.variables))
        self._compiled_accelerations = self._compiled_flights and self.library.speed == "design"
        self._uses_position = bool({"x", "y"} & self.library.sources)
        if self._compiled is not None:
            from ._forces_compiled import run_accelerations

            self._run_compiled = run_accelerations
        self._compiled_reads = {base.base for base, _, _ in self._bases}
        self._inertia = np.array(coriolis_factors(self.ship))

    # ----------------------------------------------------------------------------------------
    def coefficient_vector(self, dof: str) -> np.ndarray:
        """Coefficients of one degree of freedom in the library's term order."""
        return np.array([self.coefficients[dof][t.text] for t in self.library.terms[dof]])

    def n_active(self) -> dict[str, int]:
        """Number of non-zero coefficients per degree of freedom."""
        return {dof: sum(value != 0.0 for value in self.coefficients[dof].values())
                for dof in DOFS}

    def forces_from_values(self, values: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Forces of eq. 15 (Prime I) from non-dimensional variables.

        Each distinct factor of the active terms is evaluated once; every term's column is the
        product of its factors' rows, and the forces are the coefficient-weighted sums of the
        columns (one matrix product for the three equations).
        """
        base = np.asarray(values["du"], dtype=float)
        if not self._slots.shape[1]:  # no active term
            return {dof: 0.0 * base for dof in DOFS}
        if self._compiled is not None and all(v in values for v in self._compiled_reads):
            names, tables = self._compiled
            stacked = np.zeros((len(names), base.size))
            for k, name in enumerate(names):
                if name in values:
                    stacked[k] = np.ravel(values[name])
            from ._forces_compiled import forces as compiled_forces

            forces = compiled_forces(stacked, *tables, self._weights[:, :, None],
                                     np.zeros(base.size, dtype=np.int64))
            if SPEED_FACTOR in values:  # the instantaneous form: forces scale with U^2
                forces = forces * np.ravel(values[SPEED_FACTOR])
            return {dof: forces[row].reshape(base.shape) for row, dof in enumerate(DOFS)}
        forces = self._weights @ self.term_columns(values)
        return {dof: forces[row].reshape(base.shape) for row, dof in enumerate(DOFS)}

    def term_columns(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """The active terms' values (n_active_terms, n_states) at non-dimensional variables,
        each the product of its factors' rows (times the speed factor (U/U0)^2 of the
        ``instantaneous`` form); the columns of :attr:`_weights`."""
        size = np.asarray(values["du"], dtype=float).size
        rows = np.ones((len(self._factors) + 1, size))
        for factor, where, powers in self._bases:
            column = np.ravel(evaluate_factor(factor, values))
            rows[where] = column if len(where) == 1 and powers[0, 0] == 1.0 else column**powers
        slots = self._slots
        columns = rows[slots[0]]
        for slot in slots[1:]:
            columns *= rows[slot]
        if SPEED_FACTOR in values:  # the instantaneous form: every term carries (U/U0)^2
            columns *= np.ravel(values[SPEED_FACTOR])
        return columns

    def variables(self, traj: Trajectory) -> dict[str, np.ndarray]:
        """The library's non-dimensional variables of a record (with this model's rudder)."""
        return record_variables(traj, self.library, self.ship.L, self.ship.U0,
                                self.rudder_signal)

    def predict_forces(self, traj: Trajectory) -> dict[str, np.ndarray]:
        """Forces of eq. 15 predicted for a record (Prime I), one array per degree of freedom."""
        return self.forces_from_values(self.variables(traj))

    @property
    def recorded_channels(self) -> list[str]:
        """The channels the library uses that a flight takes from the record (all but the
        heading, the position and the rudder rate, which the flight makes itself; the sources
        of a variable made from the motion, such as the true wind of the apparent wind)."""
        return sorted(self.library.sources - set(CORE_VARIABLES)
                      - {"psi", "x", "y", "delta_rate"})

    def flight_variables(self, u, v, r, delta, psi, channels: Mapping, position=None,
                         rudder_rate=None) -> dict:
        """The library's variables in a flight: the motion's (:func:`motion_variables`, in the
        library's speed form), the recorded ``channels`` (library scaling, over U0), the
        variables made from the flown motion (the apparent wind), the flown position (x, y)
        [m] and the shapes of it, and the servo's ``rudder_rate`` [rad/s] (without a
        position: the origin, and every shape 0, away from its line; a still rudder when no
        rate is given)."""
        ship, library = self.ship, self.library
        values = motion_variables(u, v, r, delta, psi, ship.L, ship.U0, library.speed)
        values.update(channels)
        zero = 0.0 * values["du"]
        if self._uses_position:
            values["x"], values["y"] = (zero, zero) if position is None else position
        derived_variables(values, library.variables, u, v, psi, ship.U0, ship.L)
        if position is None:  # no place (a stability analysis): away from every shape's line
            values.update({name: zero for name in library.variables if is_shape_name(name)})
        if "delta_rate" in library.variables:
            values["delta_rate"] = (zero if rudder_rate is None else rudder_rate) \
                * ship.L / ship.U0
        if library.speed == "instantaneous":
            rescaled_to_speed(values, [n for n in values if n not in _MOTION],
                              np.sqrt(values[SPEED_FACTOR]))
        return values

    def dynamics(self, channels: Mapping[str, float] | None = None, *, records=None
                 ) -> AbkowitzDynamics:
        """Simulator dynamics of eq. 14 (see :mod:`sindyship.simulation`).

        Channels the library uses beyond the heading come from ``records`` as time series
        (records that share their sample times, one flight each), or are held at the constant
        values of ``channels`` (library scaling).
        """
        if records is not None and self.recorded_channels:
            series = channel_series([self.library.aligned(r) for r in records],
                                    self.recorded_channels, self.ship.L, self.ship.U0)
            return AbkowitzDynamics(self, dict(channels or {}), series)
        missing = sorted(set(self.recorded_channels) - set(channels or {}))
        if missing:
            raise SindyshipInputError(
                f"the model's library uses the channel {missing[0]!r}; pass its value to fly "
                "the model (channels={...})."
            )
        return AbkowitzDynamics(self, dict(channels or {}))

    # ----------------------------------------------------------------------------------------
    def table(self) -> pd.DataFrame:
        """Coefficients as a table, Prime I and x 1e-5 (the units of paper Tables 7-9)."""
        rows = []
        for dof in DOFS:
            for term in self.library.terms[dof]:
                value = self.coefficients[dof][term.text]
                rows.append({"equation": dof, "term": term.text, "name": term.identifier(dof),
                             "value": value, "value_1e-5": value * 1e5})
        return pd.DataFrame(rows)

    def __str__(self) -> str:
        from .export import equations_text

        return equations_text(self)

    def _repr_latex_(self) -> str:
        from .export import equations_latex

        return equations_latex(self)

    def __repr__(self) -> str:
        counts = ", ".join(f"{d}: {n}/{len(self.library.terms[d])}"
                           for d, n in self.n_active().items())
        return (f"AbkowitzModel(ship={self.ship.name!r}, library={self.library.name!r}, "
                f"optimizer={self.optimizer.get('name')!r}, active terms {counts})")

    # ----------------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The saved-model layout (JSON-ready)."""
        return {
            "format_version": FORMAT_VERSION,
            "sindyship_version": __version__,
            "ship": self.ship.name,
            "ship_definition": ship_to_dict(self.ship),
            "ship_digest": ship_digest(self.ship),
            "library": self.library.to_dict(),
            "optimizer": _jsonable(self.optimizer),
            "rudder_signal": self.rudder_signal,
            "nondim": {"system": "prime-I", "L": self.ship.L, "U0": self.ship.U0},
            "coefficients": {dof: dict(self.coefficients[dof]) for dof in DOFS},
            "info": _jsonable(self.info),
        }

    def save(self, path: str | Path) -> None:
        """Write the model as JSON (to a temporary file, then renamed).

        Raises
        ------
        SindyshipInputError
            When a coefficient is not finite or beyond :data:`MAX_COEFFICIENT` in magnitude,
            which no saved model may hold (such a fit comes from records that do not belong to
            the ship, or from a ship file with the wrong units).
        """
        largest, name = max(((abs(value), f"{dof}[{term}]")
                             for dof, terms in self.coefficients.items()
                             for term, value in terms.items()), default=(0.0, ""),
                            key=lambda pair: pair[0] if math.isfinite(pair[0]) else math.inf)
        if not largest <= MAX_COEFFICIENT:
            raise SindyshipInputError(
                f"the fit gave {name} a coefficient of magnitude {largest:.3g}, beyond the "
                f"{MAX_COEFFICIENT:g} a saved model may hold: the records cannot tell its term "
                "from others (a channel with as few values as the terms' powers, such as "
                "revolutions n at two settings for 1, n and n^2), or they do not belong to the "
                f"ship {self.ship.name!r} (check its file's units); record more distinct "
                "values, drop terms from the library, or fit with --optimizer prior.")
        if Path(path).is_dir():
            raise SindyshipInputError(f"{path} is a folder; give the model a file name, such as "
                                      f"{Path(path) / 'model.json'}.")
        write_text_atomic(path, json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n")

    @classmethod
    def from_dict(cls, data: Mapping, *, source: str = "<model>", ship: Ship | None = None
                  ) -> AbkowitzModel:
        """Rebuild a model from :meth:`to_dict` output, checking every field.

        A model of format 2 carries its ship's definition and digest, so it flies the ship it
        was fitted for even where a file of the same name differs; ``ship`` then must have the
        same digest.  A format-1 model names its ship only (a built-in name or a file).
        """
        if not isinstance(data, Mapping):
            raise SindyshipInputError(f"{source}: a saved model is a JSON object.")
        _check_format(data, source)
        optimizer = _optimizer_of(data, source)
        ship = _ship_of(data, source, ship)
        _check_nondim(data["nondim"], ship, source)
        library = TermLibrary.from_dict(data["library"], source=source)
        clean = _coefficients_of(data["coefficients"], library, source)
        rudder_signal = data.get("rudder_signal", "actual")
        if rudder_signal not in ("actual", "commanded"):
            raise SindyshipInputError(
                f"{source}: rudder_signal must be 'actual' or 'commanded', not {rudder_signal!r}."
            )
        try:
            return cls(ship=ship, library=library, coefficients=clean, optimizer=optimizer,
                       rudder_signal=rudder_signal, info=dict(data.get("info", {})))
        except SindyshipInputError as error:
            raise SindyshipInputError(f"{source}: {error}") from None

    @classmethod
    def load(cls, path: str | Path, *, ship: Ship | None = None) -> AbkowitzModel:
        """Read a saved model (JSON)."""
        path = Path(path)
        from .records import PARQUET_SUFFIXES

        if path.suffix.lower() in (".csv", *PARQUET_SUFFIXES):
            raise SindyshipInputError(f"{path} is a record, not a saved model; give the "
                                      "model's JSON file (sindyship fit ... --out MODEL.json).")
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SindyshipInputError(f"{path}: no such model file.") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise SindyshipInputError(f"{path}: cannot read the model ({exc}).") from None
        try:
            data = json.loads(text, object_pairs_hook=_no_duplicate_keys)
        except json.JSONDecodeError as exc:
            raise SindyshipInputError(
                f"{path}: not valid JSON (line {exc.lineno}: {exc.msg}); the file is truncated "
                "or was edited by hand."
            ) from None
        except SindyshipInputError as exc:
            raise SindyshipInputError(f"{path}: {exc}; the file was edited by hand.") from None
        except ValueError as exc:  # an integer of thousands of digits
            raise SindyshipInputError(f"{path}: holds a number too long to read ({exc}); the "
                                      "file was edited by hand.") from None
        except RecursionError:
            raise SindyshipInputError(
                f"{path}: the JSON is nested too deeply to be a sindyship model."
            ) from None
        return cls.from_dict(data, source=str(path), ship=ship)


def paper_model(ship: Ship, method: str = "LS", csv_path: str | Path | None = None
                ) -> AbkowitzModel:
    """The paper's own identified coefficients (Tables 7-9) as a model.

    Parameters
    ----------
    method : {"LS", "Lasso", "SVR"}
    csv_path : path, optional
        The coefficients CSV (``term`` keys in the library syntax; values x 1e-5); default:
        the copy shipped with sindyship.
    """
    from .library import load_library
    from .paper import paper_coefficients

    table = paper_coefficients(csv_path)
    column = f"{method}_1e-5"
    coefficients = {
        dof: dict(zip(rows["term"], rows[column] * 1e-5, strict=True))
        for dof, rows in ((d, table[table["equation"] == d]) for d in DOFS)
    }
    return AbkowitzModel(ship=ship, library=load_library("abkowitz"), coefficients=coefficients,
                         optimizer={"name": f"paper-{method.lower()}", "params": {}})

"""The checks of a saved model (JSON) as it is read back: every field, with one sentence
naming the file and the field for what is wrong (:meth:`sindyship.model.AbkowitzModel.load`)."""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from .errors import SindyshipInputError
from .library import TermLibrary
from .ships import Ship, load_ship, ship_digest, ship_from_dict
from .targets import DOFS

FORMAT_VERSION = 2


#: Coefficients beyond this magnitude (Prime I) are no hydrodynamic derivative of any ship: a
#: model that holds one was edited or corrupted, and would diverge at once.
MAX_COEFFICIENT = 1e6


def _check_format(data: Mapping, source: str) -> None:
    version = data.get("format_version")
    if version is None:
        raise SindyshipInputError(f"{source}: not a sindyship model (no format_version).")
    if not isinstance(version, int) or isinstance(version, bool):
        raise SindyshipInputError(
            f"{source}: format_version must be a whole number such as {FORMAT_VERSION}, not "
            f"{json.dumps(version)[:20]}; the file was edited or is not a sindyship model.")
    if version > FORMAT_VERSION:
        raise SindyshipInputError(
            f"{source}: saved by a newer sindyship (format {version}); upgrade sindyship "
            "to load it."
        )
    if version < 1:
        raise SindyshipInputError(
            f"{source}: format_version {version} does not exist (1 to {FORMAT_VERSION} are "
            "known); the file was edited or is not a sindyship model."
        )
    for key in ("ship", "library", "coefficients", "nondim"):
        if key not in data:
            raise SindyshipInputError(f"{source}: the saved model lacks {key!r}.")
    for key in ("optimizer", "info"):
        if not isinstance(data.get(key, {}), Mapping):
            raise SindyshipInputError(f"{source}: {key!r} must be a JSON object.")


def _optimizer_of(data: Mapping, source: str) -> dict:
    optimizer = dict(data.get("optimizer", {"name": "given", "params": {}}))
    if not isinstance(optimizer.get("name"), str) or not isinstance(
            optimizer.get("params"), Mapping):
        raise SindyshipInputError(
            f"{source}: 'optimizer' needs a text 'name' and an object 'params'."
        )
    return optimizer


def _ship_of(data: Mapping, source: str, ship: Ship | None) -> Ship:
    """The model's own ship (format 2), checked against ``ship`` when one is given."""
    definition = data.get("ship_definition")
    if definition is None and data["format_version"] >= 2:
        raise SindyshipInputError(
            f"{source}: a model of format 2 carries its ship's definition, and this one lacks "
            "'ship_definition'; the file was edited (refit the model rather than editing it).")
    if definition is not None:
        if not isinstance(definition, Mapping):
            raise SindyshipInputError(f"{source}: 'ship_definition' must be a JSON object.")
        own = ship_from_dict(dict(definition), source=f"{source} (its ship)")
        if "ship_digest" not in data:
            raise SindyshipInputError(
                f"{source}: the saved model lacks 'ship_digest', which checks its ship's "
                "definition; the file was edited (refit the model rather than editing it).")
        if data.get("ship_digest") != ship_digest(own) or data["ship"] != own.name:
            raise SindyshipInputError(
                f"{source}: the ship definition does not match its digest; the file was edited "
                "(refit the model rather than editing it)."
            )
        if ship is not None and ship_digest(ship) != ship_digest(own):
            renamed = ship_digest(replace(ship, name=own.name, title=own.title)) == \
                ship_digest(own)
            raise SindyshipInputError(
                f"{source}: the model was fitted for ship {own.name!r}, "
                + ("the ship given under another name" if renamed else
                   "whose particulars differ from those of the ship given")
                + f" ({ship.name!r}); leave out --ship to use the model's own ship."
            )
        return own
    if ship is not None:
        return ship
    if not isinstance(data["ship"], str):
        raise SindyshipInputError(f"{source}: 'ship' must be a ship name or file.")
    try:
        return load_ship(data["ship"])
    except SindyshipInputError as error:
        raise SindyshipInputError(
            f"{source}: the model's ship {data['ship']!r} cannot be loaded ({error}); "
            "pass the ship with --ship."
        ) from None


def _check_nondim(nondim, ship: Ship, source: str) -> None:
    numbers = [nondim.get(key) if isinstance(nondim, Mapping) else None for key in ("L", "U0")]
    try:
        L, U0 = (float(x) if isinstance(x, int | float) and not isinstance(x, bool) else math.nan
                 for x in numbers)
    except OverflowError:  # an integer of hundreds of digits
        L = U0 = math.nan
    if not (math.isfinite(L) and math.isfinite(U0)):
        raise SindyshipInputError(f"{source}: 'nondim' needs numbers L and U0.")
    if not (math.isclose(L, ship.L) and math.isclose(U0, ship.U0)):
        raise SindyshipInputError(
            f"{source}: the model was made for L = {L} m, U0 = {U0} m/s but ship "
            f"{ship.name!r} has L = {ship.L} m, U0 = {ship.U0} m/s; pass the matching ship."
        )


def _coefficients_of(coefficients, library: TermLibrary, source: str
                     ) -> dict[str, dict[str, float]]:
    """Finite, plausible coefficients keyed by exactly the library's terms."""
    if not isinstance(coefficients, Mapping) or set(coefficients) != set(DOFS):
        raise SindyshipInputError(f"{source}: 'coefficients' needs the keys X, Y and N.")
    clean: dict[str, dict[str, float]] = {}
    for dof in DOFS:
        if not isinstance(coefficients[dof], Mapping):
            raise SindyshipInputError(
                f"{source}: coefficients {dof!r} must be an object of term: value pairs."
            )
        known = [t.text for t in library.terms[dof]]
        unknown = sorted(set(coefficients[dof]) - set(known))
        if unknown:
            raise SindyshipInputError(
                f"{source}: coefficient {dof}[{unknown[0]!r}] is not a term of the model's "
                f"library {library.name!r}; the file was edited."
            )
        missing = [term for term in known if term not in coefficients[dof]]
        if missing:
            raise SindyshipInputError(
                f"{source}: coefficient {dof}[{missing[0]!r}] is missing: every term of the "
                f"model's library {library.name!r} has a value (0 for a term the optimizer "
                "dropped); the file was edited."
            )
        clean[dof] = {}
        for term, value in coefficients[dof].items():
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not math.isfinite(value) or abs(value) > MAX_COEFFICIENT:
                raise SindyshipInputError(
                    f"{source}: coefficient {dof}[{term!r}] must be a finite number of "
                    f"magnitude at most {MAX_COEFFICIENT:g}, not {value!r}."
                )
            clean[dof][term] = float(value)
    return clean


def _no_duplicate_keys(pairs: list[tuple[str, object]]) -> dict:
    keys = [key for key, _ in pairs]
    repeated = sorted({key for key in keys if keys.count(key) > 1})
    if repeated:
        raise SindyshipInputError(f"the key {repeated[0]!r} appears twice in one JSON object")
    return dict(pairs)


def _jsonable(value):
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic | np.ndarray):  # through the float rule below
        return _jsonable(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if value is None or isinstance(value, str | int | float | bool):
        return value
    return str(value)



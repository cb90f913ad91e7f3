"""Ship files: reading and checking a TOML ship, the ship as data, and its digest."""

from __future__ import annotations

import difflib
import hashlib
import json
import math
import tomllib
from dataclasses import MISSING, asdict, fields, replace
from importlib import resources
from pathlib import Path
from typing import Any

from ..errors import SindyshipInputError
from ._groups import (
    BUILTIN_SHIPS,
    MassProperties,
    Particulars,
    Propeller,
    Rudder,
    Servo,
    Ship,
)


def _ship_dir() -> Path:
    return Path(str(resources.files("sindyship") / "ships"))


def _finite(value: Any, what: str, source: str) -> float:
    """A finite number from a ship file, or an error naming the file and the key."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise SindyshipInputError(f"{source}: {what} must be a finite number, not {value!r}.")
    return float(value)


#: Quantities that must be positive, by section.
_POSITIVE = {
    "particulars": ("L", "B", "d", "displacement", "rho", "U0"),
    "mass": ("m", "I_zz"),
    "propeller": ("D_P",),
    "rudder": ("A_R",),
    "servo": ("rate_max", "delta_max"),
}


#: Physical ranges of ship-file values: (section, key) -> (low, high, open ends, unit and why).
#: Beyond them the simulator's step (at most T_R/4 and 0.1 L/U0) or its state leaves what a
#: displacement ship can be: a servo time constant of 1e-7 L/U0 would take billions of steps.
_RANGES = {
    ("particulars", "L"): (0.1, 1000.0, "[]", "m"),
    ("particulars", "B"): (0.01, 500.0, "[]", "m"),
    ("particulars", "d"): (0.01, 100.0, "[]", "m"),
    ("particulars", "displacement"): (1e-6, 1e8, "[]", "m^3"),
    ("particulars", "scale"): (0.0, 1000.0, "(]", "the model scale of the measurements, 1 at "
                                                  "full scale"),
    ("mass", "m"): (0.0, 10.0, "(]", "mass / (0.5 rho L^2 d): the KCS has 0.18"),
    ("mass", "I_zz"): (0.0, 10.0, "(]", "yaw inertia / (0.5 rho L^4 d): the KCS has 0.011"),
    ("mass", "m_x"): (0.0, 10.0, "[]", "added mass / (0.5 rho L^2 d)"),
    ("mass", "m_y"): (0.0, 10.0, "[]", "added mass / (0.5 rho L^2 d)"),
    ("mass", "J_zz"): (0.0, 10.0, "[]", "added inertia / (0.5 rho L^4 d)"),
    ("particulars", "U0"): (0.0, 50.0, "(]", "m/s"),
    ("particulars", "rho"): (900.0, 1100.0, "[]", "kg/m^3: fresh water is 1000, sea water 1025"),
    ("servo", "T_R"): (0.01, 10.0, "[]", "units of L/U0: the KCS has 1, a model's fast servo 0.1"),
    ("servo", "rate_max"): (0.1, 100.0, "[]", "deg/s: steering gear turns 2.3-20 deg/s"),
    ("servo", "delta_max"): (5.0, 90.0, "[)", "deg: rudders go hard over at 25-45 deg"),
}
#: Block coefficients displacement / (L B d) of ship hulls: below, a length in feet or a
#: displacement in another unit; above 1, a hull fuller than its box.
BLOCK_COEFFICIENT_RANGE = (0.25, 1.0)
#: How far a given mass m may stand from the displacement's, rho displacement, as a fraction.
MASS_TOLERANCE = 0.05
#: Largest Froude number U0 / sqrt(g L) of a displacement ship's approach speed.
MAX_FROUDE = 1.0


def _check_range(section: str, key: str, value: float, source: str) -> None:
    low, high, ends, unit = _RANGES[(section, key)]
    ok = (value > low if ends[0] == "(" else value >= low) and (
        value < high if ends[1] == ")" else value <= high)
    if not ok:
        raise SindyshipInputError(
            f"{source}: [{section}] {key} = {value!r} is outside its physical range "
            f"{ends[0]}{low:g}, {high:g}{ends[1]} ({unit})."
        )


def _check_physics(particulars: Particulars, servo: Servo | None, source: str,
                   mass: MassProperties | None = None) -> None:
    """Refuse ship values outside their physical ranges (:data:`_RANGES`), each named (the
    particulars first, before any arithmetic on them)."""
    groups = {"particulars": particulars, "servo": servo, "mass": mass}
    for (section, key) in _RANGES:
        if groups[section] is not None:
            _check_range(section, key, getattr(groups[section], key), source)
    for key, limit in (("B", 1.0), ("d", 1.0)):
        if getattr(particulars, key) > limit * particulars.L:
            raise SindyshipInputError(
                f"{source}: [particulars] {key} = {getattr(particulars, key):g} m is more than the "
                f"length L = {particulars.L:g} m; check the values and their units."
            )
    c_b = particulars.displacement / (particulars.L * particulars.B * particulars.d)
    low, high = BLOCK_COEFFICIENT_RANGE
    if not low <= c_b <= high:
        raise SindyshipInputError(
            f"{source}: [particulars] displacement = {particulars.displacement:g} m^3 in L x B x d "
            f"= {particulars.L:g} x {particulars.B:g} x {particulars.d:g} m is a block "
            f"coefficient of {c_b:.4g}, outside the {low:g}-{high:g} of ship hulls; check the "
            "values and their units (metres, m^3)."
        )
    if abs(particulars.x_G) > 0.5 * particulars.L:
        raise SindyshipInputError(
            f"{source}: [particulars] x_G = {particulars.x_G:g} m lies outside the hull (more than "
            f"L/2 = {0.5 * particulars.L:g} m from midship); give it in metres from midship."
        )
    froude = particulars.U0 / math.sqrt(9.81 * particulars.L)
    if froude > MAX_FROUDE:
        raise SindyshipInputError(
            f"{source}: [particulars] U0 = {particulars.U0:g} m/s on L = {particulars.L:g} m is a "
            f"Froude number of {froude:.3g}, above the {MAX_FROUDE:g} of any displacement ship; "
            "check U0 and L."
        )


def _refuse_unknown_keys(table: dict, names: set[str], section: str, source: str) -> None:
    """Refuse the first key of ``table`` not in ``names``, naming a close valid one."""
    unknown = sorted(set(table) - names)
    if unknown:
        close = difflib.get_close_matches(unknown[0], sorted(names), n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise SindyshipInputError(
            f"{source}: unknown key {unknown[0]!r} in [{section}]; {hint}valid keys are "
            f"{', '.join(sorted(names))}."
        )


def _group(cls: type, table: Any, section: str, source: str) -> Any:
    if not isinstance(table, dict):
        raise SindyshipInputError(
            f"{source}: section [{section}] is missing; copy the layout of the built-in kcs.toml."
        )
    _refuse_unknown_keys(table, {f.name for f in fields(cls)}, section, source)
    missing = [f.name for f in fields(cls) if f.name not in table and f.default is MISSING]
    if missing:
        raise SindyshipInputError(
            f"{source}: key {missing[0]!r} is missing from [{section}]; add it with its value."
        )
    for key, value in table.items():
        if key in ("wake_model",):
            continue
        if key == "K_T":
            if not (isinstance(value, list) and len(value) == 3
                    and all(isinstance(x, int | float) for x in value)):
                raise SindyshipInputError(
                    f"{source}: [{section}] K_T must be a list of three numbers [a0, a1, a2]."
                )
            continue
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not number or not math.isfinite(value):
            raise SindyshipInputError(
                f"{source}: [{section}] {key} must be a finite number, not {value!r}."
            )
    for key in _POSITIVE.get(section, ()):
        if key in table and not table[key] > 0:
            raise SindyshipInputError(
                f"{source}: [{section}] {key} must be positive, not {table[key]!r}."
            )
    values = dict(table)
    if "K_T" in values:
        values["K_T"] = tuple(float(x) for x in values["K_T"])
    return cls(**values)


#: The top-level keys and sections of a ship file; other top-level keys are ignored, unless
#: one is a near miss of these (a misspelt key or section, refused by :func:`_check_misspelt`).
SHIP_FILE_KEYS = ("name", "title", "hull_form", "speed_reference", "coriolis", "particulars",
                  "mass", "hull", "propeller", "rudder", "servo", "abkowitz")


def _check_misspelt(data: dict, source: str) -> None:
    """Refuse a top-level key or section that is a near miss of one of
    :data:`SHIP_FILE_KEYS`: ignored, a misspelt ``[servo]`` would leave the ship with an
    assumed servo, a misspelt ``speed_reference`` with the design speed form."""
    for key, value in data.items():
        if key in SHIP_FILE_KEYS:
            continue
        close = difflib.get_close_matches(key, SHIP_FILE_KEYS, n=1, cutoff=0.8)
        if close:
            kind = "section" if isinstance(value, dict) else "key"
            shown = f"[{key}]" if kind == "section" else repr(key)
            raise SindyshipInputError(
                f"{source}: unknown top-level {kind} {shown}; did you mean {close[0]!r}? "
                "Rename it (other unknown top-level keys are ignored)."
            )


def _check_top_level(data: dict, source: str) -> None:
    for key in ("name", "hull_form", "speed_reference", "coriolis"):
        if not isinstance(data.get(key), str):
            raise SindyshipInputError(f"{source}: top-level key {key!r} (a string) is missing.")
    choices = {
        "hull_form": ("beta", "standard"),
        "speed_reference": ("design", "instantaneous"),
        "coriolis": ("rigid-body", "with-added-mass"),
    }
    for key, valid in choices.items():
        if data[key] not in valid:
            raise SindyshipInputError(
                f"{source}: {key} = {data[key]!r} is not one of {', '.join(valid)}."
            )
    for section in ("mass", "hull", "rudder", "abkowitz"):
        if section in data and not isinstance(data[section], dict):
            raise SindyshipInputError(f"{source}: [{section}] must be a table of numbers.")


def _mass_properties(data: dict, p: Particulars, source: str) -> MassProperties:
    """[mass] with m from the displacement and I_zz from k_zz when not given (Prime II)."""
    mass_table = dict(data.get("mass") or {})
    # first: a misspelt k_zz would read as a missing one
    _refuse_unknown_keys(mass_table, {f.name for f in fields(MassProperties)} | {"k_zz"},
                         "mass", source)
    k_zz = mass_table.pop("k_zz", None)
    if k_zz is not None:
        k_zz = _finite(k_zz, "[mass] k_zz", source)
        if not 0.0 < k_zz <= 1.0:
            raise SindyshipInputError(
                f"{source}: [mass] k_zz = {k_zz!r} is outside its physical range (0, 1] (the yaw "
                "radius of gyration over L: 0.25 for most ships)."
            )
    scale_m = 0.5 * p.rho * p.L**2 * p.d
    displaced = p.rho * p.displacement / scale_m
    if "m" not in mass_table:
        mass_table["m"] = displaced
    given = _finite(mass_table["m"], "[mass] m", source)
    if abs(given / displaced - 1.0) > MASS_TOLERANCE:
        raise SindyshipInputError(
            f"{source}: [mass] m = {given:g} and the displacement's rho displacement / (0.5 rho "
            f"L^2 d) = {displaced:.4g} differ by {abs(given / displaced - 1.0):.0%}; give m as "
            "mass / (0.5 rho L^2 d) (Prime II), correct the one that is wrong, or leave m out "
            "to take it from the displacement."
        )
    if "I_zz" not in mass_table:
        if k_zz is None:
            raise SindyshipInputError(f"{source}: [mass] needs I_zz or k_zz.")
        m_dim = mass_table["m"] * scale_m
        inertia = m_dim * (k_zz * p.L) ** 2 + m_dim * p.x_G**2
        mass_table["I_zz"] = inertia / (0.5 * p.rho * p.L**4 * p.d)
    return _group(MassProperties, mass_table, "mass", source)


def _rudder_group(data: dict, propeller: Propeller, source: str) -> Rudder:
    """[rudder] with f_alpha from the aspect ratio lambda and eta from H_R when given."""
    rudder_table = dict(data.get("rudder") or {})
    for key in ("lambda", "H_R"):
        if key in rudder_table:
            rudder_table[key] = _finite(rudder_table[key], f"[rudder] {key}", source)
            if rudder_table[key] <= 0:
                raise SindyshipInputError(f"{source}: [rudder] {key} must be positive.")
    if "lambda" in rudder_table:
        lam = rudder_table.pop("lambda")
        rudder_table.setdefault("f_alpha", 6.13 * lam / (2.25 + lam))
    if "H_R" in rudder_table:
        rudder_table.setdefault("eta", propeller.D_P / rudder_table["H_R"])
        rudder_table.pop("H_R")
    return _group(Rudder, rudder_table, "rudder", source)


def _hull_coefficients(data: dict, source: str) -> dict[str, float]:
    hull = data.get("hull")
    if not isinstance(hull, dict):
        raise SindyshipInputError(f"{source}: section [hull] is missing.")
    needed = HULL_COEFFICIENTS[data["hull_form"]]
    missing = [k for k in needed if k not in hull]
    if missing:
        raise SindyshipInputError(f"{source}: [hull] coefficient {missing[0]} is missing.")
    unknown = sorted(set(hull) - set(needed))
    if unknown:
        raise SindyshipInputError(
            f"{source}: unknown [hull] coefficient {unknown[0]!r} for hull_form "
            f"{data['hull_form']!r}."
        )
    return {k: float(_finite(v, f"[hull] {k}", source)) for k, v in hull.items()}


def _abkowitz_added_masses(data: dict, source: str) -> dict[str, float]:
    abkowitz = dict(data.get("abkowitz") or {})
    valid_abk = {"X_udot", "Y_vdot", "Y_rdot", "N_vdot", "N_rdot"}
    unknown = sorted(set(abkowitz) - valid_abk)
    if unknown:
        raise SindyshipInputError(f"{source}: unknown [abkowitz] key {unknown[0]!r}.")
    values = {k: float(_finite(v, f"[abkowitz] {k}", source)) for k, v in abkowitz.items()}
    for key, mass in (("X_udot", "m_x"), ("Y_vdot", "m_y"), ("N_rdot", "J_zz")):
        if values.get(key, 0.0) > 0.0:
            raise SindyshipInputError(
                f"{source}: [abkowitz] {key} = {values[key]:g} is positive; an added mass makes "
                f"it negative ({key} = -{mass} d/L), so check its sign.")
    return values


#: Rudder servo of a ship file that gives none: a time constant of 0.1 L/U0, the rate of the
#: IMO steering-gear rule (35 deg to 30 deg the other side in 28 s, 2.32 deg/s full scale,
#: Froude-scaled by the ship's ``scale``: a model's times are shorter by sqrt(scale), its
#: rates faster by as much) and 35 deg hard over.
DEFAULT_SERVO = {"T_R": 0.1, "rate_max": 65.0 / 28.0, "delta_max": 35.0}


def clarke_added_masses(p: Particulars, m_prime_i: float) -> dict[str, float]:
    """Acceleration derivatives (Prime I) estimated from the main dimensions.

    The sway and yaw derivatives are the empirical formulas of Clarke, Gedling & Hine (1983),
    *The application of manoeuvring criteria in hull design using linear theory*, Trans. RINA
    125, 45-68, with C_B from the displacement; the surge derivative, which Clarke does not
    give, is taken as 5 % of the mass, a common estimate for slender hulls.

    Parameters
    ----------
    p : Particulars
    m_prime_i : float
        Mass / (0.5 rho L^3).

    Returns
    -------
    dict
        ``X_udot``, ``Y_vdot``, ``Y_rdot``, ``N_vdot``, ``N_rdot`` (Prime I).

    Examples
    --------
    >>> ship = load_ship("kcs")
    >>> est = clarke_added_masses(ship.particulars, ship.prime_i_inertia()["m"])
    >>> round(est["Y_vdot"] * 1e5), round(est["N_rdot"] * 1e5)  # paper Table 6: -732, -43
    (-838, -49)
    """
    c_b = p.displacement / (p.L * p.B * p.d)
    base = math.pi * (p.d / p.L) ** 2
    b_l, b_t = p.B / p.L, p.B / p.d
    return {
        "X_udot": -0.05 * m_prime_i,
        "Y_vdot": -base * (1.0 + 0.16 * c_b * b_t - 5.1 * b_l**2),
        "Y_rdot": -base * (0.67 * b_l - 0.0033 * b_t**2),
        "N_vdot": -base * (1.1 * b_l - 0.041 * b_t),
        "N_rdot": -base * (1.0 / 12.0 + 0.017 * c_b * b_t - 0.33 * b_l),
    }


def _identification_ship(data: dict, source: str) -> Ship:
    """A ship file without [hull], [propeller] and [rudder]: enough to identify and fly an
    Abkowitz model (particulars, mass, inertia).

    Every value the file gives is kept as written.  What it leaves out and a flight needs is
    assumed, and each assumption is named in :attr:`Ship.assumptions`: the acceleration
    derivatives of eq. 14 (from the Prime II added masses ``m_x``, ``m_y``, ``J_zz`` where
    given, else the estimates of :func:`clarke_added_masses`; ``Y_rdot`` and ``N_vdot`` from
    Clarke unless [abkowitz] gives them) and the rudder servo (:data:`DEFAULT_SERVO`).
    """
    if not isinstance(data.get("name"), str):
        raise SindyshipInputError(f"{source}: top-level key 'name' (a string) is missing.")
    for section in ("mass", "abkowitz", "servo"):
        if section in data and not isinstance(data[section], dict):
            raise SindyshipInputError(f"{source}: [{section}] must be a table of numbers.")
    particulars = _group(Particulars, data.get("particulars"), "particulars", source)
    _check_physics(particulars, None, source)
    given_mass = dict(data.get("mass") or {})
    k = particulars.d / particulars.L
    mass_table = {"m_x": 0.0, "m_y": 0.0, "J_zz": 0.0, **given_mass}
    mass = _mass_properties({"mass": mass_table}, particulars, source)
    given_abkowitz = _abkowitz_added_masses(data, source)
    estimates = clarke_added_masses(particulars, mass.m * k)
    from_mass = {"X_udot": ("m_x", -mass.m_x * k), "Y_vdot": ("m_y", -mass.m_y * k),
                 "N_rdot": ("J_zz", -mass.J_zz * k)}
    abkowitz, assumed = {}, []
    for key in ("X_udot", "Y_vdot", "Y_rdot", "N_vdot", "N_rdot"):
        if key in given_abkowitz:
            abkowitz[key] = given_abkowitz[key]
        elif key in from_mass and from_mass[key][0] in given_mass:
            abkowitz[key] = from_mass[key][1]
        else:
            abkowitz[key] = estimates[key]
            assumed.append(key)
    # the Prime II added masses the file leaves out follow the derivatives used
    filled = {name: -abkowitz[key] / k for key, (name, _) in from_mass.items()
              if name not in given_mass}
    mass = replace(mass, **filled)
    assumptions = []
    if assumed:
        assumptions.append(
            f"acceleration derivatives {', '.join(assumed)} estimated from the main dimensions "
            "(Clarke et al. 1983): " + ", ".join(f"{key} = {abkowitz[key]:.4g}"
                                                 for key in assumed)
            + " (Prime I); give them in [abkowitz] or as m_x, m_y, J_zz in [mass]")
    servo_table = {**DEFAULT_SERVO, **dict(data.get("servo") or {})}
    if "rate_max" not in (data.get("servo") or {}):
        servo_table["rate_max"] = DEFAULT_SERVO["rate_max"] * math.sqrt(particulars.scale)
    servo = _group(Servo, servo_table, "servo", source)
    servo_assumed = [key for key in DEFAULT_SERVO if key not in (data.get("servo") or {})]
    if servo_assumed:
        values = {"T_R": f"T_R = {servo.T_R:g} L/U0",
                  "rate_max": f"rate_max = {servo.rate_max:.3g} deg/s",
                  "delta_max": f"delta_max = {servo.delta_max:g} deg"}
        assumptions.append(
            "rudder servo " + ", ".join(values[key] for key in servo_assumed)
            + " (the IMO steering-gear rate, Froude-scaled); give [servo] with the ship's own")
    assumptions.append("Coriolis terms of the rigid body with the added masses (eq. 14)")
    if "speed_reference" not in data:
        assumptions.append('speed_reference = "design" (forces over the design speed U0); give '
                           'speed_reference = "instantaneous" for forces that scale with the '
                           "instantaneous speed")
    _check_physics(particulars, servo, source, mass)
    return Ship(
        name=data["name"],
        title=str(data.get("title", data["name"])),
        hull_form="none",
        speed_reference=_speed_reference(data, source),
        coriolis="with-added-mass",
        particulars=particulars,
        mass=mass,
        hull={},
        propeller=None,
        rudder=None,
        servo=servo,
        abkowitz=abkowitz,
        assumptions=tuple(assumptions),
    )


def _speed_reference(data: dict, source: str) -> str:
    """An identification ship's ``speed_reference``: ``design`` unless the file says."""
    value = data.get("speed_reference", "design")
    if value not in ("design", "instantaneous"):
        raise SindyshipInputError(
            f"{source}: speed_reference = {value!r} is not one of design, instantaneous."
        )
    return value


def ship_from_dict(data: dict, source: str = "<ship>") -> Ship:
    """Build a :class:`Ship` from the parsed TOML layout, validating every field.

    A file with none of [hull], [propeller] and [rudder] describes a ship for identification
    only (:func:`_identification_ship`): it needs ``name``, [particulars] and [mass] (``I_zz``
    or ``k_zz``); [abkowitz] and [servo] are optional (Clarke's added masses,
    :data:`DEFAULT_SERVO`).
    """
    _check_misspelt(data, source)
    mmg = [section for section in ("hull", "propeller", "rudder") if section in data]
    if not mmg:
        given = [key for key in ("hull_form", "coriolis") if key in data]
        if given:
            raise SindyshipInputError(
                f"{source}: {' and '.join(given)} belong{'s' if len(given) == 1 else ''} to a "
                "ship file with the MMG model's [hull], [propeller] and [rudder], which this one "
                f"lacks; remove {'it' if len(given) == 1 else 'them'} for a ship for "
                "identification only (its Coriolis terms are the "
                "rigid body's with the added masses), or give those sections.")
        return _identification_ship(data, source)
    _check_top_level(data, source)
    particulars = _group(Particulars, data.get("particulars"), "particulars", source)
    if particulars.L <= 0 or particulars.d <= 0 or particulars.U0 <= 0 or particulars.rho <= 0:
        raise SindyshipInputError(f"{source}: L, d, U0 and rho in [particulars] must be positive.")
    _check_physics(particulars, None, source)
    mass = _mass_properties(data, particulars, source)
    propeller = _group(Propeller, data.get("propeller"), "propeller", source)
    if propeller.wake_model not in ("constant", "drift"):
        raise SindyshipInputError(
            f"{source}: [propeller] wake_model must be 'constant' or 'drift'."
        )
    servo = _group(Servo, data.get("servo"), "servo", source)
    _check_physics(particulars, servo, source, mass)
    return Ship(
        name=data["name"],
        title=str(data.get("title", data["name"])),
        hull_form=data["hull_form"],
        speed_reference=data["speed_reference"],
        coriolis=data["coriolis"],
        particulars=particulars,
        mass=mass,
        hull=_hull_coefficients(data, source),
        propeller=propeller,
        rudder=_rudder_group(data, propeller, source),
        servo=servo,
        abkowitz=_abkowitz_added_masses(data, source),
    )


HULL_COEFFICIENTS = {
    "beta": (
        "X_0", "X_bb", "X_br_minus_my", "X_rr", "X_bbb",
        "Y_b", "Y_r_minus_mx", "Y_bb", "Y_bbr", "Y_brr", "Y_rrr",
        "N_b", "N_r", "N_bb", "N_bbr", "N_brr", "N_rrr",
    ),
    "standard": (
        "R_0", "X_vv", "X_vr", "X_rr", "X_vvvv",
        "Y_v", "Y_r", "Y_vvv", "Y_vvr", "Y_vrr", "Y_rrr",
        "N_v", "N_r", "N_vvv", "N_vvr", "N_vrr", "N_rrr",
    ),
}


def ship_to_dict(ship: Ship) -> dict:
    """The ship in the TOML layout of :func:`ship_from_dict` (JSON-ready): a saved model keeps
    it, so that the ship it was fitted for travels with it.

    Examples
    --------
    >>> kcs = load_ship("kcs")
    >>> ship_from_dict(ship_to_dict(kcs)) == kcs
    True
    """
    out: dict[str, Any] = {"name": ship.name, "title": ship.title,
                           "particulars": asdict(ship.particulars), "mass": asdict(ship.mass),
                           "servo": asdict(ship.servo), "abkowitz": dict(ship.abkowitz)}
    if not ship.has_mmg and ship.speed_reference != "design":
        out["speed_reference"] = ship.speed_reference
    if ship.has_mmg:
        propeller = asdict(ship.propeller)
        propeller["K_T"] = list(propeller["K_T"])
        out.update(hull_form=ship.hull_form, speed_reference=ship.speed_reference,
                   coriolis=ship.coriolis, hull=dict(ship.hull), propeller=propeller,
                   rudder=asdict(ship.rudder))
    return out


def ship_to_toml(ship: Ship) -> str:
    """The ship as the text of a ship TOML file (:func:`ship_to_dict`'s layout), which
    :func:`load_ship` reads back to an equal ship: a ship made in Python (a Froude-scaled
    built-in one) for ``--ship``.

    Examples
    --------
    >>> import tempfile
    >>> full = load_ship("kvlcc2").scaled(45.7)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "full.toml"
    ...     _ = path.write_text(ship_to_toml(full))
    ...     load_ship(path) == full
    True
    """
    def value(item) -> str:
        if isinstance(item, bool):
            return "true" if item else "false"
        if isinstance(item, str):
            return json.dumps(item, ensure_ascii=False)  # a TOML basic string
        if isinstance(item, list | tuple):
            return "[" + ", ".join(value(v) for v in item) + "]"
        return repr(item)  # int, or float: repr reads back to the same number

    data = ship_to_dict(ship)
    lines = [f"{key} = {value(item)}" for key, item in data.items() if not isinstance(item, dict)]
    for section, table in data.items():
        if isinstance(table, dict) and table:
            lines += ["", f"[{section}]", *(f"{key} = {value(item)}"
                                            for key, item in table.items())]
    return "\n".join(lines) + "\n"


def ship_digest(ship: Ship) -> str:
    """SHA-256 of the ship's definition (:func:`ship_to_dict`, keys sorted): two ships with one
    name but other particulars have different digests."""
    text = json.dumps(ship_to_dict(ship), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def load_ship(name_or_path: str | Path) -> Ship:
    """Load a built-in ship by name (``kcs``, ``kvlcc2``) or a ship TOML file.

    Examples
    --------
    >>> load_ship("kvlcc2").particulars.L
    7.0
    """
    text_name = str(name_or_path)
    if text_name in BUILTIN_SHIPS:
        path = _ship_dir() / f"{text_name}.toml"
    else:
        path = Path(text_name)
        if not path.is_file():
            if text_name.lower() in BUILTIN_SHIPS:
                raise SindyshipInputError(f"there is no ship named {text_name!r}; the built-in "
                                          f"ship is {text_name.lower()!r} (lower case).")
            if path.name and path.suffix == "" and path.with_suffix(".toml").is_file():
                raise SindyshipInputError(f"{text_name}: no such ship file; did you mean "
                                          f"{path.with_suffix('.toml')}?")
            raise SindyshipInputError(
                f"{text_name}: no such ship file; use a built-in ship ({', '.join(BUILTIN_SHIPS)}) "
                "or the path of a TOML file laid out like sindyship/ships/kcs.toml."
            )
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SindyshipInputError(f"{path}: not a valid TOML file ({exc}).") from None
    except ValueError as exc:  # an integer of thousands of digits
        raise SindyshipInputError(f"{path}: holds a number too long to read ({exc}); write it "
                                  "with fewer digits.") from None
    return ship_from_dict(data, source=str(path))

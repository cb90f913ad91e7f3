"""A record's variables non-dimensionalised for the terms, and the regressor matrix."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from sindyship.errors import SindyshipInputError
from sindyship.terms import (
    CORE_VARIABLES,
    DERIVED_SOURCES,
    SPEED_FLOOR,
    Term,
    describe_variable,
    is_shape_name,
    parse_shape,
    read_over_speed,
    shape_values,
    sources_of,
)

from ._objects import Effect, TermLibrary

if TYPE_CHECKING:
    from sindyship.trajectory import Trajectory


# ---------------------------------------------------------------------------- numbers
_SCALINGS = {
    "surge": lambda x, L, U0: x / U0 - 1.0,
    "speed": lambda x, L, U0: x / U0,
    "rate": lambda x, L, U0: x * L / U0,
    "none": lambda x, L, U0: x,
}

#: The two reference speeds of a library (:attr:`TermLibrary.speed`).
SPEED_FORMS = ("design", "instantaneous")
#: The key of the speed factor (U/U0)^2 in a dictionary of variables of the ``instantaneous``
#: form (no variable can be named so).
SPEED_FACTOR = "_U2"


def speed_ratio(u, v, U0: float):
    """U/U0 with U = sqrt(u^2 + v^2), at least :data:`SPEED_FLOOR` (SI speeds)."""
    return np.maximum(np.hypot(u, v) / U0, SPEED_FLOOR)


def apparent_wind(u, v, psi, wind_speed, wind_dir):
    """The wind the ship feels: speed [m/s] and the angle off the bow it comes from [rad,
    positive from starboard], from the true wind (``wind_speed`` [m/s] from ``wind_dir``
    [rad, clockwise from north]) and the ship's own motion (u, v [m/s] over ground, heading
    psi [rad]).

    Examples
    --------
    >>> speed, angle = apparent_wind(5.0, 0.0, 0.0, 0.0, 0.0)  # calm: a head wind of 5 m/s
    >>> float(speed), float(angle)
    (5.0, 0.0)
    >>> speed, angle = apparent_wind(0.0, 0.0, 0.0, 10.0, np.pi / 2)  # at rest, wind from east
    >>> float(speed), round(float(np.degrees(angle)))
    (10.0, 90)
    """
    relative = np.asarray(wind_dir, dtype=float) - np.asarray(psi, dtype=float)
    # the air's velocity relative to the ship, body axes (x forward, y to starboard)
    u_air = -np.asarray(wind_speed) * np.cos(relative) - np.asarray(u)
    v_air = -np.asarray(wind_speed) * np.sin(relative) - np.asarray(v)
    return np.hypot(u_air, v_air), np.arctan2(-v_air, -u_air)


def motion_variables(u, v, r, delta, psi, L: float, U0: float, speed: str = "design") -> dict:
    """The library's motion variables at SI states (paper eq. 14-15).

    ``design``: Prime I with the design speed U0, ``du = u/U0 - 1``, ``v = v/U0``,
    ``r = r L/U0``.  ``instantaneous``: ``v`` and ``r`` over the instantaneous speed U
    (:func:`speed_ratio`), ``du`` still ``u/U0 - 1`` (how the coefficients change with the
    speed), and the speed factor (U/U0)^2 under :data:`SPEED_FACTOR`, which multiplies every
    term (the forces scale with the square of the speed).
    """
    un = np.asarray(u, dtype=float) / U0
    values = {"du": un - 1.0, "delta": delta, "psi": psi}
    if speed == "instantaneous":
        ratio = speed_ratio(u, v, U0)
        values.update(v=np.asarray(v) / (U0 * ratio), r=np.asarray(r) * L / (U0 * ratio))
        values[SPEED_FACTOR] = ratio * ratio
    else:
        values.update(v=np.asarray(v) / U0, r=np.asarray(r) * L / U0)
    return values


def rescaled_to_speed(values: dict, names, ratio) -> None:
    """Channels of the ``instantaneous`` form over the speed: those made non-dimensional with
    U0 (``speed`` and ``rate`` scaling, e.g. n L/U0) divided by U/U0 = ``ratio``, in place."""
    for name in names:
        if name in values and read_over_speed(name):
            values[name] = values[name] / ratio


def derived_variables(values: dict, names, u, v, psi, U0: float, L: float | None = None
                      ) -> None:
    """The derived variables among ``names`` from the SI motion and the recorded channels in
    ``values`` (library scaling), in place: the apparent wind
    (:data:`sindyship.terms.DERIVED_SOURCES`), and the shapes of the position
    (:func:`sindyship.terms.shape_values`, from ``values["x"]``, ``values["y"]`` [m] and the
    ship length ``L``)."""
    for name in names:
        shape = parse_shape(name)
        if shape is not None:
            if L is None or "x" not in values or "y" not in values:
                raise SindyshipInputError(
                    f'the shape "{name}" is made from the position: pass values["x"], '
                    'values["y"] [m] and the ship length L.'
                )
            values[name] = shape_values(shape, values["x"], values["y"], L)
    if not ({"wind_app_speed", "wind_app_angle"} & set(names)):
        return
    speed, angle = apparent_wind(u, v, psi, np.asarray(values["wind_speed"]) * U0,
                                 values["wind_dir"])
    values["wind_app_speed"] = speed / U0
    values["wind_app_angle"] = angle


def nondimensional_variables(
    trajectory: Trajectory,
    L: float,
    U0: float,
    *,
    needed: Iterable[str] | TermLibrary | Effect | None = None,
    rudder: np.ndarray | None = None,
    speed: str = "design",
) -> dict[str, np.ndarray]:
    """The library variables of a record, non-dimensional in the Prime-I system (eq. 14).

    With the ship length ``L`` and the design speed ``U0`` (constant, not the instantaneous
    speed): ``du = u/U0 - 1``, ``v = v/U0``, ``r = r L/U0``, ``delta`` the rudder angle
    [rad], ``delta_rate`` its rate by central differences times L/U0, ``psi`` the heading
    [rad], ``n = n L/U0`` (n in rps), ``wind_speed`` over U0, ``wind_dir`` [rad], the apparent
    wind ``wind_app_speed`` over U0 and ``wind_app_angle`` [rad] (:func:`apparent_wind`, from
    the record's own motion).  Any other channel is passed through as recorded (SI units).
    With ``speed="instantaneous"`` the speeds and rates are over U instead of U0
    (:func:`motion_variables`) and the speed factor (U/U0)^2 is added.

    Parameters
    ----------
    trajectory : Trajectory
        The record, in SI units.
    L, U0 : float
        Ship length [m] and design speed [m/s].
    needed : iterable of str, TermLibrary or Effect, optional
        The variables to compute; a library or effect stands for the variables its terms
        use.  Default: du, v, r and delta.
    rudder : numpy.ndarray, optional
        The rudder angle [rad] to use for ``delta`` (e.g. the commanded one); default the
        record's actual rudder angle, else its commanded one.
    speed : {"design", "instantaneous"}
        The reference speed of the non-dimensional variables.

    Returns
    -------
    dict of str to numpy.ndarray
        One array per needed variable, du, v, r, delta first.

    Raises
    ------
    SindyshipInputError
        If the record lacks a channel that is needed (the message names the channel and
        the library or effect), or ``L``, ``U0`` or ``rudder`` are not valid.

    Examples
    --------
    >>> import pandas as pd
    >>> from sindyship.trajectory import Trajectory
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": [10.0, 5.0], "v": [0.0, 2.5],
    ...                       "r": [0.0, 0.05], "x": [0.0, 1.0], "y": [0.0, 0.0],
    ...                       "psi": [0.0, 0.1], "delta": [0.0, 0.2]})
    >>> values = nondimensional_variables(Trajectory(frame, "demo"), L=100.0, U0=10.0)
    >>> {name: value.tolist() for name, value in values.items()}
    {'du': [0.0, -0.5], 'v': [0.0, 0.25], 'r': [0.0, 0.5], 'delta': [0.0, 0.2]}
    """
    for label, value in (("L", L), ("U0", U0)):
        if not (np.isfinite(value) and value > 0):
            raise SindyshipInputError(f"{label} must be a positive number, not {value!r}.")
    if speed not in SPEED_FORMS:
        raise SindyshipInputError(f"speed must be one of {', '.join(SPEED_FORMS)}, not "
                                  f"{speed!r}.")
    if needed is None:
        names, requester = set(CORE_VARIABLES), "the model"
    elif isinstance(needed, TermLibrary | Effect):
        kind = "library" if isinstance(needed, TermLibrary) else "effect"
        names, requester = set(needed.variables), f'{kind} "{needed.name}"'
    else:
        names, requester = set(needed), "a term"
    record = f'record "{trajectory.name}"' if trajectory.name else "the record"
    derived = {name for name in names if name in DERIVED_SOURCES or is_shape_name(name)}
    sources = {source for name in derived for source in sources_of(name)}
    order = sorted(names - derived | sources, key=lambda n: (n not in CORE_VARIABLES,
                                                             _core_rank(n), n))
    out: dict[str, np.ndarray] = {}
    for name in order:
        column = _column(trajectory, describe_variable(name), rudder, requester, record)
        out[name] = _SCALINGS[describe_variable(name).scaling](column, float(L), float(U0))
    if derived:
        motion = ((trajectory["u"], trajectory["v"], trajectory["psi"])
                  if derived & set(DERIVED_SOURCES) else (None, None, None))  # the wind's
        derived_variables(out, derived, *motion, U0, float(L))
    if speed == "instantaneous":
        ratio = speed_ratio(trajectory["u"], trajectory["v"], U0)
        rescaled_to_speed(out, [n for n in out if n not in ("du",)], ratio)
        out[SPEED_FACTOR] = ratio * ratio
    for name in sources - names:
        out.pop(name)
    return out


def _column(trajectory: Trajectory, variable, rudder, requester: str, record: str
            ) -> np.ndarray:
    """The SI column of a variable in a record (the rudder, its rate, or a channel)."""
    if variable.column == "rudder_rate":
        angle = np.asarray(rudder, dtype=float) if rudder is not None else trajectory.rudder
        return np.gradient(angle, trajectory.t) if trajectory.n_samples > 1 else 0 * angle
    if variable.column == "rudder":
        if rudder is not None:
            column = np.asarray(rudder, dtype=float)
            if column.shape != (trajectory.n_samples,):
                raise SindyshipInputError(
                    f"the rudder angle given for {record} has shape {column.shape}, "
                    f"not ({trajectory.n_samples},)."
                )
            return column
        if trajectory.has("delta") or trajectory.has("delta_c"):
            return trajectory.rudder
        raise SindyshipInputError(
            f'{requester} needs the rudder angle ("delta" or "delta_c"), which '
            f"{record} does not have; add the column to the record."
        )
    if trajectory.has(variable.column):
        return trajectory[variable.column]
    raise SindyshipInputError(
        f'{requester} needs the channel "{variable.column}", which {record} does not have; '
        "add the column to the record."
    )


def _core_rank(name: str) -> int:
    return CORE_VARIABLES.index(name) if name in CORE_VARIABLES else len(CORE_VARIABLES)


def feature_matrix(terms: Sequence[Term | str], values: Mapping[str, np.ndarray]) -> np.ndarray:
    """The regressor matrix: one column per term (paper eq. 17), one row per sample.

    Parameters
    ----------
    terms : sequence of Term (or term text)
        The terms of one degree of freedom, in order.
    values : mapping of str to numpy.ndarray
        The variables, e.g. from :func:`nondimensional_variables`.

    Returns
    -------
    numpy.ndarray
        Shape (n_samples, n_terms); for arrays of more dimensions, the terms are the last
        axis.

    Examples
    --------
    >>> import numpy as np
    >>> feature_matrix(["1", "v", "v^2 r"], {"v": np.array([1.0, 2.0]), "r": np.array([3.0, 4.0])})
    array([[ 1.,  1.,  3.],
           [ 1.,  2., 16.]])
    """
    parsed = [t if isinstance(t, Term) else Term(t) for t in terms]
    columns = [term.evaluate(values) for term in parsed]
    shapes = [c.shape for c in columns] or [np.shape(next(iter(values.values()), []))]
    shape = np.broadcast_shapes(*shapes)
    if not columns:
        return np.empty((*shape, 0))
    return np.stack([np.broadcast_to(c, shape) for c in columns], axis=-1)


def record_variables(record: Trajectory, library: TermLibrary, L: float, U0: float,
                     rudder_signal: str = "actual") -> dict[str, np.ndarray]:
    """The non-dimensional variables a library's terms need from a record, with the rudder
    angle the fit uses: the actual one (``delta``, else ``delta_c``) or the commanded one,
    and every channel the library delays read at ``t + delay`` (:meth:`TermLibrary.aligned`).

    Raises
    ------
    SindyshipInputError
        When the commanded rudder is asked for and the record has no ``delta_c``.
    """
    record = library.aligned(record)
    rudder = None
    if rudder_signal == "commanded":
        if not record.has("delta_c"):
            raise SindyshipInputError(
                f"{record.name}: the model uses the commanded rudder but the record has no "
                "delta_c column; record it or fit with --rudder-signal actual."
            )
        rudder = record["delta_c"]
    elif not record.has("delta"):
        rudder = record["delta_c"]
    needed = set(library.variables) | set(CORE_VARIABLES)
    return nondimensional_variables(record, L, U0, needed=needed, rudder=rudder,
                                    speed=library.speed)

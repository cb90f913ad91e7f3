"""A record's variables non-dimensionalised for the terms, and the regressor matrix."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from sindyship.errors import SindyshipInputError
from sindyship.terms import CORE_VARIABLES, Term, describe_variable

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


def nondimensional_variables(
    trajectory: Trajectory,
    L: float,
    U0: float,
    *,
    needed: Iterable[str] | TermLibrary | Effect | None = None,
    rudder: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The library variables of a record, non-dimensional in the Prime-I system (eq. 14).

    With the ship length ``L`` and the design speed ``U0`` (constant, not the instantaneous
    speed): ``du = u/U0 - 1``, ``v = v/U0``, ``r = r L/U0``, ``delta`` the rudder angle
    [rad], ``delta_rate`` its rate by central differences times L/U0, ``psi`` the heading
    [rad], ``n = n L/U0`` (n in rps), ``wind_speed`` over U0, ``wind_dir`` [rad].  Any other
    channel is passed through as recorded (SI units).

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
    if needed is None:
        names, requester = set(CORE_VARIABLES), "the model"
    elif isinstance(needed, TermLibrary | Effect):
        kind = "library" if isinstance(needed, TermLibrary) else "effect"
        names, requester = set(needed.variables), f'{kind} "{needed.name}"'
    else:
        names, requester = set(needed), "the terms"
    record = f'record "{trajectory.name}"' if trajectory.name else "the record"
    order = sorted(names, key=lambda n: (n not in CORE_VARIABLES, _core_rank(n), n))
    out: dict[str, np.ndarray] = {}
    for name in order:
        variable = describe_variable(name)
        if variable.column == "rudder_rate":
            angle = (np.asarray(rudder, dtype=float) if rudder is not None
                     else trajectory.rudder)
            column = np.gradient(angle, trajectory.t) if trajectory.n_samples > 1 else 0 * angle
        elif variable.column == "rudder":
            if rudder is not None:
                column = np.asarray(rudder, dtype=float)
                if column.shape != (trajectory.n_samples,):
                    raise SindyshipInputError(
                        f"the rudder angle given for {record} has shape {column.shape}, "
                        f"not ({trajectory.n_samples},)."
                    )
            elif trajectory.has("delta") or trajectory.has("delta_c"):
                column = trajectory.rudder
            else:
                raise SindyshipInputError(
                    f'{requester} needs the rudder angle ("delta" or "delta_c"), which '
                    f"{record} does not have."
                )
        elif trajectory.has(variable.column):
            column = trajectory[variable.column]
        else:
            raise SindyshipInputError(
                f'{requester} needs the channel "{variable.column}", which {record} does not have.'
            )
        out[name] = _SCALINGS[variable.scaling](column, float(L), float(U0))
    return out


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
    return nondimensional_variables(record, L, U0, needed=needed, rudder=rudder)

"""Virtual captive (towing-tank) tests from the MMG model, and the captive-test CSV.

A captive test holds the ship on a prescribed steady motion (constant u, v, r and rudder angle
delta, no accelerations) and measures the forces needed to hold it.  :func:`captive_tests`
makes such tests with the MMG model of paper sections 2.1-2.1.4, evaluating the one force
function :func:`sindyship.mmg.force_components` (no copy of its physics):

``static-drift``
    Drift angle beta = atan2(-v, u) from -beta_max to +beta_max (default 20 deg) at the
    carriage speed U: u = U cos(beta), v = -U sin(beta), r = 0, delta = 0.
``rudder``
    Rudder angle from -35 to +35 deg in straight motion (u = U, v = r = 0).
``pure-yaw``
    Non-dimensional yaw rate r' = r L / U0 from -0.6 to 0.6 with v = 0 at midship (a rotating
    arm, or the steady part of a pure-yaw test), u = U, delta = 0.
``drift-yaw``
    The grid of drift angles times yaw rates (rotating arm with drift), delta = 0.

What the forces are (the convention of the captive CSV)
-------------------------------------------------------
In a steady test a dynamometer between carriage and model reads the force the model exerts on
it.  Newton's law in the moving body axes at midship gives, with no accelerations,

    reading = F_hydro + C_RB,

where C_RB are the rigid-body Coriolis and centrifugal terms of the model's own mass (paper
eq. 11: X_C = m v r + m x_G r^2, Y_C = -m u r, N_C = -m x_G u r).  In a static-drift or a
rudder test r = 0 and C_RB vanishes; in a rotating-arm or pure-yaw test the model's
centrifugal force is part of the reading, and towing tanks subtract it (the "inertia
correction") to report hydrodynamic forces.  **The X, Y and N of a captive file are these
hydrodynamic forces: the reading minus C_RB**, dimensional, in body axes at midship.  A raw
rotating-arm reading is corrected with :func:`rigid_body_forces`.

The hydrodynamic force contains everything the water exerts in the steady motion: hull,
propeller and rudder forces and the added-mass Coriolis and Munk terms (the fluid's momentum
carried round by the turning body axes).  For the MMG model that is the sum of all parts of
:func:`~sindyship.mmg.force_components` minus the rigid-body part (the KCS keeps its
added-mass terms inside the hull coefficients: ``X_br_minus_my``, ``Y_r_minus_mx``, paper
eq. 3; a ship with ``coriolis = "with-added-mass"`` carries them in its Coriolis part, which
counts here too).  For an identified Abkowitz model (paper eq. 14) the same quantity is the
fitted force of eq. 15 plus the added-mass part of the protocol's Coriolis terms, Munk moment
included, (X'_udot ... as in :func:`sindyship.targets.coriolis`); :mod:`sindyship.forces`
evaluates it.  So the derivatives a captive test measures relate to the identified
coefficients as, e.g., Y_r(captive) = Y'_r + X'_udot and N_v(captive) = N'_v + Y'_vdot -
X'_udot (Prime I).

The captive CSV
---------------
One row per measured condition, columns ``u``, ``v`` [m/s], ``r`` [rad/s], ``delta`` [rad],
optional ``n`` [rps], and the measured ``X``, ``Y`` [N] and ``N`` [N m].  Headers may carry a
unit as in the measurement CSV (``r [deg/s]``, ``delta [deg]``, ``X [kN]``, ``N [kNm]``);
:func:`write_captive_csv` writes bare SI headers.
"""

from __future__ import annotations

import csv
import io
import numbers
import os
from pathlib import Path

import numpy as np
import pandas as pd

from ._io import write_text_atomic
from .errors import SindyshipInputError
from .library import TermLibrary, record_variables
from .measurements import UNITS
from .mmg import force_components
from .plausibility import MAX_REVOLUTION_RATIO
from .ships import Ship
from .terms import CORE_VARIABLES, DERIVED_SOURCES
from .trajectory import Trajectory
from .units import parse_headers

__all__ = [
    "CAPTIVE_COLUMNS",
    "FORCE_COLUMNS",
    "TESTS",
    "captive_tests",
    "check_captive_scale",
    "check_force_scale",
    "classify_tests",
    "force_scales",
    "read_captive_csv",
    "rigid_body_forces",
    "steady_conditions",
    "steady_variables",
    "write_captive_csv",
]

TESTS = ("static-drift", "rudder", "pure-yaw", "drift-yaw")
CAPTIVE_COLUMNS = ("u", "v", "r", "delta")
FORCE_COLUMNS = ("X", "Y", "N")
#: Columns a captive-test CSV may add: the revolutions, and where the ship is held and how it
#: heads (for a model whose terms depend on the position or the heading).
OPTIONAL_CAPTIVE_COLUMNS = ("n", "x", "y", "psi")
_FORCE_QUANTITY = {"X": "force", "Y": "force", "N": "moment"}
#: A non-dimensional v', r' or a rudder angle [rad] below this counts as zero when a captive
#: row is assigned to a test type.
ZERO_TOLERANCE = 1e-9


def force_scales(ship: Ship, system: str) -> np.ndarray:
    """Newtons (and N m) per unit of non-dimensional X, Y, N in a prime system.

    Prime I: 0.5 rho L^2 U0^2 and 0.5 rho L^3 U0^2; Prime II: 0.5 rho L d U0^2 and
    0.5 rho L^2 d U0^2 (ships module docstring).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> bool(np.allclose(force_scales(kcs, "prime-II") / force_scales(kcs, "prime-I"),
    ...                  kcs.d_over_L))
    True
    """
    p = ship.particulars
    q = 0.5 * p.rho * p.U0**2
    if system == "prime-I":
        return q * np.array([p.L**2, p.L**2, p.L**3])
    if system == "prime-II":
        return q * p.d * np.array([p.L, p.L, p.L**2])
    raise SindyshipInputError(f"unknown prime system {system!r}; use 'prime-I' or 'prime-II'.")


def rigid_body_forces(ship: Ship, u, v, r) -> tuple:
    """Rigid-body Coriolis and centrifugal terms of the ship's own mass, SI (paper eq. 11).

    The part of a steady captive reading that is inertia, not water:
    (m v r + m x_G r^2, -m u r, -m x_G u r) [N, N, N m] at u, v [m/s] and r [rad/s], the
    rigid-body Coriolis terms of the MMG model (paper eq. 11), from the ship's mass and centre
    of gravity alone (a ship file made for identification has them).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> X, Y, N = rigid_body_forces(kcs, 12.0, 0.0, 0.01)
    >>> mass = kcs.particulars.rho * kcs.particulars.displacement
    >>> round(float(Y / (-mass * 12.0 * 0.01)), 2)  # -m u r with m = rho * volume
    1.0
    """
    p = ship.particulars
    mass = ship.mass.m * 0.5 * p.rho * p.L**2 * p.d  # Prime II -> kg
    u, v, r = (np.asarray(a, dtype=float) for a in (u, v, r))
    return (mass * v * r + mass * p.x_G * r * r, -mass * u * r, -mass * p.x_G * u * r)


def _mmg_hydrodynamic(ship: Ship, u, v, r, delta, n=None) -> tuple:
    """MMG hydrodynamic forces, SI: all parts of force_components minus rigid-body inertia
    (propeller revolutions ``n`` [rps], default the ship's)."""
    U0, L = ship.U0, ship.L
    parts = force_components(ship, u / U0, v / U0, r * L / U0, delta, n=n)
    scale = force_scales(ship, "prime-II")
    total = [scale[i] * sum(np.asarray(p[i], dtype=float) for p in parts.values())
             for i in range(3)]
    rigid = rigid_body_forces(ship, u, v, r)
    return tuple(total[i] - rigid[i] for i in range(3))


def _sweep(test: str, points: int, beta_max: float, delta_max: float, r_max: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(beta [rad], r' [-], delta [rad]) of one test type."""
    beta = np.linspace(-beta_max, beta_max, points)
    yaw = np.linspace(-r_max, r_max, points)
    zero = np.zeros(points)
    if test == "static-drift":
        return np.radians(beta), zero, zero
    if test == "rudder":
        return zero, zero, np.radians(np.linspace(-delta_max, delta_max, points))
    if test == "pure-yaw":
        return zero, yaw, zero
    grid_beta, grid_r = np.meshgrid(np.radians(beta), yaw, indexing="ij")
    return grid_beta.ravel(), grid_r.ravel(), np.zeros(grid_beta.size)


#: Most conditions of one sweep (a drift-yaw grid holds its square).
MAX_POINTS = 201
#: Fastest carriage, as a multiple of the design speed: tests run faster are of another ship
#: or scale (the KCS's tests given a coaster whose U0 is 6.5 m/s run at 1.9 times it).
MAX_CARRIAGE_SPEED_RATIO = 1.6
#: Slowest carriage: the design speed divided by this (tests at half speed are common).
SPEED_SCALE_FACTOR = 3.0


def _carriage_speed_of(ship: Ship, speed: float) -> bool:
    """Whether captive tests of ``ship`` may run at ``speed`` [m/s] (more than U0 divided by
    :data:`SPEED_SCALE_FACTOR`, at most :data:`MAX_CARRIAGE_SPEED_RATIO` times U0)."""
    return bool(np.isfinite(speed) and ship.U0 / SPEED_SCALE_FACTOR < speed
                <= MAX_CARRIAGE_SPEED_RATIO * ship.U0)


def captive_tests(ship: Ship, test: str = "all", *, points: int = 21, speed: float | None = None,
                  beta_max: float = 20.0, delta_max: float = 35.0, r_max: float = 0.6,
                  revolutions: float | None = None) -> pd.DataFrame:
    """Virtual steady captive tests with the MMG model (paper sections 2.1-2.1.4).

    Parameters
    ----------
    ship : Ship
        The ship and its MMG model.
    test : {"static-drift", "rudder", "pure-yaw", "drift-yaw", "all"}
        Test type (module docstring); ``"all"`` stacks the four.
    points : int
        Conditions per sweep (odd numbers include the straight-ahead point); ``drift-yaw`` is
        a grid of ``points`` x ``points``.
    speed : float, optional
        Carriage speed U [m/s] (default the design speed U0).
    beta_max, delta_max : float
        Largest drift and rudder angles [deg].
    r_max : float
        Largest non-dimensional yaw rate r' = r L / U0.
    revolutions : float, optional
        Propeller revolutions [rps] held through the tests, above 0 and at most
        :data:`sindyship.plausibility.MAX_REVOLUTION_RATIO` times the ship's, as a record's
        (default the ship's ``n_P``): a model tested at the revolutions of its free-running
        trials.

    Returns
    -------
    pandas.DataFrame
        Columns ``u``, ``v`` [m/s], ``r`` [rad/s], ``delta`` [rad], ``n`` [rps] (the propeller
        revolutions) and the hydrodynamic ``X``, ``Y`` [N], ``N`` [N m] in body axes at
        midship (the reading minus the rigid-body inertia; module docstring).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> frame = captive_tests(load_ship("kcs"), "static-drift", points=5)
    >>> [round(float(b), 1) for b in np.degrees(np.arctan2(-frame.v, frame.u))]
    [-20.0, -10.0, 0.0, 10.0, 20.0]
    >>> bool(frame.Y.iloc[0] < 0 < frame.Y.iloc[-1])  # Y has the sign of beta
    True
    """
    if test == "all":
        return pd.concat([captive_tests(ship, t, points=points, speed=speed, beta_max=beta_max,
                                        delta_max=delta_max, r_max=r_max,
                                        revolutions=revolutions) for t in TESTS],
                         ignore_index=True)
    if test not in TESTS:
        raise SindyshipInputError(
            f"unknown captive test {test!r}; choose one of {', '.join(TESTS)} or all."
        )
    if not ship.has_mmg:
        raise SindyshipInputError(
            f"ship {ship.name!r} has no MMG hull, propeller and rudder coefficients, so it has no "
            "virtual captive tests; give a ship file with [hull], [propeller] and [rudder], or "
            "compare a model with measured captive tests (sindyship forces MODEL CAPTIVE.csv)."
        )
    if isinstance(points, bool) or not (isinstance(points, int | np.integer)
                                        and 2 <= points <= MAX_POINTS):
        raise SindyshipInputError(f"a captive sweep takes 2 to {MAX_POINTS} points, not "
                                  f"{points!r}.")
    U = ship.U0 if speed is None else float(speed)
    if not _carriage_speed_of(ship, U):
        raise SindyshipInputError(
            f"the carriage speed must be more than a third of the ship's design speed and at "
            f"most {MAX_CARRIAGE_SPEED_RATIO:g} times it ({ship.U0 / SPEED_SCALE_FACTOR:.4g} to "
            f"{MAX_CARRIAGE_SPEED_RATIO * ship.U0:.4g} m/s), not {speed!r} m/s."
        )
    n = _revolutions(ship, revolutions)
    beta, r_nd, delta = _sweep(test, int(points), beta_max, delta_max, r_max)
    u = U * np.cos(beta)
    v = -U * np.sin(beta)
    r = r_nd * ship.U0 / ship.L
    X, Y, N = _mmg_hydrodynamic(ship, u, v, r, delta, n=n)
    return pd.DataFrame({"u": u, "v": v, "r": r, "delta": delta, "n": np.full(u.size, n),
                         "X": X, "Y": Y, "N": N})


def _revolutions(ship: Ship, revolutions) -> float:
    """The propeller revolutions [rps] of the tests: the ship's, or those given, checked."""
    own = ship.propeller.n_P
    if revolutions is None:
        return float(own)
    if isinstance(revolutions, bool) or not isinstance(revolutions, numbers.Real) or not (
            0.0 < revolutions <= MAX_REVOLUTION_RATIO * own):
        raise SindyshipInputError(
            f"the propeller revolutions of captive tests must be above 0 and at most "
            f"{MAX_REVOLUTION_RATIO:g} times the ship's {own:.4g} rps (rps, not rpm), not "
            f"{revolutions!r}.")
    return float(revolutions)


def classify_tests(frame: pd.DataFrame, ship: Ship) -> np.ndarray:
    """The test type of every captive row, from which of v', r' and delta are non-zero.

    ``static-drift`` (v only), ``rudder`` (delta only), ``pure-yaw`` (r only), ``drift-yaw``
    (v and r), ``combined`` (the rudder with v or r) and ``straight`` (none), all going ahead;
    ``astern`` for a row whose surge speed u is zero or negative, whatever else it holds (a
    four-quadrant test's second quadrant).

    Examples
    --------
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> sorted(set(classify_tests(captive_tests(kcs, "all", points=4), kcs)))
    ['drift-yaw', 'pure-yaw', 'rudder', 'static-drift']
    """
    v = np.abs(frame["v"].to_numpy(float) / ship.U0) > ZERO_TOLERANCE
    r = np.abs(frame["r"].to_numpy(float) * ship.L / ship.U0) > ZERO_TOLERANCE
    d = np.abs(frame["delta"].to_numpy(float)) > ZERO_TOLERANCE
    names = np.full(len(frame), "combined", dtype=object)
    names[~v & ~r & ~d] = "straight"
    names[v & ~r & ~d] = "static-drift"
    names[~v & ~r & d] = "rudder"
    names[~v & r & ~d] = "pure-yaw"
    names[v & r & ~d] = "drift-yaw"
    names[~(frame["u"].to_numpy(float) > 0.0)] = "astern"
    return names


def steady_variables(captive: pd.DataFrame, library: TermLibrary, ship: Ship,
                     rudder_signal: str = "actual") -> dict[str, np.ndarray]:
    """A library's non-dimensional variables at each captive condition, held steady
    (:func:`steady_conditions`).

    The commanded rudder is the actual one, a channel the library delays reads what the
    table gives (the condition has held it) and the rudder does not move (``delta_rate``
    0); each row stands alone (its time is only its place).

    Parameters
    ----------
    captive : pandas.DataFrame
        Conditions: ``u``, ``v``, ``r``, ``delta`` and every channel the library's terms
        read, SI (as :func:`read_captive_csv` gives).
    library : TermLibrary
    ship : Ship
        Gives L and U0.
    rudder_signal : {"actual", "commanded"}

    Raises
    ------
    SindyshipInputError
        When the table lacks a column the terms read (one sentence naming it and the fix).

    Examples
    --------
    >>> from sindyship.library import load_library
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> values = steady_variables(captive_tests(kcs, "pure-yaw", points=3),
    ...                           load_library("abkowitz"), kcs)
    >>> [round(float(x), 2) for x in values["r"]]
    [-0.6, 0.0, 0.6]
    """
    missing = [c for c in CAPTIVE_COLUMNS if c not in captive.columns]
    if missing:
        raise SindyshipInputError(
            f"the captive table lacks the column '{missing[0]}'; give u, v, r and delta."
        )
    needed = set(library.sources) - set(CORE_VARIABLES) - {"psi", "x", "y", "delta_rate"}
    if "psi" in library.variables or set(DERIVED_SOURCES) & library.variables:
        needed.add("psi")  # the heading, or the wind's direction relative to the bow
    absent = sorted(needed - set(captive.columns))
    if absent:
        names = ", ".join(absent)
        raise SindyshipInputError(
            f"the model's terms read {names}, which the captive table does not give; add "
            f"{'a column' if len(absent) == 1 else 'columns'} {names} with the value each "
            "condition was held at (in a towing tank's still air wind_speed 0, with any "
            "wind_dir and psi), or use a model without that effect."
        )
    if {"x", "y"} & library.sources - set(captive.columns):
        raise SindyshipInputError(
            "the model's terms depend on where the ship is (its position x, y, or a shape of "
            "it such as a bank's pull), which the captive table does not give; add columns x "
            "and y [m] to say where each condition is held."
        )
    values = record_variables(steady_conditions(captive, library), library, ship.L, ship.U0,
                              rudder_signal)
    if "delta_rate" in values:
        values["delta_rate"] = np.zeros(len(captive))
    return values


def steady_conditions(captive: pd.DataFrame, library: TermLibrary) -> Trajectory:
    """The captive conditions as a record named ``captive`` whose rows stand alone: the
    commanded rudder is the actual one, a channel the library delays reads what the table
    gives, and each row's time is only its place."""
    conditions = captive.assign(delta_c=captive["delta"]).reset_index(drop=True)
    conditions["t"] = np.arange(len(conditions), dtype=float)
    return Trajectory(conditions, name="captive", meta={"aligned": dict(library.delays)})


#: Measured captive forces whose size (RMS) differs from a model's by more than this factor
#: are in another unit: a kN figure read as newtons is 1000 times too small, while a fitted
#: model's forces come within some tens of the measured ones even where their shapes disagree
#: (least squares fitted on gusty records: 30 times in Y).
FORCE_SCALE_FACTOR = 300.0
def check_force_scale(dof: str, measured: np.ndarray, predicted: np.ndarray,
                      predictor: str) -> None:
    """Refuse a measured captive force :data:`FORCE_SCALE_FACTOR` times or more larger or
    smaller (RMS) than ``predicted``, what ``predictor`` (words: "the model predicts")
    expects: a unit the header does not say (forces in kN under a bare ``X``)."""
    size = float(np.sqrt(np.mean(np.square(measured))))
    expected = float(np.sqrt(np.mean(np.square(predicted))))
    if size > 0.0 and expected > 0.0 and not (
            1.0 / FORCE_SCALE_FACTOR < size / expected < FORCE_SCALE_FACTOR):
        raise SindyshipInputError(
            f"the measured {dof} is {size / expected:.3g} times the size {predictor} (RMS), "
            "so the forces are likely in another unit than the header says; give it in the "
            f"header, e.g. '{dof} [{'kNm' if dof == 'N' else 'kN'}]'."
        )




def check_captive_scale(captive: pd.DataFrame, ship: Ship, *, reads_revolutions: bool,
                        whose: str = "the model's ship") -> None:
    """Refuse captive tests far from the ship's design speed (another ship, or another scale),
    and, where the terms read them (``reads_revolutions``), revolutions far above the ship's
    own (rpm under a bare ``n`` header are 60 times too high, and the forces would be
    blamed); ``whose`` names the ship in the message."""
    from .plausibility import excess_revolutions

    speed = float(np.median(np.hypot(captive["u"], captive["v"])))
    if not _carriage_speed_of(ship, speed):
        raise SindyshipInputError(
            f"the captive tests run at {speed:.3g} m/s (median), far from the design speed "
            f"{ship.U0:.3g} m/s of {whose} {ship.name!r}; give captive tests of the same ship "
            "at the same scale (Froude-scale them first)."
        )
    if "n" not in captive.columns or not reads_revolutions:
        return
    typical = float(np.median(np.abs(captive["n"].to_numpy(float))))
    excess = excess_revolutions(typical, ship)
    if excess is None:
        return
    ratio, rpm = excess
    hint = ("they look like rpm: write the header as 'n [rpm]'" if rpm else
            "check the unit of n and that the ship (full or model scale) is right")
    raise SindyshipInputError(
        f"the captive tests' revolutions n have a median of {typical:.4g}, {ratio:.3g} "
        f"times the propeller revolutions n = {ship.propeller.n_P:.4g} rps of {whose} "
        f"{ship.name!r}; {hint}."
    )


# ---------------------------------------------------------------------------------------------
# The captive CSV
# ---------------------------------------------------------------------------------------------
def write_captive_csv(frame: pd.DataFrame, path: str | os.PathLike[str]) -> Path:
    """Write captive tests as a CSV with bare SI headers, atomically.

    Values are written with ``repr`` (they read back identical).  Columns: ``u, v, r, delta``,
    ``n`` when present, then ``X, Y, N``.

    Raises
    ------
    SindyshipInputError
        When a column is missing or the file cannot be written.
    """
    target = Path(path)
    missing = [c for c in (*CAPTIVE_COLUMNS, *FORCE_COLUMNS) if c not in frame.columns]
    if missing:
        raise SindyshipInputError(
            f"{target}: the captive table lacks the column '{missing[0]}'; captive tests need "
            "u, v, r, delta, X, Y and N."
        )
    columns = [*CAPTIVE_COLUMNS, *(["n"] if "n" in frame.columns else []), *FORCE_COLUMNS]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    values = frame[columns].to_numpy(dtype=float).tolist()
    writer.writerows([repr(x) for x in row] for row in values)
    try:
        write_text_atomic(target, buffer.getvalue())
    except OSError as error:
        raise SindyshipInputError(
            f"{target}: cannot write the file ({error.strerror or error}); check that its "
            "folder can be written."
        ) from error
    return target


def read_captive_csv(path: str | os.PathLike[str]) -> pd.DataFrame:
    """Read a captive-test CSV into SI units.

    Headers and units are parsed as for the measurement CSV
    (:mod:`sindyship.measurements`): ``r [deg/s]``, ``delta [deg]``, ``u [kn]``,
    ``n [rpm]``, ``X [kN]``, ``N [kNm]``.  The optional columns ``n``, and ``x``, ``y``
    [m], ``psi`` (where each condition is held, for a model whose terms depend on the
    position or the heading) are kept, and so is any other column of numbers, as a channel
    a model's terms may read (``depth`` of a shallow-water test, heel ``phi``, ``wind_speed``);
    columns holding text are ignored.

    Returns
    -------
    pandas.DataFrame
        Columns ``u, v, r, delta`` (the optional ones when given) and ``X, Y, N``, SI.

    Raises
    ------
    SindyshipInputError
        One sentence naming the file and the column or row: missing or unreadable file, no
        data rows, missing or duplicate column, unknown or wrong unit, text, NaN or inf in a
        number, a rudder angle or yaw rate that looks like degrees in a radian column.
    """
    from . import measurements

    source = str(path)
    raw = measurements.parse_csv_text(measurements.read_text(Path(path), source), source)
    columns = parse_headers([str(h) for h in raw.columns], source)
    by_name = {c.name: (position, c) for position, c in enumerate(columns)}
    wanted = [*CAPTIVE_COLUMNS, *FORCE_COLUMNS]
    missing = [name for name in wanted if name not in by_name]
    if missing:
        raise SindyshipInputError(
            f"{source}: missing column '{missing[0]}'; a captive-test CSV needs the columns "
            "u, v [m/s], r [rad/s], delta [rad], X, Y [N] and N [N m] (n [rps] optional)."
        )
    if len(raw) == 0:
        raise SindyshipInputError(
            f"{source}: has no data rows; give one row per captive condition after the header."
        )
    out = {}
    optional = [name for name in OPTIONAL_CAPTIVE_COLUMNS if name in by_name]
    known = {*CAPTIVE_COLUMNS, *OPTIONAL_CAPTIVE_COLUMNS, *FORCE_COLUMNS}
    optional += [c.name for position, c in enumerate(columns) if c.name not in known
                 and pd.to_numeric(raw.iloc[:, position], errors="coerce").notna().all()]
    for name in [*CAPTIVE_COLUMNS, *optional, *FORCE_COLUMNS]:
        position, column = by_name[name]
        if name in _FORCE_QUANTITY and column.unit is not None:
            _check_force_unit(column, _FORCE_QUANTITY[name], source)
        values = measurements.column_as_float(raw.iloc[:, position].to_numpy(), column, raw.index,
                                        source)
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise SindyshipInputError(
                f"{source}: column '{column.header}' has no finite value in row "
                f"{raw.index[bad[0]]} (counting the header as row 1); write a number there "
                "or delete the row."
            )
        out[name] = values * column.factor
    frame = pd.DataFrame(out)
    _check_captive_plausible(frame, by_name, raw.index, source)
    return frame


def _check_force_unit(column, quantity: str, source: str) -> None:
    key = column.unit.replace(" ", "")
    found = UNITS.get(key) or next((q for s, q in UNITS.items() if s.lower() == key.lower()),
                                   None)
    if found is None or found[0] != quantity:
        units = ", ".join(s for s, (q, _) in UNITS.items() if q == quantity)
        raise SindyshipInputError(
            f"{source}: column '{column.header}' needs a unit of {quantity}; use one of {units}."
        )


def _check_captive_plausible(frame: pd.DataFrame, by_name: dict, index, source: str) -> None:
    from .measurements import MAX_RUDDER_ANGLE, MAX_SPEED, MAX_YAW_RATE

    limits = (("u", MAX_SPEED, "any ship speed", "m/s"), ("v", MAX_SPEED, "any ship speed", "m/s"),
              ("delta", MAX_RUDDER_ANGLE, "any rudder angle", "rad; write 'delta [deg]' if the "
               "values are degrees"),
              ("r", MAX_YAW_RATE, "any ship's yaw rate", "rad/s; write 'r [deg/s]' if the "
               "values are deg/s"))
    for name, limit, what, unit in limits:
        values = np.abs(frame[name].to_numpy())
        position = int(np.argmax(values))
        if values[position] > limit:
            header = by_name[name][1].header
            raise SindyshipInputError(
                f"{source}: column '{header}' reaches {frame[name].iloc[position]:.6g} in row "
                f"{index[position]} (counting the header as row 1), beyond {what} "
                f"({limit:g} {unit})."
            )

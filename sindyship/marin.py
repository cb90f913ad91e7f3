"""Loader for the KVLCC2 free-running manoeuvres measured at MARIN (SIMMAN 2008), full scale.

Six records (turning circles at +-35 deg, zig-zags 10/10 and 20/20 to both sides) of the KVLCC2
tanker, tested at model scale 1:45.7 (Lpp 7.0 m) and converted by MARIN to full scale (Lpp
320 m).  :func:`read_marin` returns them as :class:`~sindyship.trajectory.Trajectory` objects in
sindyship's conventions, still at full scale; :func:`to_model_scale` Froude-scales a record to
the model (the built-in kvlcc2 ship, docs/ship-toml.md, is the 7 m model).

File format
-----------
Two title lines, then rows of 11 numbers separated by tabs: time [s], x0 [m], y0 [m], roll phi
[deg], heading psi [deg], u [m/s], v [m/s], roll rate p [deg/s], yaw rate r [deg/s], rudder
delta [deg], propeller rev [rpm].  Rows that hold only tabs are skipped.

How the loader handles the files
--------------------------------
- Every value has three significant figures.  The time column therefore steps by 1 s after
  100 s and by 10 s after 1000 s, so time is rebuilt as ``t = i * 0.1353`` s over the kept
  rows (``MARIN_DT``).  The loader refuses a file whose recorded times stray from that grid by
  more than their rounding (1 % + one step), which would mean missing rows.  A least-squares
  fit of the recorded times gives 0.13526 s; over a 2100 s record the two grids drift apart by
  0.5 s, inside the 5 s rounding of the recorded times there.
- Positions are quantised in the same way (10 m steps beyond 1 km), the heading to 0.1 deg
  below 100 deg and to 1 deg above: differentiate neither without smoothing over tens of
  seconds.  The recorded u, v, r
  and p are the velocity channels to use.
- The u and v columns are earth-fixed velocity components (north, east): they integrate to
  the positions (see below).  They are rotated by psi into body-fixed surge and sway.
- Propeller revolutions become ``n`` in rps (full scale, about 1.53 rps = 91.5 rpm).
- Roll angle and roll rate are kept as the extra channels ``phi`` [rad] and ``p`` [rad/s],
  positive starboard down (right-handed about the forward axis; p follows d phi / dt with a
  correlation of at least 0.997).

Sign convention (decided from the data)
---------------------------------------
x0 points north and y0 east, psi is clockwise from north, r = d psi / dt, and a positive
recorded rudder angle turns the ship to port.  The loader therefore keeps x0, y0, psi, r, phi
and p as recorded and negates only the rudder angle: ``delta = -delta_recorded``.  In
sindyship's convention ``tc_35`` is a port turn with delta = -35 deg and ``tc_-35`` a starboard
turn with delta = +35 deg; the short names in ``MARIN_FILES`` keep MARIN's labels.

Kinematics alone cannot tell this reading from its mirror image (y0 to port, psi
anticlockwise, positive rudder to starboard): both make the files self-consistent.  The
evidence, checked by the tests:

- The recorded earth-fixed velocity, integrated at 0.1353 s, reproduces x0, y0 within 7 m
  over the 4.5 to 5.4 km of each zig-zag (within 145 m, 1.5 %, over the 9 km turning
  circles, where the mismatch grows by about 70 m per full circle).  The recorded r follows
  the heading: its correlation with the slope of psi over +-5 s exceeds 0.9997 in the
  zig-zags, and over +-20 s exceeds 0.996 in the turning circles (whose 1 deg heading steps
  need the longer window).  So x0, y0, psi, u, v and r share one frame: either reading above.
- The roll decides between the two.  In every record the least-squares slope of phi against
  U r (U the speed, r the recorded yaw rate) is negative, -3.3 to -8.3 deg per m/s^2: under
  this reading the ship heels outward in a turn (port side down in a starboard turn), as a
  ship with its centre of gravity above the centre of the lateral hull force does; the mirror
  reading would make it heel inward, in the turning circles and in every zig-zag alike.  The
  roll sign is the same (starboard down) in either right-handed reading.
- The turn labelled 35, a port turn under this reading, is the tighter one: advance 3.02 L and
  tactical diameter 3.07 L against 3.09 L and 3.33 L for the starboard turn, as expected of a
  single right-handed propeller.  A positive rudder angle turning to port is also the
  ITTC/SNAME sign (positive rudder = trailing edge to port).

Records for the command line
----------------------------
``python3 -m sindyship.marin OUT`` writes the six records as measurement CSVs at full scale,
resampled onto a 1 s grid (``tc_35.csv``, ...), and the full-scale ship they belong to
(:func:`full_scale_ship`, ``kvlcc2-full-scale.toml``) into the folder ``OUT``
(:func:`write_records`), for ``sindyship fit ... --ship OUT/kvlcc2-full-scale.toml``.

Left as found: the ship rolls (up to 0.9 deg), which a 3-DOF model leaves out; in the turning
circles the roll also swings by about 0.3 deg once per circle, and the velocity-position
mismatch grows once per circle in mirror-image directions for the two turns.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from sindyship._io import write_text_atomic
from sindyship.errors import SindyshipInputError
from sindyship.measurements import trajectory_from_frame, write_csv
from sindyship.ships import Ship, load_ship, ship_to_toml
from sindyship.trajectory import Trajectory

__all__ = [
    "MARIN_COLUMNS",
    "MARIN_DT",
    "MARIN_FILES",
    "MARIN_LPP",
    "MARIN_SCALE",
    "default_marin_dir",
    "execute_index",
    "full_scale_ship",
    "read_marin",
    "to_model_scale",
    "write_records",
]

#: Short names of the six records and their file names.
MARIN_FILES: dict[str, str] = {
    "tc_35": "MARIN_FREE_KVLCC2_tc_35_m.dat",
    "tc_-35": "MARIN_FREE_KVLCC2_tc_-35_m.dat",
    "zz_10": "MARIN_FREE_KVLCC2_zz_10_m.dat",
    "zz_-10": "MARIN_FREE_KVLCC2_zz_-10_m.dat",
    "zz_20": "MARIN_FREE_KVLCC2_zz_20_m.dat",
    "zz_-20": "MARIN_FREE_KVLCC2_zz_-20_m.dat",
}
#: The names of the MARIN files, as a pattern.
MARIN_PATTERN = "MARIN_FREE_KVLCC2_*_m.dat"

MARIN_DT = 0.1353  #: sample interval of the files [s], full scale
MARIN_LPP = 320.0  #: length between perpendiculars of the full-scale ship [m]
MARIN_SCALE = 45.7  #: model scale factor (the 7.0 m model is 1:45.7)

#: The eleven columns of a MARIN file, in order.
MARIN_COLUMNS = ("time", "x0", "y0", "phi", "psi", "u", "v", "p", "r", "delta", "rev")

_ENVIRONMENT = "SINDYSHIP_MARIN_DIR"


def default_marin_dir() -> Path | None:
    """Return the folder of the MARIN files, or None when it is absent.

    The folder is ``$SINDYSHIP_MARIN_DIR`` when that variable is set (and not empty), else
    ``shared/data/kvlcc2-marin`` beside the project folder.

    Returns
    -------
    pathlib.Path or None
        The resolved folder if it exists.

    Examples
    --------
    >>> folder = default_marin_dir()
    >>> folder is None or (folder / MARIN_FILES["tc_35"]).name.endswith("_m.dat")
    True
    """
    configured = os.environ.get(_ENVIRONMENT, "").strip()
    if configured:
        folder = Path(configured).expanduser()
    else:
        folder = Path(__file__).parents[1] / ".." / "shared" / "data" / "kvlcc2-marin"
    folder = folder.resolve()
    return folder if folder.is_dir() else None


def read_marin(path: str | os.PathLike[str]) -> Trajectory:
    """Read one MARIN KVLCC2 file into a full-scale :class:`Trajectory` in SI units.

    See the module documentation for the format, the conversions and the sign convention.

    Parameters
    ----------
    path : str or os.PathLike
        A ``MARIN_FREE_KVLCC2_*_m.dat`` file.

    Returns
    -------
    Trajectory
        Columns ``t, u, v, r, x, y, psi, delta, n, phi, p``; named after the file stem, with
        ``meta`` holding ``source``, ``title`` (the second title line), ``full_scale`` (True),
        ``lpp`` (320.0 m) and ``scale_factor`` (45.7).

    Raises
    ------
    SindyshipInputError
        When the file is missing or unreadable, a row does not hold 11 numbers, or the
        recorded times do not follow the 0.1353 s sampling.

    Examples
    --------
    A turn to port as MARIN records it (positive rudder, heading decreasing):

    >>> import tempfile
    >>> rows = [f"{i * 0.1353:.3g}\\t{8 * i * 0.1353:.3g}\\t0\\t0\\t{-0.5 * i:.3g}\\t8\\t0"
    ...         f"\\t0\\t-3.7\\t35\\t91.5" for i in range(3)]
    >>> text = "MARIN\\nTurning for KVLCC2 : 35 (deg)\\n\\n" + "\\n".join(rows) + "\\n\\t\\t\\n"
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "MARIN_FREE_KVLCC2_tc_35_m.dat"
    ...     _ = path.write_text(text)
    ...     record = read_marin(path)
    >>> record.n_samples, record.dt
    (3, 0.1353)
    >>> [round(float(np.rad2deg(record[c][0])), 6) for c in ("delta", "r")]
    [-35.0, -3.7]
    >>> round(float(record["n"][0]), 4)
    1.525
    """
    source = str(path)
    try:
        # The files are ASCII; latin-1 reads any byte, so odd title characters cannot fail.
        lines = Path(path).read_text(encoding="latin-1").splitlines()
    except FileNotFoundError:
        raise SindyshipInputError(f"{source}: file not found; check the path.") from None
    except OSError as error:
        raise SindyshipInputError(
            f"{source}: cannot be read ({error.strerror or error}); check the path."
        ) from None

    values = []
    numbers = []
    for number, line in enumerate(lines, start=1):
        fields = line.split()
        if number <= 2:
            if len(fields) == len(MARIN_COLUMNS) and _all_numbers(fields):
                raise SindyshipInputError(
                    f"{source}: line {number} holds numbers where a MARIN file has its two "
                    "title lines; restore the title lines."
                )
            continue
        if not fields:
            continue  # rows of tabs only
        if len(fields) != len(MARIN_COLUMNS):
            raise SindyshipInputError(
                f"{source}: line {number} holds {len(fields)} values instead of "
                f"{len(MARIN_COLUMNS)} ({', '.join(MARIN_COLUMNS)}); give a MARIN KVLCC2 file."
            )
        row = []
        for column, field in zip(MARIN_COLUMNS, fields, strict=True):
            try:
                row.append(float(field))
            except ValueError:
                raise SindyshipInputError(
                    f"{source}: line {number}, column '{column}' holds '{field}' where a "
                    "number is expected; correct the file."
                ) from None
        values.append(row)
        numbers.append(number)
    if len(values) < 2:
        raise SindyshipInputError(
            f"{source}: fewer than two data rows after the two title lines; give a MARIN file."
        )

    raw = dict(zip(MARIN_COLUMNS, np.array(values).T, strict=True))
    t = MARIN_DT * np.arange(len(values))
    _check_recorded_time(raw["time"], t, numbers, source)

    psi = np.unwrap(np.deg2rad(raw["psi"]))
    north, east = raw["u"], raw["v"]
    frame = pd.DataFrame(
        {
            "t": t,
            "u": north * np.cos(psi) + east * np.sin(psi),
            "v": -north * np.sin(psi) + east * np.cos(psi),
            "r": np.deg2rad(raw["r"]),
            "x": raw["x0"],
            "y": raw["y0"],
            "psi": psi,
            "delta": -np.deg2rad(raw["delta"]),
            "n": raw["rev"] / 60.0,
            "phi": np.deg2rad(raw["phi"]),
            "p": np.deg2rad(raw["p"]),
        }
    )
    record = trajectory_from_frame(frame, Path(path).stem, source=source)
    title = lines[1].strip() if len(lines) > 1 else ""
    meta = {
        "source": source,
        "title": title,
        "full_scale": True,
        "lpp": MARIN_LPP,
        "scale_factor": MARIN_SCALE,
    }
    return Trajectory(record.data, name=record.name, meta=meta)


def execute_index(trajectory: Trajectory) -> int:
    """Index of the rudder execute: the first sample where |delta - delta(0)| > 1 deg.

    Manoeuvre figures (advance, tactical diameter, overshoots) are measured from this sample.
    The actual rudder angle is used when recorded, else the commanded one.

    Parameters
    ----------
    trajectory : Trajectory
        A record with a rudder channel.

    Returns
    -------
    int
        The sample index.

    Raises
    ------
    SindyshipInputError
        When the rudder never moves more than 1 deg from its first value.

    Examples
    --------
    >>> frame = pd.DataFrame({"t": [0.0, 1.0, 2.0, 3.0], "u": 8.0, "v": 0.0, "r": 0.0,
    ...                       "x": [0.0, 8.0, 16.0, 24.0], "y": 0.0, "psi": 0.0,
    ...                       "delta": np.deg2rad([-1.0, -0.5, 0.5, 10.0])})
    >>> execute_index(Trajectory(frame, "demo"))
    2
    """
    rudder = trajectory.rudder
    moved = np.flatnonzero(np.abs(rudder - rudder[0]) > np.deg2rad(1.0))
    if moved.size == 0:
        raise SindyshipInputError(
            f"{trajectory.name or '<data>'}: the rudder never moves more than 1 deg from its "
            "first value, so the record has no rudder execute; use a manoeuvre record."
        )
    return int(moved[0])


def to_model_scale(trajectory: Trajectory, scale: float = MARIN_SCALE) -> Trajectory:
    """Froude-scale a full-scale record down to a model of scale 1:``scale``.

    Lengths divide by ``scale``, times and speeds by ``sqrt(scale)``, angular rates and
    propeller revolutions multiply by ``sqrt(scale)``; angles are unchanged.

    Parameters
    ----------
    trajectory : Trajectory
        A full-scale record with the channels ``t, u, v, r, x, y, psi``, rudder angles and
        optionally ``n``, ``phi``, ``p``.
    scale : float, default 45.7
        The scale factor (full-scale length over model length).

    Returns
    -------
    Trajectory
        The model-scale record; ``meta`` says ``full_scale`` False and gives ``lpp`` at model
        scale when the input had it.

    Raises
    ------
    ValueError
        When the record holds a channel whose scaling is not known.

    Examples
    --------
    >>> frame = pd.DataFrame({"t": [0.0, 6.76], "u": 7.93, "v": 0.0, "r": 0.0,
    ...                       "x": [0.0, 53.6], "y": 0.0, "psi": 0.0, "delta": 0.0,
    ...                       "n": 1.525})
    >>> model = to_model_scale(Trajectory(frame, "run", {"lpp": 320.0}))
    >>> [round(float(model[c][-1]), 3) for c in ("t", "u", "x", "n")]
    [1.0, 1.173, 1.173, 10.309]
    >>> round(model.meta["lpp"], 3)
    7.002
    """
    root = math.sqrt(scale)
    factors = {
        "t": 1.0 / root,
        "u": 1.0 / root,
        "v": 1.0 / root,
        "r": root,
        "p": root,
        "x": 1.0 / scale,
        "y": 1.0 / scale,
        "psi": 1.0,
        "phi": 1.0,
        "delta": 1.0,
        "delta_c": 1.0,
        "n": root,
    }
    unknown = [column for column in trajectory.data.columns if column not in factors]
    if unknown:
        raise ValueError(f"no Froude scaling known for the channels {unknown}")
    data = trajectory.data.copy()
    for column in data.columns:
        data[column] = data[column] * factors[column]
    meta = dict(trajectory.meta, full_scale=False, scale_factor=scale)
    if "lpp" in meta:
        meta["lpp"] = meta["lpp"] / scale
    return Trajectory(data, name=trajectory.name, meta=meta)


def _all_numbers(fields: list[str]) -> bool:
    try:
        [float(field) for field in fields]
    except ValueError:
        return False
    return True


def _check_recorded_time(
    recorded: np.ndarray, rebuilt: np.ndarray, numbers: list[int], source: str
) -> None:
    """Refuse records whose time column does not follow the 0.1353 s grid (missing rows)."""
    allowed = 0.01 * np.abs(recorded) + MARIN_DT
    bad = np.flatnonzero(np.abs(recorded - rebuilt) > allowed)
    if bad.size:
        i = bad[0]
        raise SindyshipInputError(
            f"{source}: line {numbers[i]} records t = {recorded[i]:g} s but sample {i} of a "
            f"{MARIN_DT} s grid is at {rebuilt[i]:.4g} s, so rows are missing; use the "
            "complete file."
        )


#: The file :func:`write_records` writes the full-scale ship to, beside the records.
FULL_SCALE_SHIP_FILE = "kvlcc2-full-scale.toml"


def full_scale_ship() -> Ship:
    """The ship of the records: the built-in KVLCC2 model (L = 7 m) Froude-scaled by
    :data:`MARIN_SCALE` (L = 319.9 m, :meth:`sindyship.ships.Ship.scaled`).

    Examples
    --------
    >>> ship = full_scale_ship()
    >>> round(ship.L, 1), round(ship.U0, 2)
    (319.9, 7.97)
    """
    return load_ship("kvlcc2").scaled(MARIN_SCALE)


def write_records(out: str | os.PathLike[str], folder: str | os.PathLike[str] | None = None,
                  *, resample: float = 1.0) -> list[Path]:
    """Write the records as measurement CSVs and their ship as a ship file.

    The six MARIN files (:data:`MARIN_FILES`) that are in ``folder`` are converted, the
    others left out (``main`` names them): a user with the zig-zags alone can fit on them.

    Parameters
    ----------
    out : str or os.PathLike
        The folder to write into (made if missing): ``tc_35.csv`` ... (``MARIN_FILES``'s
        short names; full scale, resampled onto a ``resample`` s grid) and
        :data:`FULL_SCALE_SHIP_FILE` (:func:`full_scale_ship`).
    folder : str or os.PathLike, optional
        The folder of the MARIN files; default :func:`default_marin_dir`.
    resample : float
        The sample interval of the CSVs [s] (the files are sampled every 0.1353 s).

    Returns
    -------
    list of pathlib.Path
        The files written, the ship file last.

    Raises
    ------
    SindyshipInputError
        When the folder does not exist or holds none of the files, ``out`` is a file, or a
        file cannot be read (nothing is written then).
    """
    source = default_marin_dir() if folder is None else Path(folder)
    if source is None:
        raise SindyshipInputError(
            "the MARIN files were not found; name their folder (--data DIR on the command "
            f"line) or set {_ENVIRONMENT}.")
    target = Path(out)
    if target.exists() and not target.is_dir():
        raise SindyshipInputError(f"{target}: exists and is not a folder; name a folder to "
                                  "write the records into.")
    if not source.is_dir():
        raise SindyshipInputError(f"{source}: no such folder; name the folder of the MARIN "
                                  f"files (--data DIR on the command line, or {_ENVIRONMENT}).")
    present = {short: source / name for short, name in MARIN_FILES.items()
               if (source / name).is_file()}
    if not present:
        raise SindyshipInputError(
            f"{source}: none of the MARIN files ({MARIN_PATTERN}) is there; name the folder "
            f"that holds them (--data DIR on the command line, or {_ENVIRONMENT}).")
    records = {short: trajectory_from_frame(read_marin(path).data, short, source=str(path),
                                            resample=resample)
               for short, path in present.items()}  # all read before any is written
    written = [write_csv(record, target / f"{short}.csv") for short, record in records.items()]
    ship = target / FULL_SCALE_SHIP_FILE
    write_text_atomic(ship, ship_to_toml(full_scale_ship()))
    return [*written, ship]


def main(argv: list[str] | None = None) -> int:
    """``python3 -m sindyship.marin OUT [--data DIR] [--resample S]`` (:func:`write_records`);
    exit 0, or 2 with one line on stderr for bad input."""
    import argparse
    import sys

    parser = argparse.ArgumentParser(
        prog="python3 -m sindyship.marin",
        description="Write the MARIN KVLCC2 records as measurement CSVs (full scale) and "
                    f"their full-scale ship file ({FULL_SCALE_SHIP_FILE}) into OUT.")
    parser.add_argument("out", help="folder to write into")
    parser.add_argument("--data", default=None, help=f"folder of the {MARIN_PATTERN} files "
                        f"(default: ${_ENVIRONMENT})")
    parser.add_argument("--resample", type=float, default=1.0,
                        help="sample interval of the CSVs [s] (default 1)")
    args = parser.parse_args(argv)
    try:
        written = write_records(args.out, args.data, resample=args.resample)
    except SindyshipInputError as error:
        print(f"python3 -m sindyship.marin: error: {error}", file=sys.stderr)
        return 2
    print(f"wrote {len(written) - 1} records and {written[-1].name} to {args.out}/",
          file=sys.stderr)
    missing = [name for short, name in MARIN_FILES.items()
               if short not in {path.stem for path in written[:-1]}]
    if missing:
        print(f"note: {', '.join(missing)} not found, so left out; add the missing files to the "
              "folder and run this again to convert them too.", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

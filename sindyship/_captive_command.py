"""Command-line verbs ``captive`` and ``forces`` (parsers and commands, wired in by cli.py).

``sindyship captive --ship kcs --test static-drift|rudder|pure-yaw|drift-yaw|all
[--points N] --out captive.csv`` writes virtual captive tests of the MMG model;
``sindyship forces model.json captive.csv [--json] [--out DIR]`` compares a saved model's forces
with a captive CSV.  Each command returns the exit status; bad input raises
:class:`~sindyship.errors.SindyshipInputError` (exit 2 in the command line).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .errors import SindyshipInputError

__all__ = ["add_captive_parser", "add_forces_parser", "cmd_captive", "cmd_forces"]


def add_captive_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``captive``: virtual steady captive tests of the MMG model, written as a CSV."""
    p = subparsers.add_parser(
        "captive", help="virtual captive (towing-tank) tests of the MMG model, as a CSV",
        description="Hold the MMG model of a ship on steady motions (static drift, rudder "
        "angle, pure yaw, drift with yaw) and write the hydrodynamic forces a dynamometer "
        "measures (rigid-body inertia removed), dimensional, body axes at midship.")
    p.add_argument("--ship", default="kcs",
                   help="built-in ship (kcs, kvlcc2) or a ship TOML file (default: kcs)")
    p.add_argument("--test", default="all",
                   choices=["static-drift", "rudder", "pure-yaw", "drift-yaw", "all"],
                   help="test type: drift angle to +-20 deg, rudder angle to +-35 deg, yaw "
                   "rate r' = r L / U0 to +-0.6, their drift-yaw grid, or all four "
                   "(default: all)")
    p.add_argument("--points", type=int, default=21,
                   help="conditions per sweep, >= 2; drift-yaw uses points x points "
                   "(default: 21)")
    p.add_argument("--speed", type=float, default=None,
                   help="carriage speed [m/s] (default: the ship's design speed U0)")
    p.add_argument("--out", required=True,
                   help="output captive CSV: u, v [m/s], r [rad/s], delta [rad], n [rps], "
                   "X, Y [N], N [N m]")
    return p


def cmd_captive(args) -> int:
    from .captive import captive_tests, write_captive_csv
    from .ships import load_ship

    _refuse_output(args.out)
    ship = load_ship(args.ship)
    frame = captive_tests(ship, args.test, points=args.points, speed=args.speed)
    write_captive_csv(frame, args.out)
    print(f"wrote {args.out}: {len(frame)} captive conditions ({args.test}) of {ship.name}",
          file=sys.stderr)
    return 0


def add_forces_parser(subparsers) -> argparse.ArgumentParser:
    """Add ``forces``: a saved model's forces against a captive CSV."""
    p = subparsers.add_parser(
        "forces", help="compare a model's forces with captive (towing-tank) tests",
        description="Predict what a captive dynamometer measures from a saved model "
        "(fitted force plus added-mass Coriolis and Munk terms) and compare with a captive "
        "CSV: correlation and relative RMS error of X, Y, N per test type and inside/outside "
        "the training envelope.")
    p.add_argument("model", help="saved model JSON")
    p.add_argument("captive", help="captive CSV: u, v, r, delta, X, Y, N (unit headers allowed)")
    p.add_argument("--ship", default=None,
                   help="ship (default: the one the model names)")
    p.add_argument("--training", nargs="*", default=None, metavar="CSV",
                   help="the model's training records, for the envelope (default: the "
                   "envelope the model keeps, if any)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON document on stdout (default: a text table)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for forces.json and captive-forces.png (default: none)")
    return p


def cmd_forces(args) -> int:
    from .captive import read_captive_csv
    from .forces import compare_forces, plot_captive_forces
    from .measurements import read_csv
    from .model import AbkowitzModel, write_text_atomic
    from .ships import load_ship

    for path in (args.model, args.captive, *(args.training or [])):
        if args.out is not None and Path(path).resolve() == Path(args.out).resolve():
            raise SindyshipInputError(f"{args.out}: the output folder is one of the inputs.")
    if args.out is not None and Path(args.out).exists() and not Path(args.out).is_dir():
        raise SindyshipInputError(f"{args.out}: exists and is not a folder; give a folder.")
    ship = load_ship(args.ship) if args.ship else None
    model = AbkowitzModel.load(args.model, ship=ship)
    captive = read_captive_csv(args.captive)
    training = [read_csv(p) for p in args.training] if args.training else None
    result = compare_forces(model, captive, training_records=training)
    if args.out is not None:
        folder = Path(args.out)
        folder.mkdir(parents=True, exist_ok=True)
        write_text_atomic(folder / "forces.json", result.to_json() + "\n")
        figure = plot_captive_forces(result)
        temporary = folder / ".captive-forces.tmp.png"
        figure.savefig(temporary, dpi=120)
        temporary.replace(folder / "captive-forces.png")
    if args.json:
        sys.stdout.write(json.dumps(result.to_dict(), indent=2) + "\n")
    else:
        print(_table(result))
    return 0


def _table(result) -> str:
    def cell(stats):
        corr, rel = stats["correlation"], stats["relative_rms"]
        c = "   n/a" if corr is None else f"{corr:6.3f}"
        r = "    n/a" if rel is None else f"{rel:7.3f}"
        return f"{c} {r}"

    rows = [("all", result.overall)]
    rows += [(test, stats) for test, stats in result.by_test.items()]
    if result.inside is not None:
        rows += [("inside envelope", result.inside), ("outside envelope", result.outside)]
    lines = [f"{'conditions':<18}" + "".join(f"{dof + ' corr  relRMS':>16}"
                                             for dof in ("X", "Y", "N"))]
    for name, stats in rows:
        lines.append(f"{name:<18}" + "".join(f"  {cell(stats[dof])}" for dof in ("X", "Y", "N")))
    return "\n".join(lines)


def _refuse_output(path: str) -> None:
    target = Path(path)
    if target.is_symlink() or (target.exists() and not target.is_file()):
        raise SindyshipInputError(
            f"{path}: the output is a folder, link or device; give a regular file path."
        )

"""``sindyship captive``: virtual captive (towing-tank) tests of the MMG model, as a CSV."""

from __future__ import annotations

from ._common import add_ship, bounded_float, bounded_int, progress, ship_file

#: The verb's line in ``sindyship --help``.
SUMMARY = "virtual captive (towing-tank) tests of the MMG model, as a CSV"


def add_parser(sub) -> None:
    """Add ``captive``: virtual steady captive tests of the MMG model, written as a CSV."""
    p = sub.add_parser(
        "captive", help=SUMMARY,
        description="Hold the MMG model of a ship on steady motions (static drift, rudder "
        "angle, pure yaw, drift with yaw) and write the hydrodynamic forces a dynamometer "
        "measures (rigid-body inertia removed), dimensional, body axes at midship.")
    add_ship(p)
    p.add_argument("--test", default="all",
                   choices=["static-drift", "rudder", "pure-yaw", "drift-yaw", "all"],
                   help="test type: drift angle to +-20 deg, rudder angle to +-35 deg, yaw "
                   "rate r' = r L / U0 to +-0.6, their drift-yaw grid, or all four "
                   "(default: all)")
    p.add_argument("--points", type=bounded_int(2, 201), default=21,
                   help="conditions per sweep, 2 to 201; drift-yaw uses points x points "
                   "(default: 21)")
    p.add_argument("--speed", type=bounded_float(0, 1000, "m/s"), default=None,
                   help="carriage speed [m/s], more than a third of the ship's design speed "
                   "and at most 1.6 times it "
                   "(default: the ship's design speed U0)")
    p.add_argument("--revolutions", type=bounded_float(0, 1000, "rps"), default=None,
                   metavar="RPS",
                   help="propeller revolutions [rps] held through the tests, above 0 and at "
                   "most 5 times the ship's (default: the ship's n_P): a model tested at the "
                   "revolutions of its free-running trials")
    p.add_argument("--out", required=True,
                   help="output captive CSV: u, v [m/s], r [rad/s], delta [rad], n [rps], "
                   "X, Y [N], N [N m]")


def run(args) -> int:
    from .._io import check_output
    from ..captive import captive_tests, write_captive_csv
    from ._common import load_cli_ship

    check_output(args.out, inputs=ship_file(args.ship), label=f"--out {args.out}",
                 suffixes=(".csv",))
    ship = load_cli_ship(args.ship, simulated=True)
    frame = captive_tests(ship, args.test, points=args.points, speed=args.speed,
                          revolutions=args.revolutions)
    write_captive_csv(frame, args.out)
    progress(f"wrote {args.out}: {len(frame)} captive conditions ({args.test}) of {ship.name}")
    return 0

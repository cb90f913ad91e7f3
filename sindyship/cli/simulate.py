"""``sindyship simulate``: fly a manoeuvre with the MMG simulator and write the measurement CSV."""

from __future__ import annotations

from ..errors import SindyshipInputError
from ._common import (
    MAX_DURATION,
    MAX_RUDDER,
    MAX_SAMPLES,
    MAX_STEP,
    MIN_STEP,
    OUT_NOTE,
    SEED,
    add_ship,
    bounded_float,
    check_inputs,
    check_simulation_cost,
    progress,
    ship_file,
)

MANOEUVRES = ["turning-circle", "zigzag", "spiral", "pull-out", "straight", "random"]


#: The verb's line in ``sindyship --help``.
SUMMARY = "fly a manoeuvre with the MMG simulator, write a CSV"


def add_parser(sub) -> None:
    from ..effects import EFFECT_RANGES

    p = sub.add_parser("simulate", help=SUMMARY,
                       description="Fly a standard manoeuvre with the MMG model of a ship and "
                       "write the measurement CSV (bare SI headers).")
    add_ship(p)
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--manoeuvre", choices=MANOEUVRES, help="the manoeuvre to fly")
    what.add_argument("--protocol", action="store_true",
                      help="fly the paper's 8 training and 3 held-out manoeuvres (3200 s at "
                      "1 Hz for the KCS; another ship's 3200 samples in its own time scale "
                      "L/U0) and write them to OUT/train/ and OUT/test/ (--out is then a "
                      "folder)")
    angle = bounded_float(0, MAX_RUDDER, "degrees", symmetric=True)
    p.add_argument("--rudder", type=angle, default=None, metavar="DEG",
                   help="rudder angle [deg]: of the turn, the zig-zag, the largest spiral step, "
                   "the pull-out, or the random rudder's amplitude; magnitude in "
                   f"(0, {MAX_RUDDER:g}] and at most the ship's rudder limit, the sign gives "
                   "the side (default 35)")
    p.add_argument("--check", type=angle, default=None, metavar="DEG",
                   help=f"zig-zag heading check angle [deg], in (0, {MAX_RUDDER:g}] "
                   "(default: the rudder angle)")
    p.add_argument("--first", choices=["starboard", "port"], default=None,
                   help="side of the first rudder (zig-zag) or of the spiral (default starboard)")
    p.add_argument("--duration", type=bounded_float(0, MAX_DURATION, "seconds"),
                   default=None, metavar="SECONDS",
                   help=f"record length [s], in (0, {MAX_DURATION:g}] and at most "
                   f"{MAX_SAMPLES:.0e} samples of --dt (default 3200)")
    p.add_argument("--dt", type=bounded_float(MIN_STEP, MAX_STEP, "seconds", low_open=False),
                   default=None, metavar="SECONDS",
                   help=f"sample interval [s], {MIN_STEP:g} to {MAX_STEP:g} (default 1; a model "
                   "needs finer, at most L/U0 / 8 for fit to resolve its accelerations: "
                   "0.742 s for kvlcc2)")
    p.add_argument("--pull-out-time", type=bounded_float(0, MAX_DURATION, "seconds"),
                   default=None, metavar="SECONDS",
                   help="pull-out: time the rudder returns to zero [s], before the record's end "
                   "(default: half the duration)")
    p.add_argument("--seed", type=SEED, default=0,
                   help="seed of the random rudder and of the random effects (noise, gusts, "
                   "wind wander, revolution changes), a whole number >= 0 (default 0)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME=VALUE",
                   help="hidden physical effect, repeatable: load [Prime II force], load_dir "
                   "[deg, the direction the load comes FROM, clockwise from north], load_arm "
                   "[x/L of its point of action], current [m/s], current_dir [deg, the "
                   "direction the current flows TOWARD], crossflow [drag coefficient], "
                   "prop_side_force [Y' at the propeller], rudder_offset [deg: recorded = true "
                   "+ offset], noise [fraction of each channel's RMS], quantise [significant "
                   "figures], wind [m/s, the mean true wind, written as wind_speed and wind_dir], "
                   "wind_dir [deg, the direction the wind comes FROM], gust [fraction of wind], "
                   "wind_wander [deg], rps [fraction of the design revolutions, written as n], "
                   "rps_step [fraction of the design revolutions], rps_step_at [fraction of the "
                   "record], rps_vary [fraction of the design revolutions], rudder_lag [s the "
                   "recorded rudder is late], rudder_stall [deg of angle of attack], bank "
                   "[Prime II force at one length], bank_distance [ship lengths east, negative "
                   "west], shallow_patch [relative increase of the linear hull derivatives "
                   "beyond an edge], patch_distance [ship lengths from the start to the edge], "
                   "patch_dir [deg, clockwise from north, across the edge]; ranges: " + ", ".join(
                       f"{name} {low:g} to {high:g}" for name, (low, high, _)
                       in EFFECT_RANGES.items() if name != "seed"))
    p.add_argument("--out", required=True, metavar="FILE|DIR",
                   help=f"output measurement CSV, a folder with --protocol ({OUT_NOTE})")


def _check_flown(record) -> None:
    if record.meta.get("diverged_at") is not None:
        raise SindyshipInputError(
            f"the simulation of {record.name} left the plausible range at t = "
            f"{record.meta['diverged_at']:.0f} s; reduce the effects' magnitudes."
        )


def _protocol(args, ship, effects) -> int:
    """The paper's manoeuvres (docs/protocol.md) as OUT/train/*.csv and OUT/test/*.csv."""
    from pathlib import Path

    from ..effects import simulate_with_effects
    from ..manoeuvres import protocol_manoeuvres
    from ..measurements import write_csv

    out = Path(args.out)
    plans = protocol_manoeuvres(ship=ship)
    for kind, plan in plans.items():
        (out / kind).mkdir(parents=True, exist_ok=True)
        for record in simulate_with_effects(ship, plan, effects):
            _check_flown(record)
            write_csv(record, out / kind / f"{record.name}.csv")
        progress(f"wrote {len(plan)} {kind}ing records to {out / kind}/" if kind == "train"
                 else f"wrote {len(plan)} held-out records to {out / kind}/")
    first = plans["train"][0]
    if first.dt != MANOEUVRE_DEFAULTS["dt"]:
        progress(f"the records are {first.duration:g} s long, sampled every {first.dt:g} s: "
                 "the protocol's 3200 samples at 1 Hz of the KCS in this ship's time scale L/U0")
    return 0


#: The manoeuvre options and their defaults: the protocol's plan fixes them all.
MANOEUVRE_DEFAULTS = {"rudder": 35.0, "check": None, "first": "starboard", "duration": 3200.0,
                      "dt": 1.0, "pull_out_time": None}


def _check_protocol_options(args) -> None:
    """Refuse a manoeuvre option with ``--protocol`` (its plan fixes the manoeuvres, their
    length and sampling), else put each option not given to its default."""
    given = [name for name in MANOEUVRE_DEFAULTS if getattr(args, name) is not None]
    if args.protocol and given:
        option = "--" + given[0].replace("_", "-")
        raise SindyshipInputError(
            f"{option} does not apply to --protocol, which flies the paper's fixed plan (3200 s "
            "at 1 Hz for the KCS, scaled by L/U0 for another ship, docs/protocol.md); leave it "
            "out, or fly single manoeuvres with --manoeuvre.")
    for name, default in MANOEUVRE_DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, default)


def run(args) -> int:
    from .._io import check_output
    from ..effects import parse_effects, simulate_with_effects
    from ..manoeuvres import Manoeuvre, check_rudder_limit
    from ..measurements import write_csv
    from ._common import load_cli_ship

    check_output(args.out, inputs=ship_file(args.ship), label=f"--out {args.out}",
                 kind="folder" if args.protocol else "file", suffixes=(".csv",))
    check_inputs(ship_file(args.ship))
    _check_protocol_options(args)
    ship = load_cli_ship(args.ship, simulated=True)
    check_rudder_limit(args.rudder, ship, "--rudder")
    check_rudder_limit(args.check, ship, "--check")
    check_simulation_cost(ship, args.duration, args.dt)
    effects = parse_effects(args.effect + ([f"seed={args.seed}"] if args.seed else []))
    if args.pull_out_time is not None and args.manoeuvre != "pull-out":
        raise SindyshipInputError("--pull-out-time is for --manoeuvre pull-out; leave it out for "
                                  "other manoeuvres.")
    if args.protocol:
        return _protocol(args, ship, effects)
    sign = 1 if args.first == "starboard" else -1
    check = args.check if args.check is not None else (args.rudder if args.manoeuvre == "zigzag"
                                                       else 0.0)
    returns = 0.5 * args.duration if args.pull_out_time is None else args.pull_out_time
    if args.manoeuvre == "pull-out" and returns >= args.duration:
        raise SindyshipInputError(f"--pull-out-time {returns:g} s is not before the record's "
                                  f"end ({args.duration:g} s); give an earlier time or a longer "
                                  "--duration.")
    manoeuvre = Manoeuvre(args.manoeuvre, rudder=args.rudder, check=check, first_sign=sign,
                          duration=args.duration, dt=args.dt, seed=args.seed,
                          pull_out_time=returns)
    (record,) = simulate_with_effects(ship, [manoeuvre], effects)
    _check_flown(record)
    write_csv(record, args.out)
    progress(f"wrote {args.out}: {record.n_samples} samples of {manoeuvre.label}")
    return 0

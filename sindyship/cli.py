"""The ``sindyship`` command line.

Exit status 0 on success, 2 on bad input (one line on stderr naming the file and the problem),
1 on anything else.  With ``--json`` exactly one JSON document goes to stdout and progress to
stderr.  Outputs are written to a temporary file and renamed.
"""

from __future__ import annotations

import argparse
import json
import sys

from . import __version__
from .errors import SindyshipInputError


def _add_simulate(sub) -> None:
    p = sub.add_parser("simulate", help="fly a manoeuvre with the MMG simulator, write a CSV",
                       description="Fly a standard manoeuvre with the MMG model of a ship and "
                       "write the measurement CSV (bare SI headers).")
    p.add_argument("--ship", default="kcs", help="built-in ship (kcs, kvlcc2) or a TOML file")
    p.add_argument("--manoeuvre", required=True,
                   choices=["turning-circle", "zigzag", "spiral", "pull-out", "straight",
                            "random"])
    p.add_argument("--rudder", type=float, default=35.0, help="rudder angle [deg]")
    p.add_argument("--check", type=float, default=None, help="zig-zag check angle [deg]")
    p.add_argument("--first", choices=["starboard", "port"], default="starboard",
                   help="side of the first rudder (zig-zag) or of the spiral")
    p.add_argument("--duration", type=float, default=3200.0, help="record length [s]")
    p.add_argument("--dt", type=float, default=1.0, help="sample interval [s]")
    p.add_argument("--seed", type=int, default=0, help="seed of the random rudder and noise")
    p.add_argument("--effect", action="append", default=[], metavar="NAME=VALUE",
                   help="physical effect, repeatable: load, load_dir, load_arm, current, "
                   "current_dir, crossflow, prop_side_force, rudder_offset, noise, quantise")
    p.add_argument("--out", required=True, help="output CSV")


def _add_fit(sub) -> None:
    p = sub.add_parser("fit", help="identify an Abkowitz model from records",
                       description="Identify an Abkowitz model (paper eq. 14-17) from "
                       "measurement CSVs and save it as JSON.")
    p.add_argument("data", nargs="+", help="measurement CSV files")
    p.add_argument("--ship", default="kcs")
    p.add_argument("--library", default="abkowitz", help="term library name or TOML file")
    p.add_argument("--effects", default="", help="comma-separated catalogue effects to add")
    p.add_argument("--optimizer", default="ls", choices=["ls", "stlsq", "lasso", "svr"])
    p.add_argument("--rudder-signal", default="actual", choices=["actual", "commanded"])
    p.add_argument("--derivative", default="five-point", choices=["five-point", "savgol"])
    p.add_argument("--window", type=float, default=21.0,
                   help="Savitzky-Golay window [s] (with --derivative savgol)")
    p.add_argument("--resample", type=float, default=None,
                   help="resample irregular records onto this interval [s]")
    p.add_argument("--smoothing", default="none", metavar="none|savgol:W|rts:W|auto",
                   help="smooth noisy records before differencing: a Savitzky-Golay or a "
                   "Kalman (RTS) smoother over W seconds, or 'auto' to choose the setting by "
                   "leave-one-manoeuvre-out flights on the training records")
    p.add_argument("--n-jobs", type=int, default=None,
                   help="parallel workers for --smoothing auto (joblib; -1: every core)")
    p.add_argument("--seed", type=int, default=0, help="seed of randomised optimizers")
    p.add_argument("--out", required=True, help="output model JSON")
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")


def _add_evaluate(sub) -> None:
    p = sub.add_parser("evaluate", help="fly a model like each record, report distances",
                       description="Fly a saved model the way each record was flown (zig-zags "
                       "closed loop) and report the Table-10 distance per file.")
    p.add_argument("model", help="saved model JSON")
    p.add_argument("data", nargs="+", help="measurement CSV files")
    p.add_argument("--ship", default=None, help="ship (default: the one the model names)")
    p.add_argument("--resample", type=float, default=None)
    p.add_argument("--json", action="store_true")


def _add_reproduce(sub) -> None:
    p = sub.add_parser("reproduce", help="run the paper's experiment on the KCS",
                       description="Train on the paper's manoeuvres, fit every optimizer, fly "
                       "the held-out manoeuvres and compare with the paper's Table 10.")
    p.add_argument("--out", default="reproduce-output", help="output folder")
    p.add_argument("--json", action="store_true")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="sindyship",
        description="Discover a ship's manoeuvring equations (Abkowitz model) from trajectories.",
    )
    parser.add_argument("--version", action="version", version=f"sindyship {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", required=True)
    _add_simulate(sub)
    _add_fit(sub)
    _add_evaluate(sub)
    _add_reproduce(sub)
    from .diagnose import add_diagnose_parser
    from .export import add_export_parser

    add_diagnose_parser(sub)
    add_export_parser(sub)
    return parser


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _emit(document: dict) -> None:
    sys.stdout.write(json.dumps(document, indent=2) + "\n")


def cmd_simulate(args) -> int:
    from .effects import parse_effects, simulate_with_effects
    from .manoeuvres import Manoeuvre
    from .measurements import write_csv
    from .ships import load_ship

    ship = load_ship(args.ship)
    effects = parse_effects(args.effect + ([f"seed={args.seed}"] if args.seed else []))
    sign = 1 if args.first == "starboard" else -1
    check = args.check if args.check is not None else (args.rudder if args.manoeuvre == "zigzag"
                                                       else 0.0)
    manoeuvre = Manoeuvre(args.manoeuvre, rudder=args.rudder, check=check, first_sign=sign,
                          duration=args.duration, dt=args.dt, seed=args.seed)
    (record,) = simulate_with_effects(ship, [manoeuvre], effects)
    if record.meta.get("diverged_at") is not None:
        raise SindyshipInputError(
            f"the simulation left the plausible range at t = {record.meta['diverged_at']:.0f} s; "
            "reduce the effects' magnitudes."
        )
    write_csv(record, args.out)
    _progress(f"wrote {args.out}: {record.n_samples} samples of {manoeuvre.label}")
    return 0


def _read_records(paths, resample=None):
    from .measurements import read_csv

    return [read_csv(p, resample=resample) for p in paths]


def cmd_fit(args) -> int:
    from .identify import fit
    from .ships import load_ship

    ship = load_ship(args.ship)
    records = _read_records(args.data, args.resample)
    effects = [e.strip() for e in args.effects.split(",") if e.strip()]
    params = {"random_state": args.seed} if args.optimizer == "svr" else {}
    smoothing = None
    if args.smoothing != "none":
        from .smoothing import SmoothingSetting, choose_smoothing, smooth_records

        if args.smoothing == "auto":
            smoothing, table = choose_smoothing(records, ship, optimizer=args.optimizer,
                                                library=args.library, effects=effects,
                                                params=params, n_jobs=args.n_jobs)
            _progress(table.to_string())
        else:
            smoothing = SmoothingSetting.parse(args.smoothing)
        _progress(f"smoothing: {smoothing.as_dict()}")
        records = smooth_records(records, smoothing)
    model = fit(records, ship, library=args.library, effects=effects, optimizer=args.optimizer,
                params=params, rudder_signal=args.rudder_signal, derivative=args.derivative,
                window=args.window)
    if smoothing is not None:
        model.info["smoothing"] = smoothing.as_dict()
    model.save(args.out)
    _progress(f"wrote {args.out}: {model!r}")
    if args.json:
        _emit({"model": str(args.out), "active_terms": model.n_active(),
               "library": model.library.name, "optimizer": model.optimizer["name"]})
    return 0


def cmd_evaluate(args) -> int:
    from .evaluation import evaluate
    from .model import AbkowitzModel
    from .ships import load_ship

    ship = load_ship(args.ship) if args.ship else None
    model = AbkowitzModel.load(args.model, ship=ship)
    records = _read_records(args.data, args.resample)
    errors = evaluate(model, records)
    if args.json:
        _emit({"errors": errors})
    else:
        for name, err in errors.items():
            div = ("" if err["diverged_at_s"] is None
                   else f", diverged at {err['diverged_at_s']:.0f} s")
            print(f"{name}: mean {err['mean_distance_L']:.4f} L, max {err['max_distance_L']:.4f} L"
                  f"{div}")
    return 0


def cmd_reproduce(args) -> int:
    from .reproduce import format_report, run

    output = run(args.out, progress=_progress)
    if args.json:
        _emit(output)
    else:
        print(format_report(output))
        print(f"Figures, coefficient tables, models and results.json are in {args.out}/")
    return 0


def cmd_diagnose(args) -> int:
    from .diagnose import cmd_diagnose as run_diagnose

    return run_diagnose(args)


def cmd_export(args) -> int:
    from .export import cmd_export as run_export

    return run_export(args)


COMMANDS = {"simulate": cmd_simulate, "fit": cmd_fit, "evaluate": cmd_evaluate,
            "reproduce": cmd_reproduce, "diagnose": cmd_diagnose, "export": cmd_export}


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return COMMANDS[args.verb](args)
    except SindyshipInputError as exc:
        message = " ".join(str(exc).split())
        print(f"sindyship {args.verb}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("sindyship: interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # a bug or an environment failure: status 1, never status 2
        print(f"sindyship {args.verb}: internal error: {type(exc).__name__}: {exc} "
              "(please report it with the command you ran)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

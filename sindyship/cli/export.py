"""``sindyship export``: a saved model's equations as text or LaTeX, or a standalone simulator."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

from ..errors import SindyshipInputError
from ._common import (
    OUT_NOTE,
    add_json,
    add_ship,
    bounded_int,
    check_inputs,
    emit,
    progress,
    ship_file,
)

#: Significant digits a double carries.
MAX_PRECISION = 17


#: The verb's line in ``sindyship --help``.
SUMMARY = "write a model's equations (LaTeX) or a standalone simulator (Python)"


def add_parser(sub) -> None:
    p = sub.add_parser(
        "export", help=SUMMARY,
        description="Print a saved model's equations, write them with its coefficient table "
        "as LaTeX, or write a standalone Python simulator that needs only numpy.")
    p.add_argument("model", help="saved model JSON")
    p.add_argument("--latex", default=None, metavar="FILE",
                   help="write the equations (align) and the coefficient table (booktabs) "
                   f"({OUT_NOTE})")
    p.add_argument("--python", default=None, metavar="FILE",
                   help=f"write a standalone simulator module (numpy only) ({OUT_NOTE})")
    p.add_argument("--compile", action="store_true",
                   help="with --python: the simulator also carries its right-hand side as "
                   "loops that numba compiles where the module runs (pip install "
                   "\"sindyship[fast]\"); without numba it warns once and runs with numpy")
    p.add_argument("--precision", type=bounded_int(1, MAX_PRECISION), default=4,
                   help=f"significant digits of printed numbers, 1 to {MAX_PRECISION} "
                   "(default 4)")
    add_ship(p, default=None)
    p.add_argument("--channel", action="append", default=[], metavar="NAME=VALUE",
                   help="default value of a recorded channel the library uses, in SI as the "
                   "measurement CSV gives it (n=1.93 for the KCS's revolutions in rps), "
                   "repeatable; the generated simulate() and zigzag() take the channels as "
                   "time series in SI (channels=...), and without a default they must be "
                   "passed there (default: no defaults)")
    add_json(p)


def _parse_channels(items: list[str]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name or not math.isfinite(number):
            raise SindyshipInputError(
                f"--channel {item!r} is not NAME=VALUE with a finite number (e.g. n=1.93)."
            )
        out[name.strip()] = number
    return out


def _check_revolutions(channels: dict[str, float], ship) -> None:
    """Refuse revolutions far above the ship's own: a value in another unit (n L/U0 of the
    library's scaling, or rpm), where --channel takes rps."""
    from ..plausibility import excess_revolutions

    excess = None if "n" not in channels else excess_revolutions(channels["n"], ship)
    if excess is not None:
        raise SindyshipInputError(
            f"--channel n={channels['n']:g} is {excess[0]:.3g} times the propeller revolutions "
            f"n = {ship.propeller.n_P:.4g} rps of the model's ship {ship.name!r}; give n in "
            "rps, as the measurement CSV has it."
        )


def _write(path: str, text: str) -> None:
    from .._io import write_text_atomic

    try:
        write_text_atomic(Path(path), text)
    except OSError as exc:
        raise SindyshipInputError(f"{path}: cannot write the file ({exc.strerror}).") from None


def _check(args) -> None:
    from .._io import check_output

    inputs = [args.model, *ship_file(args.ship)]
    if args.latex and args.python and Path(args.latex).resolve() == Path(args.python).resolve():
        raise SindyshipInputError(
            f"--latex and --python both name {args.latex}; give two different files."
        )
    for option in ("latex", "python"):
        target = getattr(args, option)
        if target is not None:
            check_output(target, inputs=inputs, label=f"--{option} {target}",
                         suffixes=(".tex",) if option == "latex" else (".py",))
    check_inputs(inputs)
    if args.compile and not args.python:
        raise SindyshipInputError("--compile applies to the simulator; give --python FILE too.")


def run(args) -> int:
    """Run ``sindyship export``; returns the exit status."""
    from ..export import equations_text, generate_python, latex_document_part
    from ..model import AbkowitzModel
    from ._common import load_cli_ship

    _check(args)
    ship = load_cli_ship(args.ship) if args.ship else None
    model = AbkowitzModel.load(args.model, ship=ship)
    channels = _parse_channels(args.channel)
    if channels and not args.python:
        raise SindyshipInputError("--channel sets the simulator's default value of a channel; "
                                  "give --python FILE too.")
    unknown = sorted(set(channels) - set(model.recorded_channels))
    if unknown:
        uses = ", ".join(model.recorded_channels) or "none"
        raise SindyshipInputError(
            f"--channel {unknown[0]}: the model's library uses no channel of that name (it "
            f"uses: {uses}); give the library's channels or drop --channel."
        )
    if args.python:
        from ..terms import channel_scaling

        _check_revolutions(channels, model.ship)
        scaled = {}  # SI, as the CSV and the generated channels=, to the library's scaling
        for name, value in channels.items():
            factor, offset = channel_scaling(name, model.ship.L, model.ship.U0)
            scaled[name] = value * factor + offset
        code = generate_python(model, source_note=f"Exported from {Path(args.model).name}.",
                               channels=scaled, compiled=args.compile)
        _write(args.python, code)
        progress(f"wrote {args.python}: simulator of {model!r}"
                 + (" (compiled by numba where it runs)" if args.compile else ""))
        if args.compile and importlib.util.find_spec("numba") is None:
            progress("numba is not installed here: the simulator will run its numpy path until "
                     'it is (pip install "sindyship[fast]")')
    if args.latex:
        _write(args.latex, latex_document_part(model, args.precision))
        progress(f"wrote {args.latex}: equations and coefficient table")
    if args.json:
        emit({"model": str(args.model), "latex": args.latex, "python": args.python,
              "compiled": bool(args.python and args.compile), "active_terms": model.n_active()})
    elif not (args.latex or args.python):
        print(equations_text(model, args.precision))
    return 0

"""``sindyship evaluate``: fly a saved model like each record and report the distances."""

from __future__ import annotations

from pathlib import Path

from ..errors import SindyshipInputError
from ._common import (
    SPEED_NOTE_RANGE,
    add_json,
    add_record_options,
    add_resample,
    add_ship,
    check_inputs,
    check_simulation_cost,
    emit,
    json_document,
    progress,
    ship_file,
)
from ._records import read_records

#: The verb's line in ``sindyship --help``.
SUMMARY = "fly a model like each record, report distances"


def add_parser(sub) -> None:
    p = sub.add_parser("evaluate", help=SUMMARY,
                       description="Fly a saved model the way each record was flown (a zig-zag "
                       "closed loop and a turn from its rudder execute, a manual approach "
                       "neither flown nor scored) and report the Table-10 distance per file.")
    p.add_argument("model", help="saved model JSON")
    p.add_argument("data", nargs="+",
                   help="measurement CSV or Parquet files, or quoted glob patterns that name "
                   "them ('trials/tc*.csv'), each reported under its file stem (or, where two "
                   "share a stem, the shortest end of their paths that tells them apart); a "
                   "file given twice is refused")
    add_ship(p, default=None)
    add_resample(p)
    add_record_options(p)
    add_json(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for evaluate.json and a figure per record "
                   "(compare-<name>.png: track, u, v, r, psi and delta flown against "
                   "recorded), written aside and put in place at the end; an existing folder "
                   "is replaced only if it holds an evaluate.json (default: none)")


def run(args) -> int:
    from .._io import check_output
    from ..evaluation import evaluate_with_flights
    from ..flight_reports import evaluation_report
    from ..model import AbkowitzModel
    from ..records import PARQUET_SUFFIXES, expand_paths
    from ._common import load_cli_ship

    if Path(args.model).suffix.lower() in (".csv", *PARQUET_SUFFIXES):
        raise SindyshipInputError(
            f"{args.model} is a record, not a saved model; give the model first: sindyship "
            "evaluate MODEL.json DATA.csv...")
    args.data = expand_paths(args.data)
    check_inputs([args.model, *args.data, *ship_file(args.ship)])
    if args.out is not None:
        check_output(args.out, inputs=[args.model, *args.data], kind="folder",
                     label=f"--out {args.out}", replaceable="evaluate.json")
    ship = load_cli_ship(args.ship) if args.ship else None
    model = AbkowitzModel.load(args.model, ship=ship)
    records = read_records(args.data, args.resample, ship=model.ship,
                           skip_checks=args.skip_check, time_range=args.time_range)
    check_simulation_cost(model.ship, max(record.duration for record in records))
    errors, flights = evaluate_with_flights(model, records)
    _note_speeds(records, errors, model.ship)
    if args.out is not None:
        _write_out(args.out, errors, flights, model)
    if args.json:
        emit({"errors": errors})
    else:
        print(evaluation_report(errors))
    return 0


def _write_out(out, errors: dict, flights: dict, model) -> None:
    """evaluate.json and a comparison figure per record, into the folder ``out`` (a progress
    bar on a terminal: a figure takes about half a second)."""
    import sys

    from tqdm.auto import tqdm

    from .._io import output_folder, save_figure, write_text_atomic
    from ..evaluation import error_summary
    from ..plotting import plot_comparison
    from ..plotting.diagnosis import figure_name

    label = f"{model.library.name} ({model.optimizer['name']})"
    with output_folder(out) as folder:
        write_text_atomic(folder / "evaluate.json", json_document({"errors": errors}))
        for name, (part, flown) in tqdm(flights.items(), desc="figures", file=sys.stderr,
                                        disable=not sys.stderr.isatty(), leave=False):
            summary = error_summary(flown, part, model.ship.L)
            save_figure(plot_comparison(part, {label: flown}, L=model.ship.L, errors=summary),
                        folder / figure_name("compare", name))
    progress(f"wrote evaluate.json and {len(flights)} figure{'s' if len(flights) > 1 else ''} "
             f"(compare-<record>.png) to {out}/")


def _note_speeds(records, errors, ship) -> None:
    """A note on stderr for each record whose flight starts far from the model ship's design
    speed: the model is identified around it, and a record of another ship or at another
    speed is flown without complaint."""
    import numpy as np

    for record in records:
        start = errors[record.name].get("start_s")
        k = 0 if start is None else int(np.searchsorted(record.t, start - 1e-9))
        ratio = float(np.hypot(record["u"][k], record["v"][k])) / ship.U0
        if not SPEED_NOTE_RANGE[0] <= ratio <= SPEED_NOTE_RANGE[1]:
            progress(f"note: {record.name} starts at {ratio:.2f} times the design speed U0 = "
                     f"{ship.U0:.4g} m/s of the model's ship {ship.name}; check that the ship "
                     "and the speed are the ones measured.")

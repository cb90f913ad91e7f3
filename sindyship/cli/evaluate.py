"""``sindyship evaluate``: fly a saved model like each record and report the distances."""

from __future__ import annotations

from pathlib import Path

from ..errors import SindyshipInputError
from ._common import (
    add_json,
    add_record_options,
    add_resample,
    add_ship,
    check_inputs,
    check_simulation_cost,
    emit,
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


def run(args) -> int:
    from ..evaluation import evaluate
    from ..model import AbkowitzModel
    from ..records import PARQUET_SUFFIXES, expand_paths
    from ..reports import evaluation_report
    from ._common import load_cli_ship

    if Path(args.model).suffix.lower() in (".csv", *PARQUET_SUFFIXES):
        raise SindyshipInputError(
            f"{args.model} is a record, not a saved model; give the model first: sindyship "
            "evaluate MODEL.json DATA.csv...")
    args.data = expand_paths(args.data)
    check_inputs([args.model, *args.data, *ship_file(args.ship)])
    ship = load_cli_ship(args.ship) if args.ship else None
    model = AbkowitzModel.load(args.model, ship=ship)
    records = read_records(args.data, args.resample, ship=model.ship,
                           skip_checks=args.skip_check, time_range=args.time_range)
    check_simulation_cost(model.ship, max(record.duration for record in records))
    errors = evaluate(model, records)
    if args.json:
        emit({"errors": errors})
    else:
        print(evaluation_report(errors))
    return 0

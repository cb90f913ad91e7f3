"""``sindyship reproduce``: the paper's experiment on the KCS, end to end."""

from __future__ import annotations

from ._common import OUT_NOTE, add_json, emit, progress

#: The verb's line in ``sindyship --help``.
SUMMARY = "run the paper's experiment on the KCS"


def add_parser(sub) -> None:
    p = sub.add_parser("reproduce", help=SUMMARY,
                       description="Train on the paper's manoeuvres, fit every optimizer, fly "
                       "the held-out manoeuvres and compare with the paper's Table 10.")
    p.add_argument("--out", default="reproduce-output", metavar="DIR",
                   help="output folder for figures, tables, models and results.json, written "
                   "aside and put in place at the end; an existing folder is replaced only "
                   f"when it is empty or a previous reproduce output ({OUT_NOTE}; default: "
                   "reproduce-output)")
    add_json(p)


def run(args) -> int:
    from .._io import check_output, output_folder
    from ..flight_reports import reproduce_report
    from ..reproduce import run as run_experiment

    check_output(args.out, kind="folder", label=f"--out {args.out}", replaceable="results.json")
    with output_folder(args.out) as tmp:
        output = run_experiment(tmp, progress=progress)
    if args.json:
        emit(output)
    else:
        print(reproduce_report(output))
        print(f"Figures, coefficient tables, models and results.json are in {args.out}/")
    return 0

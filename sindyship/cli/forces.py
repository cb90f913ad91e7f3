"""``sindyship forces``: a saved model's forces against captive (towing-tank) measurements."""

from __future__ import annotations

from pathlib import Path

from ..errors import SindyshipInputError
from ._common import add_json, add_ship, emit, progress

#: The verb's line in ``sindyship --help``.
SUMMARY = "compare a model's forces with captive (towing-tank) tests"


def add_parser(sub) -> None:
    """Add ``forces``: a saved model's forces against a captive CSV."""
    p = sub.add_parser(
        "forces", help=SUMMARY,
        description="Predict what a captive dynamometer measures from a saved model "
        "(fitted force plus added-mass Coriolis and Munk terms) and compare with a captive "
        "CSV: correlation and relative RMS error of X, Y, N per test type and inside/outside "
        "the training envelope.")
    p.add_argument("model", help="saved model JSON")
    p.add_argument("captive", help="captive CSV: u, v, r, delta, X, Y, N (unit headers allowed)")
    add_ship(p, default=None)
    p.add_argument("--training", nargs="*", default=None, metavar="CSV",
                   help="the model's training records, for the envelope (default: the "
                   "envelope the model keeps, if any)")
    add_json(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for forces.json and captive-forces.png (default: none); an "
                   "existing folder is replaced only if it holds a forces.json")


def _check_order(model: str, captive: str) -> None:
    """Refuse a CSV where the model belongs or a JSON where the captive CSV belongs."""
    if Path(model).suffix.lower() == ".csv" or Path(captive).suffix.lower() == ".json":
        raise SindyshipInputError(
            f"{model} and {captive}: the saved model (JSON) comes first and the captive CSV "
            "second; run sindyship forces MODEL.json CAPTIVE.csv."
        )


def run(args) -> int:
    from .._io import check_output, output_folder, save_figure, write_text_atomic
    from ..captive import read_captive_csv
    from ..forces import compare_forces, forces_report, plot_captive_forces
    from ..model import AbkowitzModel
    from ._common import check_inputs, load_cli_ship, ship_file
    from ._records import read_records

    inputs = [args.model, args.captive, *(args.training or []), *ship_file(args.ship)]
    check_inputs(inputs)  # a FIFO or a device never reaches a reader
    _check_order(args.model, args.captive)
    if args.out is not None:
        check_output(args.out, inputs=[args.model, args.captive, *(args.training or [])],
                     kind="folder", label=f"--out {args.out}", replaceable="forces.json")
    ship = load_cli_ship(args.ship) if args.ship else None
    model = AbkowitzModel.load(args.model, ship=ship)
    captive = read_captive_csv(args.captive)
    # the training records read as fit reads them: checked against the model's ship (another
    # ship's records would move the envelope silently) and cut to the part under way
    training = read_records(args.training, ship=model.ship) if args.training else None
    try:
        result = compare_forces(model, captive, training_records=training)
    except SindyshipInputError as exc:
        raise SindyshipInputError(f"{args.captive}: {exc}") from None
    if args.out is not None:
        with output_folder(args.out) as folder:
            write_text_atomic(folder / "forces.json", result.to_json() + "\n")
            save_figure(plot_captive_forces(result), folder / "captive-forces.png", dpi=120)
        progress(f"wrote forces.json and captive-forces.png to {args.out}/")
    if args.json:
        emit(result.to_dict())
    else:
        print(forces_report(result))
    return 0

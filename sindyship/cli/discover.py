"""``sindyship discover``: search the residual of a fitted library for an effect no catalogue
lists, and write it as an effect file."""

from __future__ import annotations

from ._common import (
    OUT_NOTE,
    add_scheduler,
    add_training_options,
    bounded_float,
    bounded_int,
    check_inputs,
    emit,
    on_cluster,
    progress,
    resolve_cli_rudder_signal,
    speed_form,
    split_names,
)
from ._records import read_records
from .fit import fit_inputs

#: The verb's line in ``sindyship --help``.
SUMMARY = "discover a missing effect that no catalogue lists"


def add_parser(sub) -> None:
    from .._diagnosis_thresholds import MEANINGFUL_SHARE

    p = sub.add_parser(
        "discover",
        help=SUMMARY,
        description="Fit the library on the records and search what its cross-validated force "
        "residual still holds: a channel that lags the force it causes (the rudder angle), and "
        "terms of pysindy feature libraries over the heading, the position, the rudder, the "
        "motion and every recorded channel. The findings are judged leaving one manoeuvre out, "
        "against the noise and chance; when catalogued effects are also meaningful, the best "
        "finding and each of them are fitted leaving one manoeuvre out and fly it, and the "
        "finding is kept only when it flies better. The discovered effect can be written as an "
        "effect file for fit --effects and diagnose --effects.",
    )
    add_training_options(p, optimizer=False)
    p.add_argument("--threshold", type=bounded_float(0, 1, "", high_open=True),
                   default=MEANINGFUL_SHARE,
                   help="share of the force error above the noise floor a finding must "
                   f"explain, in (0, 1) (default {MEANINGFUL_SHARE})")
    p.add_argument("--rounds", type=bounded_int(1, 5), default=1,
                   help="search again with each discovery added, up to this many rounds, 1 to "
                   "5 (default 1: the best finding)")
    add_scheduler(p, work="the search's fits and grids")
    p.add_argument("--out", default=None, metavar="EFFECT.toml",
                   help="write the discovered effect here, in the catalogue's format "
                   f"(docs/effects.md; {OUT_NOTE}; default: do not write)")


def run(args) -> int:
    """Run ``sindyship discover``; text report on stdout, or one JSON document with --json."""
    from .._io import check_output, write_text_atomic
    from ..arguments import check_training_speed, check_two_records
    from ..library import load_effect
    from ..records import expand_paths
    from ._common import load_cli_ship, note_records_ship

    args.data = expand_paths(args.data)
    if args.out is not None:
        check_output(args.out, inputs=fit_inputs(args), label=f"--out {args.out}",
                     suffixes=(".toml",))
    check_inputs(fit_inputs(args))
    ship = load_cli_ship(args.ship)
    records = read_records(args.data, args.resample, ship=ship, skip_checks=args.skip_check,
                           time_range=args.time_range)
    check_training_speed(ship, records)
    from ..identify import resolve_library

    library = resolve_library(args.library, (), speed_form(args, ship))
    check_two_records(records, "discover")
    from ..identify import delta_recorded

    resolve_cli_rudder_signal(args, delta_recorded(records))
    effects = [load_effect(name) for name in split_names(args.effects)]
    # the search (scikit-learn with it) once the files, ship and library pass: their refusals
    # come in a fraction of a second, before any cluster starts
    from ..diagnose import discover

    with on_cluster(args.scheduler, args.n_jobs) as n_jobs:
        progress(f"sindyship discover: {len(records)} records, library {args.library}")
        found = discover(records, ship, library=library,
                         effects=effects, rudder_signal=args.rudder_signal,
                         derivative=args.derivative, window=args.window,
                         smoothing=None if args.smoothing == "none" else args.smoothing,
                         threshold=args.threshold, max_rounds=args.rounds, n_jobs=n_jobs)
    document = found.to_json()
    if args.out is not None:
        if found.accepted:
            write_text_atomic(args.out, found.effect_toml())
            progress(f"wrote {args.out}: refit with --effects {args.out}")
        else:
            progress(f"nothing was discovered: {args.out} was not written")
        document["effect_file"] = str(args.out) if found.accepted else None
    note_records_ship(args, ship, records)
    if args.json:
        emit(document)
    else:
        print(found.report(args.out if found.accepted else None))
    return 0

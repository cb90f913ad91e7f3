"""``sindyship diagnose``: where a fitted model fails, and which catalogued effect is missing."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

from ._common import (
    OUT_NOTE,
    add_scheduler,
    add_training_options,
    bounded_float,
    bounded_int,
    check_inputs,
    check_simulation_cost,
    emit,
    on_cluster,
    progress,
    report_prior_coverage,
    resolve_cli_rudder_signal,
    speed_form,
    split_names,
)
from ._records import read_record_sets
from .fit import fit_inputs

#: Most diagnosis rounds, and most candidates confirmed per round (each a refit and a flight).
MAX_ROUNDS = 20
MAX_CONFIRM = 20


#: The verb's line in ``sindyship --help``.
SUMMARY = "show where a fitted model fails and which effect is missing"


def add_parser(sub) -> None:
    from .._diagnosis_thresholds import MEANINGFUL_SHARE

    p = sub.add_parser(
        "diagnose",
        help=SUMMARY,
        description="Fit the library on the training records, fly it like each record, show "
        "the force residuals and rank the catalogued physical effects "
        "(libraries/effects/*.toml) by the share of the cross-validated force error they "
        "explain; confirm the best by refitting and re-flying.",
    )
    add_training_options(p, n_jobs_default=1)
    p.add_argument("--candidates", default="", metavar="NAME,...",
                   help="comma-separated effects to score (default: the whole catalogue)")
    p.add_argument("--test", nargs="+", default=[], metavar="HELD_OUT.csv",
                   help="held-out records (files or quoted glob patterns): flown before and "
                   "after, never fitted on (default: none)")
    add_scheduler(p, work="the diagnosis's fits, flights and grids")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for figures, report.txt and diagnose.json, written aside and "
                   "put in place at the end; an existing folder is replaced only when it is "
                   f"empty or a previous diagnose output ({OUT_NOTE}; default: none)")
    p.add_argument("--rounds", type=bounded_int(1, MAX_ROUNDS), default=1,
                   help="add the best confirmed effect and diagnose again, up to this many "
                   f"times, 1 to {MAX_ROUNDS} (default 1: diagnose once)")
    p.add_argument("--threshold", type=bounded_float(0, 1, "", high_open=True),
                   default=MEANINGFUL_SHARE,
                   help="share of the force error that is meaningful, in (0, 1) "
                   f"(default {MEANINGFUL_SHARE})")
    p.add_argument("--confirm", type=bounded_int(0, MAX_CONFIRM), default=2,
                   help="best candidates to confirm by refitting and re-flying, 0 to "
                   f"{MAX_CONFIRM} (default 2); while they are refuted, the next meaningful "
                   "one is re-flown too")


def _log_line(start: float):
    """A line on stderr with the seconds since ``start``, for a run whose stderr is no
    terminal (a log), where no progress bar is drawn."""
    def log(line: str) -> None:
        progress(f"{line} ({time.perf_counter() - start:.0f} s)")

    return log


def _log_round(start: float):
    """A line on stderr as each round ends (:func:`_log_line`): the round's summary."""
    from ..reports import round_line

    log = _log_line(start)
    return lambda k, rnd: log(round_line(k, rnd))


def _write_folder(out: Path, result, iterative, text: str, document: dict, progress_bar: bool
                  ) -> None:
    from .._io import save_figure, write_text_atomic
    from ..plotting import plot_before_after, plot_rounds, save_diagnosis_figures

    save_diagnosis_figures(result, out, progress=progress_bar)
    if iterative is not None:
        save_figure(plot_rounds(iterative), out / "rounds.png")
        for k, rnd in enumerate(iterative.rounds, 1):
            if rnd.change is not None:
                save_figure(plot_before_after(rnd.change), out / f"round-{k}-before-after.png")
                write_text_atomic(out / f"round-{k}-before-after.csv",
                                  rnd.change.table.to_csv(index=False))
    write_text_atomic(out / "report.txt", text + "\n")
    write_text_atomic(out / "diagnose.json", json.dumps(document, indent=2) + "\n")


def run(args) -> int:
    """Run ``sindyship diagnose``; text report on stdout, or one JSON document with --json."""
    from .._io import check_output, output_folder
    from ..arguments import check_training_speed, check_two_records
    from ..library import load_effect, names_a_file
    from ..records import expand_paths
    from ._common import load_cli_ship, note_records_ship

    start = time.perf_counter()
    args.data, args.test = expand_paths(args.data), expand_paths(args.test)
    if args.out is not None:
        check_output(args.out, inputs=fit_inputs(args), kind="folder",
                     label=f"--out {args.out}", replaceable="diagnose.json")
    check_inputs(fit_inputs(args))
    ship = load_cli_ship(args.ship)
    records, test = read_record_sets(args.data, args.test, resample=args.resample,
                                     ship=ship, skip_checks=args.skip_check,
                                     time_range=args.time_range)
    check_training_speed(ship, records)
    check_simulation_cost(ship, max(record.duration for record in records + test))
    from ..identify import check_term_values, resolve_library

    library = resolve_library(args.library, split_names(args.effects), speed_form(args, ship))
    check_two_records(records, "diagnose")
    from ..identify import delta_recorded

    resolve_cli_rudder_signal(args, delta_recorded(records))
    # every candidate named, and the terms of the user's own effect files checked on the
    # records, before the long work (an effect whose channels the records lack is reported
    # untestable by the diagnosis)
    candidates = {name: load_effect(name) for name in split_names(args.candidates)}
    own = [effect for name, effect in candidates.items() if names_a_file(name)]
    testable = [e for e in own if all(r.has(c) for c in e.channels for r in records + test)]
    if testable:
        check_term_values(library.extended(*testable), records + test, ship,
                          rudder_signal=args.rudder_signal)
    # the diagnosis (scikit-learn with it) once the files, ship, library and effect files
    # pass: their refusals come in a fraction of a second
    from ..diagnose import diagnose, diagnose_iteratively

    if args.optimizer == "prior":
        report_prior_coverage(ship, library)
    options = {
        "effects": split_names(args.candidates) or None,
        "threshold": args.threshold,
        "confirm": args.confirm,
        "optimizer": args.optimizer,
        "rudder_signal": args.rudder_signal,
        "derivative": args.derivative,
        "window": args.window,
        "n_jobs": args.n_jobs,
        "smoothing": None if args.smoothing == "none" else args.smoothing,
    }
    bar = sys.stderr.isatty()
    iterative = None
    with on_cluster(args.scheduler, args.n_jobs) as n_jobs:
        progress(f"sindyship diagnose: {len(records)} training and {len(test)} held-out "
                 f"records, library {library.name}")
        options["n_jobs"] = n_jobs
        options["on_stage"] = None if bar else _log_line(start)
        if args.rounds > 1:
            iterative = diagnose_iteratively(records, ship, library=library, test=test,
                                             max_rounds=args.rounds, progress=bar,
                                             on_round=None if bar else _log_round(start),
                                             **options)
            result = iterative.rounds[0].diagnosis
        else:
            result = diagnose(records, ship, library=library, test=test, progress=bar,
                              **options)
    # the verdict's command reads the records as they were read here
    result.settings["read_options"] = _read_options(args)
    document = result.to_json()
    text = result.report(ship_argument=args.ship, effect_arguments=split_names(args.effects))
    if iterative is not None:
        document.update(iterative.to_json())
        text += "\n\n" + iterative.report(ship_argument=args.ship,
                                           effect_arguments=split_names(args.effects))
    document["seconds"] = time.perf_counter() - start
    if args.out is not None:
        out = Path(args.out)
        with output_folder(out) as tmp:
            _write_folder(tmp, result, iterative, text, document, bar)
        progress(f"sindyship diagnose: figures, report.txt and diagnose.json are in {out}/")
    note_records_ship(args, ship, records, sampling=False)  # the report cautions
    if args.json:
        emit(document)
    else:
        print(text)
    return 0


def _read_options(args) -> list[str]:
    """The options that said how the records were read (resampling, checks skipped, the time
    range), as the verdict's command repeats them."""
    import shlex

    options = [] if args.resample is None else [f"--resample {args.resample:g}"]
    options += [f"--skip-check {name}" for name in args.skip_check]
    if args.time_range != "auto":
        options.append(f"--time-range {shlex.quote(args.time_range)}")
    return options

"""``sindyship fit``: identify an Abkowitz model from records and save it as JSON."""

from __future__ import annotations

from ..arguments import check_training_speed
from ._common import (
    OUT_NOTE,
    SEED,
    add_training_options,
    bounded_float,
    bounded_int,
    check_inputs,
    emit,
    load_cli_ship,
    note_records_ship,
    progress,
    report_prior_coverage,
    resolve_cli_rudder_signal,
    resolved_library,
    ship_file,
    speed_form,
    split_names,
)
from ._records import read_records
from ._streamed import add_stream_options, streamed_fit

#: The verb's line in ``sindyship --help``.
SUMMARY = "identify an Abkowitz model from records"
#: Mean distance [ship lengths] past which fit notes that its model flies one of its own
#: training records far off (the paper's identified models miss held-out manoeuvres by up
#: to 2 L; a record the model was fitted on should not be missed by half of that).
TRAINING_FLIGHT_NOTE_L = 1.0
#: The most training records whose flights fit names on stderr (``--json`` gives all).
TRAINING_FLIGHTS_SHOWN = 12


def add_parser(sub) -> None:
    p = sub.add_parser("fit", help=SUMMARY,
                       description="Identify an Abkowitz model (paper eq. 14-15, by the "
                       "regression of eq. 16-18) from measurement CSVs (or Parquet files with "
                       "the same columns; quoted glob patterns such as 'fleet/*.parquet' name "
                       "many) and save it as JSON.")
    add_training_options(p, n_jobs_default=None, recommended=True)
    add_stream_options(p)
    p.add_argument("--seed", type=SEED, default=0,
                   help="seed of randomised optimizers, a whole number >= 0 (default 0)")
    p.add_argument("--prior-strength", type=bounded_float(0, 1, "", low_open=False),
                   default=None, metavar="S",
                   help="with --optimizer prior: the weight of the ship's prior, in [0, 1], as "
                   "a share of the force's sum of squares that one prior standard deviation "
                   "costs (default 1e-5; smaller follows the data, larger the prior)")
    p.add_argument("--refine", type=bounded_int(0, 1000, "a whole number of evaluations"),
                   default=None, metavar="N",
                   help="refine the fitted coefficients by the error of the records' flights "
                   "(regularised output error by multiple shooting: every record from its "
                   "flight start cut into segments, each flown from its measured state; the "
                   "fit's own objective, with the prior of a prior fit, holds what the flights "
                   "cannot tell apart), at most N evaluations of the flights' error, each "
                   "accepted step with exact sensitivities; 0 does not refine (default: 60 "
                   "with --optimizer prior, 0 with the others)")
    p.add_argument("--segment", type=bounded_float(0, 1e6, "seconds"), default=None,
                   metavar="SECONDS",
                   help="length of the refinement's segments [s] (default: three stages of "
                   "5, 15 and 45 L/U0, none longer than the longest record)")
    p.add_argument("--refine-weight", type=bounded_float(0, 1e6, "", low_open=False),
                   default=None, metavar="W",
                   help="weight of the fit's own objective (force error over its sum of "
                   "squares, and the prior) against the flights' mean squared error in the "
                   "refinement, >= 0 (default 0.01; 0 refines by the flights alone)")
    p.add_argument("--captive", default=None, metavar="CSV",
                   help="captive (towing-tank) tests of the same ship, fitted beside the "
                   "records (hybrid identification): a captive CSV of u, v, r, delta and the "
                   "measured hydrodynamic X, Y, N, as sindyship captive writes and sindyship "
                   "forces reads; they separate the terms the records cannot (default: none)")
    p.add_argument("--captive-share", type=bounded_float(0, 1, "", high_open=True),
                   default=None, metavar="S",
                   help="with --captive: the share of the regression's weight the captive "
                   "tests carry together, in (0, 1) (default 0.01: the records decide what "
                   "they pin down, the captive tests what the records leave free)")
    p.add_argument("--out", required=True, metavar="FILE",
                   help=f"output model JSON ({OUT_NOTE})")
    p.add_argument("--no-identifiability", action="store_true",
                   help="skip the report of terms the records cannot separate (VIF above "
                   "1e5 or a sign that flips between leave-one-manoeuvre-out fits) and of the "
                   "tests that would separate them (default: report it on stderr and in JSON)")


def _smoothing(args, records, ship, effects, params, speed):
    """The smoothing setting the options ask for (None for ``none``); ``auto`` chooses it with
    the fit's library in its speed form."""
    if args.smoothing == "none":
        return None
    from ..identify import resolve_library
    from ..smoothing import SmoothingSetting, choose_smoothing, default_candidates

    if args.smoothing != "auto":
        return SmoothingSetting.parse(args.smoothing)
    progress(f"choosing the smoothing (--smoothing auto): up to {len(default_candidates(ship))} "
             f"settings, each fitted {len(records)} times with one record left out and flown "
             "on it; the table follows when they are done")
    setting, table = choose_smoothing(records, ship, optimizer=args.optimizer,
                                      library=resolve_library(args.library, (), speed),
                                      effects=effects, params=params,
                                      rudder_signal=args.rudder_signal,
                                      derivative=args.derivative, window=args.window,
                                      n_jobs=args.n_jobs)
    progress(table.to_string())
    tried = {(row.method, row.window_s) for row in table.itertuples()}
    left = [c.label for c in default_candidates(ship) if c.method != "none"
            and (c.method, c.window) not in tried]
    if left:
        progress(f"--smoothing auto left out {', '.join(left)}: a window longer than a record, "
                 "or holding too few of its samples")
    return setting


def optimizer_params(args) -> dict:
    """The optimizer's parameters the options give (``--seed``, ``--prior-strength``).

    Raises
    ------
    SindyshipInputError
        For ``--prior-strength`` without ``--optimizer prior``.
    """
    from ..errors import SindyshipInputError

    params = {"random_state": args.seed} if args.optimizer == "svr" else {}
    if args.prior_strength is not None:
        if args.optimizer != "prior":
            raise SindyshipInputError(
                f"--prior-strength weighs the prior of --optimizer prior, not of "
                f"{args.optimizer}; add --optimizer prior or drop --prior-strength."
            )
        params["strength"] = args.prior_strength
    return params


def fit_inputs(args) -> list[str]:
    """Every file ``fit`` or ``diagnose`` reads: records, ship, library and effect files."""
    library = [] if args.library is None else [args.library]  # None: a built-in default
    captive = [] if getattr(args, "captive", None) is None else [args.captive]
    return [*args.data, *getattr(args, "test", []), *ship_file(args.ship), *library,
            *split_names(args.effects), *captive]


def _captive(args, ship, library):
    """The captive tests ``--captive`` names (None without it), read and checked against the
    ship and the library before the records are read (a refusal names the file);
    ``--captive-share`` without them, or with a streamed fit, is refused."""
    from ..errors import SindyshipInputError

    if args.captive is None:
        if args.captive_share is not None:
            raise SindyshipInputError("--captive-share weighs the captive tests of --captive; "
                                      "add --captive CSV or drop --captive-share.")
        return None
    if args.stream or args.scheduler:
        raise SindyshipInputError("--captive goes with a fit in memory, not a streamed one; "
                                  "drop --stream and --scheduler, or --captive.")
    from ..captive import read_captive_csv
    from ..hybrid import captive_design

    captive = read_captive_csv(args.captive)
    try:
        captive_design(captive, ship, library)
    except SindyshipInputError as error:
        raise SindyshipInputError(f"{args.captive}: {error}") from error
    return captive


def _check_refine_options(args) -> None:
    """Refuse refinement options while the refinement is off (``--refine 0``, or by default
    for any optimizer but the prior fit's)."""
    refining = args.refine if args.refine is not None else args.optimizer == "prior"
    for option, value in (("--segment", args.segment), ("--refine-weight", args.refine_weight)):
        if value is not None and not refining:
            from ..errors import SindyshipInputError

            raise SindyshipInputError(f"{option} sets the refinement, which is off (--refine 0 "
                                      f"or --optimizer {args.optimizer}); add --refine N or "
                                      f"drop {option}.")


def run(args) -> int:
    from .._io import check_output
    from ..records import expand_paths

    args.data = expand_paths(args.data)
    _check_refine_options(args)
    params = optimizer_params(args)
    check_output(args.out, inputs=fit_inputs(args), label=f"--out {args.out}",
                 suffixes=(".json",))
    check_inputs(fit_inputs(args))
    ship = load_cli_ship(args.ship)
    from ..identify import delta_recorded, fit, resolve_library

    speed = speed_form(args, ship)
    args.library = resolved_library(args, speed)
    effects = split_names(args.effects)
    library = resolve_library(args.library, effects, speed)
    captive = _captive(args, ship, library)
    # the refinement's modules (scikit-learn among them) once the arguments, files, ship,
    # library and effects pass: their refusals come in a fraction of a second
    from ..refine import MAX_EVALUATIONS

    if args.refine is None:  # on for the prior fit
        args.refine = MAX_EVALUATIONS if args.optimizer == "prior" else 0
    if args.stream or args.scheduler:  # the rudder signal from the files' headers
        from pathlib import Path

        from ..records import record_columns

        columns = {path: record_columns(path) for path in args.data}
        resolve_cli_rudder_signal(args, [(Path(path).stem, "delta" in names)
                                         for path, names in columns.items() if names is not None])
        return _run_streamed(args, ship, params, speed)
    if args.n_jobs not in (None, 1) and args.smoothing != "auto":
        progress(f"note: --n-jobs {args.n_jobs} is not used: it sets the workers of --smoothing "
                 "auto and --stream (with numba the refinement flies its segments on every core "
                 "by itself).")
    records = read_records(args.data, args.resample, ship=ship, skip_checks=args.skip_check,
                           time_range=args.time_range)
    check_training_speed(ship, records)
    resolve_cli_rudder_signal(args, delta_recorded(records))
    smoothing = _smoothing(args, records, ship, effects, params, speed)
    if smoothing is not None:
        from ..smoothing import smooth_records

        progress(f"smoothing the records before differencing: {smoothing.label}"
                 if smoothing.method != "none" else
                 "not smoothing the records: --smoothing auto chose them as they are")
        records = smooth_records(records, smoothing)
    settings = {"library": library, "optimizer": args.optimizer, "params": params,
                "rudder_signal": args.rudder_signal, "derivative": args.derivative,
                "window": args.window, "speed": speed}
    if captive is None:
        model = fit(records, ship, **settings)
    else:
        from ..hybrid import CAPTIVE_SHARE, fit_hybrid

        model = fit_hybrid(records, ship, captive, captive_share=args.captive_share or
                           CAPTIVE_SHARE, **settings)
        kept = model.info["captive"]
        progress(f"captive tests: {kept['rows']} condition{'' if kept['rows'] == 1 else 's'} ("
                 + ", ".join(f"{kind} {count}" for kind, count in kept["tests"].items())
                 + f") fitted beside the records, carrying {kept['share']:.3g} of the "
                 "regression's weight")
    if smoothing is not None:
        model.info["smoothing"] = smoothing.as_dict()
    report_prior_fit(model)
    if args.refine:
        model = _refined(model, records, args)
    model.save(args.out)
    progress(f"wrote {args.out}: {model!r}")
    agreement = None if captive is None else _captive_agreement(model, captive)
    state = model.info.get("straight_run")  # a raised prior strength is the fit's strength
    fitted_params = params if state is None else {**params, "strength": state["strength"]}
    report = None if args.no_identifiability else _identifiability(
        args, records, ship, library, fitted_params, model.info.get("captive"))
    flights = _training_flights(model, records)
    note_records_ship(args, ship, records)
    if args.json:
        emit({"model": str(args.out), "active_terms": model.n_active(),
              "library": model.library.name, "speed": model.library.speed,
              "optimizer": model.optimizer["name"],
              "identifiability": None if report is None else report.to_dict(),
              "refined": model.info.get("refined"), "training_flights": flights,
              **({} if agreement is None else {"captive_agreement": agreement})})
    return 0


def _captive_agreement(model, captive) -> dict:
    """The saved model's forces against the captive tests it was fitted with
    (:func:`sindyship.forces.compare_forces`): one line per test type on stderr, the
    correlation of X, Y and N; the ``by_test`` of ``forces --json``."""
    from ..forces import compare_forces

    by_test = compare_forces(model, captive).by_test
    cells = []
    for test, forces in by_test.items():
        values = [forces[f]["correlation"] for f in "XYN"]
        if any(v is not None for v in values):
            cells.append(f"{test} " + " / ".join("n/a" if v is None else f"{v:+.2f}"
                                                 for v in values))
    progress("the saved model against the captive tests given (correlation of X / Y / N; "
             "sindyship forces for more): " + ", ".join(cells))
    return by_test


def _training_flights(model, records) -> dict:
    """The saved model flown like each training record, as ``sindyship evaluate`` flies it
    (:func:`sindyship.evaluation.evaluate`): a line of mean distances on stderr, and a note
    for the records it flies more than :data:`TRAINING_FLIGHT_NOTE_L` off or diverges on
    (least squares can fit every force within a few per cent and still fly a straight run
    tens of ship lengths off; ``diagnose`` says whether the library misses physics there)."""
    from ..evaluation import evaluate

    flights = evaluate(model, records)
    cells = {name: (f"diverged at {e['diverged_at_s']:g} s" if e["diverged_at_s"] is not None
                    else f"{e['mean_distance_L']:.3g}") for name, e in flights.items()}
    shown = list(cells)[:TRAINING_FLIGHTS_SHOWN]
    more = len(cells) - len(shown)
    progress("training flights (mean distance [L], flown as sindyship evaluate flies them): "
             + ", ".join(f"{name} {cells[name]}" for name in shown)
             + (f", and {more} more (--json gives every one)" if more else ""))
    far = [name for name, e in flights.items()
           if e["diverged_at_s"] is not None or e["mean_distance_L"] > TRAINING_FLIGHT_NOTE_L]
    if far:
        named = ", ".join(f"{name} ({cells[name]}{'' if flights[name]['diverged_at_s'] else ' L'})"
                          for name in far[:TRAINING_FLIGHTS_SHOWN])
        progress(f"note: the model diverges on, or flies more than {TRAINING_FLIGHT_NOTE_L:g} "
                 f"L off, records it was fitted on: {named}"
                 + (f" and {len(far) - TRAINING_FLIGHTS_SHOWN} more"
                    if len(far) > TRAINING_FLIGHTS_SHOWN else "")
                 + "; physics the library lacks, or terms the records do not pin down: "
                 "sindyship diagnose on the same records says which, and sindyship evaluate "
                 "shows where.")
    return flights


def _refined(model, records, args, n_jobs=1):
    """The model refined by its records' flights (:func:`sindyship.refine.refine`), with
    each step and what the refinement did on stderr."""
    from ..refine import VALIDATION_RECORDS, refine

    progress(f"refining by the records' flights (multiple shooting, at most {args.refine} "
             "evaluations)")
    refined = refine(model, records, max_evaluations=args.refine, segment_s=args.segment,
                     prior_weight=args.refine_weight, progress=True, n_jobs=n_jobs)
    done = refined.info["refined"]
    if done["refused_unstable"]:
        progress(f"not refined: {done['stopped']} (the prior fit's stability requirement).")
    elif done.get("refused_validation") and done["validation"].get("half_refused"):
        progress(f"not refined: {done['stopped']}.")
    elif done.get("refused_validation"):
        progress(f"not refined: {done['stopped']}: the records' flights would be matched by "
                 "terms they do not pin down.")
    elif done.get("refused_turning"):
        progress(f"not refined: {done['stopped']}: the records do not span those turns, and "
                 "their flights pulled terms they do not pin down, or terms standing in for an "
                 "effect the library lacks (add turning circles to the records, fit with the "
                 "effect sindyship diagnose names on the same records, or fly the fitted "
                 "model).")
    elif done["cost_after"] < done["cost_before"]:
        change, moved = done["largest_change"], done["force_change"]
        progress(f"refined: flight error (rms over the compared samples) "
                 f"{done['flight_rms_before']:.4g} -> {done['flight_rms_after']:.4g} in "
                 f"{done['evaluations']} evaluations and {done['jacobians']} Jacobians "
                 f"({done['stopped']}); the forces moved by "
                 + ", ".join(("n/a" if share is None else f"{share:.1%}") + f" ({dof})"
                             for dof, share in moved.items())
                 + f" of their rms over the records ({change['coefficient']} moved most for "
                 f"its size, {change['relative']:+.1%}).")
    else:
        progress(f"not refined: no step lowered the error ({done['cost_before']:.4g}); the "
                 "fitted coefficients are kept.")
    if done["largest_change"] is not None and "validation" not in done:
        progress(f"note: with {len(records)} record{'s' if len(records) > 1 else ''} the "
                 "refinement is not checked on records it was not refined on (that needs "
                 f"{VALIDATION_RECORDS} or more): judge it on other manoeuvres before using it.")
    if not done["converged"] and not done["refused_unstable"] \
            and not done.get("refused_turning") and not done.get("refused_validation"):
        progress(f"note: the refinement stopped before it converged ({done['stopped']}); a "
                 "larger --refine lets it finish.")
    moved_unstable = not done["straight_run_stable"] and done["largest_change"] is not None
    if moved_unstable and "straight_run" in refined.info:  # a prior fit its prior left unstable
        progress("warning: the refined model is unstable in straight running, as the prior fit "
                 "it started from is, so a disturbance grows in its flights (as it does for a "
                 "course-unstable ship, which large tankers often are); fly it on records it was "
                 "not refined on.")
    elif moved_unstable:
        progress("warning: the refined model is unstable in straight running, so a disturbance "
                 "grows in its flights; refine a --optimizer prior fit, which starts stable, "
                 "and fly it on records it was not refined on.")
    elif not done["straight_run_stable"] and "straight_run" not in refined.info:
        progress("warning: the model (its fitted coefficients kept) is unstable in straight "
                 "running, so a disturbance grows in its flights; fit it with --optimizer "
                 "prior, which starts stable.")
    return refined


def _run_streamed(args, ship, params: dict, speed: str) -> int:
    """``fit --stream`` (or ``--scheduler``): the model from per-record factors reduced on a
    Dask cluster; a refinement then reads the records into memory (unless they would fill
    more than half of it) and flies their segments on the cluster's workers."""
    effects = split_names(args.effects)
    model, summary, whole = streamed_fit(args, ship, effects, params, speed)
    check_training_speed(ship, fastest=max(whole.fastest, default=None))
    report_prior_fit(model)
    if args.refine and _too_many_to_refine(summary["samples"], model):
        args.refine = 0
    flights = None  # flown when the refinement has read the records
    if args.refine:
        from ._common import on_cluster

        model.save(args.out)  # kept should reading or refining the records fail
        progress(f"wrote {args.out}: the streamed fit; the refinement reads the records into "
                 "memory (--refine 0 streams throughout)")
        records = read_records(args.data, args.resample, ship=ship,
                               skip_checks=args.skip_check, time_range=args.time_range)
        if args.smoothing not in ("none", None):
            from ..smoothing import SmoothingSetting, smooth_records

            records = smooth_records(records, SmoothingSetting.parse(args.smoothing))
        with on_cluster(args.scheduler, args.n_jobs) as workers:
            model = _refined(model, records, args, n_jobs=workers if args.scheduler else
                             (args.n_jobs or 1))
    model.save(args.out)
    progress(f"wrote {args.out}: {model!r}")
    if args.refine:
        flights = _training_flights(model, records)
    if not args.no_identifiability:
        progress("Identifiability: not reported for a streamed fit (it needs the samples); "
                 "fit a subset in memory to see it.")
    note_records_ship(args, ship, streamed=whole)
    if args.json:
        emit({"model": str(args.out), "active_terms": model.n_active(),
              "library": model.library.name, "speed": model.library.speed,
              "optimizer": model.optimizer["name"], "identifiability": None,
              "streamed": summary, "refined": model.info.get("refined"),
              **({} if flights is None else {"training_flights": flights})})
    return 0


def _too_many_to_refine(samples: int, model) -> bool:
    """Whether a streamed fit's records are too many to refine: the refinement flies them from
    memory with the sensitivities of every active coefficient, and where that takes more than
    half of the machine's memory it is skipped with a notice (the fit is saved as fitted)."""
    from ._common import BYTES_PER_SAMPLE, REFINE_BYTES_PER_TERM, memory_short

    terms = sum(model.n_active().values())
    need = samples * (BYTES_PER_SAMPLE + REFINE_BYTES_PER_TERM * terms)
    have = memory_short(need)
    if have is None:
        return False
    progress(f"not refined: the refinement flies the records from memory, {samples:.3g} "
             f"samples with the sensitivities of {terms} coefficients, about "
             f"{need / 1e9:.3g} GB, more than half of this machine's {have / 1e9:.3g} GB; the "
             "streamed fit is saved as fitted (refine it on a subset of the records in memory, "
             "or pass --refine 0 to stream throughout).")
    return True


def report_prior_fit(model) -> None:
    """On stderr, for a ``prior`` fit: the ship's estimates its library has no term for, and
    what the stability requirement did (nothing for another fit)."""
    if model.optimizer["name"] != "prior":
        return
    report_prior_coverage(model.ship, model.library)
    state = model.info.get("straight_run")
    if not state or (state["stable"] and not state["raised"]):
        return
    if state["stable"]:
        progress(f"the fit was unstable in straight running; raising the prior's strength "
                 f"{state['raised']} times (to {state['strength']:g}) made it stable.")
    else:
        from ..identify import MOST_RAISED_STRENGTH

        reached = (f"raised to {state['strength']:g}" if state["raised"]
                   else f"at {state['strength']:g}")
        larger = (", or a larger --prior-strength" if state["strength"] < MOST_RAISED_STRENGTH
                  else "")
        progress(f"warning: the model is unstable in straight running even with the prior's "
                 f"strength {reached}, so a disturbance grows in its flights: the ship itself "
                 "may be course-unstable (full-form ships such as tankers often are; a spiral "
                 "test with a loop shows it), else add manoeuvres that the identifiability "
                 f"report names{larger}.")


def _identifiability(args, records, ship, library, params, captive=None):
    """Terms the records cannot separate, on stderr (the remedies need the ship's MMG), for
    the fit's library (its effects included, in its speed form); ``captive`` is a hybrid
    fit's ``info["captive"]``, whose test types decide what they hold."""
    if len(records) < 2:
        progress("note: no identifiability report from one record (it compares fits that "
                 "leave a manoeuvre out); give two or more records for it.")
        return None
    from ..identifiability import identifiability

    # the members draw their own seeds (uncertainty.ensemble); the strength is the fit's
    members = {k: v for k, v in params.items() if k != "random_state"}
    report = identifiability(records, ship, library=library, effects=(),
                             optimizer=args.optimizer, params=members,
                             rudder_signal=args.rudder_signal,
                             remedies=ship.has_mmg)
    text = report.text()
    if text:
        held = [kind for kind in (captive or {}).get("tests", {}) if kind != "straight"]
        rest = ("the ship's prior decides the rest" if args.optimizer == "prior" else
                "the rest is the records' guess")
        verdict = (f"the captive {', '.join(held)} tests given decide what they hold "
                   f"(--captive); {rest}" if held else
                   "the ship's prior decides what the records cannot (--optimizer prior)"
                   if args.optimizer == "prior" else
                   "their coefficients are not trustworthy as derivatives; --optimizer prior "
                   "lets the ship's semi-empirical derivatives decide them")
        progress(f"Identifiability (terms these records cannot separate; {verdict}):")
        for line in text.splitlines():
            progress(f"  {line}")
    return report

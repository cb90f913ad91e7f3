"""``sindyship fit``: identify an Abkowitz model from records and save it as JSON."""

from __future__ import annotations

from ._common import (
    OUT_NOTE,
    SEED,
    add_training_options,
    bounded_float,
    bounded_int,
    check_inputs,
    emit,
    progress,
    report_prior_coverage,
    ship_file,
    split_names,
)
from ._records import read_records
from ._streamed import add_stream_options, streamed_fit


def add_parser(sub) -> None:
    p = sub.add_parser("fit", help="identify an Abkowitz model from records",
                       description="Identify an Abkowitz model (paper eq. 14-17) from "
                       "measurement CSVs (or Parquet files with the same columns; quoted glob "
                       "patterns such as 'fleet/*.parquet' name many) and save it as JSON.")
    add_training_options(p, n_jobs_default=None)
    add_stream_options(p)
    p.add_argument("--seed", type=SEED, default=0,
                   help="seed of randomised optimizers, a whole number >= 0 (default 0)")
    p.add_argument("--prior-strength", type=bounded_float(0, 1, "", low_open=False),
                   default=None, metavar="S",
                   help="with --optimizer prior: the weight of the ship's prior, in [0, 1], as "
                   "a share of the force's sum of squares that one prior standard deviation "
                   "costs (default 1e-5; smaller follows the data, larger the prior)")
    p.add_argument("--refine", type=bounded_int(0, 1000, "a whole number of steps"),
                   default=0, metavar="N",
                   help="refine the fitted coefficients by the error of the records' flights "
                   "(output error; each record flown as evaluate flies it), at most N trial "
                   "steps, each accepted one with a Jacobian that flies the model once per "
                   "non-zero coefficient (10 is typical: a minute on 8 records of 3200 s; 1 or "
                   "2 may refine nothing); 0 does not refine (default)")
    p.add_argument("--out", required=True, metavar="FILE",
                   help=f"output model JSON ({OUT_NOTE})")
    p.add_argument("--no-identifiability", action="store_true",
                   help="skip the report of terms the records cannot separate (VIF above "
                   "1e5 or a sign that flips between leave-one-manoeuvre-out fits) and of the "
                   "tests that would separate them (default: report it on stderr and in JSON)")


def _smoothing(args, records, ship, effects, params):
    """The smoothing setting the options ask for (None for ``none``)."""
    if args.smoothing == "none":
        return None
    from ..smoothing import SmoothingSetting, choose_smoothing

    if args.smoothing != "auto":
        return SmoothingSetting.parse(args.smoothing)
    setting, table = choose_smoothing(records, ship, optimizer=args.optimizer,
                                      library=args.library, effects=effects, params=params,
                                      n_jobs=args.n_jobs)
    progress(table.to_string())
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
    return [*args.data, *getattr(args, "test", []), *ship_file(args.ship), args.library,
            *split_names(args.effects)]


def run(args) -> int:
    from .._io import check_output
    from ..identify import fit
    from ..records import expand_paths
    from ..ships import load_ship

    args.data = expand_paths(args.data)
    params = optimizer_params(args)
    check_output(args.out, inputs=fit_inputs(args), label=f"--out {args.out}",
                 suffixes=(".json",))
    check_inputs(fit_inputs(args))
    ship = load_ship(args.ship)
    if args.stream or args.scheduler:
        if args.refine:
            from ..errors import SindyshipInputError

            raise SindyshipInputError("--refine flies the records, which a streamed fit "
                                      "(--stream or --scheduler) does not hold in memory; fit "
                                      "in memory or drop --refine.")
        return _run_streamed(args, ship, params)
    records = read_records(args.data, args.resample, ship=ship, skip_checks=args.skip_check,
                           time_range=args.time_range)
    effects = split_names(args.effects)
    smoothing = _smoothing(args, records, ship, effects, params)
    if smoothing is not None:
        from ..smoothing import smooth_records

        progress(f"smoothing: {smoothing.as_dict()}")
        records = smooth_records(records, smoothing)
    model = fit(records, ship, library=args.library, effects=effects, optimizer=args.optimizer,
                params=params, rudder_signal=args.rudder_signal, derivative=args.derivative,
                window=args.window)
    if smoothing is not None:
        model.info["smoothing"] = smoothing.as_dict()
    report_prior_fit(model)
    if args.refine:
        model = _refined(model, records, args.refine)
    model.save(args.out)
    progress(f"wrote {args.out}: {model!r}")
    state = model.info.get("straight_run")  # a raised prior strength is the fit's strength
    fitted_params = params if state is None else {**params, "strength": state["strength"]}
    report = None if args.no_identifiability else _identifiability(args, records, ship, effects,
                                                                   fitted_params)
    if args.json:
        emit({"model": str(args.out), "active_terms": model.n_active(),
              "library": model.library.name, "optimizer": model.optimizer["name"],
              "identifiability": None if report is None else report.to_dict(),
              "refined": model.info.get("refined")})
    return 0


def _refined(model, records, evaluations: int):
    """The model refined by its records' flights (:func:`sindyship.refine.refine`), with
    what the refinement did on stderr."""
    import sys

    from ..refine import refine

    progress(f"refining by the records' flights (at most {evaluations} trial steps)")
    refined = refine(model, records, max_evaluations=evaluations, progress=sys.stderr.isatty())
    done = refined.info["refined"]
    if done["refused_unstable"]:
        progress(f"not refined: {done['stopped']} (the prior fit's stability requirement).")
    elif done["cost_after"] < done["cost_before"]:
        change = done["largest_change"]
        progress(f"refined: flight error (half the sum of squares) {done['cost_before']:.4g} -> "
                 f"{done['cost_after']:.4g} in {done['evaluations']} trial steps and "
                 f"{done['jacobians']} Jacobians; {change['coefficient']} moved most "
                 f"({change['relative']:+.1%}).")
    else:
        progress(f"not refined: no step lowered the flight error ({done['cost_before']:.4g}); "
                 "the fitted coefficients are kept (a larger --refine allows more steps).")
    if not done["straight_run_stable"]:
        progress("warning: the refined model is unstable in straight running, so a disturbance "
                 "grows in its flights; refine a --optimizer prior fit, which starts stable, "
                 "or fewer steps, and fly it on records it was not refined on.")
    return refined


def _run_streamed(args, ship, params: dict) -> int:
    """``fit --stream``: the model from per-record factors reduced on a Dask cluster."""
    effects = split_names(args.effects)
    model, summary = streamed_fit(args, ship, effects, params)
    report_prior_fit(model)
    model.save(args.out)
    progress(f"wrote {args.out}: {model!r}")
    if not args.no_identifiability:
        progress("Identifiability: not reported for a streamed fit (it needs the samples); "
                 "fit a subset in memory to see it.")
    if args.json:
        emit({"model": str(args.out), "active_terms": model.n_active(),
              "library": model.library.name, "optimizer": model.optimizer["name"],
              "identifiability": None, "streamed": summary})
    return 0


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
                 f"strength {reached}; its flights may diverge (add manoeuvres that the "
                 f"identifiability report names{larger}).")


def _identifiability(args, records, ship, effects, params):
    """Terms the records cannot separate, on stderr (the remedies need the ship's MMG)."""
    if len(records) < 2:
        return None
    from ..identifiability import identifiability

    # the members draw their own seeds (uncertainty.ensemble); the strength is the fit's
    members = {k: v for k, v in params.items() if k != "random_state"}
    report = identifiability(records, ship, library=args.library, effects=effects,
                             optimizer=args.optimizer, params=members,
                             rudder_signal=args.rudder_signal,
                             remedies=ship.has_mmg)
    text = report.text()
    if text:
        verdict = ("the ship's prior decides what the records cannot (--optimizer prior)"
                   if args.optimizer == "prior" else
                   "their coefficients are not trustworthy as derivatives; --optimizer prior "
                   "lets the ship's semi-empirical derivatives decide them")
        progress(f"Identifiability (terms these records cannot separate; {verdict}):")
        for line in text.splitlines():
            progress(f"  {line}")
    return report

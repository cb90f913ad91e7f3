"""``sindyship fit --stream``: the fit from per-record factors reduced on a Dask cluster
(:mod:`sindyship.streaming`), for records that do not fit in memory together."""

from __future__ import annotations

from pathlib import Path

from ._common import progress, scheduler_address


def add_stream_options(p) -> None:
    """``--stream`` and ``--scheduler``."""
    p.add_argument("--stream", action="store_true",
                   help="fit from per-record factors reduced on a Dask cluster (one record "
                   "file at a time, never all samples in memory; a refinement, on by "
                   "default for the prior fit, reads them); needs the cluster extra, "
                   'python3 -m pip install "sindyship[cluster]" (default: read every record '
                   "into memory)")
    p.add_argument("--scheduler", type=scheduler_address, default=None, metavar="ADDRESS",
                   help="address of a running Dask scheduler (tcp://host:8786) to stream the "
                   "fit on; implies --stream (default: a local cluster of --n-jobs worker "
                   "processes, every core when unset)")


def streamed_fit(args, ship, effects, params, speed=None):
    """The model of the streamed fit and what the JSON reports of it.

    Returns
    -------
    model : AbkowitzModel
    summary : dict
        ``{"records", "samples", "workers", "scheduler"}``.
    whole : sindyship.streaming.Reduction
        The records' reduction (their names, speeds and sampling steps among it).
    """
    from ..optimizers import make_optimizer
    from ..streaming import connect, fit_reduction, reduce_files, stream_settings, time_window
    from ._records import _refuse_repeats, record_keys, report_reading

    paths = [Path(p) for p in args.data]
    _refuse_repeats(paths)
    settings = stream_settings(
        ship, library=args.library, effects=effects, rudder_signal=args.rudder_signal,
        derivative=args.derivative, window=args.window, smoothing=args.smoothing,
        resample=args.resample, skip_checks=args.skip_check,
        time_range=time_window(args.time_range), speed=speed)
    estimator = make_optimizer(args.optimizer, **params)
    estimator.check_factor_fit(len(paths))
    workers = args.n_jobs if args.n_jobs and args.n_jobs > 0 else None
    with connect(args.scheduler, workers) as client:
        count = len(client.scheduler_info().get("workers", {}))
        progress(f"streaming {len(paths)} records on {count} Dask workers "
                 f"({args.scheduler or 'local cluster'})")
        whole, records = reduce_files(paths, settings, names=record_keys(paths), client=client,
                                      keep_records=estimator.cross_validates, progress=True)
    for path, note in whole.notes:
        report_reading(path, [note], None)
    for path, *cut in whole.cuts:
        report_reading(path, [], tuple(cut))
    model = fit_reduction(whole, settings, optimizer=args.optimizer, params=params,
                          records=records)
    summary = {"records": len(whole.names), "samples": whole.n_samples, "workers": count,
               "scheduler": args.scheduler or "local"}
    return model, summary, whole

"""A model identified from the merged factors of the records (:func:`fit_files`,
:func:`fit_reduction`)."""

from __future__ import annotations

import os
from collections.abc import Sequence

from ..errors import SindyshipInputError
from ..identify import dof_params, fitted_model, resolve_library, straight_run_stable
from ..model import AbkowitzModel
from ..optimizers import make_optimizer
from ..ships import Ship
from ..smoothing import SmoothingSetting
from ..targets import DOFS
from ._cluster import reduce_files
from ._reduce import Reduction, StreamSettings

__all__ = ["fit_files", "fit_reduction", "stream_settings"]


def stream_settings(ship: Ship, *, library: str = "abkowitz", effects: Sequence[str] = (),
                    rudder_signal: str = "actual", derivative: str = "five-point",
                    window: float = 21.0, smoothing: SmoothingSetting | str | None = None,
                    resample: float | None = None, skip_checks: Sequence[str] = (),
                    time_range: tuple[float, float] | str = "auto",
                    speed: str | None = None) -> StreamSettings:
    """Checked :class:`StreamSettings`: the library and the smoothing are resolved here, so
    a bad one is refused before any record is read.

    Raises
    ------
    SindyshipInputError
        For a library given as an object (the workers need its name or file), an unknown
        library or effect, or ``smoothing="auto"``.
    """
    if not isinstance(library, str | os.PathLike):
        raise SindyshipInputError(
            "a streamed fit needs the library by name or TOML path (each worker reads it); "
            "pass library='abkowitz' or the file's path."
        )
    resolve_library(os.fspath(library), tuple(effects), speed)
    if isinstance(smoothing, str):
        if smoothing == "auto":
            raise SindyshipInputError(
                "smoothing 'auto' flies every training record and needs them all in memory; "
                "give a streamed fit a fixed setting such as savgol:21 or rts:21."
            )
        smoothing = SmoothingSetting.parse(smoothing)
    if smoothing is not None and smoothing.method == "none":
        smoothing = None
    # a library or effect given as a file goes to the workers by its absolute path
    library, effects = _absolute(library), tuple(_absolute(e) for e in effects)
    return StreamSettings(ship=ship, library=os.fspath(library), effects=tuple(effects),
                          rudder_signal=rudder_signal, derivative=derivative,
                          window=float(window), smoothing=smoothing, resample=resample,
                          skip_checks=tuple(skip_checks), time_range=time_range, speed=speed)


def _absolute(name):
    """A file's absolute path; a catalogue name as it is."""
    return os.path.abspath(name) if os.path.isfile(name) else name


def fit_reduction(whole: Reduction, settings: StreamSettings, *, optimizer: str = "ls",
                  params: dict | None = None, records: Sequence[Reduction] | None = None
                  ) -> AbkowitzModel:
    """Identify an Abkowitz model from merged factors (paper eq. 14-18).

    Parameters
    ----------
    whole : Reduction
        The factors of all records (:func:`reduce_files`).
    settings : StreamSettings
        The settings the records were reduced with.
    optimizer : {"ls", "stlsq", "lasso"}
        ``svr`` needs every sample and is refused.
    params : dict, optional
        The optimizer's parameters.
    records : sequence of Reduction, optional
        Every record's factors, for an optimizer that cross-validates (leave one record
        out: the fold without record ``k`` is the merge of all the others' factors).

    Returns
    -------
    AbkowitzModel
        As :func:`sindyship.identify.fit` makes it on the same records, with
        ``info["streamed"]``.
    """
    lib = resolve_library(settings.library, settings.effects, settings.speed)
    terms = {dof: [t.text for t in lib.terms[dof]] for dof in DOFS}
    info = {
        "training": list(whole.names),
        "n_samples": int(whole.n_samples),
        "derivative": settings.derivative,
        "window_s": settings.window if settings.derivative != "five-point" else None,
        "selected": None,
        "envelope": whole.envelope,
        "streamed": {"records": len(whole.names),
                     "factors": "one triangular factor per record and degree of freedom, "
                                "merged as a binary tree"},
    }
    if settings.smoothing is not None:
        info["smoothing"] = settings.smoothing.as_dict()

    def fitted_with(strength: float | None) -> AbkowitzModel:
        chosen = dict(params or {}) if strength is None else {**(params or {}),
                                                             "strength": strength}
        fitted = {}
        for dof in DOFS:
            estimator = make_optimizer(optimizer, **dof_params(optimizer, chosen, settings.ship,
                                                               dof, terms[dof], lib.speed))
            if estimator.cross_validates and records is None:
                raise ValueError(f"optimizer {optimizer!r} cross-validates: pass records=.")
            parts = [r.factors[dof] for r in records] if records is not None else []
            fitted[dof] = estimator.fit_factors(parts, whole.factors[dof])
        return fitted_model(settings.ship, lib, fitted, terms, optimizer=optimizer,
                            rudder_signal=settings.rudder_signal, info=info)

    model = fitted_with(None)
    if optimizer == "prior":
        model = straight_run_stable(model, fitted_with)
    return model


def fit_files(paths: Sequence[str | os.PathLike], ship: Ship, *, optimizer: str = "ls",
              params: dict | None = None, names: Sequence[str] | None = None, client=None,
              progress: bool = False, **options) -> AbkowitzModel:
    """Identify an Abkowitz model from record files that need not fit in memory together.

    Each file is one partition: read, checked, smoothed and turned into the regression
    problems of :func:`sindyship.identify.design` where it is (a worker of ``client``), and
    reduced there to the triangular factor of every degree of freedom (the least-squares
    problem of eq. 18).  The factors are merged as a binary tree (TSQR) and the optimizer
    fits from them: the coefficients of :func:`sindyship.identify.fit` on the same records,
    up to rounding.

    Parameters
    ----------
    paths : sequence of str or os.PathLike
        Measurement CSV or Parquet files.
    ship : Ship
        The ship the records belong to.
    optimizer : {"ls", "stlsq", "lasso"}
        Regression method; ``params`` go to its constructor (``svr`` needs every sample and
        is refused).
    names : sequence of str, optional
        The records' names (default: the file stems).
    client : distributed.Client, optional
        The Dask cluster to reduce on (:func:`connect`); default: this process, one record
        at a time.
    progress : bool
        Progress bar of the records on stderr.
    **options
        ``library``, ``effects``, ``rudder_signal``, ``derivative``, ``window``,
        ``smoothing`` (a fixed setting), ``resample``, ``skip_checks``, ``time_range``
        (:func:`stream_settings`).

    Returns
    -------
    AbkowitzModel

    Examples
    --------
    >>> import tempfile
    >>> from sindyship import MMGModel, Manoeuvre, fly, load_ship
    >>> from sindyship.measurements import write_csv
    >>> ship = load_ship("kcs")
    >>> runs = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=35, duration=400),
    ...                             Manoeuvre("zigzag", rudder=20, check=20, duration=400)])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     files = [write_csv(run, f"{folder}/{k}.csv") for k, run in enumerate(runs)]
    ...     model = fit_files(files, ship)
    >>> model.info["n_samples"], model.info["streamed"]["records"]
    (800, 2)
    """
    settings = stream_settings(ship, **options)
    make_optimizer(optimizer, **(params or {})).check_factor_fit(len(paths))
    keep = make_optimizer(optimizer, **(params or {})).cross_validates
    whole, records = reduce_files(paths, settings, names=names, client=client,
                                  keep_records=keep, progress=progress)
    return fit_reduction(whole, settings, optimizer=optimizer, params=params, records=records)

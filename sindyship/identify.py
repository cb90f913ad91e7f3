"""Identification: from records to a fitted Abkowitz model (paper sections 3.2-3.5).

:func:`design` turns records into one regression problem per degree of freedom (the feature
matrix of the library's terms, the eq. 16 target and the record each sample comes from);
:func:`fit` solves them with any optimizer of :mod:`sindyship.optimizers` behind one interface
and returns an :class:`~sindyship.model.AbkowitzModel`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import RudderSignalNote, SindyshipInputError
from .library import (
    SPEED_FACTOR,
    Effect,
    TermLibrary,
    load_effect,
    load_library,
    record_variables,
)
from .model import AbkowitzModel
from .priors import COMPLETE_LIBRARY
from .ships import Ship
from .targets import DOFS, regression_targets
from .trajectory import Trajectory


@dataclass(frozen=True)
class Design:
    """The regression problem of one degree of freedom.

    Attributes
    ----------
    features : ndarray, shape (n_samples, n_terms)
        Library terms evaluated on every sample of every record (stacked).
    target : ndarray, shape (n_samples,)
        Forces of eq. 16 (Prime I).
    groups : ndarray, shape (n_samples,)
        Index of the record each sample comes from (for leave-one-manoeuvre-out CV).
    terms : tuple of str
        Term texts, the columns of ``features``.
    """

    features: np.ndarray
    target: np.ndarray
    groups: np.ndarray
    terms: tuple[str, ...]


def resolve_library(library: str | TermLibrary = "abkowitz", effects: Sequence[str] = (),
                    speed: str | None = None) -> TermLibrary:
    """A library by name or path, extended by named effects of the catalogue, in the speed
    form ``speed`` (``"design"`` or ``"instantaneous"``; None keeps the library's own,
    :attr:`sindyship.library.TermLibrary.speed`)."""
    if isinstance(effects, str):
        raise TypeError(f"effects must be a list of effect names such as [{effects!r}], not a "
                        "string.")
    if not isinstance(library, TermLibrary | str):
        raise TypeError(f"library must be a library name, a file or a TermLibrary, not "
                        f"{type(library).__name__}.")
    lib = library if isinstance(library, TermLibrary) else load_library(library)
    if effects:
        lib = lib.extended(*[e if isinstance(e, Effect) else load_effect(e) for e in effects])
    return lib if speed is None else lib.with_speed(speed)


def design(records: Sequence[Trajectory], ship: Ship, library: TermLibrary, *,
           rudder_signal: str = "actual", derivative: str = "five-point",
           window: float = 21.0) -> dict[str, Design]:
    """Regression problems per degree of freedom from records (paper eq. 16-17).

    Examples
    --------
    >>> from sindyship import load_ship, MMGModel, Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> runs = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=35, duration=300)])
    >>> problems = design(runs, ship, load_library("abkowitz"))
    >>> problems["Y"].features.shape
    (300, 22)
    """
    if not records:
        raise SindyshipInputError("no records to fit; pass at least one measurement CSV.")
    check_channels(library, records)
    check_delays(library, records, rudder_signal)
    n_total = sum(record.n_samples for record in records)
    # one column-major array per degree of freedom, filled column by column: no stacking
    # copies, and the layout LAPACK works in
    features = {dof: np.empty((n_total, len(library.terms[dof])), order="F") for dof in DOFS}
    target = {dof: np.empty(n_total) for dof in DOFS}
    group_array = np.empty(n_total, dtype=int)
    start = 0
    for index, record in enumerate(records):
        stop = start + record.n_samples
        values = record_variables(record, library, ship.L, ship.U0, rudder_signal)
        factor = values.get(SPEED_FACTOR, 1.0)  # (U/U0)^2 of the instantaneous form
        forces = regression_targets(record, ship, method=derivative, window=window)
        columns = {}  # a term of several degrees of freedom is evaluated once
        for dof in DOFS:
            for j, term in enumerate(library.terms[dof]):
                if term.text not in columns:
                    columns[term.text] = term_column(term, values, factor, record)
                features[dof][start:stop, j] = columns[term.text]
            target[dof][start:stop] = forces[dof]
        group_array[start:stop] = index
        start = stop
    return {
        dof: Design(features=features[dof], target=target[dof], groups=group_array,
                    terms=tuple(t.text for t in library.terms[dof]))
        for dof in DOFS
    }


#: Largest magnitude a term may reach in a record: beyond it the squares that least squares
#: forms overflow (non-dimensional terms are of order one; a channel in odd units is not).
MAX_TERM_VALUE = 1e100


def term_column(term, values: dict, factor, record: Trajectory) -> np.ndarray:
    """A term's column of the regression matrix on one record (the library's ``values`` of
    it, times the speed ``factor`` of the instantaneous form), refused in one line when it
    is not finite or so large that the fit would overflow."""
    with np.errstate(over="ignore", invalid="ignore"):
        column = term.evaluate(values) * factor
    column = np.broadcast_to(np.asarray(column, dtype=float), (record.n_samples,))
    if np.isfinite(column).all() and float(np.abs(column).max(initial=0.0)) <= MAX_TERM_VALUE:
        return column
    channels = ", ".join(sorted(set(term.variables) - {"du", "v", "r", "delta"})) or "the motion"
    raise SindyshipInputError(
        f'the term "{term.text}" is not finite or beyond {MAX_TERM_VALUE:.0e} on record '
        f'"{record.name}" (from {channels}); give the channel in units that keep it near one, '
        "or leave the term out.")


def check_term_values(library: TermLibrary, records: Sequence[Trajectory], ship: Ship, *,
                      rudder_signal: str = "actual") -> None:
    """Every term of ``library`` finite and within :data:`MAX_TERM_VALUE` on every record, as
    :func:`design` requires; a check to run before long work that builds designs later.

    Parameters
    ----------
    library : TermLibrary
        The terms to check (with their delays and speed form, as the fit reads them).
    records : sequence of Trajectory
        The records the terms are evaluated on.
    ship : Ship
        Gives L and U0 for the non-dimensional variables (eq. 15).
    rudder_signal : {"actual", "commanded"}
        The rudder angle the terms read.

    Raises
    ------
    SindyshipInputError
        Naming the first term and record that break it, or a channel a record lacks.

    Examples
    --------
    >>> from sindyship import load_ship, MMGModel, Manoeuvre, fly
    >>> ship = load_ship("kcs")
    >>> runs = fly(MMGModel(ship), [Manoeuvre("zigzag", rudder=10, check=10, duration=100)])
    >>> check_term_values(load_library("abkowitz"), runs, ship)  # nothing to report
    """
    check_channels(library, records)
    for record in records:
        values = record_variables(record, library, ship.L, ship.U0, rudder_signal)
        factor = values.get(SPEED_FACTOR, 1.0)
        for dof in DOFS:
            for term in library.terms[dof]:
                term_column(term, values, factor, record)


def check_delays(library: TermLibrary, records: Sequence[Trajectory], rudder_signal: str
                 ) -> None:
    """Every channel the library delays must be one the fit reads, in every record.

    Raises
    ------
    SindyshipInputError
        Naming the channel, and the record that lacks it or the rudder signal the fit reads.
    """
    from .terms import describe_variable

    read = {describe_variable(v).column for v in library.variables} - {"rudder", "rudder_rate"}
    for channel in library.delays:
        for record in records:
            rudder = "delta_c" if rudder_signal == "commanded" or not record.has("delta") \
                else "delta"
            if channel in ("delta", "delta_c") and channel != rudder:
                raise SindyshipInputError(
                    f"the library delays {channel}, but the fit of record \"{record.name}\" "
                    f"reads the rudder angle from {rudder}; delay {rudder} instead, or fit with "
                    f"--rudder-signal {'actual' if channel == 'delta' else 'commanded'}."
                )
            if channel not in ("delta", "delta_c") and channel not in read:
                raise SindyshipInputError(
                    f"the library delays {channel}, which none of its terms uses; remove the "
                    "delay or add terms in it."
                )
            if not record.has(channel):
                raise SindyshipInputError(
                    f"the library delays {channel}, which record \"{record.name}\" does not have; "
                    "add the column to the data or remove the delay."
                )


def check_channels(library: TermLibrary, records: Sequence[Trajectory]) -> None:
    """Every data channel a term uses must be in every record.

    Raises
    ------
    SindyshipInputError
        Naming the file the term comes from (the library's or an effect's), the degree of
        freedom, the term, the channel and the record.
    """
    from .library import available_effects
    from .terms import describe_variable, sources_of

    catalogued = {}  # (dof, term) -> the catalogue's effect that adds it
    for name in library.effects:
        if name in available_effects():  # an effect file's terms are the library's own
            effect = load_effect(name)
            for dof in DOFS:
                for term in effect.terms[dof]:
                    catalogued.setdefault((dof, term.text), effect)
    for record in records:
        for dof in DOFS:
            for term in library.terms[dof]:
                for column in sorted({describe_variable(source).column for variable
                                      in term.variables for source in sources_of(variable)}):
                    if column in ("rudder", "rudder_rate") or record.has(column):
                        continue
                    effect = catalogued.get((dof, term.text))
                    if effect is not None:
                        needs = ", ".join(f'"{c}"' for c in effect.channels)
                        channels = "channels" if len(effect.channels) > 1 else "channel"
                        raise SindyshipInputError(
                            f'the effect "{effect.name}" needs the {channels} {needs} in every '
                            f'record, and record "{record.name}" has no "{column}"; add the '
                            f"column to the data or fit without the effect."
                        )
                    where = library.source or f'library "{library.name}"'
                    raise SindyshipInputError(
                        f'{where}: the {dof} term "{term.text}" uses the channel "{column}", '
                        f'which record "{record.name}" does not have; add the column to the '
                        "data or remove the term."
                    )


#: The library of the recommended fit (``optimizer="prior"``, ``sindyship fit`` without
#: ``--library``) in each speed form: the paper's terms with the surge term ``v r``, and in the
#: instantaneous form also quadratic cross-flow drag, which a ship that slows in a turn
#: reaches far beyond the drift angles and yaw rates its records span.
RECOMMENDED_LIBRARIES = {"design": COMPLETE_LIBRARY, "instantaneous": "abkowitz-vr-crossflow"}


def recommended_library(speed: str = "design") -> str:
    """The name of the recommended fit's library in a speed form.

    In the design form (paper eq. 16, Prime I) the paper's terms and the surge term ``v r``
    of the MMG hull model (``abkowitz-vr``, every term the prior has an estimate for); in the
    ``instantaneous`` form, where forces scale with (U/U0)^2 and a turn that loses half its
    speed doubles its r' = r L/U, the same with the cross-flow drag terms ``|v| v``,
    ``|r| r``, ``|v| r`` and ``v |r|`` in sway and yaw (``abkowitz-vr-crossflow``), which
    extrapolate to large drift as the separated flow does (they have no semi-empirical
    estimate and take the prior's weak pull toward zero).

    Parameters
    ----------
    speed : {"design", "instantaneous"}
        The library's speed form (:attr:`sindyship.library.TermLibrary.speed`).

    Returns
    -------
    str
        A built-in library name.

    Raises
    ------
    SindyshipInputError
        For another speed form.

    Examples
    --------
    >>> recommended_library("design"), recommended_library("instantaneous")
    ('abkowitz-vr', 'abkowitz-vr-crossflow')
    """
    if speed not in RECOMMENDED_LIBRARIES:
        raise SindyshipInputError(f'speed must be "design" or "instantaneous", not {speed!r}.')
    return RECOMMENDED_LIBRARIES[speed]


def fit(records: Sequence[Trajectory], ship: Ship, *, library: str | TermLibrary = "abkowitz",
        effects: Sequence[str] = (), optimizer: str = "ls", params: dict | None = None,
        rudder_signal: str = "actual", derivative: str = "five-point", window: float = 21.0,
        problems: dict[str, Design] | None = None, speed: str | None = None,
        part_of_set: bool = False) -> AbkowitzModel:
    """Identify an Abkowitz model from records.

    The ``prior`` optimizer also requires a model that is stable in straight running: it
    raises the prior's strength, a few times at most, until the model is
    (:func:`straight_run_stable`; ``info["straight_run"]`` says how it ended), and warns
    (:class:`~sindyship.priors.PriorCoverageNote`) when the library has no term for some of
    the ship's estimates (:func:`sindyship.priors.coverage_note`).

    Parameters
    ----------
    records : sequence of Trajectory (or measurement CSV paths)
        Training records (SI), each uniformly sampled, with finite motion; one made by hand
        is checked as a measurement CSV is (:func:`sindyship.arguments.check_records`).
    ship : Ship or str
        Gives L, U0 and the Prime I inertia (paper Table 6); its MMG coefficients are not used.
        A built-in name (``"kcs"``) or a ship TOML file is loaded.
    library : str or TermLibrary
        Term library (default the paper's ``abkowitz``).
    effects : sequence of str
        Catalogue effects whose terms are added to the library.
    optimizer : {"ls", "stlsq", "lasso", "svr", "prior"}
        Regression method; ``params`` go to its constructor.  ``prior`` is least squares
        drawn toward the ship's semi-empirical derivatives (:mod:`sindyship.priors`).
    rudder_signal : {"actual", "commanded"}
        Rudder angle used in the features (the protocol uses the actual angle); records that
        all lack the actual angle are fitted on the commanded one, with a
        :class:`~sindyship.errors.RudderSignalNote` (:func:`fitted_rudder_signal`).
    derivative, window
        Acceleration estimate (:func:`sindyship.targets.derivative`).
    problems : dict, optional
        Precomputed :func:`design` output for the same records and library (saves time when
        several optimizers are fitted to one data set).
    speed : {"design", "instantaneous"}, optional
        The speed form of the library (:attr:`sindyship.library.TermLibrary.speed`); default
        the library's own.
    part_of_set : bool
        The records are part of a training set (left out one by one): the set's speed
        check (:func:`sindyship.arguments.check_training_speed`) is not made on them.

    Returns
    -------
    AbkowitzModel
    """
    from .arguments import as_records, as_ship, check_records, check_training_speed, positive_number

    ship = as_ship(ship)
    records = check_records(as_records(records), ship)
    if not part_of_set:
        check_training_speed(ship, records)
    window = positive_number(window, "window")
    if optimizer not in _optimizer_names():
        raise SindyshipInputError(f"optimizer must be one of {', '.join(_optimizer_names())}, "
                                  f"not {optimizer!r}.")
    lib = resolve_library(library, effects, speed)
    rudder_signal = resolve_rudder_signal(records, rudder_signal)
    if problems is None:
        problems = design(records, ship, lib, rudder_signal=rudder_signal,
                          derivative=derivative, window=window)
    info = {"training": [r.name for r in records], "n_samples": int(len(problems["X"].target)),
            "derivative": derivative, "window_s": window if derivative != "five-point" else None,
            "selected": None,  # filled in by fitted_model
            "envelope": training_envelope(records, ship)}
    if ship.assumptions:  # what an identification-only ship file left to sindyship
        info["ship_assumptions"] = list(ship.assumptions)
    terms = {dof: problems[dof].terms for dof in DOFS}

    def fitted_with(strength: float | None) -> AbkowitzModel:
        chosen = dict(params or {}) if strength is None else {**(params or {}),
                                                             "strength": strength}
        return fitted_model(ship, lib, _fit_each(problems, optimizer, chosen, ship, lib.speed),
                            terms, optimizer=optimizer, rudder_signal=rudder_signal, info=info)

    model = fitted_with(None)
    if optimizer == "prior":
        _note_prior_coverage(ship, lib)
        model = straight_run_stable(model, fitted_with)
    return model


def delta_recorded(records: Sequence[Trajectory]) -> list[tuple[str, bool]]:
    """Each record's name and whether it has the actual rudder angle ``delta``."""
    return [(record.name, record.has("delta")) for record in records]


def fitted_rudder_signal(with_delta: Sequence[tuple[str, bool]], rudder_signal: str = "actual"
                         ) -> tuple[str, str | None]:
    """The rudder angle a fit uses, and a note when it is not the one asked for.

    ``with_delta`` holds each record's name and whether it has ``delta``
    (:func:`delta_recorded`; a streamed fit reads it from the files' headers).  The actual
    angle needs it in every record: a fit on the commanded angle
    taken for the actual one would count the steering gear's lag twice when flown.  Records
    that all lack it are fitted on the commanded angle (a model whose rudder input is the
    command, the lag inside its forces), with a note; some lacking it are refused.

    Examples
    --------
    >>> import pandas as pd
    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "u": 1.0, "v": 0.0, "r": 0.0, "x": [0.0, 1.0],
    ...                       "y": 0.0, "psi": 0.0, "delta_c": 0.0})
    >>> fitted_rudder_signal(delta_recorded([Trajectory(frame, "no-delta")]))[0]
    'commanded'
    """
    if rudder_signal != "actual":
        return rudder_signal, None
    missing = [name for name, has_delta in with_delta if not has_delta]
    if not missing:
        return "actual", None
    if len(missing) < len(with_delta):
        named = ", ".join(missing[:3]) + (f" and {len(missing) - 3} more" if len(missing) > 3
                                          else "")
        raise SindyshipInputError(
            f"{named} {'has' if len(missing) == 1 else 'have'} no actual rudder angle (delta) "
            "while the other records do; give every record its delta column, or fit all on "
            "the commanded angle (--rudder-signal commanded).")
    return "commanded", ("the records have no actual rudder angle (delta), so the model is "
                         "fitted on the commanded one (--rudder-signal commanded): the "
                         "steering gear's lag is inside its forces; record delta to fit the "
                         "rudder's own force")


def resolve_rudder_signal(records: Sequence[Trajectory], rudder_signal: str = "actual") -> str:
    """The rudder angle a fit uses (:func:`fitted_rudder_signal`), with a
    :class:`~sindyship.errors.RudderSignalNote` when it is not the one asked for."""
    signal, note = fitted_rudder_signal(delta_recorded(records), rudder_signal)
    if note is not None:
        warnings.warn(note[0].upper() + note[1:] + ".", RudderSignalNote, stacklevel=3)
    return signal


def _optimizer_names() -> list[str]:
    from .optimizers import OPTIMIZERS

    return sorted(OPTIMIZERS)


def _note_prior_coverage(ship: Ship, library: TermLibrary) -> None:
    """Warn (:class:`sindyship.priors.PriorCoverageNote`) when the library has no term for
    some of the ship's semi-empirical estimates."""
    from .priors import PriorCoverageNote, coverage_note

    note = coverage_note(ship, library)
    if note is not None:
        warnings.warn(note[0].upper() + note[1:], PriorCoverageNote, stacklevel=3)


def _fit_each(problems: dict[str, Design], optimizer: str, params: dict | None,
              ship: Ship, speed: str = "design") -> dict:
    """One fitted estimator per degree of freedom."""
    from .optimizers import make_optimizer

    fitted = {}
    for dof in DOFS:
        problem = problems[dof]
        estimator = make_optimizer(optimizer, **dof_params(optimizer, params, ship, dof,
                                                            problem.terms, speed))
        try:
            fitted[dof] = estimator.fit(problem.features, problem.target, groups=problem.groups)
        except (TypeError, ValueError) as exc:
            if type(exc).__name__ != "InvalidParameterError":  # scikit-learn's, on a value
                raise
            raise SindyshipInputError(f"optimizer {optimizer!r} refuses its parameters "
                                      f"({params}): {str(exc).rstrip('.')}.") from None
    return fitted


#: How often the ``prior`` fit raises its strength tenfold to reach a straight-run-stable
#: model (:func:`straight_run_stable`).
STABILITY_RAISES = 3
#: The strength the raises start from when the fit's own is smaller (0 is least squares).
LEAST_RAISED_STRENGTH = 1e-8
#: The largest strength a raise goes to: the prior then weighs as much as the forces' sum of
#: squares (the top of ``fit --prior-strength``).
MOST_RAISED_STRENGTH = 1.0


def straight_run_stable(model: AbkowitzModel, refit) -> AbkowitzModel:
    """The ``prior`` fit's straight-run stability requirement.

    A model that is unstable in straight running
    (:func:`sindyship.stability.straight_run_stability`) is refitted with the prior's
    strength raised tenfold (from at least :data:`LEAST_RAISED_STRENGTH`), at most
    :data:`STABILITY_RAISES` times and never above :data:`MOST_RAISED_STRENGTH`, so that the
    prior's (stable) linear derivatives weigh more.  The model records the strength it ends
    with and whether it is stable (``info["straight_run"]``): a model still unstable after the
    raises is returned as it is, for the caller to report.

    Parameters
    ----------
    model : AbkowitzModel
        The ``prior`` fit.
    refit : callable
        ``refit(strength) -> AbkowitzModel``: the same fit with another strength.
    """
    from .stability import straight_run_stability

    strength = max(float(model.optimizer["params"]["strength"]), LEAST_RAISED_STRENGTH)
    stable = straight_run_stability(model).stable
    raises = 0
    while not stable and raises < STABILITY_RAISES and strength * 10.0**raises < \
            MOST_RAISED_STRENGTH:
        raises += 1
        model = refit(min(strength * 10.0**raises, MOST_RAISED_STRENGTH))
        stable = straight_run_stability(model).stable
    model.info["straight_run"] = {"stable": stable,
                                  "strength": float(model.optimizer["params"]["strength"]),
                                  "raised": raises}
    return model


#: The parameters of the ``prior`` optimizer that :mod:`sindyship.priors` fills in per degree
#: of freedom (a saved model keeps them in ``info["prior"]``, not in its optimizer's params).
PRIOR_ARRAYS = ("mean", "scale", "relations")


def dof_params(optimizer: str, params: dict | None, ship: Ship, dof: str,
                terms: Sequence[str], speed: str = "design") -> dict:
    """The optimizer's parameters for one degree of freedom: the ship's prior for ``prior``
    (:func:`sindyship.priors.prior_parameters`, in the library's speed form) unless given."""
    out = dict(params or {})
    if optimizer == "prior":
        from .priors import prior_parameters

        for key, value in prior_parameters(ship, dof, terms, speed=speed).items():
            out.setdefault(key, value)
    return out


def fitted_model(ship: Ship, library: TermLibrary, fitted: dict, terms: dict[str, Sequence[str]],
                 *, optimizer: str, rudder_signal: str, info: dict) -> AbkowitzModel:
    """The model of fitted estimators, one per degree of freedom (eq. 17's coefficients).

    Parameters
    ----------
    ship, library
        What was fitted.
    fitted : dict of str to estimator
        The fitted optimizer of every degree of freedom (its ``coef_`` in the order of
        ``terms``).
    terms : dict of str to sequence of str
        The term texts of every degree of freedom.
    optimizer, rudder_signal
        As given to :func:`fit`.
    info : dict
        What the model records of its training; the hyper-parameters the optimizers chose
        are put in as ``"selected"`` (in its place, when ``info`` has the key).

    Returns
    -------
    AbkowitzModel
        With the estimators as ``estimators_``.
    """
    coefficients = {}
    for dof in DOFS:
        coef = np.asarray(fitted[dof].coef_, dtype=float).reshape(-1)
        coefficients[dof] = dict(zip(terms[dof], coef.tolist(), strict=True))
    info = dict(info)
    info["selected"] = {dof: _selected(est) for dof, est in fitted.items()}
    saved = {k: v for k, v in fitted["X"].get_params().items() if k not in PRIOR_ARRAYS}
    if optimizer == "prior":
        info["prior"] = {dof: {key: fitted[dof].get_params()[key] for key in PRIOR_ARRAYS}
                         for dof in DOFS}
    model = AbkowitzModel(ship=ship, library=library, coefficients=coefficients,
                          optimizer={"name": optimizer, "params": saved},
                          rudder_signal=rudder_signal, info=info)
    model.estimators_ = fitted
    return model


#: The variables whose training ranges make a model's envelope (:func:`training_envelope`).
ENVELOPE_VARIABLES = ("v", "r", "delta")


def training_envelope(records: Sequence[Trajectory], ship: Ship) -> dict[str, list[float]]:
    """Ranges of v', r' (over U0) and the actual rudder angle [rad] in training records.

    Returns
    -------
    dict
        ``{"v": [min, max], "r": [min, max], "delta": [min, max]}``: a JSON-ready form that a
        fitted model can keep in its ``info["envelope"]``.
    """
    if not records:
        raise SindyshipInputError("no training records to take the envelope from.")
    v = np.concatenate([rec["v"] for rec in records]) / ship.U0
    r = np.concatenate([rec["r"] for rec in records]) * ship.L / ship.U0
    delta = np.concatenate([rec.rudder for rec in records])
    return {name: [float(np.min(x)), float(np.max(x))]
            for name, x in zip(ENVELOPE_VARIABLES, (v, r, delta), strict=True)}


def _selected(estimator) -> dict:
    """Hyper-parameters an optimizer chose by cross-validation (for reports)."""
    out = {}
    for name in ("alpha_", "threshold_", "C_", "epsilon_"):
        value = getattr(estimator, name, None)
        if value is not None:
            out[name.rstrip("_")] = np.asarray(value).reshape(-1).tolist()
    return out

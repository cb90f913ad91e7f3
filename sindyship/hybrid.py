"""Trajectories and captive tests in one regression (hybrid identification).

Free-running records leave combinations of terms unseparated: along a zig-zag v' moves with
r' and r' with the rudder, so the fit can trade one derivative against another and still
match every sample (``sindyship fit`` reports them, :mod:`sindyship.identifiability`).
Captive tests hold the motion apart (static drift, rudder, pure yaw, drift and yaw), and a
towing tank that ran some of them is the cheapest way to separate those terms.  A hybrid fit
solves paper eq. 16 on the records' samples and on the captive conditions together.

**Captive rows.**  At a steady condition the accelerations vanish, and the hydrodynamic force a
dynamometer measures (the captive CSV's convention, :mod:`sindyship.captive`) is, in Prime I
with the force scales s and the rigid-body terms C_RB (:mod:`sindyship.forces`),

    F_captive = s (F' + C') - C_RB,

so each condition is a row of eq. 16 with the target

    F' = (F_captive + C_RB) / s - C'

(C' the Coriolis terms of eq. 14, Munk moment included) and the library's terms evaluated at
the condition (:func:`sindyship.captive.steady_variables`), times (U/U0)^2 in the
instantaneous speed form, as :func:`sindyship.identify.design` builds the records' rows.

**Weights.**  A record holds thousands of samples, a captive programme tens of conditions.
The captive rows together carry the share ``captive_share`` of the regression's weight: each
row is multiplied by sqrt(w), w = share / (1 - share) * n_samples / n_conditions.  The
default :data:`CAPTIVE_SHARE` is small, as the prior of ``--optimizer prior`` is: the records
decide what they pin down, the captive tests the combinations the records leave free, which
any weight decides.  On the KCS's three zig-zags with a prior fit, shares from 0.003 to 0.5
all bring the forces' lowest correlation with the MMG's captive tests to 0.999 (from 0.97);
a large share also moves what the records pin down, toward forces measured in steady
conditions (eq. 16's target on records carries the identification's added masses, which are
never exactly the ship's).

A hybrid model keeps its captive conditions and share in ``info["captive"]``, so that the
refinement (:func:`sindyship.refine.refine`, whose penalty is the fit's own objective) and
its check on half of the records fit and hold it to the same captive rows.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from .captive import (
    CAPTIVE_COLUMNS,
    FORCE_COLUMNS,
    check_captive_scale,
    check_force_scale,
    classify_tests,
    force_scales,
    rigid_body_forces,
    steady_conditions,
    steady_variables,
)
from .errors import SindyshipInputError
from .identify import (
    Design,
    design,
    fit,
    resolve_library,
    resolve_rudder_signal,
    term_column,
)
from .library import SPEED_FACTOR, TermLibrary
from .model import AbkowitzModel, coriolis_of_values
from .optimizers import ALWAYS_TRAINED
from .priors import prior_parameters
from .ships import Ship
from .targets import DOFS
from .trajectory import Trajectory

__all__ = ["CAPTIVE_SHARE", "captive_design", "fit_hybrid", "model_design", "with_captive"]

#: The share of the regression's weight the captive rows carry together by default.
CAPTIVE_SHARE = 0.01


def captive_design(captive: pd.DataFrame, ship: Ship, library: TermLibrary, *,
                   rudder_signal: str = "actual") -> dict[str, Design]:
    """Rows of eq. 16 from captive measurements (module docstring), unweighted.

    Parameters
    ----------
    captive : pandas.DataFrame
        Captive conditions and the hydrodynamic forces measured there, SI (as
        :func:`sindyship.captive.read_captive_csv` gives, or
        :func:`sindyship.captive.captive_tests` makes).
    ship : Ship
    library : TermLibrary
        The terms (and speed form) of the fit.
    rudder_signal : {"actual", "commanded"}
        The rudder angle the terms read (a captive rudder is both).

    Returns
    -------
    dict of str to Design
        Every row in the group :data:`~sindyship.optimizers.ALWAYS_TRAINED`: in every
        training set of a cross-validation and never held out (a captive condition is not a
        manoeuvre; left out as one, a test type made cross-validated optimizers choose models
        of two to eight terms).

    Raises
    ------
    SindyshipInputError
        For a table that lacks a column the terms read, holds conditions going astern, is of
        another ship or scale (:func:`sindyship.captive.check_captive_scale`), or whose sway
        force or yaw moment is :data:`~sindyship.captive.FORCE_SCALE_FACTOR` times or more
        larger or smaller (RMS) than the ship's semi-empirical derivatives predict there
        (:func:`sindyship.priors.prior_parameters`; within 0.8 to 1.9 times on the KCS's and
        the KVLCC2's virtual tests), or falls where they rise (a negative correlation: other
        axes or signs), or whose rudder tests' sway force rises or yaw moment falls with the
        rudder angle, or whose surge force is that many times smaller or larger than its
        sway force: a unit the header does not say, kN under a bare ``Y``.

    Examples
    --------
    >>> from sindyship.captive import captive_tests
    >>> from sindyship.identify import resolve_library
    >>> from sindyship.model import paper_model
    >>> from sindyship.ships import load_ship
    >>> kcs = load_ship("kcs")
    >>> model = paper_model(kcs, "LS")
    >>> tests = captive_tests(kcs, "rudder", points=5)
    >>> from sindyship.forces import model_captive_forces
    >>> measured = tests.assign(**model_captive_forces(model, tests))  # what it predicts
    >>> rows = captive_design(measured, kcs, model.library)
    >>> coefficients = [model.coefficients["N"][t] for t in rows["N"].terms]
    >>> bool(np.allclose(rows["N"].features @ coefficients, rows["N"].target))
    True
    """
    missing = [c for c in FORCE_COLUMNS if c not in captive.columns]
    if missing:
        raise SindyshipInputError(
            f"the captive table lacks the measured force '{missing[0]}'; a fit needs X, Y "
            "and N at every condition."
        )
    astern = int(np.sum(~(captive["u"].to_numpy(float) > 0.0)))
    if astern:
        raise SindyshipInputError(
            f"the captive table has {astern} condition{'' if astern == 1 else 's'} going "
            "astern (u <= 0), which a model expanded about its design speed ahead does not "
            "describe; leave them out of the table given to fit."
        )
    check_captive_scale(captive, ship, reads_revolutions="n" in library.sources,
                        whose="the ship")
    _check_surge_scale(captive)
    values = steady_variables(captive, library, ship, rudder_signal)
    factor = values.get(SPEED_FACTOR, 1.0)
    coriolis = coriolis_of_values(ship, values)
    scales = force_scales(ship, "prime-I")
    rigid = rigid_body_forces(ship, *(captive[c].to_numpy(float) for c in ("u", "v", "r")))
    n = len(captive)
    steady = steady_conditions(captive, library)  # names the table in a term's refusal
    groups = np.full(n, ALWAYS_TRAINED, dtype=int)
    out = {}
    for i, dof in enumerate(DOFS):
        terms = library.terms[dof]
        features = np.empty((n, len(terms)), order="F")
        for j, term in enumerate(terms):
            features[:, j] = term_column(term, values, factor, steady)
        measured = captive[FORCE_COLUMNS[i]].to_numpy(float)
        target = (measured + rigid[i]) / scales[i] - np.broadcast_to(coriolis[i], (n,))
        if dof != "X":  # the surge force's parts nearly cancel in some tests
            estimated = prior_parameters(ship, dof, [t.text for t in terms],
                                         speed=library.speed)["mean"]  # the ship's prior
            expected = scales[i] * (features @ np.asarray(estimated, dtype=float)
                                    + coriolis[i]) - rigid[i]
            check_force_scale(dof, measured, expected,
                              "the ship's estimated derivatives predict")
            _check_force_sign(dof, measured, expected)
        out[dof] = Design(features=features, target=target, groups=groups,
                          terms=tuple(t.text for t in terms))
    _check_rudder_sign(captive, ship)
    return out


def _check_force_sign(dof: str, measured: np.ndarray, expected: np.ndarray) -> None:
    """Refuse a sway force or yaw moment that falls where the ship's estimated derivatives
    say it rises: axes or signs other than sindyship's.  On the KCS's and the KVLCC2's
    virtual tests they correlate by 0.93 or more (every test type whose prediction varies)."""
    correlation = _correlation(measured, expected)
    if correlation is not None and correlation < 0.0:
        raise SindyshipInputError(
            f"the measured {dof} correlates {correlation:+.2f} with what the ship's estimated "
            "derivatives predict, so its sign convention is not sindyship's (v and Y positive "
            "to starboard, r and N positive turning the bow to starboard, body axes at "
            f"midship); flip the column or check the axes."
        )


def _check_rudder_sign(captive: pd.DataFrame, ship: Ship) -> None:
    """Refuse rudder tests whose sway force rises or yaw moment falls with the rudder angle.

    The ship's estimated derivatives have no rudder terms to compare with, but a rudder aft
    of midship pushes the stern to port and turns the bow to starboard for a positive angle
    in sindyship's convention: in the rudder tests of the KCS and the KVLCC2 (design and half
    speed) Y correlates -0.997 and N +0.997 with the angle.  Rows of other test types are
    checked against the derivatives (:func:`_check_force_sign`).
    """
    rudder = classify_tests(captive, ship) == "rudder"
    angle = captive["delta"].to_numpy(float)[rudder]
    wrong = {}
    for dof, sign in (("Y", -1.0), ("N", 1.0)):
        correlation = _correlation(captive[dof].to_numpy(float)[rudder], angle)
        if correlation is not None and sign * correlation < 0.0:
            wrong[dof] = correlation
    if not wrong:
        return
    convention = ("a rudder aft gives Y negative and N positive for a positive angle in "
                  "sindyship's convention (delta positive turns the bow to starboard)")
    if len(wrong) == 2:  # both forces against the angle: the angle's sign is the odd one
        raise SindyshipInputError(
            f"the measured Y and N of the rudder tests correlate {wrong['Y']:+.2f} and "
            f"{wrong['N']:+.2f} with the rudder angle, where {convention}: negate the "
            "column delta."
        )
    ((dof, correlation),) = wrong.items()
    raise SindyshipInputError(
        f"the measured {dof} of the rudder tests correlates {correlation:+.2f} with the rudder "
        f"angle, where {convention}: negate the column {dof}, or check its axes."
    )


def _correlation(a: np.ndarray, b: np.ndarray) -> float | None:
    """Pearson correlation of ``a`` and ``b``; None for fewer than three values or either
    constant (nothing to judge a sign by)."""
    if a.size < 3 or np.std(a) == 0.0 or np.std(b) == 0.0:
        return None
    return float(np.corrcoef(a, b)[0, 1])


def _check_surge_scale(captive: pd.DataFrame) -> None:
    """Refuse a surge force :data:`~sindyship.captive.FORCE_SCALE_FACTOR` times or more
    smaller or larger than the sway force beside it: a unit its header does not say.  (The
    sway force is checked against the ship's estimated derivatives; the surge force's own
    prediction nearly cancels in pure yaw.  Its RMS is 0.025 to 1.04 times the sway force's
    on the KCS's and the KVLCC2's virtual tests, static drift to pure yaw, 3 to 21
    conditions each.)"""
    check_force_scale("X", captive["X"].to_numpy(float), captive["Y"].to_numpy(float),
                      "of the measured Y beside it")


def with_captive(problems: Mapping[str, Design], captive: Mapping[str, Design],
                 share: float = CAPTIVE_SHARE) -> dict[str, Design]:
    """The records' problems with the captive rows below them, weighted so that the captive
    rows carry ``share`` of the weight together (module docstring)."""
    if not 0.0 < share < 1.0:
        raise SindyshipInputError(f"the captive share must be between 0 and 1 (exclusive), not "
                                  f"{share!r}.")
    out = {}
    for dof in DOFS:
        base, rows = problems[dof], captive[dof]
        weight = math.sqrt(share / (1.0 - share) * len(base.target) / len(rows.target))
        out[dof] = Design(features=np.asfortranarray(np.vstack([base.features,
                                                                weight * rows.features])),
                          target=np.concatenate([base.target, weight * rows.target]),
                          groups=np.concatenate([base.groups, rows.groups]),
                          terms=base.terms)
    return out


def _hybrid_problems(records, ship, library, captive, share, rudder_signal, derivative,
                     window) -> dict[str, Design]:
    problems = design(records, ship, library, rudder_signal=rudder_signal,
                      derivative=derivative, window=window)
    return with_captive(problems, captive_design(captive, ship, library,
                                                 rudder_signal=rudder_signal), share)


def fit_hybrid(records: Sequence[Trajectory], ship: Ship, captive: pd.DataFrame, *,
               captive_share: float = CAPTIVE_SHARE, library: str | TermLibrary = "abkowitz",
               effects: Sequence[str] = (), speed: str | None = None,
               rudder_signal: str = "actual", derivative: str = "five-point",
               window: float = 21.0, **options) -> AbkowitzModel:
    """Identify an Abkowitz model from records and captive tests together.

    As :func:`sindyship.identify.fit` (``options``: ``optimizer``, ``params``), with the
    captive conditions' rows of eq. 16 below the records' (module docstring).  The model keeps
    the conditions, their test types and the share in ``info["captive"]``.

    Examples
    --------
    >>> from sindyship import MMGModel, Manoeuvre, fly, load_ship
    >>> from sindyship.captive import captive_tests
    >>> kcs = load_ship("kcs")
    >>> runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=600)])
    >>> model = fit_hybrid(runs, kcs, captive_tests(kcs, "static-drift", points=5))
    >>> model.info["captive"]["tests"], model.info["captive"]["share"]
    ({'static-drift': 4, 'straight': 1}, 0.01)
    """
    lib = resolve_library(library, effects, speed)
    rudder_signal = resolve_rudder_signal(records, rudder_signal)
    problems = _hybrid_problems(records, ship, lib, captive, captive_share, rudder_signal,
                                derivative, window)
    model = fit(records, ship, library=lib, rudder_signal=rudder_signal,
                derivative=derivative, window=window, problems=problems, **options)
    kinds = classify_tests(captive, ship)
    columns = [c for c in captive.columns if c in (*CAPTIVE_COLUMNS, *FORCE_COLUMNS)
               or pd.api.types.is_numeric_dtype(captive[c])]
    model.info["n_samples"] = int(sum(record.n_samples for record in records))
    model.info["captive"] = {
        "share": float(captive_share), "rows": len(captive),
        "tests": {str(kind): int(np.sum(kinds == kind)) for kind in dict.fromkeys(kinds)},
        "conditions": {c: captive[c].to_numpy(float).tolist() for c in columns},
    }
    return model


def _captive_of(model: AbkowitzModel) -> tuple[pd.DataFrame, float] | None:
    kept = model.info.get("captive")
    if not kept:
        return None
    return pd.DataFrame(kept["conditions"]), float(kept["share"])


def _estimate(model: AbkowitzModel) -> dict:
    """How the model's fit estimated the accelerations (``derivative``, ``window``)."""
    return {"derivative": model.info.get("derivative", "five-point"),
            "window": model.info.get("window_s") or 21.0}


def model_design(model: AbkowitzModel, records: Sequence[Trajectory], *,
                 captive: bool = True) -> dict[str, Design]:
    """The regression problems of eq. 16 on ``records``, made as the model's fit made them:
    with its captive rows when it has them (``info["captive"]``) and ``captive`` is True."""
    kept = _captive_of(model) if captive else None
    if kept is None:
        return design(records, model.ship, model.library, rudder_signal=model.rudder_signal,
                      **_estimate(model))
    estimate = _estimate(model)
    return _hybrid_problems(records, model.ship, model.library, kept[0], kept[1],
                            model.rudder_signal, estimate["derivative"], estimate["window"])


def fitted_again(model: AbkowitzModel, records: Sequence[Trajectory]) -> AbkowitzModel:
    """The model's fit (its library, optimizer and parameters, rudder signal, acceleration
    estimate and captive rows) on other records."""
    settings = {"library": model.library, "optimizer": model.optimizer["name"],
                "params": dict(model.optimizer["params"]), "rudder_signal": model.rudder_signal,
                **_estimate(model)}
    kept = _captive_of(model)
    if kept is None:
        return fit(records, model.ship, part_of_set=True, **settings)
    return fit_hybrid(records, model.ship, kept[0], captive_share=kept[1], part_of_set=True,
                      **settings)

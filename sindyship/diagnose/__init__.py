"""Where an identified model fails, and which physical effect is missing.

The questions a user asks after :func:`sindyship.identify.fit`, in order:

Compare
    :func:`compare` flies the identified model the way each record was flown (zig-zags
    closed loop, :func:`sindyship.flights.fly_like`) and summarises the error per
    manoeuvre: mean and maximum distance in ship lengths, RMS heading and speed error, and
    the time a flight diverged, if it did.
Where it fails
    :func:`force_residuals` gives the force residual of each equation, the measured force
    of paper eq. 16 minus the model's eq. 15, over time with the manoeuvre phases
    (:func:`manoeuvre_phases`: rudder steps and reversals, steady turns) and binned over
    drift angle, yaw rate, rudder angle and heading (:data:`STATE_BINS`).
Which effect is missing
    :func:`diagnose` scores every effect of the catalogue (``libraries/effects/*.toml``) by
    leave-one-manoeuvre-out cross-validation: for each training record in turn, the library
    alone and the library plus the effect's terms are fitted (least squares) on the other
    records and predict the held-out record's forces.  With SSE the summed squared error of
    those predictions, ``explained = mean over X, Y, N of clip(1 - SSE_with / SSE_without, 0,
    1)``: the share of the remaining force error that the effect's terms explain on
    manoeuvres they were not fitted on.  Both sides are refitted, so that the effect is not
    credited with error the library's own terms absorb once refitted.  The best candidates are
    then confirmed by refitting the library with them and re-flying the manoeuvres.  Effects
    whose channels the data lack are listed as not testable, with the channels to record.
What no catalogue lists
    :func:`discover` searches the residual for a channel that lags the force it causes and
    for terms of pysindy feature libraries (:mod:`sindyship.diagnose.discovery`); the
    diagnosis runs it when nothing catalogued is meaningful and the model is visibly wrong.
Add it and watch the error fall
    :func:`before_after` refits with added effects and tabulates the error on every
    manoeuvre, training and held-out, before and after; :func:`diagnose_iteratively` repeats
    diagnosis and addition until no effect explains a meaningful share
    (:data:`MEANINGFUL_SHARE`).

A share is *meaningful* from 5 % (:data:`MEANINGFUL_SHARE`).  The reason is measured, not
assumed (``benchmarks/bench_diagnose.py``): on data made by an Abkowitz model itself every
catalogued effect explains 0.0 %; on the symmetric KCS without a hidden effect the effects
that are physically absent there (asymmetry, environment) explain at most 1.0 %; over a grid
of 41 hidden loads, currents, propeller side forces and rudder offsets the expected effect
explained 26 % to 94 %.  5 % is five times the false-alarm level and five times below the
weakest hidden effect.  A candidate is *confirmed* when refitting with it and re-flying the
training manoeuvres cuts their mean distance by at least 10 % (geometric mean over the
manoeuvres, :data:`CONFIRMING_RATIO`) without a new divergence.

The command ``sindyship diagnose`` is in :mod:`sindyship.cli.diagnose`; the text of every
result is made by :mod:`sindyship.reports` and its figures by :mod:`sindyship.plotting`.

Examples
--------
>>> from sindyship import load_ship, MMGModel, Manoeuvre, fly
>>> ship = load_ship("kcs")
>>> runs = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=r, duration=400)
...                             for r in (35, -35, 20)])
>>> result = diagnose(runs, ship, effects=["asymmetry", "wind"], fly_training=False)
>>> result.ranking[0].effect.name, [n.effect.name for n in result.not_testable]
('asymmetry', ['wind'])
>>> 0.0 <= result.ranking[0].explained <= 1.0
True
"""

from __future__ import annotations

from .._diagnosis_thresholds import CONFIRMING_RATIO, MEANINGFUL_SHARE
from ._flights import fly_model
from .before_after import BeforeAfter, before_after
from .compare import ManoeuvreComparison, compare
from .diagnosis import Diagnosis, diagnose
from .discovery import Discovery, Finding, discover
from .iteration import IterativeDiagnosis, Round, diagnose_iteratively
from .phases import Phase, manoeuvre_phases
from .residuals import STATE_BINS, Residuals, StateBins, force_residuals
from .scoring import EffectScore, NotTestable

__all__ = [
    "CONFIRMING_RATIO",
    "MEANINGFUL_SHARE",
    "STATE_BINS",
    "BeforeAfter",
    "Diagnosis",
    "Discovery",
    "EffectScore",
    "Finding",
    "IterativeDiagnosis",
    "ManoeuvreComparison",
    "NotTestable",
    "Phase",
    "Residuals",
    "Round",
    "StateBins",
    "before_after",
    "compare",
    "diagnose",
    "diagnose_iteratively",
    "discover",
    "fly_model",
    "force_residuals",
    "manoeuvre_phases",
]

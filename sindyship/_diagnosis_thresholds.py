"""Thresholds of the diagnosis (:mod:`sindyship.diagnose`), shared with its command line.

A module of numbers alone, outside the diagnosis package, so that the parsers of
``sindyship diagnose`` and ``sindyship discover`` show the defaults without importing the
diagnosis (and scikit-learn with it): a refused command answers at once.
"""

from __future__ import annotations

__all__ = [
    "BOOTSTRAP",
    "NOISE_CAP",
    "NOISE_VISIBLE",
    "SIGNIFICANCE",
    "COLLINEAR_VIF",
    "CONFIRMING_RATIO",
    "FLIGHT_OVERRIDE_RATIO",
    "FLIGHTS_PREFER_RATIO",
    "MEANINGFUL_SHARE",
    "UNEXPLAINED_SHARE",
]

#: Smallest share of the cross-validated force error an effect must explain to matter (see
#: :mod:`sindyship.diagnose` for why 5 %).
MEANINGFUL_SHARE = 0.05
#: Largest after/before ratio of the training flights' mean distance (geometric mean over the
#: manoeuvres) that confirms an effect: a 10 % gain, above the few per cent by which any
#: extra term moves a flight.
CONFIRMING_RATIO = 0.9
#: An effect below the force-share threshold is still added when re-flying the training
#: records with it brings them at least this much closer (geometric mean of after over before,
#: as a confirmation): under noise a force share can hide what the flights show, and a verdict
#: never disagrees with a confirmation.
FLIGHT_OVERRIDE_RATIO = CONFIRMING_RATIO
#: Of two meaningful effects both confirmed by re-flying, the one the force error ranks lower
#: is named when its training flights' ratio is at most this share of the other's (twice as
#: close): the flights judge the model's use, the force share only points to candidates.
FLIGHTS_PREFER_RATIO = 0.5
#: Share of a measured force (squared relative RMS error of the leave-one-manoeuvre-out
#: predictions) above which most of it is unexplained and the library cannot be complete.
UNEXPLAINED_SHARE = 0.5
#: Variance inflation factor above which a term is reported as collinear with others: its
#: coefficient's variance is inflated 100 times (its standard error 10 times) by the others.
COLLINEAR_VIF = 100.0
#: Bootstrap resamples of the manoeuvres behind an effect's significance.
BOOTSTRAP = 1000
#: Quantile of the resampled gain that must stay above zero for a significant gain (5 %).
SIGNIFICANCE = 0.05
#: Largest share of an equation's error taken for noise: the share above the noise floor is
#: then at most 20 times the plain share, however noisy the records.
NOISE_CAP = 0.95
#: Noise-floor share of an equation's cross-validated error below which the rest of the
#: error is visibly more than noise: the diagnosis then searches beyond the catalogue.
NOISE_VISIBLE = 0.9

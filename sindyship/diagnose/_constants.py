"""Thresholds and names shared by the diagnosis modules."""

from __future__ import annotations

from ..reports import DOF_NAMES, SETS

__all__ = ["CONFIRMING_RATIO", "DOF_NAMES", "MEANINGFUL_SHARE", "SETS"]

#: Smallest share of the cross-validated force error an effect must explain to matter (see
#: :mod:`sindyship.diagnose` for why 5 %).
MEANINGFUL_SHARE = 0.05
#: Largest after/before ratio of the training flights' mean distance (geometric mean over the
#: manoeuvres) that confirms an effect: a 10 % gain, above the few per cent by which any
#: extra term moves a flight.
CONFIRMING_RATIO = 0.9

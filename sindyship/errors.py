"""Exceptions that sindyship raises for problems a user can fix, and its warnings."""

from __future__ import annotations


class SindyshipInputError(ValueError):
    """Bad input handed to sindyship by a user (a file, an option, an argument).

    The message is one sentence that names the file and the column, row or term at fault and
    says how to fix it.  The command line prints it on one line and exits with status 2.
    """


class PriorCoverageNote(UserWarning):
    """The ``prior`` fit's library has no term for some of the ship's estimates
    (:func:`sindyship.priors.coverage_note`; also ``sindyship.priors.PriorCoverageNote``)."""


class RudderSignalNote(UserWarning):
    """The records have no actual rudder angle, so a fit uses the commanded one
    (:func:`sindyship.identify.fitted_rudder_signal`)."""

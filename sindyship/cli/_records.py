"""Reading the measurement CSVs a verb is given."""

from __future__ import annotations


def read_records(paths, resample=None):
    """The records of ``paths``, in order (:func:`sindyship.measurements.read_csv`)."""
    from ..measurements import read_csv

    return [read_csv(p, resample=resample) for p in paths]

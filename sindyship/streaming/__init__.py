"""Fitting records that do not fit in memory together: one record file at a time, on Dask.

The least-squares problem of every degree of freedom (paper eq. 18: the library columns of
eq. 17 against the forces of eq. 16) is reduced, record by record, to the triangular factor
``R`` of its rows ``[X | y]`` (``Z = Q^T y`` is its last column above the diagonal, the root
of the residual sum of squares its last diagonal entry), a few dozen rows however long the
record.  Factors of
different records combine exactly: the factor of a union of records is the QR of their
stacked factors (TSQR), merged here as a binary tree.  Every optimizer that works on the
compressed problem (``ls``, ``stlsq``, ``lasso``) fits from the merged factor, its
leave-one-manoeuvre-out folds from the factors of all the other records, and gives the
coefficients of the in-memory fit up to rounding.  ``svr`` needs every sample and is refused.

- :mod:`sindyship.records` (re-exported here): which files a list of paths and glob patterns
  names; reading a measurement CSV or a Parquet file with the same columns through the same
  checks.
- :mod:`._reduce`: one record file to its factors (:func:`reduce_record`), and the merge.
- :mod:`._cluster`: a Dask client (:func:`connect`: a scheduler's address, or a
  ``LocalCluster``) and the reduction of many files on it (:func:`reduce_files`), or in this
  process.
- :mod:`._fit`: the model from the merged factors (:func:`fit_reduction`, :func:`fit_files`).

Examples
--------
On a cluster (``python3 -m pip install "sindyship[cluster]"``)::

    from sindyship.streaming import connect, expand_paths, fit_files

    with connect() as client:          # or connect("tcp://scheduler:8786")
        model = fit_files(expand_paths(["fleet/*.parquet"]), ship, client=client)
"""

from __future__ import annotations

from ..records import PARQUET_SUFFIXES, expand_paths, read_record, time_window
from ._cluster import DASK_INSTALL, check_scheduler_address, connect, reduce_files
from ._fit import fit_files, fit_reduction, stream_settings
from ._reduce import Reduction, StreamSettings, merge_reductions, reduce_record

__all__ = [
    "DASK_INSTALL",
    "PARQUET_SUFFIXES",
    "Reduction",
    "StreamSettings",
    "check_scheduler_address",
    "connect",
    "expand_paths",
    "fit_files",
    "fit_reduction",
    "merge_reductions",
    "read_record",
    "reduce_files",
    "reduce_record",
    "stream_settings",
    "time_window",
]

"""Where the records are reduced: a Dask cluster (one task per record file, the factors
merged as a binary tree on the cluster), or this process, one record at a time.

Dask is the optional extra ``cluster``; without it only the in-process path runs.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from ..errors import SindyshipInputError
from ..optimizers import pairwise_tree
from ._reduce import Reduction, StreamSettings, merge_all, merge_reductions, reduce_record

__all__ = ["DASK_INSTALL", "connect", "reduce_files"]

#: How to install what the cluster needs.
DASK_INSTALL = 'python3 -m pip install "sindyship[cluster]"'

#: Seconds to wait for a scheduler given by address.
CONNECT_TIMEOUT_S = 20


def _distributed():
    """The ``distributed`` package, or a one-line error saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise SindyshipInputError(
            f"a streamed fit runs on Dask, which is not installed; install it with {DASK_INSTALL}."
        ) from None
    return distributed


@contextmanager
def connect(scheduler: str | None = None, n_workers: int | None = None) -> Iterator:
    """A ``dask.distributed`` client, closed on leaving the block.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://host:8786``).  Without one, a
        ``LocalCluster`` of single-threaded worker processes is started for the block.
    n_workers : int, optional
        Worker processes of the local cluster (default: one per core this process may use).

    Raises
    ------
    SindyshipInputError
        When Dask is not installed, or the scheduler cannot be reached.
    """
    distributed = _distributed()
    if scheduler:
        try:
            client = distributed.Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError, ValueError) as exc:
            reason = " ".join(str(exc).split())[:160]
            raise SindyshipInputError(
                f"cannot reach the Dask scheduler at {scheduler} ({reason}); start it "
                "(dask scheduler) or check the address."
            ) from None
        with client:
            yield client
        return
    if n_workers is None or n_workers < 1:
        n_workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
            os.cpu_count() or 1)
    # a record's error reaches the caller as an exception: the workers' own log of it (a
    # traceback at level ERROR) stays quiet
    cluster = distributed.LocalCluster(n_workers=n_workers, threads_per_worker=1,
                                       processes=True, dashboard_address=":0",
                                       silence_logs=logging.CRITICAL)
    try:
        with distributed.Client(cluster) as client:
            yield client
    finally:
        cluster.close()


def reduce_files(paths: Sequence[str | os.PathLike], settings: StreamSettings, *,
                 names: Sequence[str] | None = None, client=None, keep_records: bool = False,
                 progress: bool = False) -> tuple[Reduction, list[Reduction] | None]:
    """Every record file reduced to its factors, and their merge.

    Parameters
    ----------
    paths : sequence of str or os.PathLike
        Record files (measurement CSV or Parquet), one partition each.
    settings : StreamSettings
        How to read the records and which problems to build.
    names : sequence of str, optional
        The records' names (default: the file stems).
    client : distributed.Client, optional
        The cluster to run on: one task per file, then a binary tree of merge tasks, all
        on the cluster; only the merged factors (and, with ``keep_records``, each record's)
        come back.  Without a client the records are reduced in this process, one at a
        time, and merged by the same tree.
    keep_records : bool
        Also return every record's reduction (needed for leave-one-record-out folds).
    progress : bool
        Show a progress bar of the records on stderr.

    Returns
    -------
    whole : Reduction
        All records merged.
    records : list of Reduction or None
        Per record, with ``keep_records``.

    Raises
    ------
    SindyshipInputError
        When there are no files, or a bad record's message (the first to fail).
    """
    from tqdm.auto import tqdm

    # absolute paths: a worker of a remote cluster does not share this process's folder
    paths = [os.path.abspath(os.fspath(p)) for p in paths]
    if not paths:
        raise SindyshipInputError("no records to fit; give at least one record file.")
    names = [Path(p).stem for p in paths] if names is None else list(names)
    bar = tqdm(total=len(paths), desc="records", unit="record", file=sys.stderr,
               disable=not progress)
    try:
        if client is None:
            parts = []
            for path, name in zip(paths, names, strict=True):
                parts.append(reduce_record(path, name, settings))
                bar.update(1)
            return merge_all(parts), (parts if keep_records else None)
        return _on_cluster(client, paths, names, settings, keep_records, bar)
    finally:
        bar.close()


def _on_cluster(client, paths, names, settings, keep_records, bar):
    """One task per file and a binary tree of merges, submitted at once (merges start as
    soon as their two halves are done)."""
    distributed = _distributed()
    futures = client.map(reduce_record, paths, names, settings=settings, pure=False)
    submitted = list(futures)

    def merge_on_cluster(a, b):
        submitted.append(client.submit(merge_reductions, a, b, pure=False))
        return submitted[-1]

    whole_future = pairwise_tree(futures, merge_on_cluster)
    try:
        for done in distributed.as_completed(futures):
            if done.status == "error":
                done.result()  # raises the worker's error here
            bar.update(1)
        whole = whole_future.result()
        records = client.gather(futures) if keep_records else None
    finally:
        client.cancel(submitted)
    return whole, records

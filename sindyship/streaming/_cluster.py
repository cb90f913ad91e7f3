"""Where the records are reduced: a Dask cluster (one task per record file, the factors
merged as a binary tree on the cluster), or this process, one record at a time.

Dask is the optional extra ``cluster``; without it only the in-process path runs.
"""

from __future__ import annotations

import logging
import os
import re
import socket
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from ..errors import SindyshipInputError
from ..optimizers import pairwise_tree
from ._reduce import Reduction, StreamSettings, merge_all, merge_reductions, reduce_record

__all__ = ["DASK_INSTALL", "check_scheduler_address", "connect", "reduce_files"]

#: How to install what the cluster needs.
DASK_INSTALL = 'python3 -m pip install "sindyship[cluster]"'

#: Seconds to wait for a scheduler given by address.
CONNECT_TIMEOUT_S = 20

#: A host name, an IPv4 address, or (between brackets) an IPv6 address.
_HOST = re.compile(r"[A-Za-z0-9]([A-Za-z0-9._-]{0,252}[A-Za-z0-9])?|[0-9A-Fa-f:.]{2,45}")


def _distributed():
    """The ``distributed`` package, or a one-line error saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise SindyshipInputError(
            f"a streamed fit runs on Dask, which is not installed; install it with {DASK_INSTALL}."
        ) from None
    return distributed


def check_scheduler_address(address: str) -> str:
    """A Dask scheduler's address, checked before anything connects.

    Parameters
    ----------
    address : str
        ``tcp://host:port`` or ``host:port`` (the scheme Dask uses by default).

    Returns
    -------
    str
        The address with its ``tcp://`` scheme.

    Raises
    ------
    SindyshipInputError
        An empty address, another scheme (``tls://`` needs certificates sindyship is not
        given, ``ucx://`` and ``inproc://`` are not reachable from a command), no host, or a
        port outside 1-65535.

    Examples
    --------
    >>> check_scheduler_address("scheduler:8786")
    'tcp://scheduler:8786'
    """
    text = str(address).strip()
    how = "give the address as tcp://host:port, as `dask scheduler` prints it"
    if not text:
        raise SindyshipInputError(f"the scheduler address is empty; {how}.")
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    if scheme.lower() != "tcp":
        raise SindyshipInputError(
            f"the scheduler address {text[:80]!r} uses {scheme[:20]}://, which sindyship "
            f"cannot connect to; {how}.")
    host, colon, port = rest.rpartition(":")
    name = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    bracketed = name is not host
    if not colon or not (port.isascii() and port.isdigit()) or not 1 <= int(port) <= 65535:
        raise SindyshipInputError(
            f"the scheduler address {text[:80]!r} has no port 1-65535; {how}.")
    if ":" in name and not bracketed and re.fullmatch(r"[0-9A-Fa-f:.]+", name):
        raise SindyshipInputError(
            f"the scheduler address {text[:80]!r} has an IPv6 host without brackets; write "
            "it as tcp://[host]:port.")
    if not _HOST.fullmatch(name) or (":" in name) != bracketed:
        raise SindyshipInputError(
            f"the scheduler address {text[:80]!r} has no valid host name or IP address; "
            f"{how}.")
    return f"tcp://{rest}"


def _client(distributed, address: str):
    """A client of the scheduler at ``address``, or a one-line error within the timeout.

    A closed port is refused at once, and a server that accepts the connection but never
    answers (Dask's own timeout does not cover the handshake) is given up after
    :data:`CONNECT_TIMEOUT_S` seconds, probe and handshake together: the client is made on a
    daemon thread that is left behind, and closes its client if it connects after that.
    """
    deadline = time.monotonic() + CONNECT_TIMEOUT_S
    host, _, port = address.removeprefix("tcp://").rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_TIMEOUT_S):
            pass
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise SindyshipInputError(
            f"cannot reach the Dask scheduler at {address} ({reason}); start it (dask "
            "scheduler) or check the address.") from None
    made: dict = {}
    lock = threading.Lock()
    left = max(deadline - time.monotonic(), 1.0)

    def make() -> None:
        try:
            client = distributed.Client(address, timeout=f"{left}s")
        except BaseException as exc:  # reported on the caller's thread
            made["error"] = exc
            return
        with lock:
            if made.get("abandoned"):  # the caller gave up waiting: nobody will close it
                client.close()
            else:
                made["client"] = client

    thread = threading.Thread(target=make, name="sindyship-connect", daemon=True)
    thread.start()
    thread.join(left)
    with lock:
        if thread.is_alive() and "client" not in made:
            made["abandoned"] = True
            raise SindyshipInputError(
                f"the server at {address} took the connection but did not answer as a Dask "
                f"scheduler within {CONNECT_TIMEOUT_S} s; check the address and that the "
                "scheduler is running.")
    if "error" in made:
        reason = " ".join(str(made["error"]).split())[:160] or type(made["error"]).__name__
        raise SindyshipInputError(
            f"cannot connect to a Dask scheduler at {address} ({reason}); start it (dask "
            "scheduler) or check the address.") from None
    return made["client"]


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
        When Dask is not installed, the address is not a ``tcp://host:port`` address
        (:func:`check_scheduler_address`), or no scheduler answers there within
        :data:`CONNECT_TIMEOUT_S` seconds.
    """
    distributed = _distributed()
    if scheduler is not None:
        client = _client(distributed, check_scheduler_address(scheduler))
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

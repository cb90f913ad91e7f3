"""One record file reduced to the small factors of its regression problems, and their merge.

:func:`reduce_record` runs where the record is (a worker of a cluster): it reads the file
(:func:`sindyship.records.read_record`), smooths it when asked, builds the regression
problem of every degree of freedom exactly as the in-memory fit does
(:func:`sindyship.identify.design`: the library terms and the eq. 16 forces) and reduces each
to its triangular factor (:class:`~sindyship.optimizers.RowFactor`: the least-squares problem
of eq. 18 on a few dozen rows).  Only the factors, the record's ranges and its notes leave the
worker.  :func:`merge_reductions` combines two reductions (one step of the tree).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field

from ..errors import SindyshipInputError
from ..optimizers import RowFactor, merge_factors, pairwise_tree
from ..ships import Ship
from ..smoothing import SmoothingSetting, smooth_records
from ..targets import DOFS, sampling_steps

__all__ = ["Reduction", "StreamSettings", "merge_reductions", "reduce_record"]


@dataclass(frozen=True)
class StreamSettings:
    """How every record is read and turned into regression problems (the options of
    ``sindyship fit``); plain data, sent to the workers.

    Attributes
    ----------
    ship : Ship
        The ship the records belong to.
    library : str
        Term library name or TOML path (resolved on each worker, so a file must be readable
        there).
    effects : tuple of str
        Catalogued effects (or effect files) added to the library.
    rudder_signal, derivative, window
        As for :func:`sindyship.identify.design`.
    smoothing : SmoothingSetting or None
        Applied to every record before differencing (a fixed setting: the automatic choice
        flies every record and needs them all in memory).
    resample, skip_checks, time_range
        As for :func:`~sindyship.records.read_record`.
    speed : {"design", "instantaneous"} or None
        The library's speed form (None: the library's own).
    """

    ship: Ship
    library: str = "abkowitz"
    effects: tuple[str, ...] = ()
    rudder_signal: str = "actual"
    derivative: str = "five-point"
    window: float = 21.0
    smoothing: SmoothingSetting | None = None
    resample: float | None = None
    skip_checks: tuple[str, ...] = ()
    time_range: tuple[float, float] | str = "auto"
    speed: str | None = None


@dataclass(frozen=True)
class Reduction:
    """The factors of one record, or of several merged, with what the model's ``info`` needs.

    Attributes
    ----------
    names, paths : list of str
        The records, in order.
    samples : list of int
        Samples of every record (after the time-range cut).
    factors : dict of str to RowFactor
        The factor of ``[features | target]`` of every degree of freedom.
    envelope : dict of str to [float, float]
        Ranges of v', r' and the rudder angle (:func:`sindyship.identify.training_envelope`).
    notes : list of (path, text)
        What the reader repaired.
    cuts : list of (path, start, stop, reason)
        Automatic time-range cuts.
    fastest : list of float
        Every record's highest speed sqrt(u^2 + v^2) [m/s].
    steps : list of float
        Every record's sampling interval in L/U0 (:func:`sindyship.targets.sampling_steps`).
    """

    names: list[str]
    paths: list[str]
    samples: list[int]
    factors: dict[str, RowFactor]
    envelope: dict[str, list[float]]
    notes: list[tuple[str, str]] = field(default_factory=list)
    cuts: list[tuple[str, float, float, str]] = field(default_factory=list)
    fastest: list[float] = field(default_factory=list)
    steps: list[float] = field(default_factory=list)

    @property
    def n_samples(self) -> int:
        return sum(self.samples)


def reduce_record(path: str | os.PathLike, name: str, settings: StreamSettings) -> Reduction:
    """Read one record file and reduce its regression problems to their factors.

    Parameters
    ----------
    path : str or os.PathLike
        A measurement CSV or Parquet file.
    name : str
        The record's name.
    settings : StreamSettings
        How to read it and which problems to build.

    Returns
    -------
    Reduction

    Raises
    ------
    SindyshipInputError
        As the reader, the smoother and :func:`sindyship.identify.design` raise them (one
        sentence naming the file or record).
    """
    from ..identify import design, resolve_library, training_envelope
    from ..records import read_record

    ship = settings.ship
    record, notes, cut = read_record(path, name=name, ship=ship, resample=settings.resample,
                                     skip_checks=settings.skip_checks,
                                     time_range=settings.time_range)
    if settings.smoothing is not None:
        (record,) = smooth_records([record], settings.smoothing)
    if settings.rudder_signal == "actual" and not record.has("delta"):
        raise SindyshipInputError(
            f"{path}: has no actual rudder angle (delta), which a streamed fit on the actual "
            "angle needs in every record; fit such records with --rudder-signal commanded.")
    library = resolve_library(settings.library, settings.effects, settings.speed)
    problems = design([record], ship, library, rudder_signal=settings.rudder_signal,
                      derivative=settings.derivative, window=settings.window)
    factors = {dof: RowFactor.of_rows(problems[dof].features, problems[dof].target)
               for dof in DOFS}
    source = os.fspath(path)
    return Reduction(
        names=[name], paths=[source], samples=[record.n_samples], factors=factors,
        envelope=training_envelope([record], ship),
        notes=[(source, note) for note in notes],
        cuts=[] if cut is None else [(source, *cut)],
        fastest=[record.fastest],
        steps=[sampling_steps([record], ship)[record.name]],
    )


def merge_reductions(a: Reduction, b: Reduction) -> Reduction:
    """The reduction of the records of ``a`` followed by those of ``b`` (a TSQR step per
    degree of freedom)."""
    envelope = {key: [min(a.envelope[key][0], b.envelope[key][0]),
                      max(a.envelope[key][1], b.envelope[key][1])] for key in a.envelope}
    return Reduction(
        names=a.names + b.names, paths=a.paths + b.paths, samples=a.samples + b.samples,
        factors={dof: merge_factors(a.factors[dof], b.factors[dof]) for dof in a.factors},
        envelope=envelope, notes=a.notes + b.notes, cuts=a.cuts + b.cuts,
        fastest=a.fastest + b.fastest, steps=a.steps + b.steps,
    )


def merge_all(reductions: Sequence[Reduction]) -> Reduction:
    """All reductions merged pairwise as a binary tree, in order."""
    return pairwise_tree(reductions, merge_reductions)

"""What every verb of the command line shares: options, their bounds, progress, JSON output.

Every number a user gives is checked when the command line is parsed, by the ``type=``
functions below: each refuses what is not finite or lies outside a physical range, and its
message gives the range and the unit (argparse adds the option's name).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys

from .._io import clean_json, physical_memory
from ..errors import SindyshipInputError
from ..library import PAPER_LIBRARY

#: The names of :data:`sindyship.optimizers.OPTIMIZERS`, spelled out so that building the
#: parser imports no scikit-learn (``sindyship --help``, ``simulate`` and a refused argument
#: answer without it); a test keeps them equal.
OPTIMIZER_NAMES = ("lasso", "ls", "prior", "stlsq", "svr")

#: Longest record [s] a verb simulates (11.6 days), and the most samples it holds.
MAX_DURATION = 1e6
MAX_SAMPLES = 10_000_000
#: Shortest sample or resampling interval [s] and longest one.
MIN_STEP, MAX_STEP = 1e-3, 3600.0
#: Largest rudder or check angle [deg] any command asks for (beyond it a rudder stalls).
MAX_RUDDER = 45.0
#: Most Runge-Kutta steps of one simulated record (about 4 minutes of work).
MAX_RK_STEPS = 1_000_000
#: Memory [bytes] one simulated or resampled sample takes, all copies included (measured:
#: 2e6 samples of ``simulate`` peak at 1.6 GB).
BYTES_PER_SAMPLE = 1000
#: Memory [bytes] a refinement takes per sample and active coefficient beyond the record: the
#: sensitivities of the six compared channels, held twice (96), and the fit's design (8).
REFINE_BYTES_PER_TERM = 104


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def bounded_float(low: float, high: float, unit: str, *, low_open: bool = True,
                  high_open: bool = False, symmetric: bool = False):
    """An argparse ``type=``: a finite float in the range, else a message with the range.

    With ``symmetric`` the range bounds the magnitude and the sign is free (rudder angles).

    Examples
    --------
    >>> bounded_float(0, 10, "s")("2.5")
    2.5
    >>> bounded_float(0, 10, "s")("0")
    Traceback (most recent call last):
    argparse.ArgumentTypeError: must be a number of s in (0, 10], not '0'
    """
    span = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    if symmetric:
        span = f"magnitude {span}"
    what = f"a number of {unit}" if unit else "a number"

    def parse(text: str) -> float:
        value = _number(text)
        size = abs(value) if symmetric else value
        ok = math.isfinite(value) and (size > low if low_open else size >= low) and (
            size < high if high_open else size <= high)
        if not ok:
            raise argparse.ArgumentTypeError(
                f"must be {what} {'of' if symmetric else 'in'} {span}, not {text!r}")
        return value

    parse.__name__ = "number"
    return parse


def bounded_int(low: int, high: int, what: str = "a whole number"):
    """An argparse ``type=``: a whole number in [low, high], else a message with the range."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {what} from {low} to {high}, not "
                                             f"{text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be {what} from {low} to {high}, not "
                                             f"{text!r}")
        return value

    parse.__name__ = "whole number"
    return parse


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def n_jobs(text: str) -> int:
    """An argparse ``type=`` for ``--n-jobs``: a positive count (capped at the cores, with a
    notice on stderr) or -1 for every core."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value == -1:
        return -1
    if value < 1:
        raise argparse.ArgumentTypeError(
            f"must be a positive number of workers (1 to the {available_cores()} cores) or -1 "
            f"for every core, not {text!r}")
    cores = available_cores()
    if value > cores:
        progress(f"sindyship: --n-jobs {value} is more than the {cores} cores; using {cores}.")
        return cores
    return value


def scheduler_address(text: str) -> str:
    """An argparse ``type=`` for ``--scheduler``: a ``tcp://host:port`` address."""
    from ..streaming import check_scheduler_address

    try:
        return check_scheduler_address(text)
    except SindyshipInputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removesuffix(".")) from None


SEED = bounded_int(0, 2**63 - 1, "a whole number")


def memory_short(need: float) -> float | None:
    """The machine's memory [bytes] when ``need`` bytes would take more than half of it, else
    None (also where the memory cannot be read)."""
    have = physical_memory()
    return have if have and need > 0.5 * have else None


def check_memory(samples: float, what: str) -> None:
    """Refuse work that would hold more samples than half the machine's memory allows."""
    need = samples * BYTES_PER_SAMPLE
    have = memory_short(need)
    if have is not None:
        raise SindyshipInputError(
            f"{what} would make {samples:.3g} samples, about {need / 1e9:.3g} GB, more than half "
            f"of this machine's {have / 1e9:.3g} GB; use a longer interval or a shorter record."
        )


def progress(message: str) -> None:
    """Progress and notices go to stderr, so ``--json`` keeps stdout to one document."""
    print(message, file=sys.stderr, flush=True)


def json_document(document: dict) -> str:
    """The text of a JSON document as ``--json`` prints it (and a verb's folder keeps it)."""
    return json.dumps(clean_json(document), indent=2) + "\n"


def emit(document: dict) -> None:
    """Write one JSON document on stdout."""
    sys.stdout.write(json_document(document))


def split_names(text: str) -> list[str]:
    """Comma-separated names, blanks dropped.

    Raises
    ------
    SindyshipInputError
        When a name is given twice.
    """
    names = [name.strip() for name in text.split(",") if name.strip()]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise SindyshipInputError(
            f"{twice[0]!r} is given twice in {text!r}; name each effect once."
        )
    return names


#: The ship records are taken to belong to when a verb that reads them is given no ``--ship``.
RECORDS_SHIP = "kcs"


def add_ship(p, *, default: str | None = "kcs", records: bool = False) -> None:
    """``--ship``: a built-in ship or a TOML file (for a verb reading ``records``: default
    :data:`RECORDS_SHIP`, named in a note when it is taken, see :func:`load_cli_ship`)."""
    if records:
        p.add_argument("--ship", default=None, metavar="NAME|FILE",
                       help="the records' ship: built-in kcs (full scale, L = 230 m) or kvlcc2 "
                       f"(the 7 m model), or a TOML file (default: {RECORDS_SHIP}, with a note)")
    elif default is None:
        p.add_argument("--ship", default=None, metavar="NAME|FILE",
                       help="ship particulars: built-in kcs (full scale, L = 230 m) or kvlcc2 "
                       "(the 7 m model), or a TOML file (default: the ship the model names)")
    else:
        p.add_argument("--ship", default=default, metavar="NAME|FILE",
                       help="ship particulars: built-in kcs (full scale, L = 230 m) or kvlcc2 "
                       f"(the 7 m model), or a TOML file (default: {default})")


def add_json(p) -> None:
    p.add_argument("--json", action="store_true",
                   help="print one JSON document on stdout and nothing else (default: text)")


def add_resample(p) -> None:
    p.add_argument("--resample", type=bounded_float(MIN_STEP, MAX_STEP, "seconds",
                                                    low_open=False),
                   default=None, metavar="SECONDS",
                   help=f"resample irregularly sampled records onto this interval [s], "
                   f"{MIN_STEP:g} to {MAX_STEP:g}; work that would need more than half the "
                   "machine's memory is refused (default: refuse irregular records)")


def add_identification(p, *, optimizer: bool = True, recommended: bool = False) -> None:
    """The options that say how a library is fitted: library, effects, optimizer, speed form,
    rudder, derivative (shared by ``fit``, ``diagnose`` and, without the optimizer,
    ``discover``).  With ``recommended`` (``fit``) the optimizer is the physics-consistent
    ``prior`` by default, on the recommended library of the speed form
    (:func:`sindyship.identify.recommended_library`)."""
    from ..identify import RECOMMENDED_LIBRARIES

    if recommended:
        design, instantaneous = (RECOMMENDED_LIBRARIES[form]
                                 for form in ("design", "instantaneous"))
        p.add_argument("--library", default=None, metavar="NAME|FILE",
                       help=f"term library name or TOML file (default with --optimizer "
                       f"prior: {design}, or {instantaneous}, which adds "
                       "cross-flow drag, when the speed form (--speed, else the ship's "
                       f"speed_reference) is instantaneous; the paper's {PAPER_LIBRARY} "
                       "with the other optimizers)")
    else:
        p.add_argument("--library", default=PAPER_LIBRARY, metavar="NAME|FILE",
                       help=f"term library name or TOML file (default: {PAPER_LIBRARY})")
    p.add_argument("--effects", default="", metavar="NAME,...",
                   help="comma-separated catalogue effects (or effect TOML files) whose terms "
                   "are added to the library (default: none)")
    if optimizer:
        default = "prior" if recommended else "ls"
        what = ("prior, least squares drawn toward the ship's semi-empirical derivatives, the "
                "recommended fit; ls is the paper's least squares" if recommended else
                "ls, least squares")
        p.add_argument("--optimizer", default=default, choices=OPTIMIZER_NAMES,
                       help=f"regression method (default: {what})")
    p.add_argument("--speed", default="auto", choices=["auto", "design", "instantaneous"],
                   help="the speed the forces and variables are made non-dimensional with: the "
                   "design speed U0 (the paper's Prime I), or the instantaneous speed U = "
                   "sqrt(u^2 + v^2), valid as a ship slows in a turn (default: auto, the "
                   "ship's speed_reference: design for kcs, instantaneous for kvlcc2)")
    p.add_argument("--rudder-signal", default="actual", choices=["actual", "commanded"],
                   help="rudder angle used in the features: the actual (servo) angle or the "
                   "commanded one (default: actual, as the paper's protocol)")
    p.add_argument("--derivative", default="five-point", choices=["five-point", "savgol"],
                   help="acceleration estimate: 5-point finite differences or a "
                   "Savitzky-Golay derivative over --window (default: five-point)")
    p.add_argument("--window", type=bounded_float(0, MAX_STEP, "seconds"), default=21.0,
                   metavar="SECONDS",
                   help=f"Savitzky-Golay window [s], in (0, {MAX_STEP:g}] (with --derivative "
                   "savgol; default 21)")


def resolved_library(args, speed: str = "design") -> str:
    """The library ``--library`` names, or its default for the optimizer and the speed form
    (:func:`sindyship.identify.recommended_library` for ``prior``)."""
    if args.library is not None:
        return args.library
    if getattr(args, "optimizer", "ls") == "prior":
        from ..identify import recommended_library

        return recommended_library(speed)
    return PAPER_LIBRARY


def speed_form(args, ship) -> str:
    """The speed form ``--speed`` asks for (``auto``: the ship's ``speed_reference``)."""
    return ship.speed_reference if args.speed == "auto" else args.speed


def add_n_jobs(p, *, default: int | None = 1) -> None:
    p.add_argument("--n-jobs", type=n_jobs, default=default, metavar="N",
                   help="parallel workers (joblib): 1 to the number of cores (more is capped "
                   f"at the cores, with a notice), or -1 for every core (default {default})")


def add_scheduler(p, *, work: str) -> None:
    """``--scheduler``: run a verb's parallel work on a Dask cluster (:func:`on_cluster`)."""
    p.add_argument("--scheduler", type=scheduler_address, default=None, metavar="ADDRESS",
                   help=f"run {work} on every worker of the Dask cluster of this scheduler "
                   "(tcp://host:8786) through joblib's dask backend (--n-jobs is then not "
                   "used); the records are read in this process (default: this machine)")


@contextlib.contextmanager
def on_cluster(scheduler: str | None, n_jobs: int | None):
    """The block's joblib work on the Dask cluster of ``scheduler`` (None: on this machine).

    Yields the ``n_jobs`` to pass on: ``n_jobs`` itself without a scheduler; with one, -1
    (every worker: ``--n-jobs`` counts this machine's cores, so it is not used there).
    """
    if scheduler is None:
        yield n_jobs
        return
    import joblib

    from ..streaming import connect

    if n_jobs not in (None, 1):
        progress("--n-jobs counts this machine's cores; with --scheduler every worker of the "
                 "cluster is used.")
    with connect(scheduler) as client:
        workers = len(client.scheduler_info().get("workers", {}))
        progress(f"running on the Dask cluster at {scheduler} ({workers} workers)")
        with joblib.parallel_config(backend="dask"):
            yield -1


#: What every output option's help says of the output policy (:func:`sindyship._io.check_output`).
OUT_NOTE = ("missing folders are created; a link, device, pipe, socket or one of the inputs is "
            "refused")


def check_inputs(paths) -> None:
    """Refuse an input that is a FIFO, a device or a socket before anything reads it: reading
    a pipe with no writer waits for ever, and ``/dev/zero`` never ends."""
    import stat

    for path in paths:
        if not path:
            continue
        try:
            mode = os.stat(path).st_mode
        except (OSError, ValueError):
            continue  # missing: the reader names it
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
            kind = ("a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a socket"
                    if stat.S_ISSOCK(mode) else "a device")
            raise SindyshipInputError(
                f"{path}: is {kind}, not a file; save the data to a regular file and give "
                "its path."
            )


def load_cli_ship(name, *, simulated: bool = False):
    """The ship ``--ship`` names (:func:`sindyship.ships.load_ship`), with each value it assumes
    (a ship file made for identification leaves out the servo or added masses) named on
    stderr; for a verb that ``simulated`` it with the MMG model, a ship without one is returned
    without them (the verb refuses it in one line).  None (a verb reading records, given no
    ``--ship``) is :data:`RECORDS_SHIP` (:func:`note_records_ship` says so)."""
    from ..ships import load_ship

    ship = load_ship(RECORDS_SHIP if name is None else name)
    if simulated and not ship.has_mmg:
        return ship
    for assumption in ship.assumptions:
        progress(f"note: ship {ship.name!r} assumes {assumption}.")
    return ship


#: Speeds, as a share of the ship's U0, beyond which a record may be of another ship or speed:
#: ``evaluate`` notes a flight that starts outside them, ``fit``, ``diagnose`` and ``discover``
#: records none of which reaches the lower one.
SPEED_NOTE_RANGE = (0.7, 1.3)
def note_records_ship(args, ship, records=None, *, sampling: bool = True,
                      streamed=None) -> None:
    """Say that records given no ``--ship`` are taken as :data:`RECORDS_SHIP`'s, and when
    none of the ``records`` reaches the lower end of :data:`SPEED_NOTE_RANGE` times the ship's
    design speed U0:
    another ship's records, or a U0 in another unit, made non-dimensional with the wrong
    length and speed fit without an error and fly wrong.  With ``sampling``, say when the
    records are sampled too coarsely for the ship's time scale
    (:func:`sindyship.targets.under_resolved`).  A streamed fit, which never holds the
    records, gives its reduction as ``streamed`` instead (its ``names``, ``fastest`` and
    ``steps``).  Called when the verb has done its work, so that an error stays one line."""
    if args.ship is None:
        progress(f"note: no --ship given: the records are taken as the {ship.name.upper()}'s "
                 f"(L = {ship.L:g} m, U0 = {ship.U0:.4g} m/s); give --ship with the records' "
                 "own ship (a built-in name or a ship TOML file) if they are another's.")
    from ..targets import sampling_steps, under_resolved

    if streamed is not None:
        fastest = max(streamed.fastest, default=None)
        steps = dict(zip(streamed.names, streamed.steps, strict=True))
    elif records:
        fastest = max(record.fastest for record in records)
        steps = sampling_steps(records, ship)
    else:
        return
    if fastest is not None and fastest < SPEED_NOTE_RANGE[0] * ship.U0:
        progress(f"note: no record reaches more than {fastest / ship.U0:.2f} times the "
                 f"design speed U0 = {ship.U0:.4g} m/s of ship {ship.name}; the model is "
                 "made non-dimensional with U0: check the ship and its U0 (in m/s).")
    coarse = under_resolved(steps, ship) if sampling else None
    if coarse:
        progress(f"note: {coarse}.")


def ship_file(name: str | None) -> list[str]:
    """The ship file among a verb's inputs (none for a built-in ship)."""
    from ..ships import BUILTIN_SHIPS

    return [] if name is None or name in BUILTIN_SHIPS else [name]


def check_simulation_cost(ship, duration: float, dt: float | None = None) -> None:
    """Refuse a simulation that would take too many samples, too much memory or too many
    Runge-Kutta steps, before any of it is allocated."""
    from ..simulation import default_step

    if dt is not None:
        samples = duration / dt
        if samples > MAX_SAMPLES:
            raise SindyshipInputError(
                f"--duration {duration:g} s at --dt {dt:g} s makes {samples:.3g} samples, more "
                f"than the {MAX_SAMPLES:.0e} a record may hold; use a longer --dt or a shorter "
                "--duration."
            )
        check_memory(samples, f"--duration {duration:g} s at --dt {dt:g} s")
    step = default_step(ship)
    steps = duration / step
    if steps > MAX_RK_STEPS:
        raise SindyshipInputError(
            f"{ship.name}'s integration step is {step:.3g} s (0.1 L/U0, at most T_R/4), so "
            f"{duration:g} s of flight needs {steps:.3g} steps, more than {MAX_RK_STEPS:.0e}; "
            f"shorten the record to at most {MAX_RK_STEPS * step:.3g} s or check the ship's "
            "L, U0 and [servo] T_R."
        )


def add_record_options(p) -> None:
    """``--skip-check`` and ``--time-range``: how records are read."""
    from ..plausibility import CHECKS

    p.add_argument("--skip-check", action="append", default=[], metavar="NAME",
                   choices=[*CHECKS, "all"],
                   help="plausibility check not to run on the records, repeatable: "
                   f"{', '.join(CHECKS)} or all (default: run every check)")
    p.add_argument("--time-range", default="auto", metavar="auto|all|START:STOP",
                   help="the part of each record to use [s]: 'auto' keeps the part under way "
                   "with the propeller running (never from rest), 'all' every sample, "
                   "START:STOP the samples between two times (default: auto)")


def smoothing_option(text: str) -> str:
    """``--smoothing``: ``none``, ``auto`` or a setting :class:`SmoothingSetting` reads
    (checked when the command line is read)."""
    if text in ("none", "auto"):
        return text
    from ..errors import SindyshipInputError
    from ..smoothing import SmoothingSetting

    try:
        SmoothingSetting.parse(text)
    except SindyshipInputError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


def add_training_options(p, *, n_jobs_default: int | None = 1, optimizer: bool = True,
                         workers: bool = True, recommended: bool = False) -> None:
    """What every verb that fits a library on records takes (``fit``, ``diagnose``,
    ``discover``): the records, the ship, how the library is fitted, smoothing, resampling,
    workers, JSON."""
    p.add_argument("data", nargs="+",
                   help="training records: measurement CSV or Parquet files, or quoted glob "
                   "patterns that name them ('fleet/*.parquet')")
    add_ship(p, records=True)
    add_identification(p, optimizer=optimizer, recommended=recommended)
    p.add_argument("--smoothing", default="none", metavar="none|savgol:W|rts:W|auto",
                   type=smoothing_option,
                   help="smooth noisy training records before differencing: a Savitzky-Golay "
                   "or a Kalman (RTS) smoother over W seconds, or 'auto' to choose the setting "
                   "by leave-one-manoeuvre-out flights on the training records (its windows "
                   "scale with the ship's L/U0) (default: none)")
    add_resample(p)
    add_record_options(p)
    if workers:
        add_n_jobs(p, default=n_jobs_default)
    add_json(p)


def resolve_cli_rudder_signal(args, with_delta) -> None:
    """``args.rudder_signal`` as the fit will use it, with a note on stderr when the records
    (``with_delta``: each one's name and whether it has ``delta``) have no actual rudder angle
    (:func:`sindyship.identify.fitted_rudder_signal`)."""
    from ..identify import fitted_rudder_signal

    args.rudder_signal, note = fitted_rudder_signal(with_delta, args.rudder_signal)
    if note is not None:
        progress(f"note: {note}.")


def report_prior_coverage(ship, library) -> None:
    """A note on stderr when the library has no term for some of the prior's estimates
    (:func:`sindyship.priors.coverage_note`)."""
    from ..priors import coverage_note

    note = coverage_note(ship, library)
    if note is not None:
        progress(f"note: {note}")

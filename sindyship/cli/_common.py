"""What every verb of the command line shares: options, progress, JSON output."""

from __future__ import annotations

import json
import sys

from .._io import clean_json

#: Default term library of every verb that fits.
DEFAULT_LIBRARY = "abkowitz"


def progress(message: str) -> None:
    """Progress and notices go to stderr, so ``--json`` keeps stdout to one document."""
    print(message, file=sys.stderr, flush=True)


def emit(document: dict) -> None:
    """Write one JSON document on stdout."""
    sys.stdout.write(json.dumps(clean_json(document), indent=2) + "\n")


def split_names(text: str) -> list[str]:
    """Comma-separated names, blanks dropped."""
    return [name.strip() for name in text.split(",") if name.strip()]


def add_ship(p, *, default: str | None = "kcs") -> None:
    """``--ship``: a built-in ship or a TOML file."""
    if default is None:
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
    p.add_argument("--resample", type=float, default=None, metavar="SECONDS",
                   help="resample irregularly sampled records onto this interval [s] "
                   "(default: refuse irregular records)")


def add_identification(p) -> None:
    """The options that say how a library is fitted: library, effects, optimizer, rudder,
    derivative (shared by ``fit`` and ``diagnose``)."""
    from ..optimizers import OPTIMIZERS

    p.add_argument("--library", default=DEFAULT_LIBRARY, metavar="NAME|FILE",
                   help=f"term library name or TOML file (default: {DEFAULT_LIBRARY})")
    p.add_argument("--effects", default="", metavar="NAME,...",
                   help="comma-separated catalogue effects (or effect TOML files) whose terms "
                   "are added to the library (default: none)")
    p.add_argument("--optimizer", default="ls", choices=sorted(OPTIMIZERS),
                   help="regression method (default: ls, least squares)")
    p.add_argument("--rudder-signal", default="actual", choices=["actual", "commanded"],
                   help="rudder angle used in the features: the actual (servo) angle or the "
                   "commanded one (default: actual, as the paper's protocol)")
    p.add_argument("--derivative", default="five-point", choices=["five-point", "savgol"],
                   help="acceleration estimate: 5-point finite differences or a "
                   "Savitzky-Golay derivative over --window (default: five-point)")
    p.add_argument("--window", type=float, default=21.0, metavar="SECONDS",
                   help="Savitzky-Golay window [s] (with --derivative savgol; default 21)")


def add_n_jobs(p, *, default: int | None = 1) -> None:
    p.add_argument("--n-jobs", type=int, default=default, metavar="N",
                   help=f"parallel workers (joblib; -1: every core; default {default})")


def add_training_options(p, *, n_jobs_default: int | None) -> None:
    """What every verb that fits a library on records takes (``fit``, ``diagnose``): the
    records, the ship, how the library is fitted, smoothing, resampling, workers, JSON."""
    p.add_argument("data", nargs="+", help="training measurement CSV files")
    add_ship(p)
    add_identification(p)
    p.add_argument("--smoothing", default="none", metavar="none|savgol:W|rts:W|auto",
                   help="smooth noisy training records before differencing: a Savitzky-Golay "
                   "or a Kalman (RTS) smoother over W seconds, or 'auto' to choose the setting "
                   "by leave-one-manoeuvre-out flights on the training records (its windows "
                   "scale with the ship's L/U0) (default: none)")
    add_resample(p)
    from ._records import add_record_options

    add_record_options(p)
    add_n_jobs(p, default=n_jobs_default)
    add_json(p)

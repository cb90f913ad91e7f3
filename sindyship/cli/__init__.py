"""The ``sindyship`` command line: one module per verb, and the only place that parses
arguments or prints.

Exit status 0 on success, 2 on bad input (one line on stderr naming the file and the problem),
1 on anything else.  With ``--json`` exactly one JSON document goes to stdout and progress to
stderr.  Outputs are written to a temporary file and renamed (:mod:`sindyship._io`).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
import warnings

from .. import __version__
from ..errors import PriorCoverageNote, SindyshipInputError
from . import (
    captive,
    diagnose,
    discover,
    effects,
    evaluate,
    export,
    fit,
    forces,
    reproduce,
    simulate,
)

#: The verbs in the order ``sindyship --help`` lists them, each a module with
#: ``add_parser(subparsers)`` and ``run(args) -> int``.
VERBS = {
    "simulate": simulate,
    "fit": fit,
    "evaluate": evaluate,
    "reproduce": reproduce,
    "diagnose": diagnose,
    "discover": discover,
    "export": export,
    "effects": effects,
    "captive": captive,
    "forces": forces,
}

__all__ = ["VERBS", "build_parser", "main"]


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr (exit status 2), like every
    other bad input; ``--help`` shows the usage."""

    def error(self, message: str):
        message = " ".join(message.split())
        self.exit(2, f"{self.prog}: error: {message}{self._did_you_mean(message)} "
                     f"(see {self.prog} --help)\n")

    def _did_you_mean(self, message: str) -> str:
        """``"; did you mean X?"`` for an unknown option or choice close to one of this
        parser's (a misspelt ``--optimiser``, verb ``fitt``), else nothing."""
        import difflib
        import re

        if message.startswith("unrecognized arguments:"):
            known = [option for option in self._option_string_actions if option.startswith("--")]
            for word in message.split(":", 1)[1].split():
                close = difflib.get_close_matches(word.split("=")[0], known, n=1, cutoff=0.75) \
                    if word.startswith("--") else []
                if close:
                    return f"; did you mean {close[0]}?"
        # (a Python whose argparse suggests a choice itself says "maybe you meant" instead)
        found = re.search(r"invalid choice: '?([^'\s]+)'? \(choose from (.*)\)$", message)
        if found:
            choices = [choice.strip(" '") for choice in found.group(2).split(",")]
            close = difflib.get_close_matches(found.group(1), choices, n=1, cutoff=0.6)
            if close:
                return f"; did you mean {close[0]}?"
        return ""


def _terminate(signum, frame):
    """SIGTERM ends the run like Ctrl-C, so temporary files and folders are removed."""
    raise KeyboardInterrupt


def build_parser(verbs=None) -> argparse.ArgumentParser:
    """The command line's parser.

    Parameters
    ----------
    verbs : collection of str, optional
        The verbs whose options are built (default: every verb); the others are listed by
        their summary line only.  A verb's options import what its defaults and choices name,
        so ``main`` builds those of the verb it runs alone.
    """
    parser = OneLineParser(
        prog="sindyship",
        description="Discover a ship's manoeuvring equations (Abkowitz model) from trajectories.",
    )
    parser.add_argument("--version", action="version", version=f"sindyship {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", required=True)
    parser.verb_parsers = sub.choices  # a verb's own parser names its usage errors
    if isinstance(verbs, str):
        verbs = {verbs}
    for name, module in VERBS.items():
        if verbs is None or name in verbs:
            module.add_parser(sub)
        else:
            sub.add_parser(name, help=module.SUMMARY)
    return parser


def _verb_of(argv: list[str]) -> str | None:
    """The verb ``argv`` names: its first word that is not an option (the command's own
    options take no value)."""
    return next((word for word in argv if not word.startswith("-")), None)


def _tolerant_streams() -> None:
    """Output that cannot be written whole ends quietly: a stdout of another encoding escapes
    what it cannot show, and a closed stdout or stderr takes nothing (the verb's files are
    written all the same)."""
    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))  # noqa: SIM115
        elif hasattr(stream, "reconfigure"):
            with contextlib.suppress(ValueError, OSError):
                stream.reconfigure(errors="backslashreplace")


def main(argv: list[str] | None = None) -> int:
    """Run one verb; return its exit status.  A reader that goes away (``--json | head``)
    ends the output quietly, with the status the verb had."""
    _tolerant_streams()
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser({_verb_of(argv)})
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # named by the verb's own parser, as its other usage errors are
        parser.verb_parsers[args.verb].error(f"unrecognized arguments: {' '.join(unknown)}")
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        status = _run(args)
        sys.stdout.flush()
        return status
    except BrokenPipeError:
        _quiet_stdout()
        return 0
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _quiet_stdout() -> None:
    """After a reader went away: later writes (and the interpreter's final flush) go nowhere."""
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())


def _run(args) -> int:
    """Run the verb ``args`` name; turn bad input into status 2 and anything else into 1."""
    try:
        with warnings.catch_warnings():
            # fit and diagnose say it once, as a note, not once per fitted model
            warnings.simplefilter("ignore", PriorCoverageNote)
            return VERBS[args.verb].run(args)
    except SindyshipInputError as exc:
        message = " ".join(str(exc).split())
        print(f"sindyship {args.verb}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("sindyship: interrupted", file=sys.stderr)
        return 1
    except BrokenPipeError:
        raise  # the reader of stdout went away: main ends quietly
    except Exception as exc:  # a bug or an environment failure: status 1, never status 2
        print(f"sindyship {args.verb}: internal error: {type(exc).__name__}: {exc} "
              "(please report it with the command you ran)", file=sys.stderr)
        return 1

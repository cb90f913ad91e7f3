"""The ``sindyship`` command line: one module per verb, and the only place that parses
arguments or prints.

Exit status 0 on success, 2 on bad input (one line on stderr naming the file and the problem),
1 on anything else.  With ``--json`` exactly one JSON document goes to stdout and progress to
stderr.  Outputs are written to a temporary file and renamed (:mod:`sindyship._io`).
"""

from __future__ import annotations

import argparse
import sys

from .. import __version__
from ..errors import SindyshipInputError
from . import captive, diagnose, effects, evaluate, export, fit, forces, reproduce, simulate

#: The verbs in the order ``sindyship --help`` lists them, each a module with
#: ``add_parser(subparsers)`` and ``run(args) -> int``.
VERBS = {
    "simulate": simulate,
    "fit": fit,
    "evaluate": evaluate,
    "reproduce": reproduce,
    "diagnose": diagnose,
    "export": export,
    "effects": effects,
    "captive": captive,
    "forces": forces,
}

__all__ = ["VERBS", "build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The parser of every verb."""
    parser = argparse.ArgumentParser(
        prog="sindyship",
        description="Discover a ship's manoeuvring equations (Abkowitz model) from trajectories.",
    )
    parser.add_argument("--version", action="version", version=f"sindyship {__version__}")
    sub = parser.add_subparsers(dest="verb", metavar="VERB", required=True)
    for module in VERBS.values():
        module.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one verb; return its exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return VERBS[args.verb].run(args)
    except SindyshipInputError as exc:
        message = " ".join(str(exc).split())
        print(f"sindyship {args.verb}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("sindyship: interrupted", file=sys.stderr)
        return 1
    except Exception as exc:  # a bug or an environment failure: status 1, never status 2
        print(f"sindyship {args.verb}: internal error: {type(exc).__name__}: {exc} "
              "(please report it with the command you ran)", file=sys.stderr)
        return 1

"""``sindyship export``: a saved model's equations as text or LaTeX, or a standalone simulator."""

from __future__ import annotations


def add_parser(sub) -> None:
    from ..export import add_export_parser

    add_export_parser(sub)


def run(args) -> int:
    from ..export import cmd_export

    return cmd_export(args)

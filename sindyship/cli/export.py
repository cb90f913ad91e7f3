"""``sindyship export``: a saved model's equations as text or LaTeX, or a standalone simulator."""

from __future__ import annotations

from ._common import OUT_NOTE, bounded_int, check_inputs, ship_file

#: Significant digits a double carries.
MAX_PRECISION = 17


def add_parser(sub) -> None:
    from ..export import add_export_parser

    p = add_export_parser(sub)
    for action in p._actions:  # bounds and output policy of the shared command line
        if action.dest == "precision":
            action.type = bounded_int(1, MAX_PRECISION)
            action.help = (f"significant digits of printed numbers, 1 to {MAX_PRECISION} "
                           f"(default {action.default})")
        elif action.dest in ("latex", "python"):
            action.help = f"{action.help} ({OUT_NOTE})"


def run(args) -> int:
    from .._io import check_output
    from ..export import cmd_export

    inputs = [args.model, *ship_file(args.ship)]
    for option in ("latex", "python"):
        target = getattr(args, option)
        if target is not None:
            check_output(target, inputs=inputs, label=f"--{option} {target}")
    check_inputs(inputs)
    return cmd_export(args)

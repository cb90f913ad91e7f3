"""``sindyship effects``: the catalogue of candidate physical effects, with their physics."""

from __future__ import annotations

import textwrap

from ._common import add_json, emit

#: The verb's line in ``sindyship --help``.
SUMMARY = "list the catalogue of physical effects and their physics"


def add_parser(sub) -> None:
    p = sub.add_parser("effects", help=SUMMARY,
                       description="List the catalogued effects the diagnosis scores "
                       "(libraries/effects/*.toml): name, title, the channels each needs beyond "
                       "u, v, r and delta, its terms and what it means physically.")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="effects to show (default: the whole catalogue)")
    add_json(p)


def run(args) -> int:
    from ..library import DOFS, available_effects, load_effect

    effects = [load_effect(name) for name in (args.names or available_effects())]
    if args.json:
        emit({"effects": [{"name": e.name, "title": e.title, "channels": list(e.channels),
                           "terms": {dof: [t.text for t in e.terms[dof]] for dof in DOFS},
                           "physics": e.physics} for e in effects]})
        return 0
    for effect in effects:
        needs = ", ".join(effect.channels) or "nothing beyond u, v, r and delta"
        print(f"{effect.name}: {effect.title} (needs {needs})")
        print(textwrap.fill(effect.physics, width=96, initial_indent="  ",
                            subsequent_indent="  "))
        print()
    return 0

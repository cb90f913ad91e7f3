"""The reference pages in docs/ stay true to the code.

Every verb and option the command-line parser knows is in docs/command-line.md, every
catalogued effect in docs/effects.md, every field of the built-in ship files in
docs/ship-toml.md; and every command-line option has help text.
"""

from __future__ import annotations

import argparse
import re
import tomllib
from pathlib import Path

import pytest

import sindyship
from sindyship.cli import build_parser

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
EFFECT_FILES = sorted((REPO / "libraries" / "effects").glob("*.toml"))
SHIP_FILES = sorted((Path(sindyship.__file__).parent / "ships").glob("*.toml"))


def verbs() -> dict[str, argparse.ArgumentParser]:
    """The sub-command parsers of ``sindyship``, by verb."""
    parser = build_parser()
    (action,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(action.choices)


def arguments(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """A parser's arguments, without -h/--help and the sub-command action."""
    return [
        a for a in parser._actions
        if not isinstance(a, argparse._HelpAction | argparse._SubParsersAction)
    ]


def spellings(action: argparse.Action) -> list[str]:
    """How an argument is written: its long options, or the name of a positional argument."""
    if not action.option_strings:
        return [action.dest]
    return [s for s in action.option_strings if s.startswith("--")] or action.option_strings


def in_backticks(name: str, text: str) -> bool:
    return f"`{name}`" in text


def test_the_index_links_every_page():
    index = (DOCS / "README.md").read_text()
    pages = sorted(p.name for p in DOCS.glob("*.md") if p.name != "README.md")
    assert {"command-line.md", "effects.md", "measurement-csv.md", "saved-models.md",
            "ship-toml.md", "term-grammar.md", "captive-csv.md"} <= set(pages)
    assert [p for p in pages if f"]({p})" not in index] == []


def test_every_verb_and_option_is_documented():
    page = (DOCS / "command-line.md").read_text()
    missing = []
    for action in arguments(build_parser()):
        missing += [s for s in spellings(action) if not in_backticks(s, page)]
    found = verbs()
    assert set(found) >= {"simulate", "fit", "evaluate", "reproduce", "diagnose", "export"}
    for verb, parser in found.items():
        if not re.search(rf"^## `{verb}`$", page, re.MULTILINE):
            missing.append(f"section ## `{verb}`")
            continue
        section = page.split(f"## `{verb}`", 1)[1].split("\n## ", 1)[0]
        for action in arguments(parser):
            missing += [f"{verb} {s}" for s in spellings(action) if not in_backticks(s, section)]
    assert missing == [], f"not in docs/command-line.md: {missing}"


def test_every_catalogued_effect_is_documented():
    page = (DOCS / "effects.md").read_text()
    names = [tomllib.loads(f.read_text())["name"] for f in EFFECT_FILES]
    assert len(names) >= 6
    assert [n for n in names if not in_backticks(n, page)] == []


def test_every_simulated_effect_is_documented():
    from dataclasses import fields

    from sindyship.effects import Effects

    page = (DOCS / "effects.md").read_text()
    names = [f.name for f in fields(Effects)]
    assert [n for n in names if f"| `{n}` |" not in page] == []


def ship_fields(data: dict) -> list[str]:
    """Every key of a ship file: top-level keys, sections as ``[name]`` and their keys."""
    out = []
    for key, value in data.items():
        if isinstance(value, dict):
            out.append(f"[{key}]")
            out += ship_fields(value)
        else:
            out.append(key)
    return out


@pytest.mark.parametrize("path", SHIP_FILES, ids=[p.stem for p in SHIP_FILES])
def test_every_field_of_the_built_in_ships_is_documented(path):
    page = (DOCS / "ship-toml.md").read_text()
    fields = ship_fields(tomllib.loads(path.read_text()))
    assert len(fields) > 40
    assert [f for f in fields if not in_backticks(f, page)] == []
    assert in_backticks(path.stem, page)


def options_without_help() -> list[str]:
    """``verb --option`` for every argument of the parser that has no help text."""
    offenders = [
        f"sindyship {spellings(a)[0]}" for a in arguments(build_parser()) if not a.help
    ]
    for verb, parser in verbs().items():
        offenders += [f"{verb} {spellings(a)[0]}" for a in arguments(parser) if not a.help]
    return offenders


def test_every_option_has_help_text():
    offenders = options_without_help()
    assert offenders == [], f"options without help text: {', '.join(offenders)}"


def test_the_term_library_file_layout_loads_as_documented(tmp_path):
    """docs/term-grammar.md's layout of a library file, its lists filled in, loads with every
    key it shows (a key written after [terms] would belong to that table)."""
    from sindyship.identify import resolve_library

    page = (DOCS / "term-grammar.md").read_text()
    block = page.split("## Term-library files", 1)[1].split("```toml\n", 1)[1].split("```")[0]
    text = (block.replace(', ...]', ']').replace('[...]', '["v", "r", "delta"]')
            .replace('"""..."""', '"""A library as the docs lay it out."""'))
    path = tmp_path / "documented.toml"
    path.write_text(text)
    library = resolve_library(str(path))
    assert library.name == "abkowitz" and library.speed == "design"
    assert library.delays == {"delta": 4.0}
    assert [t.text for t in library.terms["X"]] == ["1", "du", "du^2", "v^2"]

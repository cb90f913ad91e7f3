"""Tests of the term parser and the Term object (sindyship.terms)."""

from __future__ import annotations

import csv
import tomllib
from pathlib import Path

import numpy as np
import pytest
import sympy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import sindyship
from sindyship.errors import SindyshipInputError
from sindyship.terms import (
    CORE_VARIABLES,
    FUNCTIONS,
    MAX_DEGREE,
    MAX_FACTORS,
    MAX_TERM_LENGTH,
    Factor,
    Term,
    parse_term,
)

REPO = Path(__file__).resolve().parents[1]
#: The paper's Tables 7-9 as shipped with the package (sindyship.paper reads the same file).
PAPER_TABLE = Path(sindyship.__file__).parent / "data" / "paper-tables-7-9.csv"
LIBRARY_FILES = [REPO / "libraries" / f"{name}.toml"
                 for name in ("abkowitz", "abkowitz-noconst", "abkowitz-vr")]


def _library_terms() -> list[str]:
    texts = []
    for path in LIBRARY_FILES:
        for terms in tomllib.loads(path.read_text())["terms"].values():
            texts += terms
    return sorted(set(texts))


EXTRA_TERMS = [
    "abs(v) v",
    "abs(r) r",
    "sign(v) v^2",
    "sin(psi)",
    "cos(psi) v",
    "wind_speed^2 cos(wind_dir)",
    "n^2 v",
    "0.5 v r",
    "2^3 delta",
    "v v r",
    "r v^2",
    "depth_m v",
]


def _values(variables, n: int = 11, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {name: rng.uniform(-1.5, 1.5, size=n) for name in sorted(variables)}


# ------------------------------------------------------------------------ valid terms
@pytest.mark.parametrize("text", _library_terms() + EXTRA_TERMS)
def test_valid_terms_parse_and_keep_their_text(text):
    term = parse_term(text)
    assert term.text == text == str(term)
    assert all(isinstance(f, Factor) and 1 <= f.power <= 9 for f in term.factors)
    assert term.identifier("Y").isidentifier()


def test_factors_are_machine_readable():
    assert Term("1").factors == ()
    assert Term("v^2 r").factors == ((None, "v", 2), (None, "r", 1))
    assert Term("abs(v) v").factors == (("abs", "v", 1), (None, "v", 1))
    assert Term("0.5 delta^3").factors == ((None, 0.5, 1), (None, "delta", 3))
    assert Term("du v delta").variables == {"du", "v", "delta"}
    assert Term("1").variables == frozenset()


@pytest.mark.parametrize(
    ("text", "subscript", "identifier", "latex", "latex_term"),
    [
        ("1", "0", "X_0", "X'_{0}", "1"),
        ("du", "u", "X_u", "X'_{u}", r"\Delta u'"),
        ("du^2", "uu", "X_uu", "X'_{uu}", r"\Delta u'^{2}"),
        ("v^2 r", "vvr", "X_vvr", "X'_{vvr}", "v'^{2} r'"),
        ("du v", "uv", "X_uv", "X'_{uv}", r"\Delta u' v'"),
        ("delta", "d", "X_d", r"X'_{\delta}", r"\delta"),
        ("delta^2 v", "ddv", "X_ddv", r"X'_{\delta\delta v}", r"\delta^{2} v'"),
        ("v r delta", "vrd", "X_vrd", r"X'_{vr\delta}", r"v' r' \delta"),
        ("abs(v) v", "|v|v", "X_absv_v", "X'_{|v|v}", "|v'| v'"),
        ("psi^2 v", "psi^2 v", "X_psi2_v", r"X'_{\psi\psi v}", r"\psi^{2} v'"),
        ("sin(psi)", "sin(psi)", "X_sinpsi", r"X'_{\sin(\psi)}", r"\sin(\psi)"),
    ],
)
def test_names_come_from_the_text(text, subscript, identifier, latex, latex_term):
    term = Term(text)
    assert term.subscript == subscript
    assert term.identifier("X") == identifier
    assert term.latex("X") == latex
    assert term.latex_term() == latex_term


# The coefficient names of the paper's Tables 7-9 (eq. 18), constant as 0 and delta as d.
PAPER_NAMES = {
    "X": "0 u uu vv rr dd vd rd uuu vvu rru ddu uvr uvd urd vrd",
    "Y": "0 u v r d uu uv ur ud vvv rrr ddd uuv uur uud vvr vvd rrv rrd ddv ddr vrd",
    "N": "0 u v r d uu uv ur ud vvv rrr ddd uuv uur uud vvr vvd rrv rrd ddv ddr vrd",
}


@pytest.mark.parametrize("dof", ["X", "Y", "N"])
def test_identifiers_read_as_the_paper_tables(dof):
    texts = tomllib.loads(LIBRARY_FILES[0].read_text())["terms"][dof]
    expected = [f"{dof}_{name}" for name in PAPER_NAMES[dof].split()]
    assert [Term(text).identifier(dof) for text in texts] == expected


def test_paper_table_uses_the_same_names():
    with PAPER_TABLE.open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 16 + 22 + 22
    for row in rows:
        name = Term(row["term"]).identifier(row["equation"])
        assert name == row["paper_name"].replace("'", ""), row


def test_identifiers_are_unique_within_a_dof():
    texts = _library_terms() + EXTRA_TERMS
    canon = {}
    for text in texts:
        canon.setdefault(Term(text).canonical(scale=False), Term(text).identifier("N"))
    assert len(set(canon.values())) == len(canon)


def test_identifier_rejects_a_bad_dof():
    with pytest.raises(ValueError, match="degree of freedom"):
        Term("v").identifier("x y")


# ------------------------------------------------------------------------ canonical form
def test_equivalent_spellings_are_different_keys_with_one_canonical_form():
    spellings = [Term("v^2 r"), Term("r v^2"), Term("v v r"), Term("r v v")]
    assert len({t.text for t in spellings}) == 4
    assert len(set(spellings)) == 4
    assert {t.canonical() for t in spellings} == {"v^2 r"}
    assert Term("v r^2").canonical() != Term("v^2 r").canonical()


def test_canonical_orders_variables_as_the_paper_and_merges_numbers():
    assert Term("delta r v du").canonical() == "du v r delta"
    assert Term("psi v").canonical() == "v psi"
    assert Term("abs(v) v").canonical() == "v abs(v)"
    assert Term("2 v 0.5").canonical() == "v"
    assert Term("3 v").canonical() == "3 v"
    assert Term("3 v").canonical(scale=False) == "v"
    assert Term("2").canonical(scale=False) == "1"


# ------------------------------------------------------------------------ numbers
@pytest.mark.parametrize("text", _library_terms() + EXTRA_TERMS)
def test_evaluate_agrees_with_sympy_lambdify(text):
    term = Term(text)
    values = _values(term.variables)
    names = sorted(term.variables)
    function = sympy.lambdify([sympy.Symbol(n, real=True) for n in names], term.sympy(), "numpy")
    expected = np.broadcast_to(function(*(values[n] for n in names)), (11,))
    np.testing.assert_allclose(term.evaluate(values), expected, rtol=1e-13, atol=0)


def test_sympy_uses_real_symbols_named_as_the_variables():
    expr = Term("abs(v) sign(r) du^2").sympy()
    assert {s.name for s in expr.free_symbols} == {"v", "r", "du"}
    assert all(s.is_real for s in expr.free_symbols)
    assert expr.has(sympy.Abs) and expr.has(sympy.sign)
    assert Term("1").sympy() == 1
    assert Term("0.5 v").sympy() == sympy.Rational(1, 2) * sympy.Symbol("v", real=True)


def test_evaluate_constant_gives_ones_of_the_data_length():
    np.testing.assert_array_equal(Term("1").evaluate({"v": np.zeros(4)}), np.ones(4))
    np.testing.assert_array_equal(Term("2").evaluate({"v": np.zeros(3)}), np.full(3, 2.0))


def test_evaluate_names_a_missing_variable():
    with pytest.raises(SindyshipInputError, match='"psi"'):
        Term("sin(psi) v").evaluate({"v": np.zeros(3)})


# ------------------------------------------------------------------------ invalid terms
INVALID = [
    "v^^2",
    "exp(v)",
    "__import__('os')",
    "__import__('os').system('touch SENTINEL')",
    "v^10",
    "v^0",
    "abs(2)",
    "abs v",
    "foo(v)",
    "",
    " ",
    "v r)",
    "v r junk!",
    "v  r",
    " v",
    "v ",
    "v\tr",
    "v*r",
    "-v",
    "2v",
    "1e5",
    "1.",
    "0 v",
    "V",
    "u",
    "v__x",
    "abs(v",
    "sin()",
    "v²",
    "lambda: 0",
    "v^9 r",
    " ".join(["v"] * (MAX_FACTORS + 1)),
    "x" * (MAX_TERM_LENGTH + 1),
]


@pytest.mark.parametrize("text", INVALID)
def test_invalid_terms_name_file_line_and_term(text):
    with pytest.raises(SindyshipInputError) as raised:
        parse_term(text, source="libraries/mine.toml", line=12)
    message = str(raised.value)
    assert message.startswith("libraries/mine.toml, line 12: the term ")
    assert text[:50].replace("\t", "\\t") in message
    assert "\n" not in message and message.endswith(".")


def test_term_constructor_raises_the_same_error_without_location():
    with pytest.raises(SindyshipInputError, match=r'^the term "exp\(v\)" is not valid'):
        Term("exp(v)")


@pytest.mark.parametrize("value", [None, 3, 1.5, b"v", ["v"]])
def test_non_text_is_rejected(value):
    with pytest.raises(SindyshipInputError, match="a term is text"):
        parse_term(value, source="f.toml", line=1)


def test_limits_are_as_documented():
    assert Term(" ".join(["v"] * MAX_FACTORS)).degree == MAX_FACTORS
    assert Term("v^9").degree == MAX_DEGREE
    assert set(FUNCTIONS) == {"abs", "sin", "cos", "sign"}
    assert CORE_VARIABLES == ("du", "v", "r", "delta")


# ------------------------------------------------------------------------ properties
_GRAMMAR_ALPHABET = "abcdeglinoprstuvw_^() .0123456789"
_atoms = st.one_of(
    st.sampled_from(["du", "v", "r", "delta", "psi", "n", "wind_speed", "depth"]),
    st.builds(lambda f, v: f"{f}({v})", st.sampled_from(FUNCTIONS), st.sampled_from(["v", "psi"])),
    st.sampled_from(["2", "0.5", "9999999999", "1"]),
)
_factors = st.builds(lambda a, p: a + p, _atoms, st.sampled_from(["", "^2", "^3", "^9"]))
_grammar_terms = st.lists(_factors, min_size=1, max_size=MAX_FACTORS + 1).map(" ".join)
_texts = st.one_of(
    st.text(max_size=60),
    st.text(alphabet=_GRAMMAR_ALPHABET, max_size=40),
    _grammar_terms,
)


@settings(
    max_examples=400, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(_texts)
def test_any_text_parses_to_a_finite_term_or_raises_input_error(text):
    try:
        term = parse_term(text, source="fuzz.toml", line=1)
    except SindyshipInputError as error:
        assert str(error).startswith("fuzz.toml, line 1: the term ")
        return
    values = {name: np.linspace(-1e3, 1e3, 9) for name in term.variables}
    column = term.evaluate(values)
    assert np.all(np.isfinite(column))
    # the canonical form (without numbers) is itself a valid term, with the same canonical form
    again = parse_term(term.canonical(scale=False))
    assert again.canonical(scale=False) == term.canonical(scale=False)


@settings(max_examples=100, deadline=None, database=None)
@given(_grammar_terms)
def test_evaluate_matches_lambdify_for_generated_terms(text):
    try:
        term = Term(text)
    except SindyshipInputError:
        return
    values = _values(term.variables, n=7, seed=1)
    names = sorted(term.variables)
    function = sympy.lambdify([sympy.Symbol(n, real=True) for n in names], term.sympy(), "numpy")
    expected = np.broadcast_to(function(*(values[n] for n in names)), (7,)).astype(float)
    np.testing.assert_allclose(term.evaluate(values), expected, rtol=1e-10, atol=0)


def test_a_code_payload_is_never_run(tmp_path, monkeypatch):
    sentinel = tmp_path / "SENTINEL"
    monkeypatch.chdir(tmp_path)
    payloads = [
        "__import__('os').system('touch SENTINEL')",
        f"__import__('os').system('touch {sentinel}')",
        'exec(\'open("SENTINEL", "w")\')',
        "v ; __import__('os').system('touch SENTINEL')",
    ]
    for payload in payloads:
        with pytest.raises(SindyshipInputError):
            parse_term(payload)
    assert not sentinel.exists()

"""Tests of term libraries, effects, the library variables and the pysindy library."""

from __future__ import annotations

import importlib.resources
import io
import json
import textwrap
import tomllib
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pandas as pd
import pysindy as ps
import pytest
from pysindy.feature_library.base import ConcatLibrary
from sklearn.base import clone
from sklearn.linear_model import LinearRegression

import sindyship.library._files as library_module
from sindyship.errors import SindyshipInputError
from sindyship.library import (
    DOFS,
    AbkowitzFeatureLibrary,
    Effect,
    TermLibrary,
    available_effects,
    available_libraries,
    builtin_library_dir,
    feature_matrix,
    load_effect,
    load_library,
    nondimensional_variables,
)
from sindyship.terms import Term
from sindyship.trajectory import Trajectory

REPO = Path(__file__).resolve().parents[1]

# The regressors of the paper's eq. 17a-c, in order, in the library syntax.
PAPER_TERMS = {
    "X": [
        "1", "du", "du^2", "v^2", "r^2", "delta^2", "v delta", "r delta", "du^3", "v^2 du",
        "r^2 du", "delta^2 du", "du v r", "du v delta", "du r delta", "v r delta",
    ],
    "Y": [
        "1", "du", "v", "r", "delta", "du^2", "du v", "du r", "du delta", "v^3", "r^3",
        "delta^3", "du^2 v", "du^2 r", "du^2 delta", "v^2 r", "v^2 delta", "r^2 v",
        "r^2 delta", "delta^2 v", "delta^2 r", "v r delta",
    ],
}  # fmt: skip
PAPER_TERMS["N"] = PAPER_TERMS["Y"]


@pytest.fixture
def rng():
    return np.random.default_rng(20240611)


def _write(tmp_path: Path, text: str, name: str = "lib.toml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text).lstrip())
    return path


# ------------------------------------------------------------------------ built-in libraries
def test_abkowitz_has_the_paper_terms_in_order():
    library = load_library("abkowitz")
    assert library.name == "abkowitz"
    assert library.system == "prime-I"
    assert "eq. 15" in library.description and "eq. 17" in library.description
    assert {dof: len(terms) for dof, terms in library.terms.items()} == {"X": 16, "Y": 22, "N": 22}
    assert list(library.terms) == list(DOFS)
    for dof in DOFS:
        assert [t.text for t in library.terms[dof]] == PAPER_TERMS[dof]
    assert library.variables == {"du", "v", "r", "delta"}
    assert library.channels == frozenset()
    assert library.source == REPO / "libraries" / "abkowitz.toml"


def test_abkowitz_noconst_is_abkowitz_without_the_constants():
    library = load_library("abkowitz-noconst")
    assert {dof: len(terms) for dof, terms in library.terms.items()} == {"X": 15, "Y": 21, "N": 21}
    for dof in DOFS:
        assert [t.text for t in library.terms[dof]] == PAPER_TERMS[dof][1:]


def test_available_libraries_lists_the_builtins():
    assert {"abkowitz", "abkowitz-noconst"} <= set(available_libraries())
    assert all(isinstance(name, str) for name in available_effects())


def test_load_by_path(tmp_path):
    assert load_library(REPO / "libraries" / "abkowitz.toml") == load_library("abkowitz")
    assert load_library(str(REPO / "libraries" / "abkowitz.toml")).name == "abkowitz"


def test_unknown_builtin_names_the_choices():
    with pytest.raises(SindyshipInputError, match="abkowitz-noconst") as raised:
        load_library("abkowitz5")
    assert '"abkowitz5"' in str(raised.value)
    with pytest.raises(SindyshipInputError, match="no such library file"):
        load_library("missing/file.toml")


@pytest.mark.parametrize("name", available_effects())
def test_builtin_effects_load_and_extend_abkowitz(name):
    effect = load_effect(name)
    assert effect.name == name
    assert effect.title and effect.physics
    extended = load_library("abkowitz").extended(effect)
    assert extended.name == f"abkowitz+{name}"
    from sindyship.terms import sources_of

    assert {s for c in extended.channels for s in sources_of(c)} <= set(effect.channels)


# ------------------------------------------------------------------------ finding the files
def test_wheel_layout_is_preferred(tmp_path, monkeypatch):
    """After a wheel install the libraries are inside the package: sindyship/libraries."""
    package = tmp_path / "site-packages" / "sindyship"
    (package / "libraries" / "effects").mkdir(parents=True)
    text = (REPO / "libraries" / "abkowitz.toml").read_text()
    (package / "libraries" / "abkowitz.toml").write_text(text.replace("abkowitz", "wheel-copy"))
    real_files = importlib.resources.files

    def files(anchor):
        return package if anchor == "sindyship" else real_files(anchor)

    monkeypatch.setattr(library_module.importlib.resources, "files", files)
    assert builtin_library_dir() == package / "libraries"
    assert available_libraries() == ("abkowitz",)
    assert available_effects() == ()
    loaded = load_library("abkowitz")
    assert loaded.name.startswith("wheel-copy") and loaded.source.parent == package / "libraries"


def test_source_checkout_falls_back_to_the_repository_folder(tmp_path, monkeypatch):
    monkeypatch.setattr(library_module.importlib.resources, "files", lambda anchor: tmp_path)
    assert Path(str(builtin_library_dir())) == REPO / "libraries"


def test_wheel_carries_the_libraries_folder():
    """pyproject force-includes libraries/ as sindyship/libraries, where the finder looks."""
    config = tomllib.loads((REPO / "pyproject.toml").read_text())
    force = config["tool"]["hatch"]["build"]["targets"]["wheel"]["force-include"]
    assert force["libraries"] == "sindyship/libraries"


# ------------------------------------------------------------------------ validation
GOOD = """
    name = "toy"
    system = "prime-I"
    description = "A toy."
    [terms]
    X = ["du"]
    Y = ["v", "r"]
    N = ["r", "v"]
"""


def test_a_good_file_loads(tmp_path):
    library = load_library(_write(tmp_path, GOOD))
    assert [t.text for t in library.terms["Y"]] == ["v", "r"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (('system = "prime-I"', 'system = "prime-I"\ncolour = "red"'), 'unknown key "colour"'),
        (('name = "toy"', "name = 3"), '"name" must be a text string'),
        (('name = "toy"', 'name = "bad name!"'), 'the name "bad name!" is not valid'),
        (('system = "prime-I"', ""), 'the key "system" is missing'),
        (("[terms]\n", "[other]\n"), 'unknown key "other"'),
        (('Y = ["v", "r"]', 'Z = ["v"]'), 'unknown degree of freedom "Z"'),
        (('Y = ["v", "r"]', ""), "gives no Y terms"),
        (('Y = ["v", "r"]', "Y = []"), "the list of Y terms is empty"),
        (('Y = ["v", "r"]', 'Y = "v"'), "Y must be a list of term strings"),
        (('Y = ["v", "r"]', "Y = [1, 2]"), "Y must be a list of term strings"),
        (('name = "toy"', 'name = "toy'), "not valid TOML"),
    ],
)
def test_structure_errors_name_the_file(tmp_path, change, message):
    path = _write(tmp_path, textwrap.dedent(GOOD).replace(*change))
    with pytest.raises(SindyshipInputError) as raised:
        load_library(path)
    assert str(raised.value).startswith(str(path))
    assert message in str(raised.value)


def test_missing_terms_table(tmp_path):
    path = _write(tmp_path, 'name = "toy"\nsystem = "prime-I"\n')
    with pytest.raises(SindyshipInputError, match=r"a \[terms\] table is missing"):
        load_library(path)


def test_bad_term_names_file_line_and_term(tmp_path):
    path = _write(
        tmp_path,
        """
        name = "toy"
        system = "prime-I"
        [terms]
        X = ["du"]
        Y = [
            "v",
            "r",
            "v^^2",
        ]
        N = ["r"]
        """,
    )
    with pytest.raises(SindyshipInputError) as raised:
        load_library(path)
    assert str(raised.value).startswith(f'{path}, line 8: the term "v^^2" is not valid')


def test_same_text_under_another_dof_finds_the_right_line(tmp_path):
    path = _write(
        tmp_path,
        """
        name = "toy"
        system = "prime-I"
        [terms]
        X = ["du", "exp(v)"]
        Y = ["v"]
        N = ["r",
             "exp(v)"]
        """,
    )
    with pytest.raises(SindyshipInputError, match=r", line 4: the term \"exp\(v\)\""):
        load_library(path)


@pytest.mark.parametrize(
    ("n_terms", "line", "repeated"),
    [
        ('["r", "v", "r"]', 7, '"r" of N repeats a term given earlier on line 7'),
        ('["v^2 r", "r",\n     "r v^2"]', 8, '(the same as "v^2 r")'),
        ('["v", "2 v"]', 7, "repeats"),
    ],
)
def test_duplicate_terms_are_rejected_by_canonical_form(tmp_path, n_terms, line, repeated):
    text = textwrap.dedent(GOOD).replace('N = ["r", "v"]', f"N = {n_terms}")
    path = _write(tmp_path, text)
    with pytest.raises(SindyshipInputError) as raised:
        load_library(path)
    message = str(raised.value)
    assert message.startswith(f"{path}, line {line}: the term")
    assert repeated in message


def test_a_code_payload_in_a_library_file_is_never_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sentinel = tmp_path / "SENTINEL"
    path = _write(
        tmp_path,
        f"""
        name = "evil"
        system = "prime-I"
        [terms]
        X = ["du"]
        Y = ["v", "__import__('os').system('touch {sentinel}')"]
        N = ["r"]
        """,
    )
    with pytest.raises(SindyshipInputError, match=r"line 5: the term \"__import__"):
        load_library(path)
    with pytest.raises(SindyshipInputError):
        AbkowitzFeatureLibrary(("__import__('os').system('touch SENTINEL')",)).fit(np.ones((3, 4)))
    assert not sentinel.exists()


def test_non_utf8_and_oversized_files(tmp_path):
    path = tmp_path / "latin.toml"
    path.write_bytes('name = "caf\xe9"\n'.encode("latin-1"))
    with pytest.raises(SindyshipInputError, match="not UTF-8"):
        load_library(path)
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * 1_000_001)
    with pytest.raises(SindyshipInputError, match="larger than"):
        load_library(big)


# ------------------------------------------------------------------------ objects
def _toy_effect() -> Effect:
    return Effect(
        name="drift",
        title="Heading-dependent drift",
        physics="A steady load that turns with the heading.",
        channels=("psi",),
        terms={"X": ["cos(psi)"], "Y": ["sin(psi)", "v", "3 r"], "N": ["sin(psi)"]},
    )


def test_extended_adds_new_terms_only():
    base = load_library("abkowitz")
    bigger = base.extended(_toy_effect())
    assert bigger.name == "abkowitz+drift"
    assert bigger.effects == ("drift",)
    assert [t.text for t in bigger.terms["Y"][-1:]] == ["sin(psi)"]
    assert len(bigger.terms["Y"]) == 23  # v and 3 r are already there (r, up to scale)
    assert bigger.channels == {"psi"}
    assert bigger.input_names == ("du", "v", "r", "delta", "psi")
    assert bigger.extended(_toy_effect()) == bigger
    assert base.extended() == base


def test_effect_checks_its_channels():
    with pytest.raises(SindyshipInputError, match='channel "psi"; add it to channels'):
        Effect("e", "E", "Text.", (), {"Y": ["sin(psi)"]})
    with pytest.raises(SindyshipInputError, match="always available"):
        Effect("e", "E", "Text.", ("v",), {"Y": ["v"]})
    with pytest.raises(SindyshipInputError, match="no terms"):
        Effect("e", "E", "Text.", (), {})


def test_load_effect_from_a_file(tmp_path):
    path = _write(
        tmp_path,
        """
        name = "crossflow_test"
        title = "Cross-flow drag"
        physics = "Quadratic drag of the hull in cross flow."
        channels = []
        [terms]
        Y = ["abs(v) v", "abs(r) r"]
        N = ["abs(v) v"]
        """,
        name="crossflow_test.toml",
    )
    effect = load_effect(path)
    assert effect.terms["X"] == ()
    assert [t.text for t in effect.terms["Y"]] == ["abs(v) v", "abs(r) r"]
    bad = _write(tmp_path, path.read_text().replace("physics", "physic"), name="bad.toml")
    with pytest.raises(SindyshipInputError, match='unknown key "physic"'):
        load_effect(bad)


def test_library_round_trips_through_json():
    library = load_library("abkowitz").extended(_toy_effect())
    data = json.loads(json.dumps(library.to_dict()))
    again = TermLibrary.from_dict(data)
    assert again == library
    assert again.effects == ("drift",)
    data["terms"]["N"].append("v^^2")
    with pytest.raises(SindyshipInputError, match='model.json: the term "v\\^\\^2"'):
        TermLibrary.from_dict(data, source="model.json")
    with pytest.raises(SindyshipInputError, match='unknown key "colour"'):
        TermLibrary.from_dict({**library.to_dict(), "colour": 1})


def test_library_is_immutable_and_hashable():
    library = load_library("abkowitz")
    assert hash(library) == hash(load_library("abkowitz"))
    assert len({library, load_library("abkowitz"), library.extended(_toy_effect())}) == 2
    assert hash(_toy_effect()) == hash(_toy_effect())
    with pytest.raises(AttributeError):
        library.name = "other"
    with pytest.raises(TypeError):
        library.terms["X"] = ()


def test_identifier_clash_is_caught():
    with pytest.raises(SindyshipInputError, match="would both be named N_absv"):
        TermLibrary("t", "prime-I", "", {"X": ["du"], "Y": ["v"], "N": ["abs(v)", "absv"]})


# ------------------------------------------------------------------------ variables
def _trajectory(samples: int = 5, **extra) -> Trajectory:
    n = samples
    t = np.arange(n, dtype=float)
    frame = pd.DataFrame(
        {
            "t": t,
            "u": np.linspace(10.0, 8.0, n),
            "v": np.linspace(0.0, 1.0, n),
            "r": np.linspace(0.0, 0.02, n),
            "x": 10 * t,
            "y": 0 * t,
            "psi": np.linspace(0.0, 0.5, n),
            "delta": np.linspace(0.0, 0.6, n),
            **extra,
        }
    )
    return Trajectory(frame, name="rec")


def test_nondimensional_variables_prime_one():
    n = 5
    traj = _trajectory(
        n,
        delta_c=np.full(n, 0.61),
        n=np.full(n, 2.0),
        wind_speed=np.full(n, 5.0),
        wind_dir=np.full(n, 1.0),
        depth=np.full(n, 30.0),
    )
    L, U0 = 100.0, 10.0
    needed = ["du", "v", "r", "delta", "psi", "n", "wind_speed", "wind_dir", "depth"]
    values = nondimensional_variables(traj, L, U0, needed=needed)
    assert list(values)[:4] == ["du", "v", "r", "delta"]
    np.testing.assert_allclose(values["du"], traj["u"] / U0 - 1)
    np.testing.assert_allclose(values["v"], traj["v"] / U0)
    np.testing.assert_allclose(values["r"], traj["r"] * L / U0)
    np.testing.assert_allclose(values["delta"], traj["delta"])
    np.testing.assert_allclose(values["psi"], traj["psi"])
    np.testing.assert_allclose(values["n"], 2.0 * L / U0)
    np.testing.assert_allclose(values["wind_speed"], 0.5)
    np.testing.assert_allclose(values["wind_dir"], 1.0)
    np.testing.assert_allclose(values["depth"], 30.0)
    commanded = nondimensional_variables(traj, L, U0, needed=["delta"], rudder=traj["delta_c"])
    np.testing.assert_allclose(commanded["delta"], 0.61)


def test_only_needed_variables_are_computed():
    traj = _trajectory()
    assert set(nondimensional_variables(traj, 100.0, 10.0)) == {"du", "v", "r", "delta"}
    assert set(nondimensional_variables(traj, 100.0, 10.0, needed={"v"})) == {"v"}
    library = load_library("abkowitz").extended(_toy_effect())
    assert set(nondimensional_variables(traj, 100.0, 10.0, needed=library)) == library.variables


def test_missing_channel_names_channel_and_library():
    library = load_library("abkowitz").extended(
        Effect("wind", "Wind", "Text.", ("wind_speed",), {"Y": ["wind_speed^2"]})
    )
    with pytest.raises(SindyshipInputError) as raised:
        nondimensional_variables(_trajectory(), 100.0, 10.0, needed=library)
    message = str(raised.value)
    assert '"wind_speed"' in message and '"abkowitz+wind"' in message and '"rec"' in message


def test_bad_scales_and_rudder_are_rejected():
    with pytest.raises(SindyshipInputError, match="U0 must be a positive number"):
        nondimensional_variables(_trajectory(), 100.0, 0.0)
    with pytest.raises(SindyshipInputError, match="rudder angle given"):
        nondimensional_variables(_trajectory(), 100.0, 10.0, rudder=np.zeros(3))


def test_feature_matrix_columns_are_the_terms(rng):
    values = {name: rng.normal(size=50) for name in ("du", "v", "r", "delta")}
    terms = load_library("abkowitz").terms["N"]
    matrix = feature_matrix(terms, values)
    assert matrix.shape == (50, 22)
    np.testing.assert_array_equal(matrix[:, 0], 1.0)
    np.testing.assert_allclose(matrix[:, 15], values["v"] ** 2 * values["r"])
    assert feature_matrix([], values).shape == (50, 0)


# ------------------------------------------------------------------------ pysindy
def _motion(rng, n: int = 400):
    x = np.column_stack(
        [rng.uniform(-0.3, 0.05, n), rng.uniform(-0.2, 0.2, n), rng.uniform(-0.5, 0.5, n)]
    )
    u = rng.uniform(-0.6, 0.6, size=(n, 1))
    values = dict(zip(("du", "v", "r", "delta"), np.hstack([x, u]).T, strict=True))
    return x, u, values


@pytest.mark.parametrize(
    "optimizer",
    [ps.STLSQ(threshold=0.0, alpha=0.0), LinearRegression(fit_intercept=False)],
    ids=["stlsq", "sklearn-ls"],
)
@pytest.mark.parametrize("dof", DOFS)
def test_sindy_fits_one_dof_at_a_time(rng, optimizer, dof):
    library = load_library("abkowitz")
    x, u, values = _motion(rng)
    terms = library.terms[dof]
    true_coef = rng.normal(size=len(terms)) * np.logspace(0, 2, len(terms))
    target = feature_matrix(terms, values) @ true_coef

    model = ps.SINDy(
        feature_library=AbkowitzFeatureLibrary.for_dof(library, dof), optimizer=clone(optimizer)
    )
    model.fit(x, t=1.0, x_dot=target[:, None], u=u, feature_names=list(library.input_names))

    coef = model.coefficients()
    assert coef.shape == (1, len(terms))
    np.testing.assert_allclose(coef[0], true_coef, rtol=1e-8, atol=1e-8)
    x_new, u_new, values_new = _motion(rng, n=50)
    prediction = model.predict(x_new, u=u_new)
    assert prediction.shape == (50, 1)
    np.testing.assert_allclose(
        prediction[:, 0], feature_matrix(terms, values_new) @ coef[0], rtol=0, atol=1e-10
    )
    assert model.get_feature_names() == [t.text for t in terms]
    out = io.StringIO()
    with redirect_stdout(out):
        model.print(lhs=[f"{dof}'"], precision=2)
        model.print()
    printed = out.getvalue().splitlines()
    assert printed[0].startswith(f"{dof}' = ") and "v r delta" in printed[0]
    assert len(printed) == 2


def test_sindy_with_several_manoeuvres(rng):
    library = load_library("abkowitz-noconst")
    terms = library.terms["Y"]
    coef = rng.normal(size=len(terms))
    xs, us, targets = [], [], []
    for n in (120, 80):
        x, u, values = _motion(rng, n)
        xs.append(x)
        us.append(u)
        targets.append((feature_matrix(terms, values) @ coef)[:, None])
    model = ps.SINDy(
        feature_library=AbkowitzFeatureLibrary.for_dof(library, "Y"),
        optimizer=ps.STLSQ(threshold=0.0, alpha=0.0),
    ).fit(xs, t=1.0, x_dot=targets, u=us)
    np.testing.assert_allclose(model.coefficients()[0], coef, rtol=1e-8, atol=1e-8)


def test_feature_library_is_an_sklearn_estimator(rng):
    lib = AbkowitzFeatureLibrary(terms=("1", "v^2 r"), input_names=("du", "v", "r", "delta"))
    assert lib.get_params() == {"terms": ("1", "v^2 r"), "input_names": ("du", "v", "r", "delta")}
    copy = clone(lib)
    assert copy is not lib and copy.get_params() == lib.get_params()
    data = rng.normal(size=(10, 4))
    lib.fit(data)
    assert (lib.n_features_in_, lib.n_output_features_) == (4, 2)
    assert not hasattr(clone(lib), "terms_")
    assert [t.text for t in lib.terms_] == ["1", "v^2 r"]
    np.testing.assert_allclose(np.asarray(lib.transform(data))[:, 1], data[:, 1] ** 2 * data[:, 2])
    sindy = ps.SINDy(feature_library=lib, optimizer=ps.STLSQ(threshold=0.0))
    assert clone(sindy).feature_library.get_params() == lib.get_params()


def test_feature_libraries_add_to_a_concat_library(rng):
    x, u, values = _motion(rng)
    inputs = ("du", "v", "r", "delta")
    lib_a = AbkowitzFeatureLibrary(terms=("v", "r"), input_names=inputs)
    lib_b = AbkowitzFeatureLibrary(terms=("abs(v) v", "v^2 r"), input_names=inputs)
    both = lib_a + lib_b
    assert isinstance(both, ConcatLibrary)
    all_terms = [Term(t) for t in ("v", "r", "abs(v) v", "v^2 r")]
    coef = np.array([1.0, -2.0, 3.0, -4.0])
    target = feature_matrix(all_terms, values) @ coef
    model = ps.SINDy(feature_library=both, optimizer=LinearRegression(fit_intercept=False))
    model.fit(x, t=1.0, x_dot=target[:, None], u=u)
    assert model.get_feature_names() == ["v", "r", "abs(v) v", "v^2 r"]
    np.testing.assert_allclose(model.coefficients()[0], coef, rtol=1e-10)


def test_feature_library_checks_its_inputs(rng):
    with pytest.raises(ValueError, match="must name each of the 3 input columns"):
        AbkowitzFeatureLibrary(terms=("v",)).fit(np.ones((4, 3)))
    with pytest.raises(SindyshipInputError, match='"psi", which is not among the inputs'):
        AbkowitzFeatureLibrary(terms=("sin(psi)",)).fit(np.ones((4, 4)))
    with pytest.raises(SindyshipInputError, match='the term "v\\^\\^2" is not valid'):
        AbkowitzFeatureLibrary(terms=("v^^2",)).fit(np.ones((4, 4)))
    with pytest.raises(ValueError, match="at least one term"):
        AbkowitzFeatureLibrary(terms=()).fit(np.ones((4, 4)))
    lib = AbkowitzFeatureLibrary(terms=("v",)).fit(np.ones((4, 4)))
    with pytest.raises(ValueError, match="input columns"):
        lib.transform(np.ones((4, 3)))


# ------------------------------------------------------- pysindy: names bound, never mislabelled
def test_feature_names_before_fit_raise_not_fitted():
    from sklearn.exceptions import NotFittedError

    with pytest.raises(NotFittedError):
        AbkowitzFeatureLibrary(terms=("v",), input_names=("v",)).get_feature_names()


def _permuted_fit(input_names):
    import pysindy as ps

    rng = np.random.default_rng(3)
    t = np.arange(400.0) * 0.1
    du, v, r = rng.normal(size=(3, 400)) * 0.1
    x = np.column_stack([v, r, du])  # columns ordered [v, r, du]
    x_dot = np.column_stack([2.0 * v, 0.0 * v, 0.0 * v])  # d/dt of the first column is 2 v
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=0.01),
                     feature_library=AbkowitzFeatureLibrary(terms=("du", "v", "r"),
                                                            input_names=input_names))
    model.fit(x, t=t, x_dot=x_dot, feature_names=["v", "r", "du"])
    return model


def test_a_permuted_column_order_prints_the_right_names():
    model = _permuted_fit(("v", "r", "du"))
    equations = model.equations()
    assert equations[0].strip() == "2.000 v"
    assert model.get_feature_names() == ["du", "v", "r"]


def test_a_library_bound_in_another_order_names_its_terms_by_position():
    with pytest.warns(UserWarning, match="binds them by position") as caught:
        model = _permuted_fit(("du", "v", "r"))
        equations = model.equations()
    # column 0, which the caller named v, is the library's "du": named by its column
    assert equations[0].strip() == "2.000 v"
    assert sum("binds them by position" in str(w.message) for w in caught) == 1


@pytest.mark.parametrize("names", [["a", "b", "c"], ["a", "b", "c", "d", "e"], ["Heel angle"]])
def test_feature_names_of_any_length_come_back_as_names(names):
    lib = AbkowitzFeatureLibrary(terms=("v^2 r", "abs(v) v", "1"), input_names=("v", "r"))
    lib.fit(np.ones((3, 2)))
    with pytest.warns(UserWarning):
        out = lib.get_feature_names(names)
    assert out == ["v^2 r", "abs(v) v", "1"]


def test_feature_names_by_position_rename_every_variable():
    lib = AbkowitzFeatureLibrary(terms=("v^2 r", "abs(v) v", "2 r", "1"), input_names=("v", "r"))
    lib.fit(np.ones((3, 2)))
    with pytest.warns(UserWarning, match="v -> a, r -> b"):
        assert lib.get_feature_names(["a", "b"]) == ["a^2 b", "abs(a) a", "2 b", "1"]


def _composition_data():
    rng = np.random.default_rng(7)
    x = rng.normal(size=(300, 3)) * 0.1
    return x, rng


@pytest.mark.parametrize("kind", ["tensored", "generalized", "concat"])
def test_the_library_composes_with_pysindy_libraries_under_user_names(kind):
    import pysindy as ps

    x, _ = _composition_data()
    own = AbkowitzFeatureLibrary(terms=("v", "r", "v^2 r"), input_names=("du", "v", "r"))
    poly = ps.PolynomialLibrary(degree=1, include_bias=False)
    library = {"tensored": lambda: ps.TensoredLibrary([own, poly]),
               "generalized": lambda: ps.GeneralizedLibrary([own, poly]),
               "concat": lambda: own + poly}[kind]()
    # representable: v alone, or v times the polynomial's sway (x1 x1) when tensored
    target = 3.0 * x[:, 1:2] * (x[:, 1:2] if kind == "tensored" else 1.0)
    model = ps.SINDy(feature_library=library, optimizer=ps.STLSQ(threshold=0.0))
    with pytest.warns(UserWarning, match="by position"):
        model.fit(x, t=1.0, x_dot=np.hstack([target, target, target]),
                  feature_names=["surge", "sway", "yaw"])
        names = model.get_feature_names()
        printed = model.equations()
    assert len(names) == library.n_output_features_ and all(isinstance(n, str) for n in names)
    assert any("sway" in n for n in names) and not any(n in ("v", "r") for n in names)
    assert len(printed) == 3 and all(isinstance(e, str) for e in printed)
    prediction = model.predict(x)
    np.testing.assert_allclose(prediction[:, 0], target[:, 0], atol=1e-8)


def test_the_library_in_discrete_sindy_prints_with_default_and_own_names():
    import pysindy as ps

    x, _ = _composition_data()
    lib = AbkowitzFeatureLibrary(terms=("v", "r^2"), input_names=("v", "r"))
    if hasattr(ps, "DiscreteSINDy"):
        model = ps.DiscreteSINDy(feature_library=lib, optimizer=ps.STLSQ(threshold=0.0))
    else:  # pysindy 2.0: the discrete-time form of SINDy
        model = ps.SINDy(feature_library=lib, optimizer=ps.STLSQ(threshold=0.0),
                         discrete_time=True)
    model.fit(x[:, 1:], t=1)
    assert model.get_feature_names() == ["v", "r^2"]  # default names x0[k], x1[k]: no rename
    with pytest.warns(UserWarning, match="by position"):
        model.fit(x[:, 1:], t=1, feature_names=["sway", "yaw"])
        assert model.get_feature_names() == ["sway", "yaw^2"]


def test_a_library_and_a_model_copy_and_pickle_for_workers(kcs, protocol_runs):
    """copy.deepcopy and pickle had failed on the library's read-only term mapping, so a model
    could not be an argument of a joblib or Dask task."""
    import copy
    import pickle

    import joblib

    from sindyship.evaluation import evaluate
    from sindyship.identify import fit

    library = load_library("abkowitz").extended(load_effect("asymmetry"))
    library = TermLibrary(library.name, library.system, library.description, library.terms,
                          effects=library.effects, delays={"delta": 2.0}, speed="instantaneous")
    for copied in (copy.deepcopy(library), pickle.loads(pickle.dumps(library))):
        assert copied == library and copied.delays == {"delta": 2.0}
        assert copied.speed == "instantaneous" and copied.effects == library.effects
    model = fit(protocol_runs["train"][:4], kcs, effects=["asymmetry"])
    twin = pickle.loads(pickle.dumps(model))
    assert twin.coefficients == model.coefficients and twin.library == model.library
    held_out = protocol_runs["test"][:1]
    (remote,) = joblib.Parallel(n_jobs=2)(joblib.delayed(evaluate)(m, held_out) for m in [model])
    assert remote == evaluate(model, held_out)

"""Shape variables of the position (a step across a line, the pull of a bank): read from their
names, computed the same way on records, in compiled and numpy flights and in multiple
shooting, refused by the generated simulator, and discovered by ``discover``."""

from __future__ import annotations

import importlib.util
import math
import tomllib

import numpy as np
import pytest

from sindyship import Manoeuvre
from sindyship.diagnose import discover
from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.errors import SindyshipInputError
from sindyship.flights import fly_like_batch
from sindyship.library import Effect, TermLibrary, load_effect, nondimensional_variables
from sindyship.model import AbkowitzDynamics, AbkowitzModel, paper_model
from sindyship.terms import (
    Term,
    describe_variable,
    is_shape_name,
    parse_shape,
    shape_name,
    shape_values,
    sources_of,
)

EDGE = "edge_b000_p020_w05"
BANK = "bank_b090_m080"


@pytest.mark.parametrize(("name", "kind", "bearing", "distance", "width"), [
    (EDGE, "edge", 0.0, 2.0, 0.5),
    ("edge_b345_m125_w20", "edge", 345.0, -12.5, 2.0),
    (BANK, "bank", 90.0, -8.0, 0.0),
])
def test_a_shape_name_carries_its_line(name, kind, bearing, distance, width):
    shape = parse_shape(name)
    assert (shape.kind, shape.bearing, shape.distance, shape.width) == (kind, bearing, distance,
                                                                        width)
    assert shape_name(kind, bearing, distance, width) == name == shape.name
    assert sources_of(name) == ("x", "y")
    assert describe_variable(name).scaling == "none"
    assert Term(f"{name} v").variables == {name, "v"}


@pytest.mark.parametrize("name", ["edge_b000_p020", "edge_b360_p020_w05", "edge_b000_p020_w00",
                                  "bank_b000_p020_w05", "edge_b00_p020_w05", "edge_b000_p20_w5",
                                  "bank_b090_m0080"])
def test_a_name_like_a_shape_that_is_not_one_is_refused_in_a_term(name):
    assert not is_shape_name(name) and sources_of(name) == (name,)
    with pytest.raises(SindyshipInputError, match="is named like a shape but is not one"):
        Term(f"{name} v")


def test_far_lines_keep_their_names_and_other_names_stay_channels():
    far = shape_name("bank", 90.0, -1300.0)
    assert far == "bank_b090_m13000" and parse_shape(far).distance == -1300.0
    assert not is_shape_name("depth") and Term("depth v").variables == {"depth", "v"}


def test_an_edge_steps_across_its_line_and_a_bank_pulls_toward_its_own():
    L = 100.0
    edge, bank = parse_shape("edge_b090_p030_w05"), parse_shape(BANK)
    east = np.array([-500.0, 250.0, 300.0, 350.0, 900.0])
    values = shape_values(edge, np.zeros(5), east, L)
    assert values[2] == pytest.approx(0.5)
    assert values[0] < 1e-9 and values[-1] > 1 - 1e-9 and np.all(np.diff(values) > 0)
    pull = shape_values(bank, np.zeros(4), np.array([-1000.0, -790.0, 0.0, 200.0]), L)
    # positive where the line (8 L west) lies ahead along the bearing (east), negative
    # beyond it; (L / distance)^2, held within L/2 of the line
    assert pull[0] == pytest.approx(1 / 4.0) and pull[1] == pytest.approx(-4.0)
    assert pull[2] == pytest.approx(-1 / 64.0) and pull[3] == pytest.approx(-1 / 100.0)


def test_a_record_gives_its_shape_from_its_own_position(kcs, protocol_runs):
    record = protocol_runs["train"][3]
    values = nondimensional_variables(record, kcs.L, kcs.U0, needed={EDGE, "v"})
    assert set(values) == {EDGE, "v"}
    expected = 0.5 * (1 + np.tanh((record["x"] / kcs.L - 2.0) / 0.5))
    np.testing.assert_allclose(values[EDGE], expected, rtol=1e-12)


def _shaped_model(kcs, base=None):
    model = base or paper_model(kcs)
    terms = {dof: [t.text for t in model.library.terms[dof]] for dof in "XYN"}
    extra = {"X": [f"{BANK} sin(psi)"], "Y": [f"{EDGE} v", f"{BANK} cos(psi)"],
             "N": [f"{EDGE} r", f"{BANK} cos(psi)"]}
    coefficients = {dof: dict(model.coefficients[dof]) for dof in "XYN"}
    for dof, texts in extra.items():
        terms[dof] += texts
        for text in texts:
            coefficients[dof][text] = {"X": 2e-3, "Y": -4e-3, "N": -1.5e-3}[dof]
    library = TermLibrary("shaped", "prime-I", "", terms)
    return AbkowitzModel(kcs, library, coefficients)


@pytest.mark.skipif(importlib.util.find_spec("numba") is None, reason="numba is not installed")
def test_compiled_and_numpy_paths_agree_on_shapes(kcs, protocol_runs, monkeypatch):
    rng = np.random.default_rng(3)
    state = [rng.normal(size=4) * s for s in (0.5, 0.5, 0.01, 0.2, 1.0)]
    state[0] += 7.0
    position = (rng.normal(size=4) * 600, rng.normal(size=4) * 600 - 1000)
    accelerations, flights = [], []
    for switch in ("0", "1"):
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", switch)
        model = _shaped_model(kcs)
        assert (model._compiled is None) == (switch == "1")
        accelerations.append(AbkowitzDynamics(model).accelerations(*state, position=position))
        flights.append(fly_like_batch(model, protocol_runs["test"]))
    for a, b in zip(*accelerations, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)
    plain = fly_like_batch(paper_model(kcs), protocol_runs["test"])
    for a, b, p in zip(*flights, plain, strict=True):
        assert np.nanmax(np.hypot(a["x"] - b["x"], a["y"] - b["y"])) / kcs.L < 1e-8
        assert np.nanmax(np.hypot(a["x"] - p["x"], a["y"] - p["y"])) / kcs.L > 0.05


@pytest.mark.parametrize("compiled", [True, False])
def test_multiple_shooting_flies_shapes_as_the_model_does(kcs, protocol_runs, compiled,
                                                         monkeypatch):
    from sindyship.shooting import fly_segments, make_segments

    if not compiled:
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", "1")
    model = _shaped_model(kcs)
    record = protocol_runs["train"][1]  # a turn: replayed through the servo
    (segments,) = make_segments(model, [record], None)
    states, jacobian = fly_segments(model, segments, sensitivities=True)
    (alone,) = fly_like_batch(model, [record])
    rows = np.arange(1, states.shape[1] + 1) * segments.every * segments.step / record.dt
    rows = rows.astype(int)[rows < record.n_samples]
    gap = np.hypot(states[0, : len(rows), 3] - alone["x"][rows],
                   states[0, : len(rows), 4] - alone["y"][rows]) / kcs.L
    assert np.nanmax(gap) < 0.02
    assert np.all(np.isfinite(jacobian[0, : len(rows)]))


def test_without_a_position_every_shape_is_away_from_its_line(kcs):
    model = _shaped_model(kcs)
    state = [np.array([7.0]), np.array([0.1]), np.array([0.001]), np.array([0.0]),
             np.array([0.3])]
    values = model.flight_variables(*state, {})
    assert values[EDGE][0] == 0.0 and values[BANK][0] == 0.0
    placed = model.flight_variables(*state, {}, position=(np.array([900.0]), np.array([0.0])))
    assert placed[EDGE][0] > 0.99 and placed[BANK][0] < 0.0


def test_the_generated_simulator_refuses_shapes_in_one_sentence(kcs):
    from sindyship.export import generate_python

    with pytest.raises(SindyshipInputError, match="a shape of it") as error:
        generate_python(_shaped_model(kcs))
    assert str(error.value).count(". ") == 0


def test_an_effect_with_a_shape_declares_the_position_it_is_made_from():
    with pytest.raises(SindyshipInputError, match='"edge_b000_p020_w05" is made from the '
                                                  'channels "x" and "y"; add them'):
        Effect("patch", "Patch", "Text.", (), {"Y": [f"{EDGE} v"]})
    assert Effect("patch", "Patch", "Text.", ("x", "y"), {"Y": [f"{EDGE} v"]}).variables == \
        {EDGE, "v"}


@pytest.fixture(scope="module")
def patch_runs():
    ship = _symmetric()
    plan = [Manoeuvre("turning-circle", rudder=35, duration=500),
            Manoeuvre("turning-circle", rudder=-35, duration=500),
            Manoeuvre("zigzag", rudder=20, check=20, duration=500),
            Manoeuvre("zigzag", rudder=10, check=10, duration=500),
            Manoeuvre("zigzag", rudder=15, check=15, duration=500)]
    return ship, simulate_with_effects(ship, plan, parse_effects(["shallow_patch=0.8",
                                                                  "patch_distance=2"]))


def _symmetric():
    from sindyship.ships import load_ship

    return load_ship("kcs").with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)


def test_tracks_far_from_the_origin_are_not_searched_for_shapes_and_the_report_says_so(
        patch_runs):
    from sindyship.trajectory import Trajectory

    ship, runs = patch_runs
    shifted = [Trajectory(r.data.assign(x=r["x"] + 3e5, y=r["y"] - 4e6), name=r.name)
               for r in runs[:3]]
    found = discover(shifted, ship, check_catalogue=False)
    assert not any(f.family in ("edge", "bank") for f in found.findings)
    assert "Shapes of the position were not searched" in found.report()
    assert found.to_json()["notes"] == found.notes and len(found.notes) == 1


def test_discover_finds_the_edge_of_a_shallow_patch_and_flights_confirm_it(patch_runs,
                                                                            tmp_path):
    ship, runs = patch_runs
    found = discover(runs, ship)
    assert [f.family for f in found.accepted] == ["edge"]
    shape = next(parse_shape(v) for v in found.best.variables if parse_shape(v))
    assert shape.kind == "edge" and shape.bearing in (0.0, 180.0)
    assert abs(shape.distance * math.cos(math.radians(shape.bearing)) - 2.0) <= 0.5
    low, high = found.best.intervals["distance_L"]
    assert low <= shape.distance <= high
    alone = next(c for c in found.contests if c.catalogued == "none")
    assert alone.winner == "finding" and alone.finding_L < 0.5 * alone.catalogued_L
    assert "A line of a shape is chosen among hundreds" in found.report()
    path = tmp_path / "patch.toml"
    path.write_text(found.effect_toml())
    assert tomllib.loads(path.read_text())["channels"] == ["x", "y"]
    effect = load_effect(path)
    assert any(shape.name in t.text for dof in "XYN" for t in effect.terms[dof])
    assert "# Shape: a smooth step" in path.read_text()


def test_captive_forces_need_the_position_of_a_model_with_shapes(kcs):
    from sindyship.captive import captive_tests, force_scales
    from sindyship.forces import model_captive_forces

    base = paper_model(kcs)
    terms = {dof: [t.text for t in base.library.terms[dof]] for dof in "XYN"}
    terms["Y"].append(f"{EDGE} v")
    coefficients = {dof: dict(base.coefficients[dof]) for dof in "XYN"}
    coefficients["Y"][f"{EDGE} v"] = -4e-3
    model = AbkowitzModel(kcs, TermLibrary("edge", "prime-I", "", terms), coefficients)
    tests = captive_tests(kcs, "static-drift", points=3)
    with pytest.raises(SindyshipInputError, match="add columns x and y"):
        model_captive_forces(model, tests)
    deep = model_captive_forces(model, tests.assign(x=-10 * kcs.L, y=0.0))
    shallow = model_captive_forces(model, tests.assign(x=10 * kcs.L, y=0.0))  # beyond the edge
    plain = model_captive_forces(base, tests)
    np.testing.assert_allclose(deep.Y, plain.Y, rtol=1e-12)
    v = tests["v"].to_numpy() / kcs.U0
    scale = force_scales(kcs, "prime-I")[1]
    np.testing.assert_allclose(shallow.Y - deep.Y, -4e-3 * v * scale, rtol=1e-9, atol=1e-6)

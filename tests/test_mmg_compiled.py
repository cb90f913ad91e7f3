"""The compiled MMG accelerations (sindyship._mmg_compiled) against the numpy reference of
sindyship.mmg: random states of every model variant, input shapes, the cases left to numpy,
and the protocol's flights."""

from __future__ import annotations

import math
import pickle
from dataclasses import replace

import numpy as np
import pytest

from sindyship import mmg
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship
from sindyship.simulation.kernels import ChannelSeries

pytest.importorskip("numba", reason="the compiled MMG accelerations need numba (sindyship[fast])")


def _variants():
    """Both built-in ships and crossings of their options: hull form, speed reference,
    Coriolis form, wake model."""
    kcs, kvlcc2 = load_ship("kcs"), load_ship("kvlcc2")
    return {
        "kcs": kcs,
        "kvlcc2": kvlcc2,
        "kcs-instantaneous-added-mass-drift": replace(
            kcs, speed_reference="instantaneous", coriolis="with-added-mass",
            propeller=replace(kcs.propeller, wake_model="drift")),
        "kvlcc2-design-rigid-body-constant": replace(
            kvlcc2, speed_reference="design", coriolis="rigid-body",
            propeller=replace(kvlcc2.propeller, wake_model="constant")),
    }


VARIANTS = _variants()


def _numpy_model(monkeypatch, *args, **kwargs) -> MMGModel:
    """A model built while SINDYSHIP_NO_COMPILE is set: it runs the numpy functions."""
    with monkeypatch.context() as patch:
        patch.setenv("SINDYSHIP_NO_COMPILE", "1")
        model = MMGModel(*args, **kwargs)
    assert not model._compile
    return model


def _states(ship, n, seed):
    """Random SI states over the simulator's plausible range (u' in (0.3, 1.6), |v'| < 0.5,
    |r'| < 1, |delta| < 40 deg)."""
    rng = np.random.default_rng(seed)
    U0, L = ship.U0, ship.L
    return (U0 * rng.uniform(0.3, 1.6, n), U0 * rng.uniform(-0.5, 0.5, n),
            U0 / L * rng.uniform(-1.0, 1.0, n), rng.uniform(-0.7, 0.7, n), rng.uniform(-4, 4, n))


def _assert_same(got, want, rtol=1e-13):
    """Equal to ``rtol`` of each acceleration's largest magnitude (some are near zero)."""
    for g, w in zip(got, want, strict=True):
        assert np.shape(g) == np.shape(w) and type(g) is type(w)
        scale = np.max(np.abs(w))
        assert np.max(np.abs(np.asarray(g) - w)) <= rtol * scale


@pytest.mark.parametrize("name", sorted(VARIANTS))
@pytest.mark.parametrize("options", [{}, {"rudder_offset": 0.02, "stall": math.radians(25)}],
                         ids=["plain", "offset-stall"])
def test_compiled_accelerations_equal_the_numpy_ones(monkeypatch, name, options):
    ship = VARIANTS[name]
    compiled = MMGModel(ship, **options)
    reference = _numpy_model(monkeypatch, ship, **options)
    u, v, r, delta, psi = _states(ship, 500, seed=len(name))
    starboard = np.random.default_rng(1).random(500) > 0.5
    for branch in (None, starboard, ~starboard):
        _assert_same(compiled.accelerations(u, v, r, delta, psi, branch=branch),
                     reference.accelerations(u, v, r, delta, psi, branch=branch))
    assert compiled._compiled_parameters is not None  # the compiled path ran


@pytest.mark.parametrize("name", sorted(VARIANTS))
def test_compiled_switching_equals_the_numpy_one(monkeypatch, name):
    ship = VARIANTS[name]
    compiled, reference = MMGModel(ship), _numpy_model(monkeypatch, ship)
    state = np.vstack(_states(ship, 300, seed=11) + (np.zeros((2, 300)),))
    state = state[[0, 1, 2, 5, 6, 4, 3]]  # u, v, r, x, y, psi, delta
    for columns in (state, state[:, 100:101], np.asfortranarray(state)[:, ::3]):
        got, want = compiled.switching(columns), reference.switching(columns)
        assert got.shape == want.shape and np.allclose(got, want, rtol=1e-14, atol=1e-15)
        assert np.array_equal(got > 0.0, want > 0.0)
    assert type(compiled.switching(state[:, 0])) is type(reference.switching(state[:, 0]))


def test_strided_states_and_the_integrators_columns(monkeypatch):
    kcs = VARIANTS["kcs"]
    state = np.asfortranarray(np.vstack(_states(kcs, 11, seed=3)))
    compiled, reference = MMGModel(kcs), _numpy_model(monkeypatch, kcs)
    for rows in (state, state[:, ::2]):  # rows with strides, as the integrator slices them
        u, v, r, delta, psi = rows
        _assert_same(compiled.accelerations(u, v, r, delta, psi),
                     reference.accelerations(u, v, r, delta, psi))


@pytest.mark.parametrize("shape", [(), (1,), (4, 3)])
def test_any_shape_and_scalars(monkeypatch, shape):
    ship = VARIANTS["kvlcc2"]
    compiled, reference = MMGModel(ship), _numpy_model(monkeypatch, ship)
    u, v, r, delta, _ = (a.reshape(shape) if shape else float(a[0])
                         for a in _states(ship, int(np.prod(shape)), seed=5))
    for branch in (None, True, np.zeros(shape, dtype=bool)):
        _assert_same(compiled.accelerations(u, v, r, delta, 0.0, branch=branch),
                     reference.accelerations(u, v, r, delta, 0.0, branch=branch))
    # a scalar speed against an array of rudder angles, integers among floats
    angles = np.linspace(-0.6, 0.6, 7)
    _assert_same(compiled.accelerations(ship.U0, 0, 0, angles, 0.0),
                 reference.accelerations(ship.U0, 0, 0, angles, 0.0))


def test_other_inputs_run_the_numpy_functions(monkeypatch):
    kcs = VARIANTS["kcs"]
    compiled, reference = MMGModel(kcs), _numpy_model(monkeypatch, kcs)
    u, v, r, delta, psi = (a.astype(np.float32) for a in _states(kcs, 5, seed=7))
    got = compiled.accelerations(u, v, r, delta, psi)
    want = reference.accelerations(u, v, r, delta, psi)
    assert all(g.dtype == w.dtype and np.array_equal(g, w) for g, w in zip(got, want, strict=True))
    with pytest.raises(ValueError):
        compiled.accelerations(np.ones(3), np.ones(4), 0.0, 0.0, 0.0)


def test_which_models_compile(monkeypatch):
    kcs = VARIANTS["kcs"]
    assert MMGModel(kcs, current=(0.5, -0.2))._compile
    series = ChannelSeries(np.array([0.0, 10.0]), {"n": np.array([[1.9, 1.9]])})
    others = [MMGModel(kcs, extra_forces=(lambda u, v, r, d, psi: (0.0, 0.0, 0.0),)),
              MMGModel(kcs, conditions=series), MMGModel(kcs, bank=(500.0, 1e-3))]
    assert not any(model._compile for model in others)
    monkeypatch.setenv("SINDYSHIP_NO_COMPILE", "0")
    assert MMGModel(kcs)._compile


def test_without_numba_the_numpy_functions_run(monkeypatch):
    kcs = VARIANTS["kcs"]
    model = MMGModel(kcs)
    monkeypatch.setattr(mmg, "_compiled_module", lambda: None)
    acc = model.accelerations(kcs.U0, 0.0, 0.0, 0.0, 0.0)
    assert model._compiled_parameters is None and [round(float(a), 7) for a in acc] == [
        1.4e-05, 0.0, 0.0]


def test_a_model_that_flew_compiled_pickles():
    model = MMGModel(VARIANTS["kcs"])
    model.accelerations(10.0, 0.5, 0.001, 0.1, 0.0)
    copy = pickle.loads(pickle.dumps(model))
    assert copy == model
    assert copy.accelerations(10.0, 0.5, 0.001, 0.1, 0.0) == model.accelerations(
        10.0, 0.5, 0.001, 0.1, 0.0)


def test_protocol_flights_are_the_numpy_ones(monkeypatch):
    kcs = VARIANTS["kcs"]
    plan = protocol_manoeuvres()
    manoeuvres = plan["train"] + plan["test"]
    compiled = fly(MMGModel(kcs), manoeuvres)
    reference = fly(_numpy_model(monkeypatch, kcs), manoeuvres)
    for a, b in zip(compiled, reference, strict=True):
        moved = np.max(np.hypot(a["x"] - b["x"], a["y"] - b["y"])) / kcs.L
        assert moved < 1e-10, a.label
        np.testing.assert_allclose(a["psi"], b["psi"], rtol=0, atol=1e-10)

"""The compiled force loop of an identified model gives the numpy path's numbers."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from sindyship.flights import fly_like_batch
from sindyship.library import TermLibrary
from sindyship.model import AbkowitzDynamics, AbkowitzModel, paper_model

pytestmark = pytest.mark.skipif(importlib.util.find_spec("numba") is None,
                                reason="numba is not installed (pip install sindyship[fast])")

TERMS = {"X": ["1", "du", "du^2", "v^2", "r^2", "delta^2", "v r", "abs(v) v", "cos(psi)"],
         "Y": ["1", "v", "r", "delta", "v^3", "v^2 r", "abs(r) r", "sign(v) delta^2",
               "sin(psi)"],
         "N": ["1", "v", "r", "delta", "r^3", "v r^2", "abs(v) r", "sign(r) v^2", "du delta^3"]}


def _model(kcs, seed=0):
    rng = np.random.default_rng(seed)
    library = TermLibrary("functions", "prime-I", "", TERMS)
    coefficients = {dof: {t: float(rng.normal()) * 1e-3 for t in TERMS[dof]} for dof in "XYN"}
    return AbkowitzModel(kcs, library, coefficients)


def test_compiled_forces_equal_the_numpy_path(kcs, monkeypatch):
    compiled = _model(kcs)
    monkeypatch.setenv("SINDYSHIP_NO_COMPILE", "1")
    plain = _model(kcs)
    assert compiled._compiled is not None and plain._compiled is None
    rng = np.random.default_rng(1)
    values = {name: rng.normal(size=(4, 5)) * 0.3 for name in ("du", "v", "r", "delta", "psi")}
    values["v"][0, 0] = 0.0  # sign(0) = 0 on both paths
    a, b = compiled.forces_from_values(values), plain.forces_from_values(values)
    for dof in "XYN":
        assert a[dof].shape == (4, 5)
        np.testing.assert_allclose(a[dof], b[dof], rtol=1e-13, atol=1e-18)
    scalar = compiled.forces_from_values({k: 0.1 for k in values})
    assert scalar["Y"].shape == ()


def test_compiled_flights_equal_the_numpy_path(kcs, protocol_runs, monkeypatch):
    compiled = fly_like_batch(paper_model(kcs), protocol_runs["test"])
    monkeypatch.setenv("SINDYSHIP_NO_COMPILE", "1")
    plain = fly_like_batch(paper_model(kcs), protocol_runs["test"])
    for a, b in zip(compiled, plain, strict=True):
        gap = np.hypot(a["x"] - b["x"], a["y"] - b["y"]) / kcs.L
        assert np.nanmax(gap) < 1e-9
        assert a.meta["diverged_at"] == b.meta["diverged_at"]


def test_compiled_accelerations_take_channels_positions_and_the_rudder_rate(kcs, monkeypatch):
    from sindyship.model import AbkowitzDynamics, ChannelSeries

    terms = {dof: list(TERMS[dof]) for dof in "XYN"}
    terms["Y"] += ["depth v", "x", "delta_rate"]
    terms["N"] += ["y r", "delta_rate", "wind"]
    library = TermLibrary("channels", "prime-I", "", terms)
    rng = np.random.default_rng(2)
    coefficients = {dof: {t: float(rng.normal()) * 1e-4 for t in terms[dof]} for dof in "XYN"}
    series = ChannelSeries(np.array([0.0, 10.0]), {"depth": rng.normal(size=(3, 2))})
    state = [rng.normal(size=3) * s for s in (0.5, 0.5, 0.01, 0.2, 1.0)]
    state[0] += 7.0
    position = (rng.normal(size=3) * 100, rng.normal(size=3) * 100)
    got = []
    for switch in ("0", "1"):
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", switch)
        model = AbkowitzModel(kcs, library, coefficients)
        assert (model._compiled is None) == (switch == "1")
        dynamics = AbkowitzDynamics(model, {"wind": 0.3}, series)
        got.append(dynamics.accelerations(*state, t=4.0, members=np.array([2, 0, 1]),
                                          position=position, rudder_rate=state[3] * 0.1))
    for a, b in zip(*got, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)


def test_a_missing_channel_is_refused_on_both_paths(kcs, monkeypatch):
    from sindyship.errors import SindyshipInputError
    from sindyship.model import AbkowitzDynamics

    library = TermLibrary("depth", "prime-I", "", {"X": ["du"], "Y": ["v", "depth v"],
                                                   "N": ["r"]})
    state = [np.array([7.0]), np.array([0.1]), np.array([0.001]), np.array([0.0]),
             np.array([0.0])]
    for switch in ("0", "1"):
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", switch)
        model = AbkowitzModel(kcs, library, {"X": {"du": -1e-3}, "Y": {"v": -1e-2,
                                                                         "depth v": 1e-3},
                                             "N": {"r": -1e-3}})
        with pytest.raises(SindyshipInputError, match="variable 'depth'"):
            AbkowitzDynamics(model).accelerations(*state)


def test_a_model_of_constant_terms_only_gives_its_constants_on_both_paths(kcs, monkeypatch):
    library = TermLibrary("constants", "prime-I", "", {"X": ["1", "du"], "Y": ["1", "v"],
                                                       "N": ["1", "r"]})
    coefficients = {"X": {"1": 1e-3}, "Y": {"1": -2e-3}, "N": {"1": 3e-4}}
    values = {name: np.array([0.1, -0.2]) for name in ("du", "v", "r", "delta", "psi")}
    for switch in ("0", "1"):
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", switch)
        model = AbkowitzModel(kcs, library, coefficients)
        forces = model.forces_from_values(values)
        np.testing.assert_allclose(forces["X"], [1e-3, 1e-3])
        np.testing.assert_allclose(forces["Y"], [-2e-3, -2e-3])
        acceleration = AbkowitzDynamics(model).accelerations(
            np.array([kcs.U0]), np.array([0.0]), np.array([0.0]), np.array([0.0]),
            np.array([0.0]))
        assert acceleration[1][0] != 0.0  # the constant sway force accelerates the ship

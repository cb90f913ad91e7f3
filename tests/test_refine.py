"""Refinement of a fitted model by the error of its flights (sindyship.refine)."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

from sindyship.errors import SindyshipInputError
from sindyship.flights import fly_coefficient_sets, fly_like_batch
from sindyship.identify import fit
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel
from sindyship.refine import flight_residuals, refine


@pytest.fixture(scope="module")
def runs(kcs):
    """A closed-loop zig-zag and a shorter turning circle (two sampling grids)."""
    return fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=400),
                               Manoeuvre("turning-circle", rudder=-25, duration=300)])


@pytest.fixture(scope="module")
def fitted(runs, kcs):
    return fit(runs, kcs)


def _with(model: AbkowitzModel, changes: dict) -> AbkowitzModel:
    coefficients = {dof: dict(terms) for dof, terms in model.coefficients.items()}
    for (dof, term), value in changes.items():
        coefficients[dof][term] = value
    return AbkowitzModel(model.ship, model.library, coefficients, dict(model.optimizer),
                         model.rudder_signal, dict(model.info))


@pytest.mark.parametrize("compiled", [True, False])
def test_coefficient_sets_fly_as_the_models_they_stand_for(runs, fitted, compiled,
                                                           monkeypatch):
    if not compiled:
        monkeypatch.setenv("SINDYSHIP_NO_COMPILE", "1")
    model = _with(fitted, {})  # built under the setting
    if not compiled:
        assert model._compiled is None
    elif importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    changes = [{}, {("N", "r"): 1.3 * model.coefficients["N"]["r"],
                    ("Y", "delta"): 0.8 * model.coefficients["Y"]["delta"]}]
    together = fly_coefficient_sets(model, changes, runs)
    for change, flights in zip(changes, together, strict=True):
        alone = fly_like_batch(_with(model, change), runs)
        for a, b in zip(alone, flights, strict=True):
            assert len(a.t) == len(b.t)
            for channel in ("x", "y", "psi", "delta"):
                assert np.max(np.abs(np.asarray(a[channel]) - np.asarray(b[channel]))) < 1e-8
    # the changed set flies somewhere else (the sets are not all the first)
    moved = np.abs(np.asarray(together[1][0]["y"]) - np.asarray(together[0][0]["y"]))
    assert moved.max() > 10.0


def test_only_active_coefficients_change(fitted):
    model = _with(fitted, {("X", "du"): 0.0})
    with pytest.raises(SindyshipInputError, match=r"X\['du'\] is not active in this model"):
        model.weights_of([{("X", "du"): 1.0}])


def test_refinement_recovers_a_spoiled_coefficient(runs, fitted):
    """A yaw damping 30 % off flies the turn wrong; refining by the flights flies the records
    better than the equation-error fit itself, and brings the damping most of the way back
    (the rest is taken by terms these two records do not separate from it)."""
    spoiled = _with(fitted, {("N", "r"): 1.3 * fitted.coefficients["N"]["r"]})
    refined = refine(spoiled, runs, max_evaluations=16)
    report = refined.info["refined"]
    assert report["records"] == [r.name for r in runs]
    assert report["jacobians"] >= 1 and report["largest_change"] is not None
    fitted_flights = fly_like_batch(fitted, runs)
    fitted_residuals = flight_residuals(fitted_flights, runs, fitted.ship.L, fitted.ship.U0,
                                        20.0)
    assert report["cost_after"] < 0.5 * fitted_residuals @ fitted_residuals
    assert report["cost_after"] < 1e-3 * report["cost_before"]
    assert abs(refined.coefficients["N"]["r"] / fitted.coefficients["N"]["r"] - 1.0) < 0.15
    # the cost reported is the cost of the refined model's flights
    flights = fly_like_batch(refined, runs)
    residuals = flight_residuals(flights, runs, refined.ship.L, refined.ship.U0, 20.0)
    assert 0.5 * residuals @ residuals == pytest.approx(report["cost_after"], rel=1e-9)
    # only non-zero coefficients move; the library and the optimizer stay
    assert refined.library is spoiled.library
    assert refined.optimizer == spoiled.optimizer
    assert json.loads(json.dumps(refined.to_dict()))["info"]["refined"]["cost_after"] > 0


def test_a_diverged_sample_costs_the_fixed_residual(runs, kcs):
    (straight,) = fly(MMGModel(kcs), [Manoeuvre("straight", duration=100)])
    flown = straight.data.copy()
    flown.loc[50:, ["u", "v", "r", "x", "y"]] = np.nan
    from sindyship.trajectory import Trajectory

    residuals = flight_residuals([Trajectory(flown, name="f")], [straight], kcs.L, kcs.U0,
                                 10.0)
    assert residuals.size == 5 * 10
    assert np.count_nonzero(residuals == 10.0) == 5 * 5


@pytest.mark.parametrize("kwargs, message", [
    ({"max_evaluations": 0}, r"max_evaluations must be at least 1"),
    ({"sample_interval_s": -1.0}, r"sample_interval_s must be a positive number"),
    ({"sample_interval_s": float("nan")}, r"sample_interval_s must be a positive number"),
])
def test_refine_refuses_bad_settings_in_one_sentence(runs, fitted, kwargs, message):
    with pytest.raises(SindyshipInputError, match=message):
        refine(fitted, runs, **kwargs)
    with pytest.raises(SindyshipInputError, match=r"at least one record"):
        refine(fitted, [])


def test_a_refinement_that_lowers_nothing_keeps_the_fitted_coefficients(runs, fitted):
    """One evaluation is the starting point only: nothing is refined, and the report says so."""
    kept = refine(fitted, runs, max_evaluations=1)
    report = kept.info["refined"]
    assert report["cost_after"] == report["cost_before"]
    assert report["largest_change"] is None
    assert kept.coefficients == fitted.coefficients


def test_a_refined_prior_fit_records_its_own_stability(runs, kcs):
    prior = fit(runs, kcs, library="abkowitz-vr", optimizer="prior")
    refined = refine(prior, runs, max_evaluations=4)
    assert refined.optimizer["name"] == "prior"
    assert refined.info["straight_run"]["stable"] is refined.info["refined"][
        "straight_run_stable"]
    assert refined.info["straight_run"]["strength"] == prior.info["straight_run"]["strength"]


def test_a_prior_fit_stays_stable_in_straight_running(runs, kcs, fitted, monkeypatch):
    """A refinement that would make a straight-run-stable prior fit unstable keeps the fit;
    a least-squares fit, which promises nothing, is refined and reported unstable."""
    import sindyship.refine as refining
    from sindyship.stability import Stability

    prior = fit(runs, kcs, library="abkowitz-vr", optimizer="prior")
    assert prior.info["straight_run"]["stable"]
    unstable = Stability(eigenvalues=(0.1, -1.0), jacobian=np.eye(2), stable=False,
                         doubling_time_L_over_U=6.9)
    monkeypatch.setattr(refining, "straight_run_stability", lambda model: unstable)
    kept = refine(prior, runs, max_evaluations=4)
    assert kept.coefficients == prior.coefficients
    assert kept.info["refined"]["stopped"].startswith("the refined model was unstable")
    assert kept.info["refined"]["refused_unstable"]
    assert kept.info["refined"]["largest_change"] is None
    assert kept.info["straight_run"]["stable"] and kept.info["refined"]["straight_run_stable"]
    refined_ls = refine(fitted, runs, max_evaluations=4)
    assert refined_ls.coefficients != fitted.coefficients
    assert refined_ls.info["refined"]["straight_run_stable"] is False
    assert refined_ls.info["refined"]["refused_unstable"] is False

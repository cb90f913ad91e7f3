"""Ensembles, conditioning and the drift figure on the protocol's training set."""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest

from sindyship.errors import SindyshipInputError
from sindyship.identify import Design, design, resolve_library
from sindyship.targets import DOFS
from sindyship.uncertainty import (
    drift_figure,
    ensemble,
    library_conditioning,
    spread_vif_agreement,
)

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def problems(kcs, protocol_runs):
    return design(protocol_runs["train"], kcs, resolve_library("abkowitz"))


@pytest.fixture(scope="module")
def bagged(kcs, protocol_runs, problems):
    return ensemble(protocol_runs["train"], kcs, "ls", "bagging", n_models=40, seed=7,
                    n_jobs=1, problems=problems)


def test_ensembles_are_identical_bit_for_bit_whatever_n_jobs(kcs, protocol_runs, problems,
                                                              bagged):
    again = ensemble(protocol_runs["train"], kcs, "ls", "bagging", n_models=40, seed=7,
                     n_jobs=2, batch_size=3, problems=problems)
    for dof in DOFS:
        assert np.array_equal(bagged.coefficients[dof], again.coefficients[dof])
    other = ensemble(protocol_runs["train"], kcs, "ls", "bagging", n_models=40, seed=8,
                     n_jobs=1, problems=problems)
    assert not np.array_equal(bagged.coefficients["Y"], other.coefficients["Y"])
    # the stream of member k does not depend on how many members there are
    fewer = ensemble(protocol_runs["train"], kcs, "ls", "bagging", n_models=5, seed=7,
                     problems=problems)
    assert np.array_equal(fewer.coefficients["N"], bagged.coefficients["N"][:5])


def test_sparse_ensembles_give_inclusion_probabilities(kcs, protocol_runs, problems):
    result = ensemble(protocol_runs["train"], kcs, "stlsq", "bagging", n_models=8, seed=1,
                      n_jobs=2, problems=problems, block=100)
    serial = ensemble(protocol_runs["train"], kcs, "stlsq", "bagging", n_models=8, seed=1,
                      n_jobs=1, problems=problems, block=100)
    for dof in DOFS:
        p = result.inclusion(dof)
        assert p.shape == (len(result.terms[dof]),)
        assert np.all((p >= 0) & (p <= 1))
        assert np.array_equal(result.coefficients[dof], serial.coefficients[dof])
    # STLSQ drops some surge terms in some members (a probability strictly inside (0, 1))
    assert np.any((result.inclusion("X") > 0) & (result.inclusion("X") < 1))
    table = result.summary()
    assert len(table) == sum(len(result.terms[d]) for d in DOFS)
    assert table["inclusion"].between(0, 1).all()
    assert (table["q05"] <= table["q50"]).all() and (table["q50"] <= table["q95"]).all()
    json.dumps(result.to_dict())


def test_leave_one_manoeuvre_out_ensemble(kcs, protocol_runs, problems):
    result = ensemble(protocol_runs["train"], kcs, scheme="lomo", problems=problems)
    assert result.n_models == 8
    assert result.members[1] == "without tc35_stbd"
    assert np.all(result.inclusion("Y") == 1.0)
    assert np.all(result.std("N") > 0)


def test_conditioning_reports_condition_numbers_and_vifs(problems):
    report = library_conditioning(problems)
    for dof in DOFS:
        vif = report[dof]["vif"]
        assert np.isnan(vif["1"])  # the constant term has no VIF
        values = np.array([v for t, v in vif.items() if t != "1"])
        assert np.all(values >= 1.0)
        assert report[dof]["condition_number"] > 100  # the paper's "parameter drift"
        assert report[dof]["n_samples"] == 8 * 3200
    # Y and N share their terms, so their conditioning is the same
    np.testing.assert_array_equal(list(report["Y"]["vif"].values()),
                                  list(report["N"]["vif"].values()))


def test_vif_matches_its_definition_and_flags_exact_collinearity():
    rng = np.random.default_rng(0)
    a, b, c = rng.normal(size=(3, 400))
    X = np.column_stack([np.ones(400), a, b, a + 0.3 * b + 0.1 * c])
    vif = library_conditioning({"X": Design(X, a, np.zeros(400), ("1", "a", "b", "ab"))}
                               )["X"]["vif"]
    for j, term in ((1, "a"), (2, "b"), (3, "ab")):
        others = np.column_stack([np.ones(400)] + [X[:, k] for k in (1, 2, 3) if k != j])
        fitted = others @ np.linalg.lstsq(others, X[:, j], rcond=None)[0]
        r2 = 1 - np.sum((X[:, j] - fitted) ** 2) / np.sum((X[:, j] - X[:, j].mean()) ** 2)
        assert vif[term] == pytest.approx(1 / (1 - r2), rel=1e-8)
    X[:, 3] = X[:, 1] + X[:, 2]
    vif = library_conditioning({"X": Design(X, a, np.zeros(400), ("1", "a", "b", "ab"))}
                               )["X"]["vif"]
    assert all(np.isinf(vif[t]) for t in ("a", "b", "ab"))


def test_spreads_agree_with_variance_inflation(problems, bagged):
    agreement = spread_vif_agreement(bagged, library_conditioning(problems))
    # measured: pooled Spearman rho 0.931 over 57 terms (X 0.889, Y 0.975, N 0.966)
    assert agreement["n_terms"] == 57
    assert agreement["pooled"] >= 0.5
    assert min(agreement["per_equation"].values()) >= 0.5


def test_drift_figure_labels_every_term(bagged):
    ax = drift_figure(bagged, "Y")
    labels = {t.get_text() for t in ax.get_xticklabels()}
    assert labels == set(bagged.terms["Y"])
    image = ax.get_images()[0].get_array()
    assert image.shape == (22, 22)
    assert np.allclose(np.diag(image), 1.0)
    ax = drift_figure(bagged, "X", order="library")
    assert [t.get_text() for t in ax.get_yticklabels()] == list(bagged.terms["X"])
    import matplotlib.pyplot as plt

    plt.close("all")


def test_bad_arguments_are_input_errors(kcs, protocol_runs, problems, bagged):
    with pytest.raises(SindyshipInputError, match="unknown ensemble scheme 'jackknife'"):
        ensemble(protocol_runs["train"], kcs, scheme="jackknife", problems=problems)
    with pytest.raises(SindyshipInputError, match="at least 2 models"):
        ensemble(protocol_runs["train"], kcs, n_models=1, problems=problems)
    with pytest.raises(SindyshipInputError, match="block"):
        ensemble(protocol_runs["train"], kcs, block=0, problems=problems)
    with pytest.raises(SindyshipInputError, match="at least two training records"):
        ensemble(protocol_runs["train"][:1], kcs, scheme="lomo")
    with pytest.raises(SindyshipInputError, match="unknown equation 'K'"):
        bagged.std("K")


def test_an_ensemble_takes_a_ship_by_name(kcs, protocol_runs, problems):
    """A built-in ship's name stands for the ship, as in fit (it had raised AttributeError)."""
    by_name = ensemble(protocol_runs["train"], "kcs", n_models=2, seed=1, n_jobs=1,
                       problems=problems)
    by_ship = ensemble(protocol_runs["train"], kcs, n_models=2, seed=1, n_jobs=1,
                       problems=problems)
    for dof in DOFS:
        assert np.array_equal(by_name.coefficients[dof], by_ship.coefficients[dof])

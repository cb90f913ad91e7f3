"""Identification: theorems on data a known Abkowitz model generated, and the paper's set-up."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pysindy as ps
import pytest

from sindyship.evaluation import distance_errors
from sindyship.flights import fly_like_batch
from sindyship.identify import design, fit
from sindyship.library import AbkowitzFeatureLibrary, feature_matrix, load_library
from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.model import AbkowitzModel, paper_model
from sindyship.optimizers import LeastSquares
from sindyship.paper import ls_agreement
from sindyship.targets import DOFS, regression_targets

GOLDEN = json.loads((Path(__file__).parent / "golden" / "kcs.json").read_text())


@pytest.fixture(scope="module")
def generated(kcs):
    """Protocol training manoeuvres flown by the paper's LS Abkowitz model itself."""
    truth = paper_model(kcs, "LS")
    runs = fly(truth.dynamics(), protocol_manoeuvres()["train"])
    assert all(r.meta["diverged_at"] is None for r in runs)
    return truth, runs


def exact_problems(truth, runs, ship):
    """Design matrices with the generating model's exact accelerations."""
    dyn = truth.dynamics()
    out = {}
    for dof in DOFS:
        A, b = [], []
        for run in runs:
            acc = dyn.accelerations(run["u"], run["v"], run["r"], run["delta"], run["psi"])
            A.append(feature_matrix(truth.library.terms[dof], truth.variables(run)))
            b.append(regression_targets(run, ship, accelerations=acc)[dof])
        out[dof] = (np.vstack(A), np.concatenate(b))
    return out


def test_ls_recovers_every_coefficient_with_exact_accelerations(generated, kcs):
    truth, runs = generated
    for dof, (A, b) in exact_problems(truth, runs, kcs).items():
        coef = LeastSquares().fit(A, b).coef_.ravel()
        true = truth.coefficient_vector(dof)
        scale = np.maximum(np.abs(true), 1e-6 * np.abs(true).max())  # X_0 is exactly 0
        assert np.max(np.abs(coef - true) / scale) < 1e-6, dof


def test_stlsq_recovers_the_true_support(kcs):
    lasso_truth = paper_model(kcs, "Lasso")  # a sparse model: 30 of 60 coefficients are zero
    runs = fly(lasso_truth.dynamics(), protocol_manoeuvres()["train"])
    assert all(r.meta["diverged_at"] is None for r in runs)
    from sindyship.optimizers import STLSQ

    for dof, (A, b) in exact_problems(lasso_truth, runs, kcs).items():
        true = lasso_truth.coefficient_vector(dof)
        coef = STLSQ(threshold=1e-8).fit(A, b).coef_.ravel()
        # the constant column is the unpenalised intercept: it stays, at (numerically) zero
        const = [t.is_constant for t in lasso_truth.library.terms[dof]]
        assert np.all(np.abs(coef[const]) < 1e-10 * np.abs(true).max())
        coef[const] = 0.0
        np.testing.assert_array_equal(coef != 0, true != 0, err_msg=dof)
        np.testing.assert_allclose(coef[true != 0], true[true != 0], rtol=1e-6)


def test_five_point_differences_at_1hz_keep_median_error_below_1_percent(generated, kcs):
    truth, runs = generated
    model = fit(runs, kcs, optimizer="ls")
    rel = []
    for dof in DOFS:
        true = truth.coefficient_vector(dof)
        got = model.coefficient_vector(dof)
        mask = true != 0
        rel.extend(np.abs(got[mask] - true[mask]) / np.abs(true[mask]))
    assert np.median(rel) <= 1e-2


def test_lasso_and_svr_forces_within_10_percent_of_ls_on_held_out_records(generated, kcs):
    truth, runs = generated
    test = fly(truth.dynamics(), protocol_manoeuvres()["test"])
    rms = {}
    for method in ("ls", "lasso", "svr"):
        model = fit(runs, kcs, optimizer=method)
        errors = []
        for run in test:
            predicted = model.predict_forces(run)
            target = regression_targets(run, kcs)
            errors.extend((predicted[d] - target[d]) / np.std(target[d]) for d in DOFS)
        rms[method] = float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))
    assert rms["lasso"] <= 1.1 * rms["ls"]
    assert rms["svr"] <= 1.1 * rms["ls"]


def test_ls_reproduces_the_papers_table_7_to_9(protocol_runs, kcs):
    model = fit(protocol_runs["train"], kcs, optimizer="ls")
    agreement = ls_agreement(model.coefficients)
    assert agreement["n_coefficients"] == 59
    assert agreement["median_rel_dev"] < 0.15
    assert agreement["sign_agreement"] >= 0.95


def test_commanded_rudder_does_not_reproduce_the_paper(protocol_runs, kcs):
    model = fit(protocol_runs["train"], kcs, optimizer="ls", rudder_signal="commanded")
    assert ls_agreement(model.coefficients)["median_rel_dev"] > 0.5


def test_papers_ls_coefficients_fly_the_protocol_chain_check(protocol_runs, kcs):
    test = protocol_runs["test"]
    flown = fly_like_batch(paper_model(kcs, "LS").dynamics(), test)
    errors = {r.name: distance_errors(f, r, kcs.L)["mean_distance_L"]
              for f, r in zip(flown, test, strict=True)}
    assert errors["tc15_port"] == pytest.approx(0.294, abs=0.005)
    assert errors["tc15_stbd"] == pytest.approx(0.200, abs=0.005)
    for name, value in GOLDEN["paper_ls_flown"].items():
        assert errors[name] == pytest.approx(value, rel=1e-6)


def test_pysindy_path_equals_our_path(protocol_runs, kcs):
    library = load_library("abkowitz")
    records = protocol_runs["train"]
    model = fit(records, kcs, library=library, optimizer="ls")
    problems = design(records, kcs, library)
    values = [model.variables(r) for r in records]
    x = np.vstack([np.column_stack([v["du"], v["v"], v["r"]]) for v in values])
    u = np.concatenate([v["delta"] for v in values])[:, None]
    for dof in DOFS:
        sindy = ps.SINDy(feature_library=AbkowitzFeatureLibrary.for_dof(library, dof),
                         optimizer=LeastSquares())
        sindy.fit(x, t=1.0, x_dot=problems[dof].target[:, None], u=u,
                  feature_names=list(library.input_names))
        sindy.print(lhs=[f"{dof}'"])
        np.testing.assert_allclose(sindy.coefficients()[0], model.coefficient_vector(dof),
                                   rtol=1e-9, atol=1e-15)
        ours = np.concatenate([model.predict_forces(r)[dof] for r in records])
        np.testing.assert_allclose(sindy.predict(x, u=u)[:, 0], ours, rtol=1e-8,
                                   atol=1e-12 * np.abs(ours).max())


def test_saved_model_round_trip(tmp_path, protocol_runs, kcs):
    model = fit(protocol_runs["train"][:3], kcs, optimizer="lasso")
    path = tmp_path / "m.json"
    model.save(path)
    again = AbkowitzModel.load(path)
    assert again.coefficients == model.coefficients
    assert again.optimizer["name"] == "lasso"
    saved = json.loads(path.read_text())
    assert saved["format_version"] == 2
    assert saved["ship_definition"]["particulars"]["L"] == kcs.L and len(saved["ship_digest"]) == 64


def test_a_saved_format_1_model_still_loads_and_flies(kcs):
    """Saved models are a contract: files written by earlier versions keep loading."""
    path = Path(__file__).parent / "fixtures" / "model-format1-lasso.json"
    model = AbkowitzModel.load(path)
    assert model.optimizer["name"] == "lasso"
    assert model.library.name == "abkowitz"
    assert model.coefficients["Y"]["v"] == pytest.approx(
        json.loads(path.read_text())["coefficients"]["Y"]["v"])
    (run,) = fly(model.dynamics(), protocol_manoeuvres(600.0)["test"][:1])
    assert run.meta["diverged_at"] is None


def test_records_without_the_actual_rudder_are_fitted_on_the_command(kcs, protocol_runs):
    """A fit that took the commanded angle for the actual one counted the steering gear's lag
    twice when flown (the held-out zig-zag 5.6 L off): records that all lack ``delta`` are
    fitted on the command, with a note, and records that mix are refused."""
    import warnings

    from sindyship.errors import RudderSignalNote, SindyshipInputError
    from sindyship.trajectory import Trajectory

    train = protocol_runs["train"]
    commanded_only = [Trajectory(r.data.drop(columns=["delta"]), r.name) for r in train]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = fit(commanded_only, kcs)
    assert model.rudder_signal == "commanded"
    assert [w.category for w in caught].count(RudderSignalNote) == 1
    assert model.coefficients == fit(train, kcs, rudder_signal="commanded").coefficients
    (flown,) = fly_like_batch(model.dynamics(), [protocol_runs["test"][2]])
    assert distance_errors(flown, protocol_runs["test"][2], kcs.L)["mean_distance_L"] < 3.0
    with pytest.raises(SindyshipInputError, match="spiral_port has no actual rudder angle"):
        fit(train[:-1] + commanded_only[-1:], kcs)


def test_a_record_too_short_to_difference_is_named(kcs):
    """Fewer than five samples cannot be differenced; the message names the record (it had
    said only "a record needs at least 5 samples")."""
    from dataclasses import replace

    from sindyship.errors import SindyshipInputError
    from sindyship.manoeuvres import Manoeuvre
    from sindyship.mmg import MMGModel

    runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=100),
                               Manoeuvre("turning-circle", rudder=20, duration=100)])
    tiny = replace(runs[1], data=runs[1].data.iloc[:3].reset_index(drop=True), name="tiny")
    with pytest.raises(SindyshipInputError, match=r"^tiny has 3 samples; 5-point differences "
                       r"need at least 5: give a longer record\.$"):
        fit([runs[0], tiny], kcs)

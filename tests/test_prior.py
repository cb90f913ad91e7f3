"""The physics-consistent fit: PriorRidge, the ship's prior and the ``prior`` optimizer."""

import json
import math
import warnings

import numpy as np
import pytest

from sindyship.captive import captive_tests
from sindyship.forces import compare_forces, model_captive_forces
from sindyship.identify import fit
from sindyship.library import load_library
from sindyship.model import AbkowitzModel
from sindyship.optimizers import LeastSquares, PriorRidge, RowFactor, make_optimizer
from sindyship.priors import (
    prior_means,
    prior_parameters,
    prior_widths,
    semi_empirical_derivatives,
)

SWEEPS = ("static-drift", "pure-yaw", "drift-yaw")


def test_zero_strength_is_least_squares(seed):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(300, 6))
    y = X @ rng.normal(size=6) + 0.01 * rng.normal(size=300)
    prior = PriorRidge(strength=0.0, mean=np.ones(6), scale=np.full(6, 0.1)).fit(X, y)
    assert np.allclose(prior.coef_, LeastSquares().fit(X, y).coef_, rtol=1e-10, atol=1e-12)


def test_prior_decides_only_what_the_data_cannot(seed):
    rng = np.random.default_rng(seed)
    v = rng.uniform(-0.3, 0.3, 400)
    r = rng.uniform(-0.3, 0.3, 400)
    X = np.column_stack([v, r, v])  # columns 0 and 2 are the same: only their sum is known
    y = X @ np.array([-0.01, 0.003, -0.02])
    model = PriorRidge(strength=1e-6, mean=[-0.012, 0.0, 0.0], scale=[0.002, None, None])
    coef = model.fit(X, y).coef_[0]
    assert coef[0] + coef[2] == pytest.approx(-0.03, rel=1e-6)  # the data's combination
    assert coef[1] == pytest.approx(0.003, rel=1e-6)
    assert coef[0] == pytest.approx(-0.012 - 0.0, abs=2e-4)  # the prior's split


def test_relation_draws_one_coefficient_toward_a_multiple_of_another():
    v = np.linspace(-0.3, 0.3, 101)
    X = np.column_stack([v, v])
    coef = PriorRidge(strength=1e-6, relations=[(1, 0, 2.0)]).fit(X, -0.03 * v).coef_[0]
    # the data fix w0 + w1 = -0.03; the prior rows (both of weight ||v||) minimise
    # w0^2 + (w1 - 2 w0)^2 on that line: w0 = -0.009, w1 = -0.021
    assert coef == pytest.approx([-0.009, -0.021], rel=1e-4)
    mean = np.array([-0.01, 5.0])  # the relation replaces column 1's mean, not the caller's
    PriorRidge(strength=1e-6, mean=mean, relations=[(1, 0, 2.0)]).fit(X, -0.03 * v)
    assert mean.tolist() == [-0.01, 5.0]


@pytest.mark.parametrize("params, message", [
    ({"mean": [0.0]}, r"the prior mean has 1 value\(s\) for 2 columns"),
    ({"mean": [None, 0.1]}, "the prior mean of column 0 is not a finite number"),
    ({"scale": [0.1, -1.0]}, "the prior scale of column 1 is not a positive number"),
    ({"scale": [np.inf, None]}, "the prior scale of column 0 is not a positive number"),
    ({"relations": [(1, 1, 2.0)]}, "relate two columns"),
    ({"relations": [(1, 0, np.nan)]}, "not two column numbers and a finite factor"),
])
def test_bad_prior_is_refused_in_one_sentence(params, message):
    X = np.column_stack([np.linspace(0, 1, 20), np.linspace(1, 0, 20) ** 2])
    with pytest.raises(ValueError, match=message):
        PriorRidge(**params).fit(X, X[:, 0])


def test_fit_from_factors_equals_fit_on_rows(seed):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(600, 5))
    X[:, 4] = X[:, 3] + 1e-6 * rng.normal(size=600)
    y = X @ rng.normal(size=5)
    params = {"strength": 1e-5, "mean": [0, 0, 0, 0.5, 0.5], "scale": [None] * 3 + [0.2, 0.2]}
    rows = PriorRidge(**params).fit(X, y).coef_
    factors = [RowFactor.of_rows(X[k:k + 200], y[k:k + 200]) for k in (0, 200, 400)]
    streamed = PriorRidge(**params).fit_factors(factors).coef_
    assert np.allclose(streamed, rows, rtol=1e-9, atol=1e-12)


def test_clarke_linear_derivatives_of_the_kcs(kcs):
    p = kcs.particulars
    c_b = p.displacement / (p.L * p.B * p.d)
    base = math.pi * (p.d / p.L) ** 2
    y_v = -base * (1 + 0.4 * c_b * p.B / p.d)  # Clarke et al. (1983)
    n_r = -base * (0.25 + 0.039 * p.B / p.d - 0.56 * p.B / p.L)
    captive = semi_empirical_derivatives(kcs)
    assert captive["Y"]["v"] == pytest.approx(y_v, rel=1e-12)
    assert captive["N"]["r"] == pytest.approx(n_r, rel=1e-12)
    assert captive["Y"]["v"] * 1e5 == pytest.approx(-1230, abs=1)  # MMG Taylor -1292
    widths = prior_widths(kcs)
    assert widths["Y"]["v"] == pytest.approx(0.5 * abs(captive["Y"]["v"]))
    largest = max(abs(v) for terms in captive.values() for t, v in terms.items()
                  if t not in ("v", "r"))
    assert widths["N"]["r^3"] == pytest.approx(0.5 * 0.1 * largest)  # the floor
    assert captive["N"]["v^2 r"] / (p.d / p.L) == pytest.approx(1.55 * c_b * p.B / p.L - 0.76)


def test_prior_means_predict_the_semi_empirical_captive_forces(kcs):
    """The conversion to fitted coefficients undoes the added-mass terms that
    model_captive_forces adds back: a model of the prior means predicts captive forces whose
    slopes are the semi-empirical derivatives."""
    library = load_library("abkowitz")
    means = prior_means(kcs)
    model = AbkowitzModel(ship=kcs, library=library, coefficients={
        dof: {t.text: means[dof].get(t.canonical(), 0.0) for t in library.terms[dof]}
        for dof in "XYN"})
    small = captive_tests(kcs, "all", points=3)
    scale = 0.5 * kcs.particulars.rho * kcs.U0**2 * kcs.L**2
    predicted = model_captive_forces(model, small)
    v = small["v"].to_numpy() / kcs.U0
    r = small["r"].to_numpy() * kcs.L / kcs.U0
    captive = semi_empirical_derivatives(kcs)
    pure_yaw = (np.abs(v) < 1e-12) & (r > 0) & (small["delta"].to_numpy() == 0)
    k = np.flatnonzero(pure_yaw)[0]
    expected_n = captive["N"]["r"] * r[k] + captive["N"]["r^3"] * r[k] ** 3
    assert predicted["N"].iloc[k] / (scale * kcs.L) == pytest.approx(expected_n, rel=1e-9)
    expected_y = captive["Y"]["r"] * r[k] + captive["Y"]["r^3"] * r[k] ** 3
    assert predicted["Y"].iloc[k] / scale == pytest.approx(expected_y, rel=1e-9)
    # drift with yaw at the design speed: every linear term, the Munk moment's conversion
    # (N'_v) the largest; the cubic terms in v and r as they are
    combined = small.iloc[:1].assign(u=kcs.U0, v=-0.1 * kcs.U0, r=0.2 * kcs.U0 / kcs.L,
                                     delta=0.0)
    n_pred = model_captive_forces(model, combined)["N"].iloc[0] / (scale * kcs.L)
    v1, r1 = -0.1, 0.2
    n = captive["N"]
    expected = (n["v"] * v1 + n["r"] * r1 + n["v^3"] * v1**3 + n["v^2 r"] * v1**2 * r1
                + n["v r^2"] * v1 * r1**2 + n["r^3"] * r1**3)
    assert n_pred == pytest.approx(expected, rel=1e-9)


def test_prior_parameters_cover_every_column(kcs):
    terms = load_library("abkowitz").terms
    params = prior_parameters(kcs, "Y", [t.text for t in terms["Y"]])
    texts = [t.text for t in terms["Y"]]
    assert len(params["mean"]) == len(params["scale"]) == len(texts)
    assert params["scale"][texts.index("v")] == pytest.approx(
        0.5 * abs(params["mean"][texts.index("v")]))
    assert params["scale"][texts.index("delta")] is None  # no estimate: the weak prior
    assert [texts.index("du v"), texts.index("v"), 1.0] in params["relations"]
    json.dumps(params)  # saved with the model: plain JSON


def _mmg_captive_x_vr(ship, step=0.01) -> float:
    """X'_vr (Prime I) of the ship's MMG model as a dynamometer measures it: the mixed
    difference of the captive surge force about straight running at the design speed."""
    from sindyship.captive import _mmg_hydrodynamic

    def surge(v, r):
        state = [np.array([x]) for x in (ship.U0, v * ship.U0, r * ship.U0 / ship.L, 0.0)]
        return _mmg_hydrodynamic(ship, *state)[0][0]

    mixed = surge(step, step) - surge(step, -step) - surge(-step, step) + surge(-step, -step)
    return mixed / (4 * step**2) / (0.5 * ship.particulars.rho * ship.U0**2 * ship.L**2)


@pytest.mark.parametrize(("name", "mmg"), [("kcs", 509e-5), ("kvlcc2", 1723e-5)])
def test_the_surge_derivative_x_vr_is_the_dynamometers(name, mmg):
    """Yoshimura & Masumoto's X'_vr includes the added-mass term m'_y v' r': it is within 30 %
    of both MMG models' captive X'_vr (not of their hull coefficients 0.047 d/L and 0.002 d/L
    without it), and the fitted prior mean moves from the captive value as the MMG's fitted
    (Taylor) X'_vr moves from its captive one."""
    from sindyship.ships import load_ship
    from sindyship.taylor import taylor_reference

    ship = load_ship(name)
    captive = _mmg_captive_x_vr(ship)
    assert captive == pytest.approx(mmg, rel=1e-3)
    estimate = semi_empirical_derivatives(ship)["X"]["v r"]
    assert estimate == pytest.approx(mmg, rel=0.3)
    fitted = taylor_reference(ship, load_library("abkowitz-vr"))["X"]["v r"]
    assert prior_means(ship)["X"]["v r"] - estimate == pytest.approx(fitted - captive,
                                                                     rel=1e-4)


def test_a_prior_fit_warns_of_estimates_its_library_has_no_term_for(kcs, protocol_runs):
    from sindyship.priors import PriorCoverageNote

    zigzags = [r for r in protocol_runs["train"] if r.name.startswith("zz")]
    with pytest.warns(PriorCoverageNote, match="The library 'abkowitz' has no X term 'v r'"):
        fit(zigzags, kcs, optimizer="prior")
    with warnings.catch_warnings():
        warnings.simplefilter("error", PriorCoverageNote)
        fit(zigzags, kcs, optimizer="prior", library="abkowitz-vr")
        fit(zigzags, kcs)  # least squares has no prior to cover


@pytest.fixture(scope="module")
def protocol_prior(kcs, protocol_runs):
    """The prior fit on the protocol's training set and its captive agreement."""
    model = fit(protocol_runs["train"], kcs, optimizer="prior", library="abkowitz-vr")
    return model, compare_forces(model, captive_tests(kcs, "all", points=11)).to_dict()[
        "by_test"]


def test_prior_fit_of_the_training_set_agrees_with_every_captive_force(protocol_prior):
    """The paper's training set, the library with v r: X, Y and N agree with the MMG's
    captive forces (correlation >= 0.95) in static drift, rudder, pure yaw and both."""
    by_test = protocol_prior[1]
    for test in (*SWEEPS, "rudder"):
        for dof in "XYN":
            assert by_test[test][dof]["correlation"] >= 0.95, (test, dof)


def test_without_v_r_the_surge_force_in_pure_yaw_has_the_wrong_sign(kcs, protocol_runs):
    model = fit(protocol_runs["train"], kcs, optimizer="prior")
    by_test = compare_forces(model, captive_tests(kcs, "pure-yaw", points=11)).to_dict()[
        "by_test"]
    assert by_test["pure-yaw"]["X"]["correlation"] < 0.0


@pytest.fixture(scope="module")
def zigzag_fits(kcs, protocol_runs):
    """Least squares and the prior fit (library with v r) on the three zig-zags alone."""
    zigzags = [r for r in protocol_runs["train"] if r.name.startswith("zz")]
    captive = captive_tests(kcs, "all", points=11)
    out = {}
    for name, library in (("ls", "abkowitz"), ("prior", "abkowitz-vr")):
        model = fit(zigzags, kcs, optimizer=name, library=library)
        out[name] = (model, compare_forces(model, captive).to_dict()["by_test"])
    return out


def test_prior_keeps_the_forces_where_least_squares_loses_them(zigzag_fits):
    """Identified on zig-zags alone: the prior fit's X, Y and N agree with the MMG's captive
    forces (correlation >= 0.9 on every sweep); least squares' Y and N do not."""
    prior = zigzag_fits["prior"][1]
    least = zigzag_fits["ls"][1]
    for test in SWEEPS:
        for dof in "XYN":
            assert prior[test][dof]["correlation"] >= 0.9, (test, dof)
    assert min(least[t][d]["correlation"] for t in SWEEPS for d in "YN") < 0.0


def test_prior_fit_is_saved_with_its_prior_and_stability(zigzag_fits, tmp_path):
    model = zigzag_fits["prior"][0]
    model.save(tmp_path / "m.json")
    data = json.loads((tmp_path / "m.json").read_text())
    assert data["optimizer"] == {"name": "prior", "params": {"strength": 1e-5}}
    assert data["info"]["straight_run"] == {"stable": True, "strength": 1e-5, "raised": 0}
    y_terms = [t.text for t in model.library.terms["Y"]]
    assert data["info"]["prior"]["Y"]["mean"][y_terms.index("v")] == pytest.approx(
        prior_means(model.ship)["Y"]["v"])


def test_unstable_fit_raises_the_prior_strength(kcs, protocol_runs, monkeypatch):
    import sindyship.stability as stability

    real = stability.straight_run_stability
    calls = []

    def unstable_twice(model):
        calls.append(model.optimizer["params"]["strength"])
        result = real(model)
        return result if len(calls) > 2 else type(result)(
            result.eigenvalues, result.jacobian, False, 1.0)

    monkeypatch.setattr(stability, "straight_run_stability", unstable_twice)
    zigzags = [r for r in protocol_runs["train"] if r.name.startswith("zz")]
    model = fit(zigzags, kcs, optimizer="prior")
    assert calls == pytest.approx([1e-5, 1e-4, 1e-3])
    assert model.info["straight_run"] == {"stable": True, "strength": pytest.approx(1e-3),
                                          "raised": 2}
    assert model.optimizer["params"]["strength"] == pytest.approx(1e-3)


@pytest.fixture
def never_stable(monkeypatch):
    """Every straight-run stability check finds the model unstable; the strengths of the
    models it checked, in order."""
    import sindyship.stability as stability

    real = stability.straight_run_stability
    calls = []

    def always_unstable(model):
        calls.append(model.optimizer["params"]["strength"])
        result = real(model)
        return type(result)(result.eigenvalues, result.jacobian, False, 1.0)

    monkeypatch.setattr(stability, "straight_run_stability", always_unstable)
    return calls


def test_an_unstable_fit_at_strength_zero_raises_from_a_floor_and_says_how_it_ended(
        kcs, protocol_runs, never_stable, capsys):
    from sindyship.cli.fit import report_prior_fit

    calls = never_stable
    zigzags = [r for r in protocol_runs["train"] if r.name.startswith("zz")]
    model = fit(zigzags, kcs, optimizer="prior", params={"strength": 0.0})
    assert calls == pytest.approx([0.0, 1e-7, 1e-6, 1e-5])
    assert model.info["straight_run"] == {"stable": False, "strength": pytest.approx(1e-5),
                                          "raised": 3}
    report_prior_fit(model)
    err = capsys.readouterr().err
    assert "warning: the model is unstable in straight running" in err and "1e-05" in err


@pytest.mark.parametrize(("start", "tried"), [(0.1, [0.1, 1.0]), (1.0, [1.0])])
def test_raises_stop_at_the_largest_strength_and_the_advice_fits(
        kcs, protocol_runs, never_stable, capsys, start, tried):
    from sindyship.cli.fit import report_prior_fit

    calls = never_stable
    zigzags = [r for r in protocol_runs["train"] if r.name.startswith("zz")]
    model = fit(zigzags, kcs, optimizer="prior", library="abkowitz-vr",
                params={"strength": start})
    assert calls == pytest.approx(tried)
    assert model.info["straight_run"]["strength"] == pytest.approx(1.0)
    report_prior_fit(model)
    err = capsys.readouterr().err
    assert "unstable in straight running even with the prior's strength" in err
    assert "a larger --prior-strength" not in err  # 1 is the largest there is


def test_the_identifiability_ensemble_uses_the_strength_the_fit_ended_with(
        kcs, protocol_runs, monkeypatch, tmp_path):
    import sindyship.identifiability as identifiability
    import sindyship.stability as stability
    from sindyship.cli import main
    from sindyship.measurements import write_csv

    real = stability.straight_run_stability
    seen = []

    def unstable_at_first(model):
        result = real(model)
        weak = model.optimizer["params"]["strength"] < 1e-4
        return type(result)(result.eigenvalues, result.jacobian, not weak, 1.0)

    def recorded(*args, **kwargs):
        seen.append(kwargs["params"])
        raise SystemExit("recorded")

    monkeypatch.setattr(stability, "straight_run_stability", unstable_at_first)
    monkeypatch.setattr(identifiability, "identifiability", recorded)
    paths = [str(write_csv(r, tmp_path / f"{r.name}.csv")) for r in protocol_runs["train"]
             if r.name.startswith("zz")]
    with pytest.raises(SystemExit, match="recorded"):
        main(["fit", *paths, "--optimizer", "prior", "--library", "abkowitz-vr", "--out",
              str(tmp_path / "m.json")])
    assert seen == [{"strength": pytest.approx(1e-4)}]


def test_make_optimizer_knows_prior():
    assert isinstance(make_optimizer("prior", strength=1e-4), PriorRidge)


def test_fit_takes_the_prior_strength_and_refuses_it_for_another_optimizer(protocol_runs,
                                                                            tmp_path, capsys):
    from sindyship.cli import main
    from sindyship.measurements import write_csv

    paths = [str(write_csv(r, tmp_path / f"{r.name}.csv")) for r in protocol_runs["train"]
             if r.name.startswith("zz")]
    out = tmp_path / "m.json"
    assert main(["fit", *paths, "--optimizer", "prior", "--library", "abkowitz",
                 "--prior-strength", "1e-7", "--refine", "0", "--no-identifiability", "--out",
                 str(out)]) == 0
    saved = json.loads(out.read_text())
    assert saved["optimizer"]["params"] == {"strength": 1e-7}
    # the paper's library has no v r in X: the fit says so, once, and names the library that
    # has it; so does a diagnosis with the prior
    err = capsys.readouterr().err
    assert err.count("note: the library 'abkowitz' has no X term 'v r' for the prior's "
                     "estimate") == 1
    assert "fit on the library 'abkowitz-vr', which has it." in err
    assert "Warning" not in err
    assert main(["fit", *paths, "--optimizer", "prior", "--refine", "0",
                 "--no-identifiability", "--out", str(tmp_path / "vr.json")]) == 0
    assert "has no" not in capsys.readouterr().err
    assert main(["diagnose", *paths, "--optimizer", "prior", "--rounds", "1", "--confirm",
                 "0", "--json"]) == 0
    err = capsys.readouterr().err
    assert err.count("has no X term 'v r'") == 1 and "Warning" not in err
    assert main(["fit", *paths, "--optimizer", "ls", "--prior-strength", "1e-7", "--out",
                 str(tmp_path / "n.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("sindyship fit: error: --prior-strength weighs the prior of "
                       "--optimizer prior, not of ls; add --optimizer prior or drop "
                       "--prior-strength.")
    assert not (tmp_path / "n.json").exists()


def test_the_diagnosis_verdict_keeps_the_prior_optimizer(kcs, protocol_runs):
    from sindyship.diagnose import diagnose

    result = diagnose(protocol_runs["train"], kcs, optimizer="prior", fly_training=False,
                      confirm=0)
    assert result.verdict == "add-effect"
    assert "--effects asymmetry --optimizer prior;" in " ".join(result.report().split())

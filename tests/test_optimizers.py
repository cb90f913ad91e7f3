"""Tests of the regression back-ends (sindyship.optimizers).

Synthetic libraries imitate the real problem: monomials up to third order of smooth, strongly
correlated signals du, v, r, delta (v follows r, r follows delta, du follows r^2), one group
of samples per "manoeuvre", a constant column, and coefficients of the sizes of the paper's
Tables 7-9.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pysindy as ps
import pytest
import scipy.linalg
from numpy.testing import assert_allclose, assert_array_equal
from sklearn.base import clone
from sklearn.linear_model import lasso_path
from sklearn.model_selection import GroupKFold, KFold, LeaveOneGroupOut
from sklearn.svm import LinearSVR
from sklearn.utils.estimator_checks import parametrize_with_checks

from sindyship import optimizers as opt
from sindyship.errors import SindyshipInputError
from sindyship.optimizers import (
    OPTIMIZERS,
    STLSQ,
    SVR,
    ForwardSelection,
    GroupedProblem,
    LassoCV,
    LeastSquares,
    LeaveOneTrajectoryOut,
    make_optimizer,
)

TERMS = [
    "1",
    "du",
    "v",
    "r",
    "delta",
    "du v",
    "du r",
    "v^3",
    "r^3",
    "delta^3",
    "v^2 r",
    "r^2 v",
    "v^2 delta",
    "r^2 delta",
    "v r delta",
]
# Sway-like coefficients (Table 8 sizes), dense, and a sparse variant.
W_DENSE = 1e-5 * np.array(
    [0.43, -22.1, -1257.6, 263.5, -246.1, 8879.9, 3777.3, -19940.8, -821.3, 55.2, -23025.3,
     -8581.0, 6067.1, 613.6, 4306.1]
)  # fmt: skip
W_SPARSE = np.where(np.isin(np.arange(len(TERMS)), [0, 2, 3, 4, 7, 10]), W_DENSE, 0.0)


def _signals(rng: np.random.Generator, n_groups: int, n_per_group: int) -> list[np.ndarray]:
    """Smooth, correlated du, v, r, delta per group (rows: samples; columns: du, v, r, delta)."""
    t = np.arange(n_per_group) / n_per_group
    out = []
    for _ in range(n_groups):
        amp, freq, phase, bias = rng.uniform([0.1, 1.0, 0, -0.2], [0.6, 4.0, 2 * np.pi, 0.2])
        delta = np.clip(bias + amp * np.sin(2 * np.pi * freq * t + phase), -0.61, 0.61)
        r = 0.9 * np.sin(2 * np.pi * freq * t + phase - 0.5) * amp + 0.8 * bias
        r += 0.05 * np.sin(2 * np.pi * 7.3 * t + rng.uniform(0, 2 * np.pi))
        v = -0.35 * r + 0.03 * np.cos(2 * np.pi * 5.1 * t + rng.uniform(0, 2 * np.pi))
        du = -0.8 * r**2 - 0.3 * v**2 + 0.01 * np.sin(2 * np.pi * 3.7 * t)
        out.append(np.column_stack([du, v, r, delta]))
    return out


def _library(S: np.ndarray) -> np.ndarray:
    index = {"du": 0, "v": 1, "r": 2, "delta": 3}
    cols = []
    for term in TERMS:
        col = np.ones(S.shape[0])
        if term != "1":
            for factor in term.split():
                base, _, power = factor.partition("^")
                col = col * S[:, index[base]] ** int(power or 1)
        cols.append(col)
    return np.column_stack(cols)


def _problem(
    seed: int, n_groups: int = 6, n_per_group: int = 400
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(library X, state S, groups)."""
    S = np.vstack(_signals(np.random.default_rng(seed), n_groups, n_per_group))
    return _library(S), S, np.repeat(np.arange(n_groups), n_per_group)


def _misfit(S: np.ndarray, size: float) -> np.ndarray:
    """A deterministic force that no library term can represent (fifth-order terms)."""
    extra = S[:, 1] ** 5 + S[:, 2] ** 5 + 0.3 * np.tanh(3 * S[:, 3]) * S[:, 2] ** 2
    return size * extra / np.std(extra)


def _rms(a: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a))))


@pytest.fixture(scope="module")
def problem() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _problem(seed=0)


# ------------------------------------------------------------------------------------------
# The scikit-learn estimator contract
# ------------------------------------------------------------------------------------------

SMALL = [
    LeastSquares(),
    LeastSquares(column_scaling=False),
    STLSQ(n_thresholds=5),
    STLSQ(threshold=0.1),
    LassoCV(alphas=8),
    LassoCV(alphas=8, selection="one_se"),
    SVR(Cs=[1.0, 100.0], epsilons=[0.0, 0.1]),
    SVR(Cs=[1.0], epsilons=[0.0, 0.1], solver="liblinear"),
    ForwardSelection(n_fixed=1, max_terms=2),
]


@pytest.mark.filterwarnings("ignore:no groups given")  # scikit-learn's checks pass no groups
@parametrize_with_checks(SMALL)
def test_sklearn_contract(estimator, check):
    # No check is expected to fail (expected_failed_checks is not needed).
    check(estimator)


@pytest.mark.parametrize("name", sorted(OPTIMIZERS))
def test_default_params_are_json(name):
    params = make_optimizer(name).get_params()
    assert json.loads(json.dumps(params)) == params
    assert clone(make_optimizer(name, **params)).get_params() == params


def test_make_optimizer_unknown_name_lists_the_valid_ones():
    with pytest.raises(SindyshipInputError) as info:
        make_optimizer("ridge")
    message = str(info.value)
    assert all(repr(name) in message for name in OPTIMIZERS)
    assert message.count(".") == 1 and "\n" not in message


def test_make_optimizer_unknown_parameter():
    with pytest.raises(SindyshipInputError, match="'alpha'.*alphas"):
        make_optimizer("lasso", alpha=0.1)


def test_make_optimizer_builds_the_named_class():
    for name, cls in OPTIMIZERS.items():
        assert type(make_optimizer(name)) is cls
    assert make_optimizer("stlsq", threshold=0.2).threshold == 0.2


# ------------------------------------------------------------------------------------------
# Shapes and the constant column
# ------------------------------------------------------------------------------------------

FAST = {
    "ls": {},
    "stlsq": {"n_thresholds": 8},
    "lasso": {"alphas": 20},
    "svr": {"Cs": [1.0, 1e4], "epsilons": [0.0, 0.05]},
    "prior": {"strength": 1e-9},
}


@pytest.mark.parametrize("name", sorted(FAST))
def test_shapes(problem, name):
    X, S, groups = problem
    y = X @ W_DENSE
    model = make_optimizer(name, **FAST[name]).fit(X, y, groups=groups)
    assert model.coef_.shape == (1, X.shape[1])
    assert model.predict(X).shape == y.shape
    Y = np.column_stack([y, 2 * y + X[:, 2]])
    model = make_optimizer(name, **FAST[name]).fit(X, Y, groups=groups)
    assert model.coef_.shape == (2, X.shape[1])
    assert model.predict(X).shape == Y.shape
    for attr in ("threshold_", "alpha_", "C_", "epsilon_"):
        if hasattr(model, attr):
            assert getattr(model, attr).shape == (2,)


@pytest.mark.parametrize("name", ["stlsq", "lasso", "svr"])
def test_scaled_constant_column_is_the_intercept(problem, name):
    X, S, groups = problem
    X2 = X.copy()
    X2[:, 0] = 2.5  # the constant term need not be 1
    y = X2 @ W_SPARSE + _misfit(S, 1e-6)
    ls = LeastSquares().fit(X2, y)
    model = make_optimizer(name, **FAST[name]).fit(X2, y, groups=groups)
    # the intercept is unpenalised: at the (near-)least-squares solution it matches LS
    assert model.coef_[0, 0] == pytest.approx(ls.coef_[0, 0], rel=0.1, abs=1e-7)


def test_intercept_is_never_thresholded(problem):
    X, S, groups = problem
    y = X @ W_SPARSE
    model = STLSQ(threshold=1e6).fit(X, y)
    assert np.flatnonzero(model.coef_[0]).tolist() == [0]
    assert model.coef_[0, 0] == pytest.approx(np.mean(y))


def test_without_constant_column_the_model_goes_through_the_origin(problem):
    X, S, groups = problem
    y = X[:, 1:] @ W_SPARSE[1:]
    for name in FAST:
        model = make_optimizer(name, **FAST[name]).fit(X[:, 1:], y, groups=groups)
        assert_allclose(model.predict(np.zeros((1, X.shape[1] - 1))), [0.0], atol=0)


def test_duplicate_and_zero_columns_get_zero_coefficients(problem):
    X, S, groups = problem
    X3 = np.column_stack([X, np.ones(X.shape[0]), np.zeros(X.shape[0])])
    y = X @ W_SPARSE
    for name in ("stlsq", "lasso", "svr"):
        model = make_optimizer(name, **FAST[name]).fit(X3, y, groups=groups)
        assert_allclose(model.coef_[0, -2:], 0.0, atol=0)


# ------------------------------------------------------------------------------------------
# Theorem-style numbers
# ------------------------------------------------------------------------------------------


def test_least_squares_recovers_exact_coefficients(problem):
    X, S, groups = problem
    assert np.linalg.cond(X / np.linalg.norm(X, axis=0)) > 1e3  # genuinely ill-conditioned
    y = X @ W_DENSE
    for scaling in (True, False):
        model = LeastSquares(column_scaling=scaling).fit(X, y)
        assert_allclose(model.coef_[0], W_DENSE, rtol=1e-9)
        assert model.rank_ == X.shape[1]


def test_stlsq_recovers_exact_support_and_coefficients(problem):
    X, S, groups = problem
    y = X @ W_SPARSE
    model = STLSQ().fit(X, y, groups=groups)
    assert_allclose(model.coef_[0], W_SPARSE, rtol=1e-9, atol=0)
    assert np.array_equal(model.coef_[0] != 0, W_SPARSE != 0)
    grid = model.cv_results_["threshold"][0]
    assert grid.shape == (30,) and np.all(np.diff(grid) > 0)
    assert model.threshold_[0] in grid
    k = int(np.flatnonzero(grid == model.threshold_[0])[0])
    assert_allclose(model.coef_path_[0, :, k], model.coef_[0])


def test_stlsq_threshold_acts_on_standardised_coefficients(problem):
    X, S, groups = problem
    y = X @ W_SPARSE
    # rescaling a column (v -> 1000 v) changes its raw coefficient, not its selection
    Xb = X.copy()
    Xb[:, 7] *= 1e3  # v^3
    a = STLSQ(threshold=0.01).fit(X, y)
    b = STLSQ(threshold=0.01).fit(Xb, y)
    assert np.array_equal(a.coef_ != 0, b.coef_ != 0)
    assert_allclose(b.coef_[0, 7] * 1e3, a.coef_[0, 7], rtol=1e-8)
    # and scaling the target does not change the selection either
    c = STLSQ(threshold=0.01).fit(X, 1e4 * y)
    assert np.array_equal(a.coef_ != 0, c.coef_ != 0)


@pytest.mark.parametrize("name", ["lasso", "svr"])
def test_cv_estimators_end_close_to_least_squares(name):
    """Noise-free data with a model misfit: held-out RMS within 10 % of least squares.

    The force has no noise but contains fifth-order terms that the library lacks (as the
    real MMG forces do for the Abkowitz library); without any misfit, least squares would
    predict the held-out group to rounding error and no ratio would mean anything.
    """
    X, S, groups = _problem(seed=1, n_groups=7)
    y = X @ W_DENSE + _misfit(S, 0.02 * np.std(X @ W_DENSE))
    train, test = groups != 6, groups == 6
    ls = LeastSquares().fit(X[train], y[train])
    model = make_optimizer(name).fit(X[train], y[train], groups=groups[train])
    rms_ls = _rms(ls.predict(X[test]) - y[test])
    rms = _rms(model.predict(X[test]) - y[test])
    assert rms <= 1.1 * rms_ls, (rms, rms_ls)


def test_lasso_path_is_exact_against_coordinate_descent(problem):
    """Where coordinate descent converges (large penalties), the objectives agree."""
    X, S, groups = problem
    y = X @ W_DENSE + _misfit(S, 1e-4)
    Y = y[:, None]
    free, intercept = opt._column_roles(X)
    st = opt._Standardiser(X, Y, free, intercept)
    Xs, ys = st.transform_X(X), st.transform_Y(Y)[:, 0]
    R, Z, _ = opt._qr(Xs, ys[:, None])
    n = X.shape[0]
    alphas = np.abs(Xs.T @ ys).max() / n * np.array([0.5, 0.1, 0.02])
    W = opt._lasso_path_exact(R, Z[:, 0], n * alphas, max_events=1000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, W_cd, _ = lasso_path(Xs, ys, alphas=alphas, tol=1e-14, max_iter=100_000)

    def objective(w, a):
        return 0.5 / n * np.sum((ys - Xs @ w) ** 2) + a * np.abs(w).sum()

    for k, a in enumerate(alphas):
        assert objective(W[:, k], a) <= objective(W_cd[:, k], a) * (1 + 1e-12)
        assert_allclose(W[:, k], W_cd[:, k], atol=1e-7)


def test_lasso_path_satisfies_kkt_to_tiny_penalties(problem):
    """Optimality (KKT) holds along the whole default grid, down to near least squares."""
    X, S, groups = problem
    y = X @ W_DENSE + _misfit(S, 1e-5)
    model = LassoCV().fit(X, y, groups=groups)
    alphas = model.alphas_[0]
    assert alphas[-1] / alphas[0] < 1e-6  # ill-conditioned, noise-free: the grid goes deep
    free, intercept = opt._column_roles(X)
    st = opt._Standardiser(X, y[:, None], free, intercept)
    Xs, ys = st.transform_X(X), st.transform_Y(y[:, None])[:, 0]
    n = X.shape[0]
    for k in (10, 50, 99):
        w = model.coef_path_[0, free, k] * st.x_scale / st.y_scale[0]
        corr = Xs.T @ (ys - Xs @ w) / n
        on = w != 0
        assert np.all(np.abs(corr[~on]) <= alphas[k] * (1 + 1e-6))
        scale = np.abs(Xs.T @ ys).max() / n
        assert_allclose(corr[on], alphas[k] * np.sign(w[on]), rtol=0, atol=1e-12 * scale)


def test_lasso_selection_and_paths(problem):
    X, S, groups = problem
    y = X @ W_DENSE + _misfit(S, 1e-3 * np.std(X @ W_DENSE))
    best = LassoCV(alphas=40).fit(X, y, groups=groups)
    one_se = LassoCV(alphas=40, selection="one_se").fit(X, y, groups=groups)
    assert one_se.alpha_[0] >= best.alpha_[0]
    assert best.mse_path_.shape == (1, 40, 6)
    k = int(np.argmin(best.mse_path_[0].mean(axis=1)))
    assert best.alpha_[0] == best.alphas_[0, k]
    assert_allclose(best.coef_path_[0, :, k], best.coef_[0])
    assert np.count_nonzero(best.coef_path_[0, 1:, 0]) == 0  # alpha_max: nothing selected
    given = LassoCV(alphas=[1e-3, 1e-1, 1e-2]).fit(X, y, groups=groups)
    assert_allclose(given.alphas_[0], [1e-1, 1e-2, 1e-3])


def test_svr_newton_matches_liblinear_where_liblinear_converges(problem):
    X, S, groups = problem
    y = X @ W_DENSE + _misfit(S, 1e-4)
    Y = y[:, None]
    free, intercept = opt._column_roles(X)
    st = opt._Standardiser(X, Y, free, None)  # no intercept: liblinear's exact problem
    Xs, ys = st.transform_X(X), st.transform_Y(Y)[:, 0]
    Xb = opt._with_ones(Xs)
    for C, eps in [(0.1, 0.0), (1.0, 0.05)]:
        wb, _, ok = opt._svr_newton(Xb, ys, C, eps, np.zeros(Xb.shape[1]), False, 1e-14, 200)
        ref = LinearSVR(
            C=C,
            epsilon=eps,
            loss="squared_epsilon_insensitive",
            dual=False,
            fit_intercept=False,
            tol=1e-12,
            max_iter=100_000,
        ).fit(Xs, ys)
        f_newton = opt._svr_objective(ys - Xs @ wb[:-1], wb[:-1], C, eps)
        f_ref = opt._svr_objective(ys - Xs @ ref.coef_, ref.coef_, C, eps)
        assert ok and wb[-1] == 0.0
        assert f_newton <= f_ref * (1 + 1e-9)
        assert f_newton == pytest.approx(f_ref, rel=1e-6)


@pytest.mark.filterwarnings("ignore:the SVR solver:sklearn.exceptions.ConvergenceWarning")
def test_svr_is_deterministic(problem):
    X, S, groups = problem
    y = X @ W_DENSE + _misfit(S, 1e-4)
    for solver in ("newton", "liblinear"):
        params = {**FAST["svr"], "solver": solver, "random_state": 3}
        a = SVR(**params).fit(X, y, groups=groups)
        b = SVR(**params).fit(X, y, groups=groups)
        assert np.array_equal(a.coef_, b.coef_)
        assert a.cv_results_["mean_mse"].shape == (1, 4)
        assert a.cv_results_["mse"].shape == (1, 4, 6)


# ------------------------------------------------------------------------------------------
# Cross-validation schemes
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["stlsq", "lasso", "svr"])
def test_groups_select_leave_one_group_out(problem, name):
    X, S, groups = problem
    y = X @ W_SPARSE + _misfit(S, 1e-5)
    est = make_optimizer(name, **FAST[name])
    with_groups = clone(est).fit(X, y, groups=groups)
    assert isinstance(with_groups.cv_, LeaveOneGroupOut)
    with pytest.warns(UserWarning, match="5 contiguous blocks, not leaving one manoeuvre out"):
        without = clone(est).fit(X, y)
    assert isinstance(without.cv_, KFold) and not without.cv_.shuffle
    assert without.cv_.get_n_splits() == 5
    ten = clone(est).set_params(cv=10).fit(X, y, groups=groups)
    assert isinstance(ten.cv_, KFold) and ten.cv_.get_n_splits() == 10
    grouped = clone(est).set_params(cv=GroupKFold(3)).fit(X, y, groups=groups)
    assert isinstance(grouped.cv_, GroupKFold)
    n_folds = {
        "stlsq": lambda m: m.cv_results_["mse"].shape[-1],
        "lasso": lambda m: m.mse_path_.shape[-1],
        "svr": lambda m: m.cv_results_["mse"].shape[-1],
    }[name]
    assert [n_folds(m) for m in (with_groups, without, ten, grouped)] == [6, 5, 10, 3]


def test_bad_groups(problem):
    X, S, groups = problem
    y = X @ W_SPARSE
    with pytest.raises(SindyshipInputError, match="one label per sample"):
        STLSQ().fit(X, y, groups=groups[:-1])
    with pytest.raises(SindyshipInputError, match="at least two groups"):
        LassoCV(alphas=5).fit(X, y, groups=np.zeros(X.shape[0]))


# ------------------------------------------------------------------------------------------
# The compression engine seen from outside: least squares, GroupedProblem, the fit template
# ------------------------------------------------------------------------------------------


def _norm_scaled(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    scale = np.linalg.norm(X, axis=0)
    scale[~(scale > 0)] = 1.0
    return X / scale, scale


def _gelsd(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    return scipy.linalg.lstsq(A, b, lapack_driver="gelsd")[0]


@pytest.mark.parametrize("n_groups, n_per_group", [(8, 400), (8, 2600)])
def test_least_squares_is_gelsd_on_norm_scaled_columns(n_groups, n_per_group):
    # 20,800 samples (8 manoeuvres of 2600, as in the protocol): the compressed solve folds
    # the rows in two blocks
    X, S, _ = _problem(seed=3, n_groups=n_groups, n_per_group=n_per_group)
    y = X @ W_DENSE + _misfit(S, 1e-4)
    Xs, scale = _norm_scaled(X)
    expected = _gelsd(Xs, y) / scale
    assert_allclose(LeastSquares().fit(X, y).coef_[0], expected, rtol=1e-10, atol=0)


def test_grouped_problem_is_least_squares_without_each_group():
    X, S, groups = _problem(seed=4, n_groups=7, n_per_group=600)
    y = X @ W_DENSE + _misfit(S, 1e-4)
    X = np.column_stack([X, np.zeros(X.shape[0])])  # an all-zero column keeps scale 1
    labels = np.array([30, 10, 20, 60, 50, 40, 0])[groups]  # groups in unsorted order
    problem = GroupedProblem(X, y, labels)
    Xs, scale = _norm_scaled(X)
    assert_array_equal(problem.scale, scale)
    assert problem.scale[-1] == 1.0
    order = np.unique(labels)
    assert [labels[m[0]] for m in problem.members] == order.tolist()
    for columns in (np.arange(X.shape[1]), np.array([0, 2, 3, 4, 7, 10]), np.array([3])):
        expected_errors = np.empty_like(y)
        for g, label in enumerate(order):
            out = labels == label
            w = _gelsd(Xs[~out][:, columns], y[~out])
            got = problem.solve(columns, leave_out=g)
            assert_allclose(got, w, rtol=1e-10, atol=1e-10 * np.max(np.abs(w)))
            expected_errors[out] = y[out] - Xs[out][:, columns] @ w
        errors = problem.lomo_errors(columns)
        assert_allclose(errors, expected_errors, rtol=0, atol=1e-10 * np.max(np.abs(y)))
        w = _gelsd(Xs[:, columns], y)
        assert_allclose(problem.solve(columns), w, rtol=1e-10, atol=1e-10 * np.max(np.abs(w)))
    assert_array_equal(problem.lomo_errors([]), y)  # no columns: nothing is predicted
    with pytest.raises(SindyshipInputError, match="one label per sample"):
        GroupedProblem(X, y, labels[:-1])


class _Ridge(opt._LinearModel):
    """Ridge regression on the standardised problem: a subclass needs only ``_reduce``."""

    _parameter_constraints: dict = {"penalty": [float]}

    def __init__(self, *, penalty: float = 0.0) -> None:
        self.penalty = penalty

    def _uses_cv(self) -> bool:
        return False

    def _reduce(self, data):
        full, R, Z, _ = data.full
        ridge = np.sqrt(self.penalty) * np.eye(R.shape[1])
        W = _gelsd(np.vstack([R, ridge]), np.vstack([Z, np.zeros((R.shape[1], Z.shape[1]))]))
        return np.vstack(
            [full.physical(W[:, t], 0.0, t, data.n_features) for t in range(data.n_targets)]
        )


def test_a_subclass_of_the_base_fits_through_the_template(problem):
    X, S, groups = problem
    y = X @ W_DENSE + _misfit(S, 1e-5)
    ridge = _Ridge().fit(X, y)
    assert_allclose(ridge.coef_, LeastSquares().fit(X, y).coef_, rtol=1e-10, atol=0)
    assert ridge.predict(X).shape == y.shape and not hasattr(ridge, "cv_")
    shrunk = _Ridge(penalty=1e3).fit(X, y)
    assert np.linalg.norm(shrunk.coef_[0, 1:]) < np.linalg.norm(ridge.coef_[0, 1:])
    assert shrunk.complexity == X.shape[1]


# ------------------------------------------------------------------------------------------
# pysindy
# ------------------------------------------------------------------------------------------


def _trajectories(n: int = 4):
    """Damped oscillations from different starts, 401 samples each, and their derivatives."""
    t = np.linspace(0.0, 8.0, 401)
    xs, dxs = [], []
    for k in range(n):
        phase = 0.7 * k
        x = np.column_stack([np.exp(-0.3 * t) * np.cos(2 * t + phase),
                             (1.0 + 0.2 * k) * np.exp(-0.3 * t) * np.sin(2 * t + phase)])
        dx = np.column_stack([-0.3 * x[:, 0] - 2 * x[:, 1] + 0.05 * x[:, 0] ** 3,
                              2 * x[:, 0] - 0.3 * x[:, 1] + 0.01])
        xs.append(x)
        dxs.append(dx + 1e-3 * np.sin(7.0 * t + k)[:, None])
    return t, xs, dxs


@pytest.mark.parametrize("name", ["stlsq", "lasso", "svr"])
def test_pysindy_reaches_leave_one_trajectory_out(name):
    """Through SINDy.fit (no groups) a LeaveOneTrajectoryOut cv gives the coefficients of a
    direct fit with groups; without it the blocks are announced, not silent."""
    t, xs, dxs = _trajectories()
    library = ps.PolynomialLibrary(degree=3)
    lengths = [len(x) for x in xs]
    through = ps.SINDy(feature_library=library,
                       optimizer=make_optimizer(name, **FAST[name],
                                                cv=LeaveOneTrajectoryOut(lengths)))
    through.fit(xs, t=t, x_dot=dxs)
    features = ps.PolynomialLibrary(degree=3).fit_transform(np.vstack(xs))
    direct = make_optimizer(name, **FAST[name]).fit(
        features, np.vstack(dxs), groups=np.repeat(np.arange(len(xs)), lengths))
    assert isinstance(direct.cv_, LeaveOneGroupOut)
    np.testing.assert_allclose(through.coefficients(), direct.coef_, rtol=1e-9, atol=1e-12)
    with pytest.warns(UserWarning, match="LeaveOneTrajectoryOut"):
        ps.SINDy(feature_library=ps.PolynomialLibrary(degree=3),
                 optimizer=make_optimizer(name, **FAST[name])).fit(xs, t=t, x_dot=dxs)


def test_leave_one_trajectory_out_refuses_lengths_that_do_not_add_up():
    X = np.zeros((10, 2))
    with pytest.raises(SindyshipInputError, match="received 10 samples but .* add up to 9"):
        list(LeaveOneTrajectoryOut([4, 5]).split(X))


@pytest.mark.parametrize("name", sorted(OPTIMIZERS))
def test_pysindy_plug_in(name):
    """pysindy.SINDy with a PolynomialLibrary fits and predicts with each optimizer."""
    t = np.linspace(0.0, 8.0, 801)
    x = np.column_stack([np.exp(-0.3 * t) * np.cos(2 * t), np.exp(-0.3 * t) * np.sin(2 * t)])
    x_dot = np.column_stack([-0.3 * x[:, 0] - 2 * x[:, 1], 2 * x[:, 0] - 0.3 * x[:, 1]])
    x_dot = x_dot + np.column_stack([0.05 * x[:, 0] ** 3, np.zeros_like(t)])
    x_dot[:, 1] += 0.01
    model = ps.SINDy(
        feature_library=ps.PolynomialLibrary(degree=3),
        optimizer=make_optimizer(name, **FAST[name],
                                 **({} if name in ("ls", "prior") else {"cv": 5})),
    )
    model.fit(x, t=t, x_dot=x_dot)
    assert model.coefficients().shape == (2, 10)
    pred = model.predict(x)
    assert pred.shape == x.shape
    assert _rms(pred - x_dot) < 1e-3 * _rms(x_dot)
    assert model.complexity >= 4
    names = model.get_feature_names()
    coef = dict(zip(names, model.coefficients()[1], strict=True))
    assert coef["1"] == pytest.approx(0.01, rel=1e-2)
    assert coef["x0"] == pytest.approx(2.0, rel=1e-3)


def test_least_squares_drops_a_direction_held_only_by_rounding():
    """Revolutions at two settings make 1, n and n^2 exactly dependent: the default rank
    threshold (1e-12 of the largest singular value of the scaled columns) gives the
    minimum-norm coefficients, which fit as well; LAPACK's machine-precision threshold had
    kept the rounding and given coefficients near 1e8 that cancel."""
    from sindyship.optimizers import LeastSquares

    rng = np.random.default_rng(0)
    n = np.where(rng.uniform(size=4000) < 0.5, 25.3, 32.6)  # n L / U0 at two settings
    v = rng.uniform(-0.2, 0.2, size=4000)
    X = np.column_stack([np.ones_like(n), n, n**2, v, n * v, n**2 * v])
    y = X @ np.array([1e-3, -2e-5, 3e-7, -1.2e-2, 1e-5, -2e-7])
    model = LeastSquares().fit(X, y)
    assert model.rank_ == 4
    assert np.max(np.abs(model.coef_)) < 1.0
    assert np.max(np.abs(model.predict(X) - y)) < 1e-12

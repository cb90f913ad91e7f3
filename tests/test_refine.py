"""Refinement of a fitted model by the error of its flights: multiple shooting with exact
sensitivities (sindyship.shooting, sindyship.refine)."""

from __future__ import annotations

import importlib
import importlib.util
import json
import math
import re

import numpy as np
import pytest

from sindyship.errors import SindyshipInputError
from sindyship.flights import fly_like_batch
from sindyship.identify import fit
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel
from sindyship.refine import default_segments, refine
from sindyship.shooting import fly_segments, make_segments, model_slots


@pytest.fixture(scope="module")
def runs(kcs):
    """A closed-loop zig-zag and a shorter turning circle (two lengths, one grid)."""
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


def test_segments_start_at_measured_states_and_cover_every_sample(runs, fitted, kcs):
    (segments,) = make_segments(fitted, runs, 100.0)
    # two samples (2 s, about 0.1 L/U0) a step; 100 s segments: 4 of the zig-zag, 3 of the turn
    assert (segments.step, segments.n_steps, segments.every) == (2.0, 50, 1)
    assert segments.n_segments == 4 + 3
    assert segments.start.tolist() == [0.0, 100.0, 200.0, 300.0, 0.0, 100.0, 200.0]
    np.testing.assert_array_equal(segments.state0[1], runs[0].state()[:6, 100])
    # the last segment of each record ends one step past its last sample (t = 400 s, 300 s)
    assert segments.valid[:4].sum() == 4 * 50 - 1 and segments.valid[4:].sum() == 3 * 50 - 1


def test_the_servo_replays_a_command_as_its_rk4_in_python_does(kcs):
    """The servo's angles of a recorded command (paper eq. 12-13, RK4 on the held command)
    equal, bit for bit, the same steps written out in Python, the rate limit and NaN
    included; the compiled loop where numba is installed."""
    import sindyship._shooting_compiled as loop
    from sindyship.simulation import servo_of

    time_constant, rate_max, delta_max = servo_of(kcs)
    generator = np.random.default_rng(3)
    t = np.cumsum(generator.uniform(0.2, 3.0, 400))
    command = np.clip(generator.normal(0.0, 0.4, 400), -delta_max, delta_max)
    command[250] = math.nan

    def slope(value, target):
        return min(max((target - value) / max(time_constant, 1e-9), -rate_max), rate_max)

    expected, expected_rate, delta = [], [], 0.05
    for i in range(len(t)):
        expected.append(delta)
        expected_rate.append(slope(delta, command[i]))
        if i + 1 == len(t):
            break
        n_sub = max(1, math.ceil((t[i + 1] - t[i]) / (0.25 * time_constant)))
        h = (t[i + 1] - t[i]) / n_sub
        for _ in range(n_sub):
            k1 = slope(delta, command[i])
            k2 = slope(delta + 0.5 * h * k1, command[i])
            k3 = slope(delta + 0.5 * h * k2, command[i])
            k4 = slope(delta + h * k3, command[i])
            delta += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    angle, rate = np.empty(len(t)), np.empty(len(t))
    loop.servo_angles(t, command, 0.05, time_constant, rate_max, angle, rate)
    np.testing.assert_array_equal(angle, expected)
    np.testing.assert_array_equal(rate, expected_rate)
    assert np.isfinite(angle[:251]).all() and np.isnan(angle[251:]).all()
    assert np.abs(np.diff(angle[:251])).max() <= rate_max * np.diff(t).max() * (1 + 1e-12)


@pytest.mark.parametrize("compiled", [True, False])
def test_sensitivities_equal_central_differences(runs, fitted, compiled):
    if compiled and importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    (segments,) = make_segments(fitted, runs, 100.0)
    states, jacobian = fly_segments(fitted, segments, sensitivities=True, compiled=compiled)
    rows, cols = model_slots(fitted)
    for k in (0, len(rows) // 2, len(rows) - 1):
        step = 1e-5 * abs(fitted._weights[rows[k], cols[k]])
        up, down = fitted._weights.copy(), fitted._weights.copy()
        up[rows[k], cols[k]] += step
        down[rows[k], cols[k]] -= step
        difference = (fly_segments(fitted, segments, up, compiled=compiled)[0]
                      - fly_segments(fitted, segments, down, compiled=compiled)[0]) / (2 * step)
        valid = segments.valid
        scale = np.max(np.abs(jacobian[..., k][valid]))
        assert scale > 0
        assert np.max(np.abs(difference[valid] - jacobian[..., k][valid])) < 1e-4 * scale


def test_the_compiled_segments_equal_the_numpy_reference(runs, fitted):
    if importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    (segments,) = make_segments(fitted, runs, 100.0)
    compiled = fly_segments(fitted, segments, sensitivities=True, compiled=True)
    reference = fly_segments(fitted, segments, sensitivities=True, compiled=False)
    np.testing.assert_allclose(compiled[0], reference[0], rtol=1e-12, atol=1e-9)
    scale = np.max(np.abs(reference[1]))  # forward differences in the state amplify rounding
    assert np.max(np.abs(compiled[1] - reference[1])) < 1e-8 * scale


def test_segments_shared_among_threads_fly_as_in_one_thread(runs, fitted, kcs, monkeypatch):
    if importlib.util.find_spec("numba") is None:
        pytest.skip("numba is not installed: the compiled path does not run")
    import numba

    whole = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=400),
                                Manoeuvre("zigzag", rudder=10, check=10, duration=400),
                                Manoeuvre("turning-circle", rudder=-25, duration=400)])
    (closed,) = make_segments(fitted, whole, None)  # two zig-zags closed loop, a turn replayed
    (pieces,) = make_segments(fitted, runs, 100.0)
    assert np.count_nonzero(closed.zigzag.sign) == 2 and pieces.n_segments > 3
    for batch in (closed, pieces):
        monkeypatch.setattr(numba, "get_num_threads", lambda: 1)
        alone = fly_segments(fitted, batch, sensitivities=True)
        monkeypatch.setattr(numba, "get_num_threads", lambda: 3)
        shared = fly_segments(fitted, batch, sensitivities=True)
        for one, many in zip(alone, shared, strict=True):
            np.testing.assert_array_equal(one, many)


def test_a_segment_flies_as_the_model_flies_the_same_stretch_alone(runs, fitted):
    """A segment is the model's own flight of that stretch of the record, from its measured
    state, with the recorded rudder: the kernel's flight of the stretch agrees to a metre."""
    from sindyship.trajectory import Trajectory

    (segments,) = make_segments(fitted, runs, 100.0)
    states, _ = fly_segments(fitted, segments)
    record = runs[0]
    stretch = record.data.iloc[100:201].drop(columns=["delta_c"]).reset_index(drop=True)
    start = {"time": float(stretch["t"].iloc[0]), "kind": "record", "reason": "the stretch"}
    (alone,) = fly_like_batch(fitted, [Trajectory(stretch, name="stretch",
                                                  meta={"flight_start": start})])
    rows = 2 * np.arange(1, 51)
    np.testing.assert_allclose(states[1, :, 3], alone["x"][rows], atol=1.0)
    np.testing.assert_allclose(states[1, :, 4], alone["y"][rows], atol=1.0)


def test_whole_flights_on_the_refinement_grid_fly_as_evaluate_flies(runs, fitted):
    """The check of a refinement flies whole records by the compiled loop on the
    refinement's grid (every other sample here, zig-zags closed loop): the mean distances of
    :func:`fly_like_batch`'s flights within 0.5 %, and a divergence where they diverge."""
    import sindyship.refine_checks as checks
    from sindyship.evaluation import compare_flights

    broken = _with(fitted, {("N", "r"): -3.0 * fitted.coefficients["N"]["r"]})
    whole = checks.flown_whole([fitted, broken], runs)
    for model, diverges, pairs in ((fitted, False, whole[0]), (broken, True, whole[1])):
        for (flown, measured), reference, record in zip(
                pairs, fly_like_batch(model, runs), runs, strict=True):
            assert measured["t"].tolist() == record["t"][::2].tolist()
            assert (flown.meta["diverged_at"] is not None) == diverges
            if not diverges:
                ours = compare_flights(flown, flown, measured, model.ship.L)["before_mean_L"]
                theirs = compare_flights(reference, reference, record,
                                         model.ship.L)["before_mean_L"]
                assert ours == pytest.approx(theirs, rel=5e-3)
                continue
            cut = flown.t >= flown.meta["diverged_at"]
            assert np.isnan(flown["x"][cut]).all() and np.isfinite(flown["x"][~cut]).all()
            assert reference.meta["diverged_at"] is not None  # the integrator's flight too
    assert checks.flown_whole([fitted], runs)[0][0][0].data.equals(whole[0][0][0].data)


def test_the_step_a_segment_diverged_at_is_where_it_first_leaves_the_plausible_range(
        runs, fitted):
    """``stopped`` names the step at whose end a segment diverged: flown that many steps it
    has not diverged, one more and it has; the states are held from its compared sample on;
    the compiled loop and the numpy reference (the zig-zag: the loop's code as Python) agree."""
    from dataclasses import replace

    broken = _with(fitted, {("N", "r"): -3.0 * fitted.coefficients["N"]["r"]})
    found = []
    for compiled in (True, False):
        steps = []
        for segments in make_segments(broken, runs, None):
            stopped = np.full(segments.n_segments, -7)
            states, _ = fly_segments(broken, segments, stopped=stopped, compiled=compiled)
            for k, step in enumerate(stopped):
                assert step >= 0 and np.all(states[k, step // segments.every:]
                                            == states[k, step // segments.every])
                for n_steps, expected in ((step, -1), (step + 1, step)):
                    short = replace(segments.take(np.array([k])), n_steps=int(n_steps))
                    again = np.full(1, -7)
                    fly_segments(broken, short, stopped=again, compiled=compiled)
                    assert again.tolist() == [expected]
            steps.extend(stopped.tolist())
        found.append(steps)
    assert found[0] == found[1]
    (segments,) = make_segments(fitted, runs[:1], None)
    stopped = np.zeros(1, dtype=int)
    fly_segments(fitted, segments, stopped=stopped)
    assert stopped.tolist() == [-1]


def test_a_library_the_shooting_loop_cannot_fly_is_checked_by_the_integrator(four, kcs,
                                                                             monkeypatch):
    """A factor of a number has no form in the shooting loop: the check on every other
    record flies the integrator's flights instead, and whole flights of zig-zags are
    refused in one sentence."""
    import sindyship.refine_checks as checks
    from sindyship.library import TermLibrary

    library = TermLibrary("half", "prime-I", "", {
        "X": ["du", "v r", "0.5 r^2"], "Y": ["v", "r", "delta", "v^3"],
        "N": ["v", "r", "delta", "r^3"]})
    model = fit(four, kcs, library=library, optimizer="ls")
    (pairs,) = checks.flown_whole([model], four)
    for (flown, record), reference in zip(pairs, fly_like_batch(model, four), strict=True):
        assert flown.data.equals(reference.data) and record is not None
    # the refinement on every other record loses a hard-over turn to starboard, so nothing
    # would be flown: here it is let keep its steps, and the check flies them
    monkeypatch.setattr(importlib.import_module("sindyship.refine"), "turns_kept",
                        lambda fitted, refined, records: None)
    refined = refine(model, four, max_evaluations=3)
    assert 0 < refined.info["refined"]["validation"]["ratio"] < math.inf
    with pytest.raises(SindyshipInputError, match=r"^the model's library has a term the "
                       r"shooting loop cannot evaluate .* refine on segments"):
        refine(model, four, max_evaluations=3, segment_s="whole", validate=False)


#: A small library the protocol's records determine well (linear and cubic sway and yaw).
SMALL = {"X": ["1", "du", "du^2", "v^2", "r^2", "delta^2", "v r"],
         "Y": ["v", "r", "delta", "v^3", "v^2 r", "v r^2", "r^3", "delta^3"],
         "N": ["v", "r", "delta", "v^3", "v^2 r", "v r^2", "r^3", "delta^3"]}


def test_refinement_recovers_a_spoiled_coefficient(kcs):
    """Records flown by an Abkowitz model itself, and that model with its yaw damping 30 %
    off: refining by the segments' flights alone brings the damping back within 0.5 % (the
    rest is the records' own integration step) and the flight error down a thousandfold."""
    from sindyship.library import TermLibrary

    plan = [Manoeuvre("turning-circle", rudder=25, duration=800),
            Manoeuvre("turning-circle", rudder=-25, duration=800),
            Manoeuvre("zigzag", rudder=20, check=20, duration=800),
            Manoeuvre("zigzag", rudder=10, check=10, duration=800)]
    truth = fit(fly(MMGModel(kcs), plan), kcs, library=TermLibrary("small", "prime-I", "",
                                                                   SMALL))
    records = fly(truth.dynamics(), plan)
    spoiled = _with(truth, {("N", "r"): 1.3 * truth.coefficients["N"]["r"]})
    # unvalidated: fitted again on half of records its own library made, the model is the
    # truth already, which no refinement can fly closer
    refined = refine(spoiled, records, prior_weight=0.0, validate=False)
    report = refined.info["refined"]
    assert report["records"] == [r.name for r in records] and report["converged"]
    assert report["method"] == "multiple shooting" and report["segments"] == 4 * 3
    assert report["flight_rms_after"] < 1e-3 * report["flight_rms_before"]
    assert abs(refined.coefficients["N"]["r"] / truth.coefficients["N"]["r"] - 1.0) < 0.005
    # the forces moved: the yaw moment by the spoiled term's force, the others hardly
    from sindyship.identify import design

    yaw = design(records, kcs, spoiled.library)["N"]
    column = yaw.features[:, list(yaw.terms).index("r")]
    spoil = 0.3 * abs(truth.coefficients["N"]["r"]) * np.sqrt(np.mean(column ** 2)) \
        / np.sqrt(np.mean(yaw.target ** 2))
    assert report["force_change"]["N"] == pytest.approx(spoil, rel=0.05)
    assert max(report["force_change"]["X"], report["force_change"]["Y"]) < 0.1 * spoil
    # only non-zero coefficients move; the library and the optimizer stay
    assert refined.library is spoiled.library
    assert refined.optimizer == spoiled.optimizer
    assert json.loads(json.dumps(refined.to_dict()))["info"]["refined"]["cost_after"] >= 0


def test_the_force_change_is_a_share_of_the_measured_force_and_none_without_one(
        runs, fitted, kcs):
    """Every coefficient 1 % larger moves each force by about 1 % of the measured one (the
    fit's error apart); on a straight run, with no sway force or yaw moment to measure, the
    share of those is None instead of a division by almost nothing."""
    from sindyship.refine import force_change

    larger = _with(fitted, {(dof, term): 1.01 * value
                            for dof, terms in fitted.coefficients.items()
                            for term, value in terms.items()})
    shares = force_change(fitted, larger, runs)
    assert all(0.008 < shares[dof] < 0.012 for dof in "XYN"), shares
    straight = fly(MMGModel(kcs), [Manoeuvre("straight", rudder=0, duration=200)])
    on_straight = force_change(fitted, larger, straight)
    assert on_straight["Y"] is None and on_straight["N"] is None


def test_a_model_whose_flights_diverge_still_gets_a_gradient(runs, fitted, kcs):
    """Whole flights of a yaw-unstable model diverge; every segment starts from a measured
    state and holds its last state in range once it diverges, so the error still falls."""
    from sindyship.evaluation import evaluate

    broken = _with(fitted, {("N", "r"): -3.0 * fitted.coefficients["N"]["r"]})
    assert not any(e["completed"] for e in evaluate(broken, runs).values())
    refined = refine(broken, runs, max_evaluations=20, prior_weight=0.0)
    report = refined.info["refined"]
    assert report["flight_rms_after"] < 0.9 * report["flight_rms_before"]


def test_a_refinement_flies_a_point_it_just_flew_once_and_ends_as_flying_it_again_does(
        runs, fitted, monkeypatch):
    """A stage asks for the same point several times in a row (its start, the search's first
    point, the point the search ended at): the flight is reused, and the refinement ends
    exactly where flying every request again ends."""
    module = importlib.import_module("sindyship.refine_problem")
    flown, fly_batches = [], module.fly_batches

    def counted(model, batches, weights, slots, sensitivities, n_jobs):
        flown.append(sensitivities)
        return fly_batches(model, batches, weights, slots, sensitivities, n_jobs)

    monkeypatch.setattr(module, "fly_batches", counted)
    settings = {"max_evaluations": 12, "segment_s": [100.0, 300.0], "validate": False}
    reused = refine(fitted, runs, **settings)
    plain, jacobians = flown.count(False), flown.count(True)
    flown.clear()
    monkeypatch.setattr(module.ShootingProblem, "_flights", lambda self, p, sensitivities: counted(
        self.model, self.batches, self.weights(p), self.slots, sensitivities, self.n_jobs))
    again = refine(fitted, runs, **settings)
    assert flown.count(True) == jacobians > 0
    # each of the two stages asked again for at least its start and its search's first point
    assert flown.count(False) >= plain + 2 * 2
    assert again.coefficients == reused.coefficients
    assert again.info["refined"]["stages"] == reused.info["refined"]["stages"]


def test_a_refinement_flies_with_one_blas_thread(runs, fitted, monkeypatch):
    """The segments fly on threads of their own; BLAS threads spinning between the products
    of J^T J would take their cores."""
    from threadpoolctl import threadpool_info

    module = importlib.import_module("sindyship.refine_problem")
    seen, fly_batches = set(), module.fly_batches

    def watched(*args):
        seen.update(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")
        return fly_batches(*args)

    monkeypatch.setattr(module, "fly_batches", watched)
    refine(fitted, runs, max_evaluations=3, segment_s=100.0, validate=False)
    assert seen <= {1}


def test_default_segments_grow_in_stages_up_to_the_longest_record(kcs, runs):
    assert [round(s) for s in default_segments(kcs, runs)] == [93, 279]  # records of 400 s
    assert [round(s) for s in default_segments(kcs, [])] == [93, 279, 838]


@pytest.mark.parametrize("kwargs, error, message", [
    ({"max_evaluations": 0}, ValueError, "max_evaluations must be a whole number"),
    ({"max_evaluations": 2.5}, ValueError, "max_evaluations must be a whole number"),
    ({"max_evaluations": math.nan}, ValueError, "max_evaluations must be a whole number"),
    ({"max_evaluations": True}, ValueError, "max_evaluations must be a whole number"),
    ({"segment_s": -1.0}, ValueError, "segment_s must be a positive number"),
    ({"segment_s": math.nan}, ValueError, "segment_s must be a positive number"),
    ({"prior_weight": -1.0}, ValueError, "prior_weight must be a non-negative number"),
    ({"prior_weight": "1"}, ValueError, "prior_weight must be a non-negative number"),
])
def test_refine_refuses_bad_settings_in_one_sentence(runs, fitted, kwargs, error, message):
    with pytest.raises(error, match=message):
        refine(fitted, runs, **kwargs)


def test_refine_refuses_what_is_not_a_model_or_records(runs, fitted):
    with pytest.raises(SindyshipInputError, match=r"at least one record"):
        refine(fitted, [])
    with pytest.raises(SindyshipInputError, match=r"^zz.csv: no such file; records are"):
        refine(fitted, "zz.csv")
    with pytest.raises(TypeError, match="records must be a list of Trajectory"):
        refine(fitted, 3)
    with pytest.raises(TypeError, match="model must be an AbkowitzModel"):
        refine("model.json", runs)


def test_a_refinement_split_across_workers_equals_one_process(runs, fitted):
    """Each segment flies on its own, so splitting them across processes changes nothing (to
    rounding: a worker started without numba flies the numpy reference)."""
    spoiled = _with(fitted, {("N", "r"): 1.3 * fitted.coefficients["N"]["r"]})
    one = refine(spoiled, runs, segment_s=100.0, max_evaluations=4)
    two = refine(spoiled, runs, segment_s=100.0, max_evaluations=4, n_jobs=2)
    for dof in "XYN":
        for term, value in one.coefficients[dof].items():
            assert two.coefficients[dof][term] == pytest.approx(value, rel=1e-8, abs=1e-15)
    assert one.info["refined"]["cost_after"] == pytest.approx(
        two.info["refined"]["cost_after"], rel=1e-8)


def test_a_refined_prior_fit_keeps_its_prior_and_its_stability(runs, kcs):
    prior = fit(runs, kcs, library="abkowitz-vr", optimizer="prior")
    refined = refine(prior, runs, max_evaluations=8)
    report = refined.info["refined"]
    assert refined.optimizer["name"] == "prior" and report["prior_weight"] == 0.01
    assert refined.info["straight_run"]["stable"] is report["straight_run_stable"]
    assert refined.info["straight_run"]["strength"] == prior.info["straight_run"]["strength"]
    # the penalty holds the linear derivatives near the prior fit's; flights alone do not
    linear = [("Y", "v"), ("Y", "r"), ("N", "v"), ("N", "r")]
    unpenalised = refine(prior, runs, max_evaluations=8, prior_weight=0.0)

    def moved(model):
        return max(abs(model.coefficients[d][t] / prior.coefficients[d][t] - 1.0)
                   for d, t in linear)

    assert moved(refined) < 0.9 * moved(unpenalised)
    assert report["flight_rms_after"] < report["flight_rms_before"]


@pytest.fixture(scope="module")
def four(kcs):
    """Four short records: enough for the refinement to validate itself on two halves."""
    return fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=400),
                               Manoeuvre("turning-circle", rudder=-25, duration=400),
                               Manoeuvre("zigzag", rudder=10, check=10, duration=400),
                               Manoeuvre("turning-circle", rudder=25, duration=400)])


def test_a_refinement_refused_on_half_the_records_is_said_to_be_so(four, kcs, monkeypatch):
    """Where the refinement on every other record is itself refused (here: it would lose a
    hard-over turn), the check says so instead of comparing the fit with itself."""
    refining = importlib.import_module("sindyship.refine")  # the module, not the function
    monkeypatch.setattr(refining, "turns_kept",
                        lambda fitted, refined, records: "diverges in a hard-over turn to port")
    prior = fit(four, kcs, library="abkowitz-vr", optimizer="prior")
    report = refine(prior, four, max_evaluations=4).info["refined"]
    check = report["validation"]
    assert check["half_refused"] == "the refined model diverges in a hard-over turn to port"
    assert not check["accepted"] and report["refused_validation"] and check["ratio"] is None
    assert report["stopped"] == (
        "refined on every other record (tc25_port, zz10_10), the refinement kept the fitted "
        "coefficients there (the refined model diverges in a hard-over turn to port), so it "
        "cannot be shown to carry over to the others; the fitted coefficients are kept")


def test_a_refinement_that_does_not_carry_over_keeps_the_fit(four, kcs, monkeypatch, capsys):
    """Fitted and refined on every other record in the order of their names, the model flies
    the others, whatever order the records come in; a refinement that does not fly them
    closer than the fit alone is refused (here: by a ratio of 0)."""
    import sindyship.refine_checks as checks

    prior = fit(four, kcs, library="abkowitz-vr", optimizer="prior")
    refined = refine(prior, four, max_evaluations=4)
    check = refined.info["refined"]["validation"]
    assert check["refined_on"] == ["tc25_port", "zz10_10"]
    assert check["flown"] == ["tc25_stbd", "zz20_20"]
    assert 0 < check["ratio"] < checks.VALIDATION_RATIO and check["accepted"]
    reordered = fit(four[::-1], kcs, library="abkowitz-vr", optimizer="prior")
    for dof, coefficients in prior.coefficients.items():
        assert reordered.coefficients[dof] == pytest.approx(coefficients, rel=1e-9, abs=1e-15)
    again = refine(reordered, four[::-1], max_evaluations=4).info["refined"]["validation"]
    assert again == {**check, "ratio": pytest.approx(check["ratio"], rel=1e-6)}
    assert refined.coefficients != prior.coefficients
    monkeypatch.setattr(checks, "VALIDATION_RATIO", 0.0)
    capsys.readouterr()
    kept = refine(prior, four, max_evaluations=4, progress=True)
    steps = capsys.readouterr().err
    assert re.search(r"checking on every other record \([\d.]+ s segments\): step 1,", steps)
    assert "refining by flights" not in steps
    # each line says how far the cost fell (from the stage's start here: one step a stage)
    costs = [float(c) for c in re.findall(r"cost ([-+.\de]+) \(", steps)]
    falls = [float(f) for f in re.findall(r"\(([-+.\de]+) % lower\)", steps)]
    assert len(falls) == len(costs) >= 2 and steps.count("(rms, non-dimensional)") == len(costs)
    assert all(0 < fall < 100 for fall in falls)
    report = kept.info["refined"]
    assert report["refused_validation"] and not report["validation"]["accepted"]
    assert kept.coefficients == prior.coefficients and report["largest_change"] is None
    assert "the fitted coefficients are kept" in report["stopped"]
    assert report["flight_rms_after"] == report["flight_rms_before"]
    # the check comes first: a refused refinement is never made on all four records
    assert report["evaluations"] == 0 and report["jacobians"] == 0 and report["stages"] == []
    assert report["refused_unstable"] is False and report["refused_turning"] is None
    assert kept.info["straight_run"] == prior.info["straight_run"]
    assert report["flight_rms_before"] > 0 and report["segments"] >= 4
    # without the check, the refinement is kept as it is
    unchecked = refine(prior, four, max_evaluations=4, validate=False)
    assert "validation" not in unchecked.info["refined"]
    assert unchecked.coefficients == refined.coefficients


def test_a_prior_fit_stays_stable_in_straight_running(runs, kcs, fitted, monkeypatch):
    """A refinement that would make a straight-run-stable prior fit unstable keeps the fit;
    a least-squares fit, which promises nothing, is refined and reported unstable."""
    refining = importlib.import_module("sindyship.refine")  # the module, not the function
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
    assert refined_ls.info["refined"]["straight_run_stable"] is False
    assert refined_ls.info["refined"]["refused_unstable"] is False


def test_a_refinement_refused_for_its_turns_reports_the_stability_of_the_model_kept(
        runs, kcs, fitted, monkeypatch):
    """Refused because it loses the hard-over turns, a refinement keeps the fitted
    coefficients, and the stability it reports is theirs, not the refused model's."""
    refining = importlib.import_module("sindyship.refine")  # the module, not the function
    from sindyship.stability import Stability, straight_run_stability

    def stability(model):  # the refined coefficients unstable, the fitted ones as they are
        if model.coefficients == fitted.coefficients:
            return straight_run_stability(model)
        return Stability(eigenvalues=(0.1, -1.0), jacobian=np.eye(2), stable=False,
                         doubling_time_L_over_U=6.9)

    assert straight_run_stability(fitted).stable
    monkeypatch.setattr(refining, "straight_run_stability", stability)
    monkeypatch.setattr(refining, "turns_kept", lambda *args: "diverges in a hard-over turn")
    kept = refine(fitted, runs, max_evaluations=4)
    report = kept.info["refined"]
    assert kept.coefficients == fitted.coefficients and report["refused_turning"]
    assert report["straight_run_stable"] is True and report["refused_unstable"] is False


def test_an_unstable_prior_fit_is_not_refined_to_a_more_unstable_model(runs, kcs,
                                                                       monkeypatch):
    """A prior fit unstable in straight running may be refined while its disturbances grow
    about as fast; a refinement whose disturbances double more than INSTABILITY_MARGIN times
    as fast keeps the fit, and says both doubling times."""
    refining = importlib.import_module("sindyship.refine")  # the module, not the function
    from sindyship.stability import Stability

    prior = fit(runs, kcs, library="abkowitz-vr", optimizer="prior")
    prior.info["straight_run"] = {**prior.info["straight_run"], "stable": False}

    def doubling(fitted_in, refined_in):
        def stability(model):
            time = fitted_in if model is prior else refined_in
            return Stability(eigenvalues=(math.log(2) / time, -1.0), jacobian=np.eye(2),
                             stable=False, doubling_time_L_over_U=time)
        return stability

    monkeypatch.setattr(refining, "straight_run_stability", doubling(8.0, 3.0))
    kept = refine(prior, runs, max_evaluations=4, validate=False)
    report = kept.info["refined"]
    assert kept.coefficients == prior.coefficients and report["refused_unstable"]
    assert report["stopped"].startswith("in straight running a disturbance of the refined "
                                        "model doubles in 3 L/U0, of the fit it started from "
                                        "in 8 L/U0")
    assert report["straight_run_stable"] is False and report["largest_change"] is None
    assert kept.info["straight_run"]["stable"] is False
    assert 8.0 / 3.0 > refining.INSTABILITY_MARGIN > 8.0 / 7.0
    monkeypatch.setattr(refining, "straight_run_stability", doubling(8.0, 7.0))
    refined = refine(prior, runs, max_evaluations=4, validate=False)
    assert refined.coefficients != prior.coefficients
    assert refined.info["refined"]["refused_unstable"] is False


def test_a_model_with_a_coefficient_no_saved_model_may_hold_is_not_saved(fitted, tmp_path):
    """A fit on records that do not belong to the ship can give coefficients near 1e295;
    saving refuses them in one sentence (loading would) and writes nothing."""
    absurd = _with(fitted, {("N", "r"): 1e295})
    with pytest.raises(SindyshipInputError, match=r"^the fit gave N\[r\] a coefficient of "
                       r"magnitude 1e\+295, beyond the 1e\+06 a saved model may hold: the "
                       r"records cannot tell its term from others"):
        absurd.save(tmp_path / "m.json")
    assert list(tmp_path.iterdir()) == []


def test_a_refinement_is_refused_when_its_hard_over_turn_diverges_widens_or_keeps_slowing(
        monkeypatch):
    """The hard-over turns the fitted model flies: the refined model must not diverge in
    them, nor turn them in a tactical diameter or end them at a speed more than
    TURN_CHECK_FACTOR from the fitted model's (the MARIN zig-zags at their own sampling
    refined into a model that slowed to 0.04 U0 turning hard over, where the fit keeps
    0.43 U0)."""
    import sindyship.refine_checks as checks

    fitted = {"starboard": {"tactical_diameter_L": 3.1, "final_speed": 0.43},
              "port": {"tactical_diameter_L": 3.3, "final_speed": 0.45}}

    def verdict(starboard):
        turns = {"fitted": fitted, "refined": {**fitted, "starboard": starboard}}
        monkeypatch.setattr(checks, "hard_over_turns", lambda model, records: turns[model])
        return checks.turns_kept("fitted", "refined", [])

    assert verdict({"tactical_diameter_L": 2.5, "final_speed": 0.30}) is None
    assert verdict(None) == ("diverges in a hard-over turn to starboard, which the fit it "
                             "started from flies")
    assert verdict({"tactical_diameter_L": 6.5, "final_speed": 0.43}) == (
        "turns to starboard at the rudder limit in a tactical diameter 2.1 times the fitted "
        "model's")
    assert verdict({"tactical_diameter_L": 2.5, "final_speed": 0.037}) == (
        "slows to 0.037 U0 in a hard-over turn to starboard, where the fit it started from "
        "keeps 0.43 U0")


def test_a_refusal_for_a_divergence_names_it_before_the_distances():
    """The refusal had read "flew the other half 0.387 times as far off as fitted
    (zz15_15 diverged)", as if closer: a diverged flight's mean covers only its time before."""
    from sindyship.refine import _refused_validation

    diverged = {"ratio": 0.387, "why": "zz15_15 diverged", "diverged": ["zz15_15"]}
    assert _refused_validation(diverged) == (
        "refined on half of the records, the model diverged on zz15_15 of the other half, "
        "which the fit flies longer (over the time both flights cover, 0.387 times as far off "
        "as fitted); the fitted coefficients are kept")
    farther = {"ratio": 1.898, "why": "no closer", "diverged": []}
    assert _refused_validation(farther) == (
        "refined on half of the records, the model flew the other half 1.898 times as far off "
        "as fitted (no closer); the fitted coefficients are kept")


def test_a_progress_line_says_how_far_the_cost_fell_since_the_last(capsys):
    from types import SimpleNamespace

    from sindyship.refine_problem import ShootingProblem

    stage = SimpleNamespace(segment_s=93.13, reported_cost=0.5, flight_rms=0.0123)
    ShootingProblem.report(stage, 1, 0.4, "refining by flights")
    ShootingProblem.report(stage, 2, 0.3, "refining by flights")
    first, second = capsys.readouterr().err.splitlines()
    assert first == ("refining by flights (93.13 s segments): step 1, cost 0.4 (20.00 % "
                     "lower), flight error 0.0123 (rms, non-dimensional)")
    assert "step 2, cost 0.3 (25.00 % lower)" in second and stage.reported_cost == 0.3
    ShootingProblem.report(stage, 3, 0.3 * (1 - 3e-7), "refining by flights")
    assert "(3.0e-05 % lower)" in capsys.readouterr().err  # a converging step, not 0.00 %

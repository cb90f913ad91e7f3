"""The pysindy comparison's own parts (``benchmarks/bench_pysindy.py``) on short manoeuvres.

The hand-written simulator must reproduce the MMG flights it is fed the MMG accelerations of,
or the pysindy numbers would measure the simulator; and the pysindy workflow must give a model
that flies.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from sindyship.evaluation import distance_errors
from sindyship.mmg import MMGModel

SCRIPT = Path(__file__).resolve().parents[1] / "benchmarks" / "bench_pysindy.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_pysindy", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def short_runs(bench, kcs):
    """The protocol's manoeuvres, 600 s each, flown by the MMG model."""
    return bench.protocol_records(kcs, duration=600.0)


def test_hand_simulator_reproduces_mmg_flights(bench, kcs, short_runs):
    plan, _, test = short_runs
    accel = bench.SIAccelerations(MMGModel(kcs), kcs)
    for rec, manoeuvre in zip(test, plan["test"], strict=True):
        flown = bench.hand_fly(accel, manoeuvre, kcs, t=rec.t)
        assert flown.meta["diverged_at"] is None
        assert bench.track_distance(flown, rec, kcs.L) < 1e-3, rec.name
        assert np.max(np.abs(flown["psi"] - rec["psi"])) < 1e-3, rec.name


def test_hand_simulator_stops_a_diverging_flight(bench, kcs, short_runs):
    plan, _, test = short_runs

    def unstable(up, vp, rp, delta, psi):  # the yaw rate grows without bound
        return 0.0, 0.0, 0.05 + rp

    flown = bench.hand_fly(unstable, plan["test"][1], kcs, t=test[1].t)
    diverged_at = flown.meta["diverged_at"]
    assert diverged_at is not None and 0.0 < diverged_at < 600.0
    assert np.isnan(flown["x"][flown.t >= diverged_at]).all()
    assert distance_errors(flown, test[1], kcs.L)["completed"] is False


def test_pysindy_fit_flies_a_held_out_record(bench, kcs, short_runs):
    plan, train, test = short_runs
    cv = bench.cross_validate(train, kcs, thresholds=(0.0, 1e-3, 1e-2, 1e-1, 1.0))
    assert cv["chosen"] in (0.0, 1e-3, 1e-2)
    assert cv["score"][-1] > 10 * min(cv["score"])
    model = bench.fit_pysindy(train, kcs, cv["chosen"])
    accel = bench.PolynomialAccelerations(model)
    assert accel.max_difference_to_predict(test[2], kcs) < 1e-10
    flown = bench.hand_fly(accel, plan["test"][1], kcs, t=test[1].t)
    errors = distance_errors(flown, test[1], kcs.L)
    assert errors["completed"]
    assert errors["mean_distance_L"] < 0.1


def test_beats_follows_the_divergence_rule(bench):
    done = {"mean_distance_L": 0.5, "diverged_at_s": None}
    better = {"mean_distance_L": 0.1, "diverged_at_s": None}
    failed = {"mean_distance_L": 0.01, "diverged_at_s": 300.0}
    later = {"mean_distance_L": 0.9, "diverged_at_s": 900.0}
    assert bench.beats(better, done) and not bench.beats(done, better)
    assert bench.beats(done, failed) and not bench.beats(failed, done)
    assert bench.beats(later, failed)

"""Conditions that change during a run (wind, revolutions): their series, their forces, their
records, and the catalogue effects that explain them."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from sindyship.cli import main
from sindyship.conditions import ornstein_uhlenbeck, revolution_series, wind_force
from sindyship.diagnose import before_after, diagnose
from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.errors import SindyshipInputError
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.simulation.kernels import ChannelSeries

TURN = Manoeuvre("turning-circle", rudder=20, duration=600)


def test_gusts_have_the_asked_spread_and_correlation_and_repeat_by_seed():
    times = np.arange(0.0, 50000.0)
    a = ornstein_uhlenbeck(times, 3.0, 10.0, np.random.default_rng(7))
    b = ornstein_uhlenbeck(times, 3.0, 10.0, np.random.default_rng(7))
    assert np.array_equal(a, b)
    assert a.std() == pytest.approx(3.0, rel=0.05)
    lag = np.corrcoef(a[:-10], a[10:])[0, 1]
    assert lag == pytest.approx(math.exp(-1.0), abs=0.03)


def test_revolutions_step_at_the_asked_fraction_of_the_record():
    n = revolution_series(np.arange(0.0, 101.0), 2.0, 0.9, 0.2, 0.25, 0.0, 18.6,
                         np.random.default_rng(0))
    assert n[24] == pytest.approx(1.8)
    assert n[25] == pytest.approx(2.2)
    assert n[-1] == pytest.approx(2.2)


@pytest.mark.parametrize(("come_from", "axis", "sign"),
                         [(0.0, 0, -1), (180.0, 0, 1), (90.0, 1, -1), (270.0, 1, 1)])
def test_the_wind_pushes_away_from_where_it_comes(kcs, come_from, axis, sign):
    """Heading north at rest: a wind from the north pushes astern, from the east to port."""
    forces = wind_force(kcs, 0.0, 0.0, 0.0, 15.0, math.radians(come_from))
    assert sign * forces[axis] > 1e-4
    assert forces[2] == pytest.approx(-0.05 * forces[1])


def test_the_wind_force_follows_the_apparent_wind(kcs):
    """Running before a wind as fast as the wind leaves no force at all."""
    forces = wind_force(kcs, 1.0, 0.0, 0.0, kcs.U0, math.pi)
    assert np.allclose(forces, 0.0, atol=1e-15)


def test_design_revolutions_as_a_series_fly_like_the_constant(kcs):
    """The time-varying path of the MMG with n = n_P everywhere is the calm-water flight."""
    (calm,) = fly(MMGModel(kcs), [TURN])
    series = ChannelSeries(TURN.times, {"n": np.full((1, len(TURN.times)), kcs.propeller.n_P)})
    (same,) = fly(MMGModel(kcs, conditions=series), [TURN])
    assert np.allclose(same["x"], calm["x"], atol=1e-9)
    assert np.allclose(same["psi"], calm["psi"], atol=1e-12)


def test_lower_revolutions_slow_the_ship_and_are_recorded(kcs):
    (slow,) = simulate_with_effects(kcs, [TURN], parse_effects(["rps=0.8"]))
    (calm,) = simulate_with_effects(kcs, [TURN])
    assert slow["n"] == pytest.approx(np.full(len(TURN.times), 0.8 * kcs.propeller.n_P))
    assert slow["u"][-1] < 0.9 * calm["u"][-1]
    assert "n" not in calm.data and "wind_speed" not in calm.data


def test_gusty_wind_is_recorded_and_every_run_of_a_batch_has_its_own(kcs):
    effects = parse_effects(["wind=15", "wind_dir=90", "gust=0.2", "wind_wander=10", "seed=3"])
    first, second = simulate_with_effects(kcs, [TURN, TURN], effects)
    again, _ = simulate_with_effects(kcs, [TURN, TURN], effects)
    assert np.array_equal(first["wind_speed"], again["wind_speed"])
    assert not np.array_equal(first["wind_speed"], second["wind_speed"])
    assert first["wind_speed"].mean() == pytest.approx(15.0, rel=0.2)
    assert 0.1 < first["wind_speed"].std() / 15.0 < 0.3
    assert np.all((first["wind_dir"] >= 0.0) & (first["wind_dir"] < 2 * math.pi))
    (calm,) = simulate_with_effects(kcs, [TURN])
    assert np.hypot(first["x"][-1] - calm["x"][-1], first["y"][-1] - calm["y"][-1]) > 50.0


def test_revolutions_that_would_stop_the_propeller_are_refused():
    with pytest.raises(SindyshipInputError, match="keep that at 0.2 or above"):
        parse_effects(["rps=0.5", "rps_step=-0.4"])


def test_simulate_writes_the_wind_and_revolution_channels(tmp_path):
    out = tmp_path / "run.csv"
    assert main(["simulate", "--manoeuvre", "straight", "--duration", "60", "--effect", "wind=10",
                 "--effect", "rps_step=0.1", "--out", str(out)]) == 0
    frame = pd.read_csv(out)
    assert {"wind_speed", "wind_dir", "n"} <= set(frame.columns)
    assert frame["n"].iloc[-1] > frame["n"].iloc[0]


def _windy(ship, manoeuvres, first_index):
    """Each run in a wind from its own mean direction, with gusts."""
    runs = []
    for k, manoeuvre in enumerate(manoeuvres, start=first_index):
        effects = parse_effects(["wind=15", f"wind_dir={(30 + 137.5 * k) % 360:.1f}", "gust=0.2",
                                 "wind_wander=10", f"seed={k + 1}"])
        runs += simulate_with_effects(ship, [manoeuvre], effects)
    return runs


def test_measured_wind_is_found_and_its_effect_flies_the_held_out_runs_better(kcs):
    """A short version of ``benchmarks/bench_measured_channels.py``."""
    train = _windy(kcs, [Manoeuvre("straight", duration=1200),
                         Manoeuvre("turning-circle", rudder=35, duration=1200),
                         Manoeuvre("turning-circle", rudder=-35, duration=1200),
                         Manoeuvre("zigzag", rudder=20, check=20, duration=1200),
                         Manoeuvre("zigzag", rudder=15, check=15, duration=1200)], 0)
    test = _windy(kcs, [Manoeuvre("turning-circle", rudder=-15, duration=1200),
                        Manoeuvre("zigzag", rudder=10, check=10, duration=1200)], 5)
    result = diagnose(train, kcs, fly_training=False, confirm=0)
    assert result.ranking[0].effect.name == "wind"
    assert result.ranking[0].meaningful
    change = before_after(train, kcs, effects=["wind"], test=test, fly_training=False)
    assert change.ratio("held-out") < 0.5
    assert all(row["after"]["diverged_at_s"] is None for row in change.rows)

"""The MMG simulator against the protocol's reference figures and the integrator's own claims."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from sindyship.errors import SindyshipInputError
from sindyship.manoeuvres import Manoeuvre, fly, turning_figures, zigzag_figures
from sindyship.mmg import MMGModel, force_components
from sindyship.simulation import (
    ConstantCommand,
    PrescribedRudder,
    ZigZagCommand,
    simulate_batch,
)

GOLDEN = json.loads((Path(__file__).parent / "golden" / "kcs.json").read_text())


def by_name(runs):
    return {r.name: r for r in runs["train"] + runs["test"]}


def test_straight_run_stays_at_equilibrium(protocol_runs, kcs):
    run = by_name(protocol_runs)["straight"]
    u = run["u"] / kcs.U0
    assert np.all(np.abs(u - 1.0001) <= 0.0005)
    assert np.max(np.abs(run["y"])) < 1e-9 and np.max(np.abs(run["psi"])) < 1e-12


@pytest.mark.parametrize(("name", "advance", "tactical"),
                         [("tc35_stbd", 3.56, 3.37), ("tc35_port", 3.42, 3.14)])
def test_turning_circle_matches_independent_implementation(protocol_runs, kcs, name, advance,
                                                           tactical):
    figures = turning_figures(by_name(protocol_runs)[name], kcs.L)
    assert figures["advance_L"] == pytest.approx(advance, rel=0.02)
    assert figures["tactical_diameter_L"] == pytest.approx(tactical, rel=0.02)


def test_port_turn_is_tighter_than_starboard(protocol_runs, kcs):
    runs = by_name(protocol_runs)
    stbd = turning_figures(runs["tc35_stbd"], kcs.L)
    port = turning_figures(runs["tc35_port"], kcs.L)
    assert port["tactical_diameter_L"] < stbd["tactical_diameter_L"] - 0.1
    assert runs["tc35_stbd"]["psi"][-1] > 0 > runs["tc35_port"]["psi"][-1]


def test_standard_figures_match_golden(protocol_runs, kcs):
    runs = by_name(protocol_runs)
    tol = GOLDEN["tolerance_rel"]
    for name, expected in GOLDEN["turning"].items():
        got = turning_figures(runs[name], kcs.L)
        for key, value in expected.items():
            assert got[key] == pytest.approx(value, rel=tol, abs=1e-9), (name, key)
    for name, expected in GOLDEN["zigzag"].items():
        got = zigzag_figures(runs[name])
        for key, value in expected.items():
            assert got[key] == pytest.approx(value, rel=tol), (name, key)


def test_a_zigzag_ended_with_the_rudder_held_keeps_its_last_overshoot(protocol_runs):
    """A trial that stops reversing after its second reversal (the MARIN 10/10 zig-zags)
    keeps the second overshoot once the heading has turned back, not before."""
    from sindyship.manoeuvres import zigzag_events
    from sindyship.trajectory import Trajectory

    run = by_name(protocol_runs)["zz10_10"]
    events = zigzag_events(run)
    third, second_peak = events["reversals"][2], events["peaks"][1]
    full = zigzag_figures(run)["second_overshoot_deg"]
    for stop, kept in ((third, True), (second_peak + 2, False)):
        # cut before the third reversal: the rudder is held from the second to the end
        figures = zigzag_figures(Trajectory(run.data.iloc[:stop].copy(), name="held"))
        assert figures["first_overshoot_deg"] == pytest.approx(
            zigzag_figures(run)["first_overshoot_deg"], rel=1e-12)
        if kept:
            assert figures["second_overshoot_deg"] == pytest.approx(full, rel=1e-12)
        else:  # the heading has hardly turned back from its peak when the record ends
            assert math.isnan(figures["second_overshoot_deg"])


def test_a_record_without_a_rudder_reversal_has_no_overshoot(protocol_runs):
    figures = zigzag_figures(by_name(protocol_runs)["tc35_stbd"])
    assert all(math.isnan(value) for value in figures.values())


def test_no_overshoot_is_counted_after_the_rudder_goes_back_amidships(protocol_runs):
    """A zig-zag whose rudder goes to 0 at its second reversal has no second overshoot (the
    heading then runs on with no rudder), and a leg whose heading never passes the heading
    at its reversal has none either."""
    from sindyship.manoeuvres import zigzag_events
    from sindyship.trajectory import Trajectory

    run = by_name(protocol_runs)["zz10_10"]
    second = zigzag_events(run)["reversals"][1]
    data = run.data.iloc[:second + 400].copy()
    for column in ("delta", "delta_c"):
        data.loc[data.index[second:], column] = 0.0
    figures = zigzag_figures(Trajectory(data, name="amidships"))
    assert math.isfinite(figures["first_overshoot_deg"])
    assert math.isnan(figures["second_overshoot_deg"])
    # a rudder that passes through exactly 0 on its way to the other side still reverses
    third = zigzag_events(run)["reversals"][2]
    data = run.data.iloc[:third].copy()
    data.loc[data.index[second], ["delta", "delta_c"]] = 0.0
    passed = zigzag_figures(Trajectory(data, name="through zero"))["second_overshoot_deg"]
    assert passed == pytest.approx(zigzag_figures(run)["second_overshoot_deg"], abs=0.2)
    turn = by_name(protocol_runs)["tc35_stbd"].data.copy()  # a small counter-rudder first
    turn.loc[turn.index[:3], ["delta", "delta_c"]] = -0.01
    turn.loc[turn.index[3:20], ["delta", "delta_c"]] = 0.0
    assert math.isnan(zigzag_figures(Trajectory(turn, name="turn"))["first_overshoot_deg"])


def test_zigzag_reverses_rudder_at_check_angle(protocol_runs):
    run = by_name(protocol_runs)["zz20_20"]
    cmd = np.sign(run["delta_c"])
    flips = np.flatnonzero(np.diff(cmd) != 0) + 1
    assert len(flips) >= 8
    psi = np.degrees(run["psi"])
    for k in flips:
        # the heading crossed +-20 deg between the two samples around each reversal
        assert abs(psi[k - 1]) <= 20.0 + 1e-9 <= abs(psi[k]) + 1e-9 or abs(psi[k]) > 20.0


def test_rudder_rate_limit_binds_with_fast_servo(kcs):
    fast = kcs.with_servo(T_R=0.1)
    (run,) = fly(MMGModel(fast), [Manoeuvre("turning-circle", rudder=35, duration=60, dt=0.25)])
    rate = np.degrees(np.diff(run["delta"]) / 0.25)
    assert rate.max() == pytest.approx(5.0, rel=0.01)
    assert np.mean(np.abs(rate[:20] - 5.0) < 0.05) > 0.9  # the first 5 s are at the limit
    assert np.degrees(run["delta"][-1]) == pytest.approx(35.0, abs=1e-3)
    (slow,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=35, duration=60, dt=0.25)])
    assert np.degrees(np.diff(slow["delta"]) / 0.25).max() < 5.0


@pytest.mark.parametrize(("sample_interval", "step"), [(1.0, None), (0.3, None), (1.0, 2.5),
                                                      (0.3, 0.37)])
def test_a_prescribed_rudder_is_flown_exactly_while_it_moves(kcs, sample_interval, step):
    """A replayed rudder angle (linear between samples) is the flown angle at every output
    time, also while it moves, alone or beside a commanded rudder that steps differently: a
    Runge-Kutta stage at the end of a step that ends on a sample takes the rate of the
    interval it ends, not of the next one (that led by h/6 of the change)."""
    t = np.arange(0.0, 60.0, sample_interval)
    ramp = np.clip(2.0 * (t - 10.0), 0.0, 20.0) - np.clip(2.0 * (t - 30.0), 0.0, 20.0)
    angles = np.radians(ramp)  # up at 2 deg/s from 10 s, back down from 30 s
    out = np.arange(0.0, 59.0, 0.25)
    state0 = np.array([kcs.U0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    for companions in ([], [ConstantCommand(math.radians(10.0))]):
        results = simulate_batch(MMGModel(kcs), [PrescribedRudder(t, angles), *companions],
                                 out, state0, step=step)
        flown = np.degrees(results[0].states[6])
        assert np.max(np.abs(flown - np.interp(out, t, ramp))) < 1e-9, len(companions)


def test_halving_the_step_moves_positions_less_than_1e4_L(kcs):
    mmg = MMGModel(kcs)
    manoeuvres = [Manoeuvre("zigzag", rudder=35, check=10, duration=1600),
                  Manoeuvre("spiral", rudder=35, duration=1600)]
    coarse = fly(mmg, manoeuvres)
    fine = fly(mmg, manoeuvres, step=0.5 * 0.1 * kcs.time_scale)
    for a, b in zip(coarse, fine, strict=True):
        assert np.max(np.hypot(a["x"] - b["x"], a["y"] - b["y"])) / kcs.L < 1e-4


def test_unstable_model_stops_with_divergence_time(kcs):
    class Unstable:
        ship = kcs

        def accelerations(self, u, v, r, delta, psi, branch=None):
            return 0.0 * u, 0.0 * u, 0.02 * r + 1e-4

    (result,) = simulate_batch(Unstable(), [ConstantCommand(0.0)], np.arange(3200.0),
                               np.array([kcs.U0, 0, 0, 0, 0, 0, 0]))
    assert result.diverged_at is not None and 10 < result.diverged_at < 3200
    k = int(result.diverged_at)
    assert np.isnan(result.states[:, k:]).all() and np.isfinite(result.states[:, :k]).all()


def test_force_function_is_the_simulators(kcs):
    mmg = MMGModel(kcs)
    u, v, r, d = 11.0, -0.6, 0.004, math.radians(20)
    parts = force_components(kcs, u / kcs.U0, v / kcs.U0, r * kcs.L / kcs.U0, d)
    assert set(parts) == {"hull", "propeller", "rudder", "coriolis"}
    a = mmg.accelerations(u, v, r, d, 0.0)
    X = sum(p[0] for p in parts.values())
    M = np.array([[kcs.mass.m + kcs.mass.m_x]])
    assert a[0] == pytest.approx(X / M[0, 0] * kcs.U0**2 / kcs.L, rel=1e-12)


def test_zigzag_first_sign_port_mirrors(kcs):
    mmg = MMGModel(kcs.with_rudder(gamma_R_port=kcs.rudder.gamma_R_stbd))
    t = np.arange(600.0)
    s0 = np.array([kcs.U0, 0, 0, 0, 0, 0, 0])
    a, b = simulate_batch(mmg, [ZigZagCommand(math.radians(20), math.radians(20), 1),
                                ZigZagCommand(math.radians(20), math.radians(20), -1)], t, s0)
    np.testing.assert_allclose(a.states[5], -b.states[5], atol=1e-9)
    np.testing.assert_allclose(a.states[4], -b.states[4], atol=1e-6)


def test_a_pull_out_on_the_command_line_returns_within_its_record(tmp_path):
    """The rudder returns at half the record unless told (it was 1000 s for every ship and
    record, so a 600 s pull-out of the 7 m KVLCC2 was a turning circle); a return after the
    record's end is refused."""
    from cli_in_process import run_sindyship

    from sindyship.measurements import read_csv

    out = tmp_path / "po.csv"
    code, _, err = run_sindyship("simulate", "--ship", "kvlcc2", "--manoeuvre", "pull-out",
                                 "--rudder", "10", "--duration", "600", "--out", str(out))
    assert code == 0, err
    record = read_csv(out)
    assert np.all(record["delta_c"][record.t >= 300.0] == 0.0)
    assert np.all(record["delta_c"][record.t < 300.0] > 0.0)
    code, _, err = run_sindyship("simulate", "--ship", "kvlcc2", "--manoeuvre", "pull-out",
                                 "--duration", "600", "--pull-out-time", "700", "--out",
                                 str(out))
    assert code == 2 and "--pull-out-time 700 s is not before the record's end" in err
    with pytest.raises(SindyshipInputError, match="pull_out_time 1000 s is not within"):
        Manoeuvre("pull-out", rudder=10, duration=600)


def test_pull_out_returns_rudder_to_zero_and_yaw_decays(kcs):
    (run,) = fly(MMGModel(kcs), [Manoeuvre("pull-out", rudder=20, pull_out_time=600,
                                           duration=1600)])
    assert np.degrees(run["delta_c"][700]) == pytest.approx(0.0)
    assert abs(run["r"][-1]) < 0.2 * abs(run["r"][599])


def test_random_rudder_is_reproducible_by_seed(kcs):
    mmg = MMGModel(kcs)
    a, b, c = fly(mmg, [Manoeuvre("random", rudder=20, seed=3, duration=900),
                        Manoeuvre("random", rudder=20, seed=3, duration=900),
                        Manoeuvre("random", rudder=20, seed=4, duration=900)])
    np.testing.assert_array_equal(a["x"], b["x"])
    assert not np.array_equal(a["delta_c"], c["delta_c"])
    assert np.degrees(np.abs(a["delta_c"])).max() <= 20.0
    assert len(np.unique(a["delta_c"])) >= 5


def test_fly_takes_a_fitted_model_as_it_does_an_mmg(kcs):
    from sindyship.model import paper_model

    model = paper_model(kcs)
    plan = [Manoeuvre("zigzag", rudder=20, check=20, duration=300)]
    (direct,) = fly(model, plan)
    (through,) = fly(model.dynamics(), plan)
    np.testing.assert_array_equal(direct.state(), through.state())


def test_a_replayed_rudder_is_interpolated_exactly_as_numpy_does():
    """The replayed angle is np.interp's, to the last bit: at, between, before and after the
    samples, for records of one, two and many samples."""
    from sindyship.simulation.kernels import PrescribedRudder

    rng = np.random.default_rng(20261127)
    for n in (1, 2, 7, 500):
        times = np.cumsum(rng.uniform(0.05, 2.0, n))
        angles = rng.normal(0.0, 0.3, n)
        rudder = PrescribedRudder(times, angles)
        probes = np.concatenate([times, times - 1e-7, times + 1e-7,
                                 rng.uniform(times[0] - 3.0, times[-1] + 3.0, 400)])
        for t in probes:
            assert rudder.value(float(t), None) == float(np.interp(t, times, angles)), (n, t)
    assert math.isnan(PrescribedRudder(np.array([0.0, 1.0]), np.zeros(2)).value(math.nan, None))


@pytest.mark.parametrize("arguments, message", [
    ({"kind": "zigzag", "rudder": 20, "check": 20, "first_sign": 0},
     r"^first_sign is 0; give \+1 \(starboard first\) or -1 \(port\)\.$"),
    ({"kind": "spiral", "rudder": 20, "first_sign": 2}, r"^first_sign is 2"),
    ({"kind": "random", "rudder": 120}, r"^rudder 120 deg is no rudder angle; Manoeuvre takes "
                                        r"degrees, up to the ship's rudder limit\.$"),
])
def test_a_manoeuvre_refuses_what_it_would_fly_wrongly(arguments, message):
    """A zig-zag with first side 0 had flown as a starboard one.  A rudder below 1 deg is
    taken (an unstable ship loops on it: tests/test_units_on_load.py)."""
    with pytest.raises(SindyshipInputError, match=message):
        Manoeuvre(**arguments)


def test_fly_refuses_a_rudder_beyond_the_ships_limit_and_a_state_of_another_shape(kcs):
    """A 60 deg turn had flown as tc60_stbd with its actual rudder held at 35 deg."""
    with pytest.raises(SindyshipInputError, match=(
            r"^tc60_stbd: rudder 60 deg is beyond the rudder limit of kcs \(35 deg\); give an "
            r"angle of magnitude up to 35 deg\.$")):
        fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=60)])
    with pytest.raises(SindyshipInputError, match=(
            r"^state0 has shape \(3,\); give 7 finite values \[u, v, r, x, y, psi, delta\]")):
        fly(MMGModel(kcs), [Manoeuvre("straight", duration=10)], state0=np.array([12.0, 0, 0]))
    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=-35, duration=10)])
    assert run.name == "tc35_port"
    with pytest.raises(TypeError, match=(
            r"^manoeuvres must be a list of Manoeuvre, not a record; to fly a model the way a "
            r"record was flown use sindyship\.evaluate")):
        fly(MMGModel(kcs), run)  # had failed inside pandas with KeyError: 0

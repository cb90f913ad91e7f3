"""Each simulator effect moves the trajectory the way its physics says."""

from __future__ import annotations

import numpy as np
import pytest

from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.errors import SindyshipInputError
from sindyship.manoeuvres import Manoeuvre

STRAIGHT = Manoeuvre("straight", duration=400)
TURN = Manoeuvre("turning-circle", rudder=20, duration=600)


def run(ship, effects, manoeuvre=STRAIGHT):
    return simulate_with_effects(ship, [manoeuvre], parse_effects(effects))[0]


@pytest.fixture(scope="module")
def calm(kcs):
    return {"straight": run(kcs, []), "turn": run(kcs, [], TURN)}


@pytest.mark.parametrize(("direction", "sign"), [(0, -1), (180, 1)])
def test_head_and_following_load_slow_or_speed_the_ship(kcs, calm, direction, sign):
    loaded = run(kcs, ["load=0.002", f"load_dir={direction}"])
    assert sign * (loaded["x"][-1] - calm["straight"]["x"][-1]) > 5.0


@pytest.mark.parametrize(("direction", "sign"), [(90, -1), (270, 1)])
def test_beam_load_first_pushes_the_ship_sideways_away_from_it(kcs, direction, sign):
    # the hull then turns (weather-vaning), so judge by the early sway velocity and drift
    loaded = run(kcs, ["load=0.002", f"load_dir={direction}"])
    assert sign * loaded["v"][5:30].mean() > 0.01
    assert sign * loaded["y"][30] > 0.1


def test_load_arm_turns_the_bow(kcs):
    # a force from the east (pushing west = to port) acting ahead of midship yaws to port
    bow = run(kcs, ["load=0.002", "load_dir=90", "load_arm=0.4"])
    stern = run(kcs, ["load=0.002", "load_dir=90", "load_arm=-0.4"])
    assert bow["psi"][50] < 0 < stern["psi"][50]


@pytest.mark.parametrize(("toward", "axis", "sign"), [(90, "y", 1), (180, "x", -1)])
def test_current_drifts_the_record_over_ground(kcs, calm, toward, axis, sign):
    drifted = run(kcs, ["current=1.0", f"current_dir={toward}"])
    t = drifted.t[-1]
    shift = drifted[axis][-1] - calm["straight"][axis][-1]
    assert shift == pytest.approx(sign * 1.0 * t, rel=1e-9)
    # the hull sees the same water: heading and yaw rate are unchanged
    np.testing.assert_allclose(drifted["psi"], calm["straight"]["psi"], atol=1e-12)
    if toward == 90:
        np.testing.assert_allclose(drifted["v"], calm["straight"]["v"] + 1.0, atol=1e-9)


def test_crossflow_drag_widens_the_turn_and_reduces_drift(kcs, calm):
    dragged = run(kcs, ["crossflow=0.5"], TURN)
    assert np.abs(dragged["v"][300:]).mean() < np.abs(calm["turn"]["v"][300:]).mean()
    assert dragged["psi"][-1] < calm["turn"]["psi"][-1]


def test_propeller_side_force_yaws_the_ship(kcs):
    # a starboard force at the stern pushes the stern to starboard: the bow turns to port
    pushed = run(kcs, ["prop_side_force=0.0005"])
    assert pushed["psi"][-1] < -0.01
    assert run(kcs, ["prop_side_force=-0.0005"])["psi"][-1] > 0.01


def test_rudder_offset_shifts_the_record_and_turns_the_ship(kcs):
    offset = run(kcs, ["rudder_offset=2"])
    # the indicator reads zero: the true rudder is -2 deg, turning to port
    assert offset["psi"][-1] < -0.05
    np.testing.assert_allclose(offset["delta"], 0.0, atol=1e-12)


def test_noise_is_reproducible_by_seed(kcs, calm):
    a = run(kcs, ["noise=0.01", "seed=4"], TURN)
    b = run(kcs, ["noise=0.01", "seed=4"], TURN)
    c = run(kcs, ["noise=0.01", "seed=5"], TURN)
    np.testing.assert_array_equal(a["r"], b["r"])
    assert not np.array_equal(a["r"], c["r"])
    residual = a["r"] - calm["turn"]["r"]
    rms = np.sqrt(np.mean(calm["turn"]["r"] ** 2))
    assert np.std(residual) == pytest.approx(0.01 * rms, rel=0.15)


def test_quantise_keeps_significant_figures(kcs):
    q = run(kcs, ["quantise=3"], TURN)
    u = q["u"][1:]
    digits = np.array([len(f"{x:.6e}".split("e")[0].replace(".", "").rstrip("0")) for x in u])
    assert digits.max() <= 3


@pytest.mark.parametrize("bad", ["gale=3", "load=abc", "noise=-1", "quantise=2.5", "load"])
def test_bad_effect_is_one_clear_error(bad):
    with pytest.raises(SindyshipInputError, match="effect"):
        parse_effects([bad])


def test_a_lagging_rudder_sensor_records_the_angle_late_and_leaves_the_motion(kcs, calm):
    lagged = run(kcs, ["rudder_lag=4"], TURN)
    t = calm["turn"].t
    assert np.array_equal(lagged["x"], calm["turn"]["x"])
    assert np.array_equal(lagged["delta_c"], calm["turn"]["delta_c"])
    np.testing.assert_allclose(lagged["delta"], np.interp(t - 4.0, t, calm["turn"]["delta"]))


def test_a_stalling_rudder_turns_wider(kcs, calm):
    stalled = run(kcs, ["rudder_stall=5"], TURN)
    assert np.ptp(stalled["y"]) > 1.1 * np.ptp(calm["turn"]["y"])


def test_a_bank_to_the_west_turns_the_bow_away_from_it(kcs, calm):
    near = run(kcs, ["bank=0.005", "bank_distance=-3"])
    assert near["y"][-1] > calm["straight"]["y"][-1] + 10.0
    with pytest.raises(SindyshipInputError, match="within one ship length"):
        parse_effects(["bank=0.005", "bank_distance=0.5"])


def test_a_shallow_patch_raises_the_linear_hull_forces_beyond_its_edge(kcs):
    """Forces: beyond the edge the linear hull derivatives are (1 + increase) times their
    deep-water values; far from it nothing changes, and on the edge half the increase."""
    from sindyship.mmg import MMGModel, patch_share

    patch = (2.0 * kcs.L, np.radians(90.0), 0.8)  # shallow east of y = 2 L
    plain, shallow = MMGModel(kcs), MMGModel(kcs, patch=patch)
    state = (0.95 * kcs.U0, -0.3, 0.004, np.radians(10.0), 0.3)
    deep = shallow.forces(*state, position=(0.0, -10.0 * kcs.L))
    assert deep["effects"] == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    beyond = shallow.forces(*state, position=(0.0, 10.0 * kcs.L))
    u, v, r = state[0] / kcs.U0, state[1] / kcs.U0, state[2] * kcs.L / kcs.U0
    beta, hull = np.arctan2(-v, u), kcs.hull
    assert beyond["effects"] == pytest.approx(
        (0.0, 0.8 * (hull["Y_b"] * beta + hull["Y_r_minus_mx"] * r),
         0.8 * (hull["N_b"] * beta + hull["N_r"] * r)), rel=1e-9)
    assert beyond["hull"] == pytest.approx(plain.forces(*state)["hull"], rel=1e-12)
    assert patch_share(kcs, patch, 0.0, 2.0 * kcs.L) == pytest.approx(0.5)
    assert shallow.uses_position and not plain.uses_position


def test_a_shallow_patch_changes_a_turn_only_once_the_ship_reaches_it(kcs, calm):
    """A 20 deg turn to starboard heads east: with shallow water beyond 1.5 L east of the
    start the track agrees with the calm one until the ship nears the edge, then the stiffer
    hull turns it wider; a patch 100 L away changes nothing."""
    far = run(kcs, ["shallow_patch=0.8", "patch_distance=100"], TURN)
    np.testing.assert_allclose(far["y"], calm["turn"]["y"], atol=1e-6)
    near = run(kcs, ["shallow_patch=0.8", "patch_distance=1.5", "patch_dir=90"], TURN)
    y_calm = calm["turn"]["y"]
    before = y_calm < 0.5 * kcs.L  # more than a ship length short of the edge
    first = int(np.argmin(before))
    np.testing.assert_allclose(near["y"][:first], y_calm[:first], atol=0.05 * kcs.L)
    assert np.ptp(near["x"]) > np.ptp(calm["turn"]["x"]) + 0.1 * kcs.L
    assert parse_effects(["shallow_patch=0.8"]).active() == ["shallow_patch"]
    with pytest.raises(SindyshipInputError, match="shallow_patch"):
        parse_effects(["shallow_patch=3"])

"""Channels in a unit their header does not say, caught on load: a rudder in radians under a
degree header, revolutions in rps under an rpm header, a wind direction in degrees under a bare
header, and which of psi, r or x, y carries the wrong unit (sindyship.plausibility)."""

from __future__ import annotations

import numpy as np
import pytest

from sindyship.errors import SindyshipInputError
from sindyship.measurements import trajectory_from_frame


@pytest.fixture(scope="module")
def records(protocol_runs):
    return {r.name: r for r in protocol_runs["train"] + protocol_runs["test"]}


def refusal(frame, **options) -> str:
    with pytest.raises(SindyshipInputError) as caught:
        trajectory_from_frame(frame, "run", source="run.csv", **options)
    message = str(caught.value)
    assert "\n" not in message and message.startswith("run.csv: ")
    return message


@pytest.mark.parametrize("name", ["zz20_20", "zz10_10", "zz35_10"])
def test_a_rudder_in_radians_under_a_degree_header_is_refused(records, name):
    """A 20/20 zig-zag of the KCS reads 0.35 deg against r' = 0.36: no rudder that small
    turns a ship that fast, and the yaw acceleration follows it."""
    data = records[name].data
    message = refusal(data.rename(columns={"delta": "delta [deg]", "delta_c": "delta_c [deg]"}),
                      ship="kcs")
    assert "rudder-size check" in message and "look like radians" in message
    assert "'delta [rad]' or a bare 'delta'" in message
    assert "deg while the ship turns to both sides at up to r' = r L/U0 = " in message
    # the same numbers under bare headers are radians, and load
    trajectory_from_frame(data, name, ship="kcs")
    # and radians under a bare header read as such but a hundred times smaller: no hint
    small = refusal(data.assign(delta=data["delta"] / 100.0, delta_c=data["delta_c"] / 100.0),
                    ship="kcs")
    assert "rudder-size check" in small and "check the unit of 'delta" in small


def test_every_protocol_record_passes_the_rudder_size_check(records):
    for record in records.values():
        trajectory_from_frame(record.data, record.name, ship="kcs")


@pytest.mark.parametrize(("manoeuvre", "rudder"), [("random", 0.3), ("random", 0.5),
                                                   ("zigzag", 0.3)])
def test_an_unstable_ship_looping_on_a_small_rudder_is_no_rudder_in_radians(manoeuvre, rudder):
    """The KVLCC2 is directionally unstable: with a few tenths of a degree of rudder it turns
    in its loop at r' = 0.2 to one side (at most 0.05 to the other), 40 times its rudder in
    radians, and its yaw acceleration follows the rudder; it turns to one side only, which a
    zig-zag in radians read as degrees never does, and loads."""
    from sindyship.manoeuvres import Manoeuvre, fly
    from sindyship.mmg import MMGModel
    from sindyship.ships import load_ship

    kvlcc2 = load_ship("kvlcc2")
    (run,) = fly(MMGModel(kvlcc2), [Manoeuvre(manoeuvre, rudder=rudder, check=10.0, dt=0.2,
                                               duration=900, seed=2)])
    turning = run["r"] * kvlcc2.L / kvlcc2.U0
    assert max(abs(turning.min()), turning.max()) > 20 * np.radians(rudder)
    trajectory_from_frame(run.data, run.name, ship=kvlcc2)


def test_a_ship_turning_on_with_its_rudder_amidships_is_no_rudder_in_radians(records, seed):
    """A pull-out: the steady turn of a hard-over turning circle with the rudder read as
    amidships (noise of 0.05 deg) turns on at r' = 0.4 but does not follow the rudder."""
    data = records["tc35_stbd"].data.iloc[400:].reset_index(drop=True)
    noise = np.radians(0.05) * np.random.default_rng(seed).standard_normal(len(data))
    trajectory_from_frame(data.assign(delta=noise, delta_c=noise), "pull-out", ship="kcs")


def test_revolutions_in_rps_under_an_rpm_header_are_refused(records, kcs):
    data = records["zz20_20"].data.assign(n=kcs.propeller.n_P)  # 1.93 rps
    message = refusal(data.rename(columns={"n": "n [rpm]"}), ship="kcs")
    assert "revolutions check" in message and "never exceeds 0.03209 rps" in message
    assert "the values look like rps, so write the header as 'n [rps]'" in message
    # a stopped propeller (n = 0 throughout) and the same numbers under a bare header load
    trajectory_from_frame(data, "run", ship="kcs")
    trajectory_from_frame(data.assign(n=0.0), "run", ship="kcs")


def test_a_wind_direction_in_degrees_under_a_bare_header_is_refused(records):
    data = records["zz20_20"].data.assign(wind_speed=5.0, wind_dir=270.0)
    message = refusal(data)
    assert "column 'wind_dir' reaches 270" in message
    assert "the values look like degrees, so write the header as 'wind_dir [deg]'" in message
    record = trajectory_from_frame(data.rename(columns={"wind_dir": "wind_dir [deg]"}), "run")
    assert record["wind_dir"][0] == pytest.approx(np.radians(270.0))


def test_the_track_tells_which_of_psi_and_r_has_the_wrong_unit(records):
    """The heading check sees psi turn 57 times more or less than the integral of r; the
    track, which (u, v) rotated by the right psi integrate to, tells which column is wrong."""
    data = records["zz20_20"].data
    psi_in_rad = refusal(data.rename(columns={"psi": "psi [deg]"}))
    assert "heading check" in psi_in_rad
    assert "'psi [deg]' looks like rad: write the header as 'psi [rad]'" in psi_in_rad
    r_in_rad = refusal(data.rename(columns={"r": "r [deg/s]"}))
    assert "heading check" in r_in_rad and "check the unit of 'r [deg/s]'" in r_in_rad
    psi_in_degrees = refusal(data.assign(psi=np.degrees(data["psi"])))
    assert "the heading looks like degrees, so write the header as 'psi [deg]'" in psi_in_degrees
    bracket = refusal(data.assign(psi=np.degrees(data["psi"])).rename(columns={
        "psi": "psi [rad]", "r": "r [rad/s]"}))
    assert "'psi [rad]' looks like deg: write the header as 'psi [deg]'" in bracket


def test_positions_in_km_are_not_taken_for_milliseconds(records):
    data = records["tc35_stbd"].data
    message = refusal(data.assign(x=data["x"] / 1000.0, y=data["y"] / 1000.0))
    assert "frame check" in message and "x and y look like km" in message
    assert "'x [km]' and 'y [km]'" in message and "milliseconds" not in message


@pytest.mark.parametrize("verb", ["evaluate", "fit"])
def test_a_record_shorter_than_one_ship_length_time_is_refused(records, tmp_path, verb):
    """Records shorter than L/U0 scored as near-perfect flights (a review's 20 samples of a
    KVLCC2 zig-zag flew 0.0001 L off, two samples for 0 s): 15 s of a KCS zig-zag (L/U0 =
    18.6 s) are refused, 39 s load."""
    from cli_in_process import run_sindyship

    from sindyship.measurements import write_csv
    from sindyship.model import paper_model
    from sindyship.ships import load_ship
    from sindyship.trajectory import Trajectory

    paper_model(load_ship("kcs"), "LS").save(tmp_path / "model.json")
    zigzag = records["zz20_20"]
    path = tmp_path / "short.csv"
    write_csv(Trajectory(zigzag.data.iloc[100:115].reset_index(drop=True), name="short"), path)
    before = ["evaluate", tmp_path / "model.json"] if verb == "evaluate" else ["fit"]
    after = [] if verb == "evaluate" else ["--out", tmp_path / "fitted.json"]
    code, out, err = run_sindyship(*before, path, "--ship", "kcs", *after)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1
    assert f"{path}: the record lasts 14 s, shorter than one ship-length time L/U0 = " in err
    assert "too short to show the ship's response to its rudder" in err
    write_csv(Trajectory(zigzag.data.iloc[100:140].reset_index(drop=True), name="short"),
              path)  # 39 s
    code, _, err = run_sindyship(*before, path, "--ship", "kcs", *after)
    assert code == 0, err


def test_revolutions_above_the_ships_raise_the_speed_limit():
    """The KVLCC2 at its published revolutions runs at 1.51 U0, with 10 % more revolutions at
    1.67 U0: simulate's own record loads (the speed check had called it knots); the same speed
    with the ship's own revolutions is refused."""
    from sindyship.effects import Effects, simulate_with_effects
    from sindyship.manoeuvres import Manoeuvre
    from sindyship.ships import load_ship

    kvlcc2 = load_ship("kvlcc2")
    (run,) = simulate_with_effects(kvlcc2, [Manoeuvre("straight", dt=0.2, duration=600)],
                                   Effects(rps=1.1))
    assert run["u"].max() / kvlcc2.U0 == pytest.approx(1.67, abs=0.02)
    trajectory_from_frame(run.data, run.name, ship=kvlcc2)
    message = refusal(run.data.assign(n=kvlcc2.propeller.n_P), ship=kvlcc2)
    assert "speed check" in message and "look like knots" in message

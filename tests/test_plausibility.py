"""Plausibility checks on load, and trials as logged (sindyship.plausibility, sindyship.trials)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest
from cli_in_process import run_sindyship

from sindyship.effects import add_noise, parse_effects, simulate_with_effects
from sindyship.errors import SindyshipInputError
from sindyship.manoeuvres import Manoeuvre, fly, protocol_manoeuvres, result_to_trajectory
from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
from sindyship.measurements import PlausibilityNote, read_csv, trajectory_from_frame, write_csv
from sindyship.mmg import MMGModel
from sindyship.plausibility import CHECKS, frame_misfit, heading_gain
from sindyship.rudder_holds import HOLD_RANGE, stretch_end
from sindyship.ships import load_ship
from sindyship.simulation import RudderCommand, simulate_batch
from sindyship.trajectory import Trajectory
from sindyship.trials import (
    explain_zigzag,
    flight_start,
    recognise_zigzag,
    trim,
    underway_window,
)


def refusal(frame: pd.DataFrame, **options) -> str:
    with pytest.raises(SindyshipInputError) as caught:
        trajectory_from_frame(frame, "run", source="run.csv", **options)
    message = str(caught.value)
    assert "\n" not in message and message.startswith("run.csv: ")
    return message


def loads(record: Trajectory, ship=None) -> Trajectory:
    """The record through the reader's checks, with warnings turned into errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return trajectory_from_frame(record.data, record.name, ship=ship)


@pytest.fixture(scope="module")
def zigzag(protocol_runs):
    return next(r for r in protocol_runs["train"] if r.name == "zz20_20")


# --- refusals ----------------------------------------------------------------------------------


def test_heading_in_degrees_under_a_bare_header_is_refused_by_fit(zigzag, tmp_path):
    data = zigzag.data.assign(psi=np.degrees(zigzag["psi"]))
    path = tmp_path / "zz.csv"
    data.to_csv(path, index=False)
    code, out, err = run_sindyship("fit", path, "--ship", "kcs", "--out",
                                   tmp_path / "model.json")
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and "Traceback" not in err
    assert str(path) in err and "heading check" in err
    assert "57.3" in err and "'psi [deg]'" in err
    assert "skip_checks=['heading']" in err
    assert not (tmp_path / "model.json").exists()
    # with its unit the same numbers load
    record = trajectory_from_frame(data.rename(columns={"psi": "psi [deg]"}), ship="kcs")
    np.testing.assert_allclose(record["psi"], zigzag["psi"], atol=1e-12)


def test_flipped_heading_sign_is_refused(zigzag):
    message = refusal(zigzag.data.assign(psi=-zigzag["psi"]))
    assert "heading check" in message and "-1" in message and "opposite" in message


def test_earth_fixed_velocities_are_refused(protocol_runs):
    turn = protocol_runs["train"][1]  # tc35_stbd
    psi, u, v = turn["psi"], turn["u"], turn["v"]
    north, east = u * np.cos(psi) - v * np.sin(psi), u * np.sin(psi) + v * np.cos(psi)
    data = turn.data.assign(u=north, v=east)
    message = refusal(data)
    assert "frame check" in message and "look earth-fixed" in message
    assert "skip_checks=['frame']" in message
    assert trajectory_from_frame(data, skip_checks=["frame"]).n_samples == turn.n_samples


def test_time_in_milliseconds_is_refused(zigzag, protocol_runs):
    data = zigzag.data.assign(t=zigzag["t"] * 1000.0)
    with_ship = refusal(data, ship="kcs")
    assert "sampling check" in with_ship and "'t [ms]'" in with_ship
    assert "steps by 1000 s over 3.199e+06 s, 53.7 and 1.72e+05 times" in with_ship
    without_ship = refusal(data)  # r then integrates to 1000 times the heading change
    assert "heading check" in without_ship and "0.001 times" in without_ship
    assert "'t [ms]'" in without_ship
    straight = protocol_runs["train"][0]  # no turn: the track is 1000 times too short instead
    message = refusal(straight.data.assign(t=straight["t"] * 1000.0))
    assert "frame check" in message and "'t [ms]'" in message


def test_knots_under_a_metre_per_second_header_are_refused(zigzag):
    data = zigzag.data.assign(u=zigzag["u"] * 3600 / 1852, v=zigzag["v"] * 3600 / 1852)
    message = refusal(data)
    assert "frame check" in message and "the track is 0.514" in message
    assert "'u [kn]'" in message
    message = refusal(data, ship="kcs", skip_checks="frame")
    assert "speed check" in message and "1.94 times the ship's design speed" in message


def test_sample_interval_far_from_the_time_scale_is_refused(zigzag):
    message = refusal(zigzag.data.assign(t=zigzag["t"] * 1e-9), ship="kcs")
    assert "sampling check" in message and "steps by 1e-09 s" in message


def test_no_motion_and_no_forward_speed_are_refused(zigzag):
    still = zigzag.data.assign(u=0.0, v=0.0, r=0.0, x=0.0, y=0.0, psi=0.0)
    assert "motion check" in refusal(still)
    astern = zigzag.data.assign(u=-zigzag["u"], v=-zigzag["v"], x=-zigzag["x"], y=-zigzag["y"])
    message = refusal(astern)
    assert "forward-speed check" in message and "never positive" in message


def test_unknown_check_name_is_refused(zigzag):
    with pytest.raises(SindyshipInputError, match="unknown plausibility check 'speeed'"):
        trajectory_from_frame(zigzag.data, skip_checks=["speeed"])
    assert set(CHECKS) == {"motion", "sampling", "heading", "frame", "speed", "revolutions",
                           "forward-speed", "rudder-sign", "rudder-size", "jumps"}


def test_a_flipped_rudder_sign_is_refused(protocol_runs):
    """A positive rudder turns the ship to starboard: every protocol record with its rudder
    negated is refused (a turn held against the rudder, or zig-zags whose yaw acceleration
    follows the rudder with the opposite sign), and every one as flown passes."""
    for record in protocol_runs["train"] + protocol_runs["test"]:
        trajectory_from_frame(record.data, record.name)
        if record.name == "straight":
            continue
        flipped = record.data.assign(delta=-record["delta"], delta_c=-record["delta_c"])
        message = refusal(flipped)
        assert "rudder-sign check" in message and "negate it if it is flipped" in message
        expected = "the other way" if record.name.startswith(("tc", "spiral")) \
            else "standard errors below zero"
        assert expected in message, (record.name, message)
        trajectory_from_frame(flipped, record.name, skip_checks=["rudder-sign"])
        # one flipped column is named: the command drives zig-zags and commanded fits
        one = record.data.assign(delta_c=-record["delta_c"])
        assert "check the sign convention of 'delta_c'" in refusal(one)


def test_the_rudder_sign_holds_at_fast_sampling_with_noise_and_in_a_strong_wind(kcs):
    """A flipped zig-zag logged at 20 Hz with 1 % noise and a flipped 200 s turn are refused;
    a 280 s turn in a beam wind 1.6 times the ship's speed, which the wind's yaw moment
    swings, passes (it turns over a quarter circle with its rudder)."""
    def simulated(manoeuvre, effects=()):
        return simulate_with_effects(kcs, [manoeuvre], parse_effects(list(effects)))[0].data

    def flipped(frame):
        return frame.assign(delta=-frame["delta"], delta_c=-frame["delta_c"])

    noisy = simulated(Manoeuvre("zigzag", rudder=20, check=20, duration=300, dt=0.05),
                      ["noise=0.01"])
    trajectory_from_frame(noisy, "zz", ship=kcs)
    assert "standard errors below zero" in refusal(flipped(noisy), ship=kcs)
    short = simulated(Manoeuvre("turning-circle", rudder=35, duration=200, dt=0.1))
    assert "deg the other way" in refusal(flipped(short), ship=kcs)
    windy = simulated(Manoeuvre("turning-circle", rudder=15, duration=280, dt=0.93),
                      ["wind=20", "wind_dir=90"])
    trajectory_from_frame(windy, "tc", ship=kcs)


def test_a_long_record_of_a_quick_zig_zag_is_no_flipped_rudder():
    """A 2 m model's 20/20 zig-zag (legs of some 8 s) logged at 0.2 s for 3200 s: blocks of a
    two-hundredth of the record (16 s) average over a leg and their yaw acceleration lags the
    rudder into the opposite sign (it was refused as a flipped rudder); blocks
    of an eighth of a leg at most read it right, and the record negated is still refused."""
    small = load_ship("kvlcc2").scaled(2.0 / 7.0)
    (run,) = fly(MMGModel(small), [Manoeuvre("zigzag", rudder=20, check=20, duration=3200,
                                             dt=0.2)])
    frame = run.data.drop(columns=["delta_c"])
    trajectory_from_frame(frame, "zz", ship=small)
    assert "standard errors below zero" in refusal(frame.assign(delta=-frame["delta"]),
                                                   ship=small)


def test_a_fast_logged_zigzag_of_the_actual_rudder_is_read_right(kcs):
    """At 0.1 s the KCS's slow servo is a string of short holds, and it leaves its last hold
    only seconds after it turned: the reversal is its turning point, so a 10/10 zig-zag reads
    10/10 (it read 10/15) with the overshoot of the commanded record (it gave 9.4 for 12.0)."""
    from sindyship.manoeuvres import zigzag_figures

    (run,) = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=10, check=10, duration=300,
                                           dt=0.1)])
    actual = Trajectory(run.data.drop(columns=["delta_c"]), "zz")
    zigzag = recognise_zigzag(actual)
    assert (zigzag.amplitude_deg, zigzag.check_deg, zigzag.first_sign) == (10, 10, 1)
    assert zigzag_figures(actual)["first_overshoot_deg"] == pytest.approx(
        zigzag_figures(run)["first_overshoot_deg"], abs=0.3)


def test_a_coarsely_logged_zigzag_is_recognised():
    """The 7 m KVLCC2 logged at 1 s (0.2 L/U0) turns up to some 5 deg between two samples, so
    the heading at its reversals spreads by more than 3 deg; the tolerance grows with r dt."""
    kvlcc2 = load_ship("kvlcc2")
    for rudder, check, first in ((10, 10, 1), (20, 20, 1), (35, 10, -1)):
        (run,) = fly(MMGModel(kvlcc2), [Manoeuvre("zigzag", rudder=rudder, check=check,
                                                   first_sign=first, duration=600, dt=1.0)])
        assert recognise_zigzag(run) == (rudder, check, first, 0.0), explain_zigzag(run)[1]


def test_weather_helm_on_a_course_change_is_no_flipped_rudder():
    """Two hours in a beam wind with 14 deg of port helm held throughout while the course is
    altered 20 deg to starboard: the ship turns against the rudder, but by far less than half
    a circle, and the rudder barely moves, so the record passes."""
    t = np.arange(0.0, 7200.0, 1.0)
    r = np.where((t >= 4000.0) & (t < 5500.0), math.radians(20.0) / 1500.0, 0.0)
    psi = np.concatenate(([0.0], np.cumsum(0.5 * (r[1:] + r[:-1]))))
    x = np.concatenate(([0.0], np.cumsum(8.0 * np.cos(0.5 * (psi[1:] + psi[:-1])))))
    y = np.concatenate(([0.0], np.cumsum(8.0 * np.sin(0.5 * (psi[1:] + psi[:-1])))))
    delta = math.radians(-14.0) + math.radians(1.5) * np.sin(t / 300.0)
    frame = pd.DataFrame({"t": t, "u": 8.0, "v": 0.0, "r": r, "x": x, "y": y, "psi": psi,
                          "delta": delta})
    trajectory_from_frame(frame, "passage")


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("t;u;v;r;x;y;psi;delta\n0;8,5;0;0;0;0;0;0\n1;8,5;0;0;8,5;0;0;0\n",
         "decimal commas (e.g. '8,5') and semicolons"),
        ("t,u,v,r,x,y,psi,delta\n0,8,5,0,0,0,0,0,0\n1,8,5,0,0,8,5,0,0,0\n",
         "decimal commas (9 comma-separated values for 8 columns)"),
        ('t,u,v,r,x,y,psi,delta\n0,"8,5",0,0,0,0,0,0\n1,"8,5",0,0,8.5,0,0,0\n',
         "the decimal comma '8,5'"),
    ],
)
def test_decimal_commas_are_recognised(tmp_path, text, fragment):
    path = tmp_path / "run.csv"
    path.write_text(text)
    with pytest.raises(SindyshipInputError) as caught:
        read_csv(path)
    assert fragment in str(caught.value) and "columns; give every row" not in str(caught.value)


def test_wrapped_heading_is_unwrapped_with_a_note(protocol_runs, tmp_path):
    turn = protocol_runs["train"][1]
    wrapped = np.angle(np.exp(1j * turn["psi"]))
    path = write_csv(Trajectory(turn.data.assign(psi=wrapped), "tc"), tmp_path / "tc.csv")
    with pytest.warns(PlausibilityNote, match=r"tc.csv: column 'psi' is kept within one turn and "
                      r"jumps by a full turn \d+ times, first into row"):
        record = read_csv(path, ship="kcs")
    np.testing.assert_allclose(record["psi"], turn["psi"], atol=1e-9)
    assert len(record.meta["notes"]) == 1 and "unwrapped" in record.meta["notes"][0]


def with_glitch(record: Trajectory, index: int, channel: str = "v",
                by: float = -5.0) -> Trajectory:
    """The record with one sample of ``channel`` moved by ``by`` [m/s]."""
    values = record[channel].copy()
    values[index] += by
    return Trajectory(record.data.assign(**{channel: values}), record.name)


def test_a_sample_leaping_away_at_the_end_is_noted_with_its_row_and_what_to_delete(
        protocol_runs, tmp_path):
    """A logging glitch in the last sample (as the MARIN turn to starboard ends): a note that
    names the row, its time, the size and the rows to delete; the record loads as it was."""
    turn = protocol_runs["train"][1]  # tc35_stbd, sampled every second
    path = write_csv(with_glitch(turn, -1), tmp_path / "tc.csv")
    with pytest.warns(PlausibilityNote) as caught:
        record = read_csv(path, ship="kcs")
    (note,) = [str(w.message) for w in caught]
    last = turn.t[-1]
    assert note == (f"{path}: 'v' changes faster than a ship accelerates at row "
                    f"{turn.n_samples + 1} (counting the header as row 1), t = {last:.10g} s (by "
                    "up to 5 m/s, 0.40 U0; a logging glitch?); the samples are used as "
                    "recorded, so delete its last row (--skip-check jumps, skip_checks=['jumps'] "
                    "in Python, silences this note).")
    assert record.meta["notes"] == [note]
    assert record["v"][-1] == pytest.approx(turn["v"][-1] - 5.0)  # used as recorded


def test_leaps_in_the_middle_are_counted_and_a_skipped_check_says_nothing(protocol_runs):
    zigzag = next(r for r in protocol_runs["train"] if r.name == "zz20_20")
    record = with_glitch(with_glitch(zigzag, 1000, "u", 4.0), 1500, "v", -3.5)
    with pytest.warns(PlausibilityNote) as caught:
        trajectory_from_frame(record.data, "zz", source="zz.csv", ship="kcs")
    (note,) = [str(w.message) for w in caught]
    t = zigzag.t
    assert (f"'u' and 'v' change faster than a ship accelerates in 2 places, the first at the "
            f"row with index label 1000, t = {t[1000]:.10g} s, the last at the row with index "
            f"label 1500, t = {t[1500]:.10g} s ('u' by up to 3.98 m/s, 0.32 U0; a logging "
            "glitch?); the samples are used as recorded, so correct the samples named (") in note
    assert loads(Trajectory(record.data, "zz"), ship=None).meta["notes"] == []  # needs a ship
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        skipped = trajectory_from_frame(record.data, "zz", ship="kcs", skip_checks=["jumps"])
    assert skipped.meta["notes"] == []


def test_a_ramp_too_steep_for_a_ship_is_named_from_its_first_sample_to_its_last(protocol_runs,
                                                                                 kcs):
    """v ramped by 0.3 U0 over 1.5 s, 0.08 L/U0 (no sample away from its running median: the
    median follows the ramp), as the MARIN turn to starboard ends on its own grid: 0.2 U0 in
    the first second, more than the 0.154 U0 allowed."""
    turn = protocol_runs["train"][1]
    v = turn["v"].copy()
    v[2000:] += 0.3 * kcs.U0 * np.clip((turn.t[2000:] - turn.t[2000]) / 1.5, 0.0, 1.0)
    with pytest.warns(PlausibilityNote) as caught:
        trajectory_from_frame(turn.data.assign(v=v), "tc", source="tc.csv", ship=kcs,
                              skip_checks=["frame"])  # v stays moved, off the track
    (note,) = [str(w.message) for w in caught]
    t = turn.t
    assert (f"'v' changes faster than a ship accelerates from the row with index label 2000, "
            f"t = {t[2000]:.10g} s, to the row with index label 2002, t = {t[2002]:.10g} s (by "
            "up to 3.7 m/s, 0.30 U0; a logging glitch?)") in note


def test_a_plateau_and_glitches_at_both_ends_are_named_where_they_are(protocol_runs, kcs):
    """Four samples of v off by 4 m/s in the middle (too wide for the running median): named
    with a sample or two on either side; the first three and the last two samples off: the
    rows to delete at each end (the first three with two good ones: a plateau at the start
    has no good samples before it to tell it by)."""
    turn = protocol_runs["train"][1]
    t = turn.t
    v = turn["v"].copy()
    v[602:606] += 4.0
    v[:3] += 4.0
    v[-2:] -= 4.0
    with pytest.warns(PlausibilityNote) as caught:
        trajectory_from_frame(turn.data.assign(v=v), "tc", source="tc.csv", ship=kcs,
                              skip_checks=["frame"])
    (note,) = [str(w.message) for w in caught]
    assert (f"in 3 places, the first from the row with index label 0, t = {t[0]:.10g} s, to "
            f"the row with index label 4, t = {t[4]:.10g} s, the last from the row with index "
            f"label {len(t) - 2}, t = {t[-2]:.10g} s, to the row with index label {len(t) - 1}") \
        in note  # the last two leap away from the running median: named exactly
    assert "so delete its first 5 rows and its last 2 rows and correct the samples in between (" \
        in note


def test_a_leap_smaller_than_the_noise_or_than_a_ship_accelerates_is_no_glitch(protocol_runs,
                                                                              kcs):
    """A leap within JUMP_SPEED and the change a ship's acceleration allows (0.154 U0 sampled
    every second) is not noted, nor a turn logged every L/U0 (the speed changes 0.1 U0 and more
    between samples at its start), nor 5 % noise."""
    turn = protocol_runs["train"][1]
    loads(with_glitch(turn, -1, by=-0.14 * kcs.U0), ship=kcs)
    step = int(kcs.time_scale // np.median(np.diff(turn.t)))  # 18 s, under L/U0
    coarse = Trajectory(turn.data.iloc[::step].reset_index(drop=True), "coarse")
    assert np.max(np.abs(np.diff(coarse["u"]))) > 0.1 * kcs.U0
    loads(coarse, ship=kcs)
    noise = {c: 0.05 * float(np.sqrt(np.mean(turn[c] ** 2))) for c in ("u", "v")}
    loads(add_noise(turn, noise, seed=3), ship=kcs)


def test_a_time_range_that_leaves_the_leap_out_leaves_the_note_out(protocol_runs, kcs,
                                                                  tmp_path):
    from sindyship.records import read_record

    turn = protocol_runs["train"][1]
    path = write_csv(with_glitch(turn, -1), tmp_path / "tc.csv")
    _, notes, _ = read_record(path, ship=kcs, time_range="all")
    assert len(notes) == 1 and "faster than a ship accelerates" in notes[0]
    _, notes, _ = read_record(path, ship=kcs, time_range=(0.0, float(turn.t[-2])))
    assert notes == []


def test_resampling_across_missing_rows_is_noted_once_on_the_command_line(protocol_runs,
                                                                           tmp_path):
    """Rows missing from a record: resampling bridges the gap with a straight line and says
    so (a resampled record with no gap is read without a note); the command line prints each
    note of the reader once, under the file's name."""
    turn = protocol_runs["train"][1]
    gapped = turn.data.drop(index=range(300, 320))
    path = write_csv(Trajectory(gapped, "tc"), tmp_path / "tc.csv")
    with pytest.warns(PlausibilityNote, match=r"tc.csv: no sample between t = 299 s and 320 s "
                      r"\(21 s, 21 times the median step\); resampling interpolates"):
        record = read_csv(path, resample=1.0)
    assert record.dt == pytest.approx(1.0) and len(record.meta["notes"]) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityNote)
        read_csv(write_csv(turn, tmp_path / "whole.csv"), resample=2.0)
        read_csv(path, resample=25.0)  # a grid coarser than the gap loses nothing to it
    code, _, err = run_sindyship("fit", path, tmp_path / "whole.csv", "--ship", "kcs",
                                 "--resample", "1", "--optimizer", "ls",
                                 "--out", tmp_path / "m.json")
    assert code == 0, err
    (line,) = [line for line in err.splitlines() if "no sample between" in line]
    assert line.startswith(f"{path}: no sample") and line.count("tc.csv") == 1


def test_revolutions_in_rpm_under_a_bare_header_are_refused_against_the_ship():
    """91.5 rpm at full scale is under the reader's absolute limit of 100 rps, but 34 times the
    full-scale KVLCC2's 2.66 rps; the same values in rps of the 7 m model (10.3) pass."""
    from sindyship.ships import load_ship

    full = load_ship("kvlcc2").scaled(45.7)
    t = np.arange(0.0, 200.0, 1.0)
    frame = pd.DataFrame({"t": t, "u": full.U0, "v": 0.0, "r": 0.0, "x": full.U0 * t,
                          "y": 0.0, "psi": 0.0, "delta": 0.0, "n": 91.5})
    message = refusal(frame, ship=full)
    assert ("the revolutions check refuses the record: column 'n' has a median of 91.5, 34.5 times "
            "the ship's propeller revolutions n = 2.655 rps; the values look like rpm, so write "
            "the header as 'n [rpm]'") in message
    frame["n"] = 1.525
    trajectory_from_frame(frame, "ok", ship=full)
    trajectory_from_frame(frame.assign(n=91.5), "skipped", ship=full,
                          skip_checks=["revolutions"])


def test_wrapped_heading_in_degrees_under_a_bare_header_is_refused(protocol_runs):
    turn = protocol_runs["train"][1]
    wrapped = np.degrees(np.angle(np.exp(1j * turn["psi"])))
    message = refusal(turn.data.assign(psi=wrapped))
    assert "heading check" in message and "degrees wrapped at +-180" in message


# --- no false refusals ------------------------------------------------------------------------


def test_protocol_records_load_with_every_check(protocol_runs):
    for record in protocol_runs["train"] + protocol_runs["test"]:
        loaded = loads(record, ship="kcs")
        assert loaded.meta["notes"] == []
        gain, span = heading_gain(record.t, record["r"], record["psi"])
        assert span < 0.1 or abs(gain - 1) < 0.002, record.name
        assert frame_misfit(record.data) < 0.003, record.name


def test_noisy_records_load(kcs, seed):
    plan = protocol_manoeuvres(duration=1200.0)
    records = simulate_with_effects(kcs, plan["train"] + plan["test"],
                                    parse_effects(["noise=0.01", f"seed={seed}"]))
    for k, record in enumerate(records):
        record = add_noise(record, {"psi": math.radians(0.1), "delta": math.radians(0.1),
                                    "x": 0.5, "y": 0.5}, seed=seed + k)
        loads(record, ship=kcs)
        assert frame_misfit(record.data) < 0.01


def test_records_in_a_current_load(kcs):
    plan = protocol_manoeuvres(duration=1200.0)
    effects = parse_effects(["current=1.0", "current_dir=60"])
    for record in simulate_with_effects(kcs, plan["train"], effects):
        loads(record, ship=kcs)


def test_kvlcc2_model_records_load():
    ship = load_ship("kvlcc2")
    plan = protocol_manoeuvres(ship=ship)  # as simulate --protocol --ship kvlcc2 flies it
    for record in fly(MMGModel(ship), plan["train"] + plan["test"]):
        loads(record, ship=ship)


def test_marin_records_load():
    folder = default_marin_dir()
    if folder is None:
        pytest.skip("MARIN KVLCC2 data folder absent")
    for name in MARIN_FILES.values():
        record = read_marin(folder / name)  # read_marin runs every check without a ship
        assert frame_misfit(record.data) < 0.05
        gain, _ = heading_gain(record.t, record["r"], record["psi"])
        assert abs(gain - 1) < 0.1


# --- trials as logged --------------------------------------------------------------------------


#: The plateaus of the logged zig-zag: a degree or so off the nominal 20 deg.
LOGGED_LEVELS = np.radians([19.0, 21.0, 20.8, 19.2, 21.0, 19.0, 20.9, 19.1])


class LoggedZigZag(RudderCommand):
    """Manual steering until ``execute``, then a zig-zag whose plateaus sit at ``levels``."""

    def __init__(self, lead_times, lead_angles, execute, levels, check):
        self.lead_times, self.lead_angles = list(lead_times), list(lead_angles)
        self.execute, self.levels, self.check = execute, list(levels), check

    def reset(self, state0):
        self.reversals, self.psi0 = 0, None

    def value(self, t, state):
        if t < self.execute - 1e-9:
            k = int(np.searchsorted(self.lead_times, t + 1e-9, side="right")) - 1
            return self.lead_angles[max(k, 0)]
        if self.psi0 is None:
            self.psi0 = float(state[5])
        level = self.levels[min(self.reversals, len(self.levels) - 1)]
        return (-1) ** self.reversals * level

    def next_change(self, t):
        later = [time for time in [*self.lead_times, self.execute] if time > t + 1e-9]
        return min(later) if later else math.inf

    def event(self, state):
        if self.psi0 is None:
            return None
        return (-1) ** self.reversals * (state[5] - self.psi0) - self.check

    def on_event(self):
        self.reversals += 1


@pytest.fixture(scope="module")
def logged_trial(kcs, tmp_path_factory):
    """A 20/20 zig-zag as logged: 200 s from rest (propeller stopped for 100 s), 150 s of
    manual steering, plateaus 1 deg off nominal, heading wrapped at +-180, blank trailing rows.
    """
    rng = np.random.default_rng(7)
    lead_times = np.arange(0.0, 150.0, 15.0)
    lead_angles = np.radians(rng.uniform(-3.0, 3.0, lead_times.size))
    command = LoggedZigZag(lead_times, lead_angles, 150.0, LOGGED_LEVELS, math.radians(20.0))
    t = np.arange(0.0, 900.0, 1.0)
    state0 = np.array([kcs.U0, 0, 0, 0, 0, 0, 0.0])
    (result,) = simulate_batch(MMGModel(kcs), [command], t, state0)
    run = result_to_trajectory(result, "zz").data
    run["t"] += 200.0
    run["n"] = 1.6
    start = pd.DataFrame({"t": np.arange(200.0)})
    start["u"] = np.clip((start["t"] - 100.0) / 100.0, 0.0, 1.0) * kcs.U0
    start["n"] = np.where(start["t"] < 100.0, 0.0, 1.6)
    start["x"] = np.cumsum(start["u"]) - start["u"].sum()
    for column in ("v", "r", "y", "psi", "delta", "delta_c"):
        start[column] = 0.0
    data = pd.concat([start, run], ignore_index=True)[list(run.columns)]
    heading = math.radians(170.0)  # turn the whole trial so that the heading passes 180 deg
    track = np.exp(1j * heading) * (data["x"] + 1j * data["y"]).to_numpy()
    data["x"], data["y"] = track.real, track.imag
    data["psi"] = np.angle(np.exp(1j * (data["psi"] + heading)))
    path = tmp_path_factory.mktemp("trial") / "trial.csv"
    write_csv(Trajectory(data, "trial"), path)
    with open(path, "a") as handle:
        handle.write("\n" + "," * (len(data.columns) - 1) + "\n\n")
    return path


def test_logged_trial_loads_with_a_note_and_its_window_is_found(logged_trial, kcs):
    with pytest.warns(PlausibilityNote, match="jumps by a full turn"):
        record = read_csv(logged_trial, ship=kcs)
    assert record.t[-1] == 1099.0  # the blank trailing rows are no samples
    start, stop, reason = underway_window(record, kcs)
    assert 200.0 <= start <= 210.0
    assert stop == 1099.0
    assert "from t = 1" in reason and "end of the record" in reason
    cut = trim(record, (start, stop))
    assert cut.t[0] == start and cut.t[-1] == stop
    np.testing.assert_array_equal(cut["x"], record["x"][record.t >= start])


def test_logged_zigzag_is_recognised(logged_trial, kcs):
    with pytest.warns(PlausibilityNote):
        record = read_csv(logged_trial, ship=kcs)
    amplitude, check, first_sign, start_time = recognise_zigzag(record)
    assert (amplitude, check, first_sign, start_time) == (20.0, 20.0, 1, 350.0)
    zigzag, reason = explain_zigzag(trim(record, underway_window(record, kcs)))
    assert zigzag == (20.0, 20.0, 1, 350.0) and "plateaus at 19.0, 21.0" in reason


def _stretch_end_one_by_one(command, i):
    """The rule of a rudder hold, sample by sample: extend while the spread stays within
    HOLD_RANGE (Python's max and min pass over NaN)."""
    j, low, high = i + 1, command[i], command[i]
    while j < len(command) and max(high, command[j]) - min(low, command[j]) <= HOLD_RANGE:
        low, high = min(low, command[j]), max(high, command[j])
        j += 1
    return j


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("quantum", [0.0, 0.5, 1.0])
def test_rudder_holds_end_where_the_sample_by_sample_rule_ends_them(seed, quantum):
    """Holds of every length (the windows' edges crossed), ramps, NaN and infinite samples,
    and logs quantised to 0.5 or 1 deg (spreads of exactly HOLD_RANGE)."""
    rng = np.random.default_rng(seed)
    lengths = rng.integers(1, 3000, 12) // rng.integers(1, 40, 12)
    pieces = [rng.uniform(-35, 35) + rng.normal(0.0, rng.choice([0.05, 0.2, 0.6]), n)
              for n in lengths]
    command = np.concatenate([np.concatenate([p, np.linspace(p[-1], 0.0, 7)]) for p in pieces])
    if quantum:
        command = np.round(command / quantum) * quantum
    odd = rng.integers(0, len(command), 9)
    command[odd] = [np.nan] * 5 + [np.inf, -np.inf, np.inf, np.nan]
    command[(odd[5] + 1) % len(command)] = np.inf  # two in a row: inf - inf is NaN
    n = len(command)
    starts = sorted({0, n - 1, n - 2, *odd, *(odd + 1) % n, *rng.integers(0, n, 150),
                     *range(0, min(n, 300))})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the rule under test warns of nothing
        got = [stretch_end(command, int(i)) for i in starts]
    with np.errstate(invalid="ignore"):  # inf - inf in the reference's arithmetic
        expected = [_stretch_end_one_by_one(command, int(i)) for i in starts]
    assert got == expected
    assert max(got[k] - i for k, i in enumerate(starts)) > 100  # windows were read
    assert got[starts.index(n - 1)] == n


def test_protocol_zigzags_are_recognised_and_turns_are_not(protocol_runs):
    found = {r.name: recognise_zigzag(r) for r in protocol_runs["train"] + protocol_runs["test"]}
    assert found["zz35_10"] == (35.0, 10.0, 1, 0.0)
    assert found["zz15_15"] == (15.0, 15.0, 1, 0.0)
    assert found["zz10_10"] == (10.0, 10.0, 1, 0.0)
    assert found["tc35_stbd"] is None and found["straight"] is None
    zigzag, reason = explain_zigzag(protocol_runs["train"][1])
    assert zigzag is None and "no run of three or more alternating angles" in reason


def test_zigzags_logged_with_the_actual_rudder_alone_are_recognised(protocol_runs, kcs):
    """Without the command, the servo brings the rudder to each angle slowly (a hold at every
    degree on the way) and reverses the 35/10 zig-zag's first leg near 26 deg before it
    settles: the same zig-zags are recognised from their first sample, and flown closed loop
    (they were replayed open loop, some 9 L off)."""
    from sindyship.evaluation import evaluate
    from sindyship.identify import fit

    runs = protocol_runs["train"] + protocol_runs["test"]
    zigzags = [r for r in runs if r.name.startswith("zz")]
    actual = [Trajectory(r.data.drop(columns=["delta_c"]), r.name) for r in zigzags]
    for record in actual:
        zigzag = recognise_zigzag(record)
        assert zigzag is not None, explain_zigzag(record)[1]
        nominal = [int(x) for x in record.name[2:].split("_")]
        assert zigzag == (nominal[0], nominal[1], 1, 0.0)
    model = fit(protocol_runs["train"], kcs)
    errors = evaluate(model, actual)
    assert {e["flown_as"] for e in errors.values()} == {"zigzag"}
    assert max(e["mean_distance_L"] for e in errors.values()) < 1.0
    # the overshoots are measured from where the rudder was put over, not where the lagging
    # actual rudder crossed zero (which gave 8.6 deg for 18.4)
    commanded = evaluate(model, zigzags)
    for name, error in errors.items():
        for key, value in error["zigzag"]["recorded"].items():
            expected = commanded[name]["zigzag"]["recorded"][key]
            assert value == pytest.approx(expected, abs=1.5 if key != "period_s" else 2.0), key


def test_a_slow_servo_logged_fast_is_read_in_means_of_samples(protocol_runs, kcs):
    """The KCS's servo logged at 10 and 20 Hz without the command: every degree of its slow
    approach held five samples and the zig-zags were not recognised (or a 10/10 with 0.1 deg
    of noise read 10/15); read in means of samples, about 80 to a leg, they are, from their
    first sample, and flown closed loop as close as with the command."""
    from sindyship.evaluation import evaluate
    from sindyship.identify import fit
    from sindyship.rudder_holds import samples_per_reading
    from sindyship.trials import _recognise_rudder

    rng = np.random.default_rng(3)
    model = fit(protocol_runs["train"], kcs)
    actual, commanded = [], []
    for rudder, check, dt, noise in ((35, 10, 0.1, 0.0), (20, 20, 0.1, 0.0),
                                     (10, 10, 0.05, 0.1)):
        (run,) = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=rudder, check=check,
                                                duration=800, dt=dt)])
        frame = run.data.drop(columns=["delta_c"])
        frame["delta"] += math.radians(noise) * rng.standard_normal(len(frame))
        record = Trajectory(frame, f"zz{rudder}_{check}")
        command = np.degrees(record.rudder)
        assert samples_per_reading(record.t, command) >= 10
        by_sample = _recognise_rudder(record.t, record["psi"], record["r"], command, False,
                                      record.t)[0]
        assert by_sample is None or by_sample[:2] != (rudder, check)
        zigzag, reason = explain_zigzag(record)
        assert zigzag == (rudder, check, 1, 0.0), reason
        assert "read in means of" in reason
        actual.append(record)
        commanded.append(run.with_name(record.name))
    flown, with_command = evaluate(model, actual), evaluate(model, commanded)
    for name, error in flown.items():
        assert error["flown_as"] == "zigzag"
        assert error["mean_distance_L"] < with_command[name]["mean_distance_L"] + 0.15, name


@pytest.mark.parametrize(("seed", "hold", "duration", "dt"),
                         [(10, (5.59, 27.94), 1117.6, 0.1), (11, (30.0, 120.0), 1200.0, 0.2)])
def test_random_rudder_steps_are_no_zigzag(kcs, seed, hold, duration, dt):
    """Random rudder steps logged with the actual rudder alone can hold three angles near one
    size that alternate in sign; read in means of samples they had passed for a 5/40 or a
    3.4/5 zig-zag and were flown closed loop (8 L off where the replay flies 0.7 L).  A
    zig-zag's rudder reverses as the heading passes the check angle on the side the leg's
    rudder turns it: theirs reversed on the other side."""
    from sindyship.flights import flown_as

    (run,) = fly(MMGModel(kcs), [Manoeuvre("random", rudder=10, seed=seed, duration=duration,
                                           dt=dt, hold=hold)])
    record = Trajectory(run.data.drop(columns=["delta_c"]), "random")
    zigzag, reason = explain_zigzag(record)
    assert zigzag is None and "toward the side the leg's rudder turns it" in reason
    assert flown_as(record)["flown_as"] == "replay-actual"


@pytest.mark.parametrize("seed", [6, 7])
def test_a_commanded_zigzag_starts_at_the_step_of_its_command(seed):
    """With the command logged, a course kept by hand before the execute wanders: the execute
    had been placed where the wheel first moved half a degree after the helmsman's last hold
    of 1 deg or more (7.2 and 1.15 L/U0 early); the command steps at the execute."""
    kvlcc2 = load_ship("kvlcc2")
    unit = kvlcc2.L / kvlcc2.U0
    (run,) = fly(MMGModel(kvlcc2), [Manoeuvre("zigzag", rudder=10, check=10,
                                               duration=30 * unit, dt=0.05 * unit,
                                               approach=8 * unit, seed=seed)])
    zigzag = recognise_zigzag(run)
    assert zigzag is not None and zigzag[:3] == (10.0, 10.0, 1)
    assert 0.0 <= zigzag.start_time - 8 * unit <= 0.05 * unit + 1e-9


def test_a_one_degree_check_angle_is_not_rounded_to_none():
    """A 10/1 zig-zag after a course kept by hand read its check angle as 0 (rounded to the
    nearest multiple of 5) and flew closed loop reversing at the execute heading; a 20/1 is
    recognised although its reversals lie 1 deg off the execute heading."""
    kvlcc2 = load_ship("kvlcc2")
    unit = kvlcc2.L / kvlcc2.U0
    for rudder in (10, 20):
        (run,) = fly(MMGModel(kvlcc2), [Manoeuvre("zigzag", rudder=rudder, check=1,
                                                   duration=30 * unit, dt=0.05 * unit,
                                                   approach=8 * unit, seed=2)])
        zigzag = recognise_zigzag(run)
        assert zigzag is not None and zigzag[0] == rudder, explain_zigzag(run)[1]
        assert 0.8 <= zigzag.check_deg <= 1.2


def test_a_helmsmans_held_wheel_before_the_execute_is_no_first_leg():
    """The campaign's 10/10 zig-zag to port logged at 0.1 s without the command: the helmsman
    held the wheel a few degrees to starboard for a minute before the execute; that hold was
    taken for a first leg the servo was creeping out to, and the zig-zag was refused (read
    from it: 10/155 from t = 14.9 s).  A servo creeping toward an angle holds within two hold
    ranges of it and never falls back."""
    from sindyship.campaign import campaign_trials, fly_trials

    trial = campaign_trials(0)["train"][1]
    (record,) = fly_trials(load_ship("kvlcc2"), [trial], dt=0.1)
    actual = Trajectory(record.data.drop(columns=["delta_c"]), trial.name)
    zigzag = recognise_zigzag(actual)
    assert zigzag is not None, explain_zigzag(actual)[1]
    assert zigzag[:3] == (10.0, 10.0, -1)
    assert abs(zigzag.start_time - recognise_zigzag(record).start_time) < 0.5


@pytest.mark.parametrize("index", [0, 1])
def test_a_zigzag_after_an_approach_holding_its_angle_is_recognised_at_its_execute(
        monkeypatch, index):
    """A helmsman holding 10 deg of weather helm for most of the approach before a 10/10
    zig-zag: that hold was taken for the zig-zag's first leg, whose reversals then shared no
    check angle, and the record was flown and scored as a 10 deg turn from t = 2.8 s, the
    ship still almost at rest.  The zig-zag is looked for from the next plateau too."""
    import sindyship.manoeuvres as manoeuvres
    from sindyship.campaign import campaign_trials, fly_trials

    monkeypatch.setitem(manoeuvres.HELMSMAN, "limit", 10.0)
    monkeypatch.setitem(manoeuvres.HELMSMAN, "gain", 6.0)
    trial = campaign_trials(7)["train"][index]
    (record,) = fly_trials(load_ship("kvlcc2"), [trial])
    approach = np.degrees(record["delta_c"][record.t < record.meta["execute_s"]])
    assert np.mean(np.abs(np.abs(approach) - 10.0) < 0.5) > 0.8  # the helm held at 10 deg
    zigzag, reason = explain_zigzag(record)
    assert zigzag is not None, reason
    assert zigzag[:3] == (10.0, 10.0, trial.first_sign)
    assert 0.0 <= zigzag.start_time - record.meta["execute_s"] <= 0.2 + 1e-9
    start = flight_start(record)
    assert start.kind == "zigzag" and start.time == zigzag.start_time


def test_a_campaign_zigzag_whose_helm_the_wind_overrides_is_warned():
    """Seed 3's held-out 15/15 zig-zag, in a 5 m/s wind seven times the model's speed, holds
    its first rudder to the end: the campaign says so instead of handing over a turn named
    zz15_15; seed 0's, which the benchmarks fly, reverses its rudder nine times."""
    from sindyship.campaign import campaign_trials, fly_trials

    kvlcc2 = load_ship("kvlcc2")
    stuck = next(t for t in campaign_trials(3)["test"] if t.kind == "zigzag")
    with pytest.warns(UserWarning, match=r"zz15_15: the commanded rudder reversed [01] time"):
        fly_trials(kvlcc2, [stuck])
    answered = next(t for t in campaign_trials(0)["test"] if t.kind == "zigzag")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fly_trials(kvlcc2, [answered])


def test_a_zigzag_like_record_that_is_no_zigzag_says_why(protocol_runs):
    """Rows missing across a reversal, resampled: the heading changes at the reversals no
    longer share a check angle, the record is replayed open loop, and the flight start and
    the evaluation report say why (they had said only that nothing was recognised)."""
    from sindyship.flight_reports import evaluation_report

    zigzag = next(r for r in protocol_runs["train"] if r.name == "zz20_20")
    reversal = int(np.flatnonzero(np.diff(np.sign(zigzag["delta_c"])) != 0)[2])
    gap = zigzag.data.drop(index=range(reversal - 3, reversal + 4))
    with pytest.warns(PlausibilityNote, match="no sample between"):
        record = trajectory_from_frame(gap, "zz_gap", resample=1.0)
    start = flight_start(record)
    assert start.kind == "record"
    assert start.reason.startswith("no zig-zag or turn recognised (as a zig-zag: the heading "
                                   "change at the 27 rudder reversals spreads over ")
    assert start.reason.endswith("no common check angle): flown from the first row, t = 0 s")
    line = evaluation_report({"zz_gap": {
        "mean_distance_L": 0.1, "max_distance_L": 0.4, "diverged_at_s": None, "completed": True,
        "flown_s": 600.0, "flown_as": "replay-commanded", "start_s": 0.0,
        "start_reason": start.reason}})
    assert "from t = 0 s; no zig-zag or turn recognised (as a zig-zag: the heading" in line
    # a turn, whose rudder never reverses, is not explained as a zig-zag
    turn = next(r for r in protocol_runs["train"] if r.name == "tc35_stbd")
    assert "as a zig-zag" not in flight_start(turn.with_name("t")).reason


def test_a_zigzag_is_flown_as_its_whole_record_recognised_it(kcs):
    """The flight start recognises the zig-zag on the whole record and the flight flies that
    recognition (it recognised the part from the execute again, which could differ)."""
    from sindyship.flights import command_for, flown_as, flown_part
    from sindyship.simulation import RecordedZigZag

    (run,) = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=800,
                                           dt=0.1, approach=150.0, seed=3)])
    record = Trajectory(run.data.drop(columns=["delta_c"]), "zz20_20")
    start = flight_start(record)
    assert start.kind == "zigzag" and 140.0 < start.time < 160.0
    assert start.zigzag["amplitude_deg"] == 20.0 and start.zigzag["check_deg"] == 20.0
    part = flown_part(record)
    command = command_for(part)
    assert isinstance(command, RecordedZigZag)
    assert part.meta["flight_start"]["zigzag"] == start.zigzag
    assert flown_as(record)["flown_as"] == "zigzag"


def test_a_record_cut_after_its_execute_holds_no_turn(protocol_runs):
    """A time range that starts in the turn leaves its execute out: no turn, so no turn
    figures measured from mid-turn."""
    from sindyship.trials import recognise_turn

    turn = protocol_runs["test"][1]
    assert recognise_turn(turn).start_time == 0.0
    assert recognise_turn(trim(turn, (100.0, 200.0))) is None


def test_never_under_way_is_refused(zigzag, kcs):
    still = Trajectory(zigzag.data.assign(u=0.1), "still")
    with pytest.raises(SindyshipInputError, match="never under way"):
        underway_window(still, kcs)


def test_a_logged_zigzag_is_flown_from_its_execute_and_scores_like_a_clean_one(
        logged_trial, kcs, protocol_runs):
    """Read through the command line's reader: the lead-in from rest and the manual steering are
    cut, the zig-zag flown closed loop from its execute with the angles it held; the error stays
    within 10 % of the same zig-zag recorded cleanly (steady at the execute, no lead-in)."""
    from sindyship.cli._records import read_records
    from sindyship.evaluation import evaluate
    from sindyship.identify import fit

    model = fit(protocol_runs["train"], kcs)
    (logged,) = read_records([logged_trial], ship=kcs)
    assert logged.t[0] >= 200.0  # never flown from rest
    errors = evaluate(model, [logged])["trial"]
    assert errors["flown_as"] == "zigzag" and errors["start_s"] == 350.0
    assert errors["start_reason"].startswith("a 20/20 zig-zag, flown closed loop")
    assert errors["amplitude_deg"] == 20.0 and errors["check_deg"] == 20.0
    assert errors["completed"] and errors["flown_s"] == 750.0
    # the same zig-zag recorded cleanly: steady at the execute, no lead-in, no wrap, no blanks
    command = LoggedZigZag([0.0], [0.0], 0.0, LOGGED_LEVELS, math.radians(20.0))
    (result,) = simulate_batch(MMGModel(kcs), [command], np.arange(750.0),
                               np.array([kcs.U0, 0, 0, 0, 0, 0, 0.0]))
    clean = result_to_trajectory(result, "clean")
    reference = evaluate(model, [clean])["clean"]
    assert reference["flown_as"] == "zigzag" and reference["start_s"] == 0.0
    assert errors["mean_distance_L"] == pytest.approx(reference["mean_distance_L"], rel=0.10)


def test_refinement_flies_a_logged_zigzag_from_its_execute(logged_trial, kcs, protocol_runs):
    """Refining by flights judges the flights evaluate judges: a logged zig-zag's lead-in is
    never flown; its segments start at the execute, and its whole flight is the closed-loop
    zig-zag from there."""
    from sindyship.cli._records import read_records
    from sindyship.identify import fit
    from sindyship.shooting import make_segments

    model = fit(protocol_runs["train"], kcs)
    (logged,) = read_records([logged_trial], ship=kcs)
    assert logged.t[0] < 350.0  # the record keeps some approach
    (segments,) = make_segments(model, [logged], 100.0)
    assert segments.start.min() == 350.0
    (whole,) = make_segments(model, [logged], None)
    assert whole.start.tolist() == [350.0] and whole.zigzag.sign.tolist() == [1]
    assert math.degrees(whole.zigzag.check[0]) == pytest.approx(20.0)


def test_the_running_integral_is_scipys_cumulative_trapezoid(seed):
    """Written out so that reading a record does not import scipy.integrate; the heading
    integrates r, the frame check the complex velocity x + i y."""
    from scipy.integrate import cumulative_trapezoid

    from sindyship.kinematics_checks import _running_integral

    rng = np.random.default_rng(seed)
    for n in (1, 2, 7, 3200):
        t = np.cumsum(rng.random(n))
        for y in (rng.standard_normal(n), rng.standard_normal(n) + 1j * rng.standard_normal(n)):
            np.testing.assert_array_equal(_running_integral(y, t),
                                          cumulative_trapezoid(y, t, initial=0.0))

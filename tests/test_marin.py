"""Tests of the MARIN KVLCC2 loader: file handling on synthetic files, conventions on the data."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import cumulative_trapezoid

from sindyship.errors import SindyshipInputError
from sindyship.marin import (
    MARIN_DT,
    MARIN_FILES,
    MARIN_LPP,
    MARIN_SCALE,
    default_marin_dir,
    execute_index,
    read_marin,
    to_model_scale,
)
from sindyship.trajectory import Trajectory

TITLE = "MARIN(Maritime Research Institute Netherlands)\nTurning for KVLCC2 : 35 (deg)\n\n"


def marin_text(rows: list[list[float]], title: str = TITLE, digits: int = 3) -> str:
    """A file in MARIN's layout: title lines, tab-separated rows, trailing tab-only rows."""
    body = "\n".join("\t".join(f"{value:.{digits - 1}E}" for value in row) for row in rows)
    return title + body + "\n\t\t\n\t\t\n"


def straight_rows(count: int, heading_deg: float = 0.0) -> list[list[float]]:
    """A ship at 8 m/s on a constant heading, rows as MARIN writes them."""
    rows = []
    for i in range(count):
        t = i * MARIN_DT
        north = 8.0 * math.cos(math.radians(heading_deg))
        east = 8.0 * math.sin(math.radians(heading_deg))
        rows.append([t, north * t, east * t, 0.1, heading_deg, north, east, 0.2, 0.0, 1.0, 91.5])
    return rows


def write(tmp_path, text: str, name: str = "MARIN_FREE_KVLCC2_zz_10_m.dat"):
    path = tmp_path / name
    path.write_text(text)
    return path


# --- file handling (no data needed) ------------------------------------------------------------


def test_short_names():
    assert set(MARIN_FILES) == {"tc_35", "tc_-35", "zz_10", "zz_-10", "zz_20", "zz_-20"}
    assert MARIN_FILES["zz_-20"] == "MARIN_FREE_KVLCC2_zz_-20_m.dat"
    assert (MARIN_LPP, MARIN_SCALE) == (320.0, 45.7)


def test_default_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("SINDYSHIP_MARIN_DIR", str(tmp_path))
    assert default_marin_dir() == tmp_path.resolve()
    monkeypatch.setenv("SINDYSHIP_MARIN_DIR", str(tmp_path / "absent"))
    assert default_marin_dir() is None


def test_synthetic_file_conventions(tmp_path):
    record = read_marin(write(tmp_path, marin_text(straight_rows(5, heading_deg=90.0))))
    assert record.name == "MARIN_FREE_KVLCC2_zz_10_m"
    assert list(record.data.columns) == [
        "t", "u", "v", "r", "x", "y", "psi", "delta", "n", "phi", "p",
    ]  # fmt: skip
    assert record.t.tolist() == [i * MARIN_DT for i in range(5)]
    # heading east, moving east: all of the earth-fixed velocity is surge
    np.testing.assert_allclose(record["u"], 8.0, atol=1e-12)
    np.testing.assert_allclose(record["v"], 0.0, atol=1e-12)
    np.testing.assert_allclose(record["psi"], math.pi / 2)
    np.testing.assert_allclose(record["delta"], -math.radians(1.0))  # sign flipped
    np.testing.assert_allclose(record["n"], 91.5 / 60.0)
    np.testing.assert_allclose(record["phi"], math.radians(0.1))
    np.testing.assert_allclose(record["p"], math.radians(0.2))
    assert record.meta["full_scale"] is True
    assert record.meta["lpp"] == 320.0 and record.meta["scale_factor"] == 45.7
    assert record.meta["title"] == "Turning for KVLCC2 : 35 (deg)"


def test_earth_fixed_velocity_is_rotated_into_body_axes(tmp_path):
    rows = straight_rows(3, heading_deg=30.0)
    for row in rows:  # ship heading 30 deg, moving north-east at 45 deg: drifting to starboard
        row[5], row[6] = 8.0 * math.cos(math.radians(45.0)), 8.0 * math.sin(math.radians(45.0))
        row[1], row[2] = row[5] * row[0], row[6] * row[0]  # the track follows the velocity
    record = read_marin(write(tmp_path, marin_text(rows, digits=17)))
    np.testing.assert_allclose(record["u"], 8.0 * math.cos(math.radians(15.0)), rtol=1e-12)
    np.testing.assert_allclose(record["v"], 8.0 * math.sin(math.radians(15.0)), rtol=1e-12)


def test_heading_is_unwrapped(tmp_path):
    rows = straight_rows(4)
    for row, heading in zip(rows, [350.0, 355.0, 0.0, 5.0], strict=True):
        row[4] = heading
    record = read_marin(write(tmp_path, marin_text(rows)))
    np.testing.assert_allclose(np.rad2deg(record["psi"]), [350.0, 355.0, 360.0, 365.0])


def test_row_with_wrong_number_of_values(tmp_path):
    text = marin_text(straight_rows(4)).replace("\t9.15E+01\n", "\n", 2)
    with pytest.raises(SindyshipInputError) as caught:
        read_marin(write(tmp_path, text))
    message = str(caught.value)
    assert message.startswith(str(tmp_path)) and "line 4" in message and "10 values" in message


def test_text_in_a_row(tmp_path):
    lines = marin_text(straight_rows(4)).split("\n")
    lines[4] = lines[4].replace("9.15E+01", "rpm")
    with pytest.raises(SindyshipInputError) as caught:
        read_marin(write(tmp_path, "\n".join(lines)))
    assert "line 5" in str(caught.value) and "'rev'" in str(caught.value)


def test_missing_title_lines(tmp_path):
    with pytest.raises(SindyshipInputError) as caught:
        read_marin(write(tmp_path, marin_text(straight_rows(4), title="")))
    assert "title lines" in str(caught.value)


def test_missing_rows_are_detected(tmp_path):
    rows = straight_rows(400)
    del rows[100:150]  # 6.8 s missing
    with pytest.raises(SindyshipInputError) as caught:
        read_marin(write(tmp_path, marin_text(rows)))
    assert "rows are missing" in str(caught.value)


def test_missing_file(tmp_path):
    with pytest.raises(SindyshipInputError) as caught:
        read_marin(tmp_path / "absent.dat")
    assert "not found" in str(caught.value)


def test_execute_index_and_no_execute():
    frame = pd.DataFrame(
        {"t": [0.0, 1.0, 2.0], "u": 1.0, "v": 0.0, "r": 0.0, "x": [0.0, 1.0, 2.0], "y": 0.0,
         "psi": 0.0, "delta_c": np.deg2rad([2.0, 2.9, 0.9])}
    )  # fmt: skip
    assert execute_index(Trajectory(frame, "a")) == 2
    frame["delta_c"] = np.deg2rad(2.0)
    with pytest.raises(SindyshipInputError) as caught:
        execute_index(Trajectory(frame, "straight"))
    assert "straight" in str(caught.value)


def test_writing_the_records_refuses_a_missing_folder_or_an_output_file(tmp_path, capsys):
    from sindyship.marin import main

    assert main([str(tmp_path / "out"), "--data", str(tmp_path / "nowhere")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nowhere: no such folder; name the folder" in err
    assert main([str(tmp_path / "out"), "--data", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "none of the MARIN files (MARIN_FREE_KVLCC2_*_m.dat)" in err
    (tmp_path / "file").write_text("x")
    assert main([str(tmp_path / "file"), "--data", str(tmp_path)]) == 2
    assert "is not a folder" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_files_present_are_written_and_the_missing_ones_named(tmp_path, capsys):
    """A folder with two of the six files: both are converted (a user with the zig-zags alone
    can fit on them), the ship file written, and the four missing files named."""
    from sindyship.marin import main

    data = tmp_path / "data"
    data.mkdir()
    for name in ("zz_10", "zz_-10"):
        write(data, marin_text(straight_rows(60)), MARIN_FILES[name])
    assert main([str(tmp_path / "out"), "--data", str(data)]) == 0
    err = capsys.readouterr().err
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "kvlcc2-full-scale.toml", "zz_-10.csv", "zz_10.csv"]
    assert "wrote 2 records and kvlcc2-full-scale.toml" in err
    missing = [MARIN_FILES[n] for n in ("tc_35", "tc_-35", "zz_20", "zz_-20")]
    assert f"note: {', '.join(missing)} not found, so left out;" in err

def test_model_scale_is_froude_scaled(tmp_path):
    record = read_marin(write(tmp_path, marin_text(straight_rows(3))))
    model = to_model_scale(record)
    root = math.sqrt(45.7)
    np.testing.assert_allclose(model.t, record.t / root)
    np.testing.assert_allclose(model["u"], 8.0 / root, rtol=1e-12)
    np.testing.assert_allclose(model["x"], record["x"] / 45.7)
    np.testing.assert_allclose(model["n"], 1.525 * root)
    np.testing.assert_allclose(model["delta"], record["delta"])
    assert model.meta["lpp"] == pytest.approx(7.002, abs=1e-3)
    assert model.meta["full_scale"] is False
    with pytest.raises(ValueError, match="wind_speed"):
        to_model_scale(Trajectory(record.data.assign(wind_speed=1.0), "w"))


# --- the real files ----------------------------------------------------------------------------

MARIN_DIR = default_marin_dir()


def needs_data(test):
    """Mark a test that reads the MARIN files: it skips without them (see conftest.py)."""
    skip = pytest.mark.skipif(MARIN_DIR is None, reason="MARIN KVLCC2 data folder absent")
    return pytest.mark.marin(skip(test))


SAMPLES = {"tc_35": 15288, "tc_-35": 15753, "zz_10": 3844, "zz_-10": 4177, "zz_20": 4481,
           "zz_-20": 5057}  # fmt: skip
EXECUTE = {"tc_35": 31, "tc_-35": 50, "zz_10": 56, "zz_-10": 31, "zz_20": 52, "zz_-20": 55}


@pytest.fixture(scope="module")
def records() -> dict[str, Trajectory]:
    if MARIN_DIR is None:
        pytest.skip("MARIN KVLCC2 data folder absent")
    return {short: read_marin(MARIN_DIR / name) for short, name in MARIN_FILES.items()}


def steady_turn(record: Trajectory) -> np.ndarray:
    """Samples of the steady part of a turning circle (rudder held, speed settled)."""
    return (record.t > 400.0) & (record.t < 1400.0)


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_samples_and_time(records, short):
    record = records[short]
    assert record.n_samples == SAMPLES[short]
    assert record.t[1] == MARIN_DT
    assert record.t[-1] == pytest.approx((SAMPLES[short] - 1) * 0.1353, rel=1e-12)
    assert record.dt == pytest.approx(0.1353, rel=1e-12)
    assert execute_index(record) == EXECUTE[short]


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_channels_in_si(records, short):
    record = records[short]
    assert 1.52 < record["n"].min() and record["n"].max() < 1.54  # 91.3 to 92.1 rpm
    assert np.abs(record["phi"]).max() < math.radians(1.0)
    assert np.abs(record["p"]).max() < math.radians(1.0)
    assert record["u"].min() > 2.0  # body-fixed surge stays ahead, unlike the recorded north
    assert record.meta["full_scale"] is True


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_velocity_integrates_to_positions(records, short):
    record = records[short]
    psi = record["psi"]
    north = record["u"] * np.cos(psi) - record["v"] * np.sin(psi)
    east = record["u"] * np.sin(psi) + record["v"] * np.cos(psi)
    x = record["x"][0] + cumulative_trapezoid(north, record.t, initial=0.0)
    y = record["y"][0] + cumulative_trapezoid(east, record.t, initial=0.0)
    miss = np.hypot(x - record["x"], y - record["y"]).max()
    track = np.hypot(np.diff(record["x"]), np.diff(record["y"])).sum()
    if short.startswith("zz"):
        assert miss < 10.0  # metres, over 4.5 to 5.4 km
    else:
        assert miss < 0.02 * track  # 140 m over 9 km: see the module documentation


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_yaw_rate_is_the_slope_of_the_heading(records, short):
    record = records[short]
    turning = short.startswith("tc")
    half = 148 if turning else 37  # +-20 s or +-5 s: heading is in 1 deg steps past 100 deg
    psi, t = record["psi"], record.t
    slope = (psi[2 * half :] - psi[: -2 * half]) / (t[2 * half :] - t[: -2 * half])
    r = record["r"][half:-half]
    assert np.corrcoef(r, slope)[0, 1] > (0.99 if turning else 0.999)
    assert np.polyfit(slope, r, 1)[0] == pytest.approx(1.0, abs=0.01)


@needs_data
@pytest.mark.parametrize(("short", "sign"), [("tc_35", -1.0), ("tc_-35", 1.0)])
def test_positive_rudder_turns_to_starboard(records, short, sign):
    record = records[short]
    steady = steady_turn(record)
    assert np.rad2deg(record["delta"][steady]).mean() == pytest.approx(35.0 * sign, abs=0.2)
    r = record["r"][steady]
    assert np.all(np.sign(r) == sign)  # starboard (positive r) for positive rudder
    assert np.rad2deg(r.mean()) == pytest.approx(0.42 * sign, abs=0.02)
    # the bow points inside the circle: the ship drifts outward, v opposite to r
    assert np.all(np.sign(record["v"][steady]) == -sign)


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_heading_first_moves_the_way_the_rudder_points(records, short):
    record = records[short]
    start = execute_index(record)
    rudder = record["delta"][start] - record["delta"][0]
    psi = record["psi"] - record["psi"][0]
    first = np.flatnonzero(np.abs(psi) > math.radians(5.0))[0]
    assert np.sign(psi[first]) == np.sign(rudder)


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_ship_heels_outward_in_turns(records, short):
    """The evidence that decides the mirror ambiguity: outward heel, negative slope on U r."""
    record = records[short]
    speed_times_rate = np.hypot(record["u"], record["v"]) * record["r"]
    design = np.column_stack([speed_times_rate, np.ones_like(speed_times_rate)])
    slope = np.linalg.lstsq(design, np.rad2deg(record["phi"]), rcond=None)[0][0]
    assert -9.0 < slope < -3.0  # deg per m/s^2


@needs_data
@pytest.mark.parametrize("short", list(MARIN_FILES))
def test_roll_rate_is_the_slope_of_the_roll_angle(records, short):
    record = records[short]
    slope = np.gradient(record["phi"], record.t)
    assert np.corrcoef(record["p"], slope)[0, 1] > 0.995


@needs_data
def test_port_turn_is_the_tighter_one(records):
    def tactical_diameter(record: Trajectory) -> float:
        start = execute_index(record)
        heading = record["psi"][start]
        x = record["x"][start:] - record["x"][start]
        y = record["y"][start:] - record["y"][start]
        turned = np.abs(record["psi"][start:] - heading)
        lateral = -x * np.sin(heading) + y * np.cos(heading)
        return abs(float(np.interp(math.pi, turned, lateral))) / MARIN_LPP

    port, starboard = tactical_diameter(records["tc_35"]), tactical_diameter(records["tc_-35"])
    assert port == pytest.approx(3.07, abs=0.02)
    assert starboard == pytest.approx(3.33, abs=0.02)


@needs_data
@pytest.mark.parametrize("step", [1.0, MARIN_DT])
def test_the_default_fit_flies_the_turns_on_either_grid(tmp_path, monkeypatch, step):
    """The default ``fit`` on the four zig-zags (21 s Savitzky-Golay derivatives) flies both
    35 deg turns without diverging, advance and tactical diameter within 10 % of the
    recorded and speed loss within 0.10, on the README's 1 s grid and on the files' own
    0.1353 s (where the refinement, kept, made the ship slow to 0.04 U0 turning hard over and
    the starboard turn 25 % too tight, until the hard-over check compared the turns' speeds)."""
    import json

    from cli_in_process import run_sindyship

    from sindyship.marin import write_records

    monkeypatch.chdir(tmp_path)
    write_records("m", MARIN_DIR, resample=step)
    zigzags = [f"m/{name}.csv" for name in ("zz_10", "zz_-10", "zz_20", "zz_-20")]
    code, _, err = run_sindyship("fit", *zigzags, "--ship", "m/kvlcc2-full-scale.toml",
                                 "--derivative", "savgol", "--window", "21", "--out", "m.json")
    assert code == 0, err
    code, out, err = run_sindyship("evaluate", "m.json", "m/tc_35.csv", "m/tc_-35.csv", "--json")
    assert code == 0, err
    # the turn to starboard ends with v ramping to -2.48 m/s in 2 s: noted, never refused
    assert err.count("faster than a ship accelerates") == 1
    assert "m/tc_-35.csv: 'v' changes faster than a ship accelerates " in err
    assert ("delete its last row (" if step == 1 else "delete its last 3") in err
    for name, errors in json.loads(out)["errors"].items():
        assert errors["completed"], name
        flown, recorded = errors["turn"]["flown"], errors["turn"]["recorded"]
        for key in ("advance_L", "tactical_diameter_L"):
            assert flown[key] == pytest.approx(recorded[key], rel=0.10), (name, key)
        assert flown["speed_loss"] == pytest.approx(recorded["speed_loss"], abs=0.10), name

"""Tests of the measurement CSV reader, validator and writer."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from sindyship import measurements
from sindyship.errors import SindyshipInputError
from sindyship.measurements import read_csv, trajectory_from_frame, write_csv
from sindyship.trajectory import Trajectory

HEADER = "t,u,v,r,x,y,psi,delta"


def rows(count: int = 3, dt: float = 0.5) -> list[str]:
    """Valid sample rows for HEADER: a ship at 8 m/s with a small rudder and yaw rate."""
    return [
        f"{i * dt!r},8.0,-0.1,0.01,{8.0 * i * dt!r},0.0,{0.01 * i * dt!r},0.05"
        for i in range(count)
    ]


def write(tmp_path, text: str, name: str = "run.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def csv_text(header: str = HEADER, lines: list[str] | None = None) -> str:
    return "\n".join([header, *(rows() if lines is None else lines)]) + "\n"


def replace_cell(line: str, column: int, value: str) -> str:
    cells = line.split(",")
    cells[column] = value
    return ",".join(cells)


def error_of(path, **options) -> str:
    with pytest.raises(SindyshipInputError) as caught:
        read_csv(path, **options)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    return message


def frame_of(**columns) -> pd.DataFrame:
    base = {
        "t": [0.0, 1.0, 2.0],
        "u": 5.0,
        "v": 0.0,
        "r": 0.0,
        "x": [0.0, 5.0, 10.0],
        "y": 0.0,
        "psi": 0.0,
        "delta": 0.0,
    }
    base.update(columns)
    return pd.DataFrame(base)


# --- reading a good file ------------------------------------------------------------------------


def test_reads_a_valid_file(tmp_path):
    record = read_csv(write(tmp_path, csv_text()))
    assert isinstance(record, Trajectory)
    assert record.name == "run"
    assert list(record.data.columns) == HEADER.split(",")
    assert record.n_samples == 3
    assert record.dt == 0.5
    assert record["x"].tolist() == [0.0, 4.0, 8.0]
    assert all(dtype == np.float64 for dtype in record.data.dtypes)
    assert record.meta["source"] == str(tmp_path / "run.csv")


def test_extra_channels_and_commanded_rudder_are_kept(tmp_path):
    header = "t,u,v,r,x,y,psi,delta_c,n,depth"
    lines = [line + ",1.5,20" for line in rows()]
    record = read_csv(write(tmp_path, csv_text(header, lines)))
    assert list(record.data.columns) == header.split(",")
    assert record.has("delta_c") and not record.has("delta")
    assert record["depth"].tolist() == [20.0, 20.0, 20.0]


def test_blank_rows_are_skipped_and_rows_keep_spreadsheet_numbers(tmp_path):
    lines = rows(4)
    lines.insert(2, "")
    lines[4] = replace_cell(lines[4], 1, "fast")  # header = row 1, so this is row 6
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "row 6 (counting the header as row 1)" in message
    assert "'u'" in message


def test_column_name_whitespace_is_tolerated(tmp_path):
    header = " t , u ,v,r,x,y, psi [ deg ] ,delta "
    record = read_csv(write(tmp_path, csv_text(header)))
    assert list(record.data.columns) == HEADER.split(",")
    assert record.meta["units"] == {"psi": "deg"}


def test_windows_line_endings(tmp_path):
    path = tmp_path / "windows.csv"
    path.write_bytes(csv_text().replace("\n", "\r\n").encode())
    assert read_csv(path)["x"].tolist() == [0.0, 4.0, 8.0]


def test_byte_order_mark_is_ignored(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes(csv_text().encode("utf-8-sig"))
    assert read_csv(path).data.columns[0] == "t"


# --- unit conversion ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("column", "unit", "value", "expected"),
    [
        ("psi", "deg", 180.0, math.pi),
        ("psi", "rad", 4.0, 4.0),
        ("delta", "deg", 35.0, math.radians(35.0)),
        ("delta", "degrees", -10.0, math.radians(-10.0)),
        ("r", "deg/s", 0.5, math.radians(0.5)),
        ("r", "deg/min", 30.0, math.radians(0.5)),
        ("r", "rad/s", 0.02, 0.02),
        ("u", "kn", 15.5, 15.5 * 1852.0 / 3600.0),
        ("u", "knots", 10.0, 10.0 * 1852.0 / 3600.0),
        ("v", "km/h", 3.6, 1.0),
        ("x", "km", 1.25, 1250.0),
        ("y", "nmi", 1.0, 1852.0),
        ("n", "rpm", 91.5, 1.525),
        ("n", "Hz", 10.0, 10.0),
        ("n", "rps", 17.95, 17.95),
        ("force", "kN", 2.5, 2500.0),
        ("force", "N", 7.0, 7.0),
        ("wind_speed", "kn", 20.0, 20.0 * 1852.0 / 3600.0),
        ("wind_dir", "deg", 270.0, 1.5 * math.pi),
    ],
)
def test_units_are_converted_to_si(tmp_path, column, unit, value, expected):
    names = HEADER.split(",")
    lines = rows()
    if column in names:
        position = names.index(column)
        names[position] = f"{column} [{unit}]"
        lines = [replace_cell(line, position, repr(value)) for line in lines]
    else:
        names.append(f"{column} [{unit}]")
        lines = [f"{line},{value!r}" for line in lines]
    # unit conversion only: the values need not be kinematically consistent
    record = read_csv(write(tmp_path, csv_text(",".join(names), lines)), skip_checks="all")
    assert record[column] == pytest.approx([expected] * 3, rel=1e-15)
    assert record.meta["units"][column] == unit


@pytest.mark.parametrize(("unit", "seconds"), [("s", 30.0), ("min", 0.5), ("h", 30.0 / 3600)])
def test_time_units(tmp_path, unit, seconds):
    lines = [replace_cell(line, 0, repr(i * seconds)) for i, line in enumerate(rows())]
    text = csv_text(HEADER.replace("t,", f"t [{unit}],", 1), lines)
    record = read_csv(write(tmp_path, text), skip_checks="all")
    assert record.t == pytest.approx([0.0, 30.0, 60.0], rel=1e-12)


def test_unknown_unit_names_the_column(tmp_path):
    message = error_of(write(tmp_path, csv_text(HEADER.replace("u", "u [furlong/fortnight]"))))
    assert "'u [furlong/fortnight]'" in message
    assert "unknown unit" in message
    assert "kn" in message  # suggests units that would do


def test_unit_of_the_wrong_quantity_names_the_column(tmp_path):
    message = error_of(write(tmp_path, csv_text(HEADER.replace("psi", "psi [m]"))))
    assert "'psi [m]'" in message
    assert "deg" in message


def test_ambiguous_unit_case_names_the_column(tmp_path):
    message = error_of(write(tmp_path, csv_text(HEADER.replace("u", "u [KN]"))))
    assert "'u [KN]'" in message
    assert "ambiguous" in message


def test_unit_case_is_forgiven_when_unambiguous(tmp_path):
    record = read_csv(write(tmp_path, csv_text(HEADER.replace("psi", "psi [DEG]"))))
    assert record["psi"][1] == pytest.approx(math.radians(0.005))


def test_malformed_header_names_the_column(tmp_path):
    message = error_of(write(tmp_path, csv_text(HEADER.replace("psi", "psi [deg"))))
    assert "column 7" in message and "'psi [deg'" in message


# --- bad files ---------------------------------------------------------------------------------


def test_missing_file(tmp_path):
    message = error_of(tmp_path / "nowhere.csv")
    assert "not found" in message


def test_folder_instead_of_file(tmp_path):
    folder = tmp_path / "folder.csv"
    folder.mkdir()
    assert "folder" in error_of(folder)


def test_unreadable_file(tmp_path, monkeypatch):
    path = write(tmp_path, csv_text())

    def refuse(self, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(type(path), "read_text", refuse)
    assert "permission denied" in error_of(path)


def test_file_that_is_not_utf8(tmp_path):
    path = tmp_path / "latin.csv"
    path.write_bytes((HEADER + ",d\u00e9riv\u00e9e\n").encode("latin-1"))
    assert "UTF-8" in error_of(path)


@pytest.mark.parametrize("text", ["", "\n\n   \n"])
def test_empty_file(tmp_path, text):
    message = error_of(write(tmp_path, text))
    assert "empty" in message


def test_header_only(tmp_path):
    message = error_of(write(tmp_path, HEADER + "\n"))
    assert "no data rows" in message


def test_one_data_row(tmp_path):
    message = error_of(write(tmp_path, csv_text(lines=rows(1))))
    assert "only one data row" in message


@pytest.mark.parametrize("missing", ["t", "u", "v", "r", "x", "y", "psi"])
def test_missing_required_column(tmp_path, missing):
    names = HEADER.split(",")
    keep = [i for i, name in enumerate(names) if name != missing]
    lines = [",".join(line.split(",")[i] for i in keep) for line in rows()]
    message = error_of(write(tmp_path, csv_text(",".join(names[i] for i in keep), lines)))
    assert f"missing column '{missing}'" in message


def test_missing_rudder_column(tmp_path):
    lines = [line.rsplit(",", 1)[0] for line in rows()]
    message = error_of(write(tmp_path, csv_text(HEADER.rsplit(",", 1)[0], lines)))
    assert "'delta' or 'delta_c'" in message


def test_missing_column_with_wrong_case_gets_a_hint(tmp_path):
    message = error_of(write(tmp_path, csv_text(HEADER.replace("psi", "Psi"))))
    assert "missing column 'psi'" in message
    assert "'Psi'" in message and "case-sensitive" in message


def test_duplicate_column_names(tmp_path):
    lines = [line + ",0.0" for line in rows()]
    message = error_of(write(tmp_path, csv_text(HEADER + ",psi [deg]", lines)))
    assert "'psi'" in message and "'psi [deg]'" in message


def test_row_with_wrong_number_of_values(tmp_path):
    lines = rows()
    lines[1] += ",7"
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "row 3 (counting the header as row 1)" in message
    assert "9 values" in message and "8 columns" in message


def test_semicolon_separated_file(tmp_path):
    text = csv_text().replace(",", ";")
    assert "commas" in error_of(write(tmp_path, text))


def test_text_in_numeric_column(tmp_path):
    lines = rows()
    lines[2] = replace_cell(lines[2], 3, "n/a")
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'r'" in message
    assert "row 4 (counting the header as row 1)" in message
    assert "'n/a'" in message


def test_empty_cell(tmp_path):
    lines = rows()
    lines[1] = replace_cell(lines[1], 5, "")
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'y'" in message and "row 3" in message and "empty cell" in message


@pytest.mark.parametrize(("cell", "word"), [("nan", "NaN"), ("inf", "infinite"), ("-inf", "inf")])
def test_nan_or_inf(tmp_path, cell, word):
    lines = rows()
    lines[2] = replace_cell(lines[2], 4, cell)
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'x'" in message
    assert "row 4 (counting the header as row 1)" in message
    assert word in message


def test_duplicate_time(tmp_path):
    lines = rows(4)
    lines[2] = replace_cell(lines[2], 0, lines[1].split(",")[0])
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "repeats" in message and "row 4" in message and "'t'" in message


def test_time_written_too_coarsely_is_named_rounded(tmp_path):
    """A 0.05 s log whose time was written to one decimal repeats every other step: removing
    the duplicates would halve the record, so the message says to write the time with more
    digits (one repeat alone still says to remove it)."""
    lines = [replace_cell(line, 0, f"{i * 0.05:.1f}") for i, line in enumerate(rows(20, 0.05))]
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert re.search(r"\b(9|10) of 19 steps repeat", message) and "more digits" in message
    assert "remove duplicate" not in message


def test_a_number_with_an_underscore_is_refused(tmp_path):
    """Python reads 2_8 as 28; no CSV writer writes it, so it is a typo, not a number."""
    lines = rows(4)
    lines[2] = replace_cell(lines[2], 1, "8_0")
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'u' has the text '8_0' in row 4" in message


@pytest.mark.parametrize("stamp", ["2024-05-01 10:00:00", "2024-05-01T10:00:00Z", "10:00:03"])
def test_a_date_time_in_the_time_column_is_named_with_its_fix(tmp_path, stamp):
    """A CSV's t is seconds: a logger's date-times there are named as such, with the two
    ways to give them (seconds, or Parquet, whose timestamps are read)."""
    lines = [replace_cell(line, 0, stamp) for line in rows(4)]
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert f"column 't' holds the date-time '{stamp}' in row 2" in message
    assert "write t as seconds" in message and "Parquet" in message
    lines = rows(4)
    lines[2] = replace_cell(lines[2], 0, "n/a")
    assert "where a number is expected" in error_of(write(tmp_path, csv_text(lines=lines)))


def test_a_quote_never_closed_names_its_row(tmp_path):
    """Python's CSV reader takes every row after an unclosed quote into one cell; the count of
    values then fails on the file's last row, which is not where the mistake is."""
    lines = rows(6)
    lines[1] = lines[1].replace(",", ',"', 1)
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "row 3 (counting the header as row 1) opens a quote" in message


def test_decreasing_time(tmp_path):
    lines = rows(4)
    lines[1], lines[2] = lines[2], lines[1]
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "goes back" in message and "row 4" in message


def test_irregular_sampling(tmp_path):
    lines = rows(6)
    lines[3] = replace_cell(lines[3], 0, "1.6")  # steps 0.5, 0.5, 0.6, 0.4, 0.5
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "irregular" in message
    assert "row 5 (counting the header as row 1)" in message
    assert "resample=" in message and "--resample DT" in message


def test_sampling_jitter_within_tolerance_is_accepted(tmp_path):
    lines = rows(6)
    lines[3] = replace_cell(lines[3], 0, repr(1.5 + 0.004))  # 0.8 % of the 0.5 s step
    assert read_csv(write(tmp_path, csv_text(lines=lines))).n_samples == 6


def test_rudder_angle_in_degrees(tmp_path):
    lines = rows()
    lines[1] = replace_cell(lines[1], 7, "35")
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'delta'" in message and "row 3" in message
    assert "'delta [deg]'" in message


def test_commanded_rudder_in_degrees(tmp_path):
    lines = [replace_cell(line, 7, "-20") for line in rows()]
    message = error_of(write(tmp_path, csv_text(HEADER.replace("delta", "delta_c"), lines)))
    assert "column 'delta_c'" in message and "row 2" in message
    assert "'delta_c [deg]'" in message


def test_impossible_rudder_angle_with_unit(tmp_path):
    lines = [replace_cell(line, 7, "350") for line in rows()]
    message = error_of(write(tmp_path, csv_text(HEADER.replace("delta", "delta [deg]"), lines)))
    assert "'delta [deg]'" in message and "350 deg" in message


def test_yaw_rate_in_degrees(tmp_path):
    lines = rows()
    lines[2] = replace_cell(lines[2], 3, "-0.8")
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'r'" in message and "row 4" in message
    assert "'r [deg/s]'" in message


def test_rudder_check_can_be_switched_off(tmp_path):
    lines = [replace_cell(replace_cell(line, 7, "1.2"), 3, "0.7") for line in rows()]
    record = read_csv(write(tmp_path, csv_text(lines=lines)), rudder_check=False,
                      skip_checks="heading")
    assert record["delta"].max() == 1.2 and record["r"].max() == 0.7


def test_large_unwrapped_heading_is_not_taken_for_degrees(tmp_path):
    lines = [replace_cell(line, 6, repr(20.0 + i)) for i, line in enumerate(rows())]
    # psi alone is changed, so the kinematic checks (heading, frame) are off here
    record = read_csv(write(tmp_path, csv_text(lines=lines)), skip_checks=["heading", "frame"])
    assert record["psi"].max() == 22.0


def test_huge_speed(tmp_path):
    lines = rows()
    lines[1] = replace_cell(lines[1], 1, "1500")
    message = error_of(write(tmp_path, csv_text(lines=lines)))
    assert "column 'u'" in message and "row 3" in message and "1500" in message


def test_revolutions_in_rpm_without_unit(tmp_path):
    lines = [line + ",1077" for line in rows()]
    message = error_of(write(tmp_path, csv_text(HEADER + ",n", lines)))
    assert "column 'n'" in message and "'n [rpm]'" in message


# --- resampling --------------------------------------------------------------------------------


def test_resample_interpolates_every_column_onto_a_regular_grid(tmp_path):
    times = [0.0, 0.9, 2.1, 3.0, 4.3]
    lines = [
        f"{t!r},8.0,0.0,0.01,{8.0 * t!r},{-2.0 * t!r},{0.01 * t!r},0.0,{3.0 + t!r}" for t in times
    ]
    path = write(tmp_path, csv_text(HEADER + ",depth", lines))
    assert "irregular" in error_of(path)
    record = read_csv(path, resample=0.5, skip_checks="all")
    grid = 0.5 * np.arange(9)  # 0 .. 4.0; 4.3 is not on the grid
    assert record.t.tolist() == grid.tolist()
    np.testing.assert_allclose(record["x"], 8.0 * grid, rtol=0, atol=1e-12)
    np.testing.assert_allclose(record["y"], -2.0 * grid, rtol=0, atol=1e-12)
    np.testing.assert_allclose(record["psi"], 0.01 * grid, rtol=0, atol=1e-15)
    np.testing.assert_allclose(record["depth"], 3.0 + grid, rtol=0, atol=1e-12)
    assert record["u"].tolist() == [8.0] * 9
    assert record.meta["resampled"] == 0.5


def test_resample_a_regular_file_onto_a_finer_grid(tmp_path):
    record = read_csv(write(tmp_path, csv_text(lines=rows(3, dt=1.0))), resample=0.25)
    assert record.n_samples == 9
    assert record["x"][1] == pytest.approx(2.0)


@pytest.mark.parametrize("step", [0.0, -0.5, float("nan"), float("inf")])
def test_resample_step_must_be_positive(tmp_path, step):
    message = error_of(write(tmp_path, csv_text()), resample=step)
    assert "resampling step" in message


def test_resample_step_longer_than_the_record(tmp_path):
    assert "longer than the record" in error_of(write(tmp_path, csv_text()), resample=5.0)


# --- writing and the round trip ----------------------------------------------------------------


def test_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(7)
    count = 50
    t = 0.1 * np.arange(count)
    frame = pd.DataFrame(
        {
            "t": t,
            "u": 7.9 + rng.standard_normal(count),
            "v": rng.standard_normal(count) / 3.0,
            "r": rng.uniform(-0.01, 0.01, count),
            "x": np.cumsum(rng.uniform(0, 1, count)) * 1e3,
            "y": rng.standard_normal(count) * 1e-300,
            "psi": np.linspace(0.0, 13.0, count),
            "delta": np.where(t > 1, -math.radians(35.0), -0.0),
            "n": 1.0 / 3.0,
            "extra": rng.standard_normal(count) * 1e200,
        }
    )
    original = Trajectory(frame, name="trip")
    path = write_csv(original, tmp_path / "trip.csv")
    assert path == tmp_path / "trip.csv"
    assert path.read_text().splitlines()[0] == ",".join(frame.columns)
    again = read_csv(path, skip_checks="all")
    assert again.name == original.name
    pd.testing.assert_frame_equal(again.data, original.data, check_exact=True)
    assert np.signbit(again["delta"][0])  # even -0.0 survives


@settings(max_examples=50, deadline=None)
@given(arrays(np.float64, 5, elements=st.floats(allow_nan=False, allow_infinity=False)))
def test_round_trip_of_any_finite_channel(tmp_path_factory, values):
    folder = tmp_path_factory.mktemp("trip")
    frame = frame_of(t=[0.0, 1.0, 2.0, 3.0, 4.0], x=[0.0, 5.0, 10.0, 15.0, 20.0], any=values)
    again = read_csv(write_csv(Trajectory(frame, "trip"), folder / "trip.csv"))
    assert again["any"].tobytes() == values.tobytes()


def test_write_replaces_an_existing_file(tmp_path):
    target = write(tmp_path, "old content\n")
    write_csv(Trajectory(frame_of(), "run"), target)
    assert read_csv(target).n_samples == 3


def test_failed_write_leaves_nothing_half_written(tmp_path, monkeypatch):
    target = write(tmp_path, "old content\n")

    def broken_replace(source, destination):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(measurements.os, "replace", broken_replace)
    with pytest.raises(SindyshipInputError) as caught:
        write_csv(Trajectory(frame_of(), "run"), target)
    assert str(target) in str(caught.value)
    assert target.read_text() == "old content\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]


def test_write_into_a_missing_folder_creates_it(tmp_path):
    """One missing-folder policy for every writer: the folder is created."""
    target = tmp_path / "missing" / "run.csv"
    write_csv(Trajectory(frame_of(), "run"), target)
    assert read_csv(target).data.equals(frame_of())


def test_write_where_a_file_blocks_the_folder(tmp_path):
    (tmp_path / "blocked").write_text("a file, not a folder")
    target = tmp_path / "blocked" / "run.csv"
    with pytest.raises(SindyshipInputError) as caught:
        write_csv(Trajectory(frame_of(), "run"), target)
    assert str(target) in str(caught.value)


# --- in-memory frames share the validator ------------------------------------------------------


def test_frame_with_units_is_converted():
    frame = frame_of(**{"psi [deg]": 90.0}).drop(columns="psi")
    record = trajectory_from_frame(frame, "f", skip_checks="frame")
    assert record["psi"].tolist() == [math.pi / 2] * 3
    assert record.name == "f"


def test_frame_rows_are_named_by_index_label():
    frame = frame_of(v=[0.0, np.nan, 0.0])
    frame.index = [10, 20, 30]
    with pytest.raises(SindyshipInputError) as caught:
        trajectory_from_frame(frame, source="memory")
    message = str(caught.value)
    assert message.startswith("memory: ")
    assert "column 'v'" in message and "index label 20" in message


def test_frame_with_text_cell():
    frame = frame_of(r=pd.Series(["0", "0.01", "fast"], dtype=object))
    with pytest.raises(SindyshipInputError) as caught:
        trajectory_from_frame(frame)
    assert "'fast'" in str(caught.value) and "index label 2" in str(caught.value)


def test_frame_with_time_as_index_gets_a_hint():
    frame = frame_of().set_index("t")
    with pytest.raises(SindyshipInputError) as caught:
        trajectory_from_frame(frame)
    assert "reset_index" in str(caught.value)


def test_frame_result_has_a_fresh_index_and_float_columns():
    frame = frame_of(t=[0, 1, 2])
    frame.index = ["a", "b", "c"]
    record = trajectory_from_frame(frame)
    assert list(record.data.index) == [0, 1, 2]
    assert record.data["t"].dtype == np.float64


def test_frame_is_not_modified():
    frame = frame_of(**{"u [kn]": 10.0}).drop(columns="u")
    before = frame.copy()
    trajectory_from_frame(frame)
    pd.testing.assert_frame_equal(frame, before)


def test_a_marin_dat_file_given_as_a_record_is_pointed_to_its_converter(tmp_path):
    raw = tmp_path / "MARIN_FREE_KVLCC2_zz_10_m.dat"
    raw.write_text("time,heading\n0,1\n1,2\n", encoding="utf-8")
    with pytest.raises(SindyshipInputError, match=r"missing columns .*\(a MARIN \.dat file is "
                                                  r"made into measurement CSVs by python3 -m "
                                                  r"sindyship\.marin OUT --data FOLDER\)"):
        read_csv(raw)

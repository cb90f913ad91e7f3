"""Smoothing noisy records: derivative errors against known derivatives, and the CV choice."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from sindyship.effects import add_noise
from sindyship.errors import SindyshipInputError
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.mmg import MMGModel
from sindyship.smoothing import (
    SmoothingSetting,
    _cv_scores,
    choose_smoothing,
    estimate_noise,
    smooth_record,
    smooth_records,
)
from sindyship.targets import five_point_derivative
from sindyship.trajectory import Trajectory

# Noise of 1 % of the channels' RMS (u, v, r), a gyro's 0.1 deg and a GPS's 0.5 m.
NOISE = {"u": 0.09, "v": 0.006, "r": 1.2e-4, "psi": math.radians(0.1), "x": 0.5, "y": 0.5}


@pytest.fixture(scope="module")
def zigzag(kcs):
    """A 20/20 zig-zag and its exact accelerations from the MMG right-hand side."""
    mmg = MMGModel(kcs)
    (run,) = fly(mmg, [Manoeuvre("zigzag", rudder=20, check=20, duration=1200)])
    acc = mmg.accelerations(run["u"], run["v"], run["r"], run["delta"], run["psi"],
                            branch=mmg.switching(run.state()) > 0)
    return run, {"u": acc[0], "v": acc[1], "r": acc[2]}


def derivative_error(record, truth, channel):
    """RMS error of the 5-point derivative over the true derivative's RMS."""
    d = five_point_derivative(record[channel], record.dt)
    inner = slice(10, -10)  # the filters' end effects are not what is measured here
    return float(np.sqrt(np.mean((d - truth[channel])[inner] ** 2))
                 / np.sqrt(np.mean(truth[channel][inner] ** 2)))


def sine_record(seed, noise):
    """u, v, r sines of known derivative (periods 150 to 400 s) plus white noise, 1 Hz."""
    t = np.arange(2000.0)
    rng = np.random.default_rng(seed)
    clean = {"u": 10.0 + np.sin(2 * np.pi * t / 400), "v": 0.5 * np.sin(2 * np.pi * t / 250),
             "r": 0.01 * np.cos(2 * np.pi * t / 150)}
    truth = {"u": 2 * np.pi / 400 * np.cos(2 * np.pi * t / 400),
             "v": 0.5 * 2 * np.pi / 250 * np.cos(2 * np.pi * t / 250),
             "r": -0.01 * 2 * np.pi / 150 * np.sin(2 * np.pi * t / 150)}
    frame = pd.DataFrame({"t": t, "x": 10 * t, "y": 0.0, "psi": 0.0, "delta": 0.0})
    for c in ("u", "v", "r"):
        frame[c] = clean[c] + rng.normal(0.0, noise[c], t.size)
    return Trajectory(frame, "sines"), truth


def test_noise_estimate_recovers_the_level(seed):
    record, _ = sine_record(seed, {"u": 0.05, "v": 0.01, "r": 1e-4})
    assert estimate_noise(record["u"]) == pytest.approx(0.05, rel=0.05)
    assert estimate_noise(record["v"]) == pytest.approx(0.01, rel=0.05)
    assert estimate_noise(record["r"]) == pytest.approx(1e-4, rel=0.05)
    assert estimate_noise(np.arange(100.0) ** 2) == 0.0  # a parabola has no third difference


def test_savgol_cuts_the_derivative_error_of_sines(seed):
    noisy, truth = sine_record(seed, {"u": 0.05, "v": 0.01, "r": 1e-4})
    smooth = smooth_record(noisy, "savgol", window=21.0)
    for c in ("u", "v", "r"):
        raw, smoothed = derivative_error(noisy, truth, c), derivative_error(smooth, truth, c)
        # measured: 4.42 -> 0.465 (u), 1.05 -> 0.111 (v), 0.321 -> 0.0335 (r): a cubic
        # Savitzky-Golay filter over 21 samples passes a tenth of the derivative noise
        assert raw > 0.3
        assert smoothed < 0.15 * raw, c
    assert np.array_equal(smooth["x"], noisy["x"])  # positions stay as recorded


def test_smoothers_cut_the_derivative_error_of_a_zigzag(zigzag, seed):
    run, truth = zigzag
    noisy = add_noise(run, NOISE, seed=seed)
    raw = {c: derivative_error(noisy, truth, c) for c in ("u", "v", "r")}
    savgol = smooth_record(noisy, "savgol", window=21.0)
    rts = smooth_record(noisy, "rts", window=21.0)
    # measured (seed 20261121), relative RMS errors of du/dt, dv/dt, dr/dt: 5-point on the raw
    # record 4.43, 0.201, 0.303; after Savitzky-Golay 0.469, 0.027, 0.051; after the Kalman
    # smoother 0.881, 0.039, 0.060
    for c in ("u", "v", "r"):
        assert derivative_error(savgol, truth, c) < 0.2 * raw[c], c
        assert derivative_error(rts, truth, c) < 0.25 * raw[c], c
    assert raw["u"] > 3.0
    # the Kalman smoother also cleans the track, using the kinematics: heading and position
    # errors well below the measurement noise
    for c, level in (("psi", NOISE["psi"]), ("x", 0.5), ("y", 0.5)):
        error = np.sqrt(np.mean((rts[c] - run[c]) ** 2))
        assert error < 0.35 * level, c
    sigma = rts.meta["smoothing"]["noise"]
    assert sigma["u"] == pytest.approx(NOISE["u"], rel=0.1)
    assert sigma["x"] == pytest.approx(0.5, rel=0.1)
    assert rts.meta["smoothing"]["noise_given"] == []
    a_u, a_v, a_r = rts.meta["accelerations"]
    assert np.sqrt(np.mean((a_r - truth["r"])[10:-10] ** 2)) < 0.3 * np.sqrt(
        np.mean((five_point_derivative(noisy["r"], 1.0) - truth["r"]) ** 2))


def test_rts_is_nearly_transparent_on_clean_data(zigzag):
    run, _ = zigzag
    smooth = smooth_record(run, "rts", window=21.0)
    for c in ("u", "v", "r"):
        assert np.max(np.abs(smooth[c] - run[c])) < 0.01 * np.max(np.abs(run[c] - run[c][0]))
    assert np.max(np.hypot(smooth["x"] - run["x"], smooth["y"] - run["y"])) < 0.01


def test_rts_takes_given_noise_levels_missing_samples_and_irregular_times(zigzag, seed):
    run, truth = zigzag
    noisy = add_noise(run, NOISE, seed=seed)
    given = smooth_record(noisy, "rts", window=21.0, noise=NOISE)
    assert given.meta["smoothing"]["noise"]["u"] == NOISE["u"]
    assert sorted(given.meta["smoothing"]["noise_given"]) == sorted(NOISE)
    # drop every 7th sample of u and v, and a block of positions (a GPS outage)
    data = noisy.data.copy()
    data.loc[::7, ["u", "v"]] = np.nan
    data.loc[300:360, ["x", "y"]] = np.nan
    gappy = smooth_record(Trajectory(data, "gappy"), "rts", window=21.0)
    assert np.all(np.isfinite(gappy.data[["u", "v", "r", "x", "y", "psi"]].to_numpy()))
    assert derivative_error(gappy, truth, "v") < 0.3 * derivative_error(noisy, truth, "v")
    # irregular sampling: keep a random 70 % of the samples
    keep = np.sort(np.random.default_rng(seed).choice(run.n_samples, 840, replace=False))
    sparse = Trajectory(noisy.data.iloc[keep].reset_index(drop=True), "sparse")
    smooth = smooth_record(sparse, "rts", window=21.0)
    err = np.sqrt(np.mean((smooth["r"] - run["r"][keep]) ** 2))
    assert err < 0.6 * NOISE["r"]


def test_none_copies_and_batches_agree(zigzag, seed):
    run, _ = zigzag
    noisy = add_noise(run, NOISE, seed=seed)
    same = smooth_record(noisy, "none")
    assert same.data.equals(noisy.data) and same.data is not noisy.data
    batch = smooth_records([noisy, noisy.with_name("again")], "rts:21")
    single = smooth_record(noisy, "rts", window=21.0)
    assert np.array_equal(batch[0].data.to_numpy(), single.data.to_numpy())
    assert np.array_equal(batch[1].data.to_numpy(), single.data.to_numpy())


def test_bad_settings_and_records_are_input_errors(zigzag):
    run, _ = zigzag
    with pytest.raises(SindyshipInputError, match="unknown smoothing method 'kalman'"):
        smooth_record(run, "kalman")
    with pytest.raises(SindyshipInputError, match="window"):
        smooth_record(run, "savgol", window=-3.0)
    with pytest.raises(SindyshipInputError, match="savgol:21"):
        SmoothingSetting.parse("savgol:wide")
    with pytest.raises(SindyshipInputError, match="noise level of 'u'"):
        smooth_record(run, "rts", noise={"u": -1.0})
    with pytest.raises(SindyshipInputError, match="'delta'"):
        smooth_record(run, "rts", noise={"delta": 0.1})
    irregular = Trajectory(run.data.drop(index=[5, 6, 7]).reset_index(drop=True), "holes")
    with pytest.raises(SindyshipInputError, match="holes: Savitzky-Golay smoothing needs uniform"):
        smooth_record(irregular, "savgol")
    data = run.data.copy()
    data.loc[3, "r"] = np.nan
    with pytest.raises(SindyshipInputError, match="channel 'r' has missing"):
        smooth_record(Trajectory(data, "gap"), "savgol")
    with pytest.raises(SindyshipInputError, match="too few"):
        smooth_record(Trajectory(run.data.iloc[:4], "stub"), "savgol")


def test_cv_score_penalises_divergence_by_the_worst_complete_flight():
    means = np.array([[1.0, 2.0, 80.0], [0.5, np.nan, 82.0], [0.1, 0.01, 90.0]])
    failed = np.array([[0, 0, 0], [0, 1, 0], [0, 1, 1]], dtype=bool)
    scores = _cv_scores(means, failed)
    assert scores[0] == pytest.approx((1.0 * 2.0 * 80.0) ** (1 / 3))
    assert scores[1] == pytest.approx((0.5 * 2.0 * 82.0) ** (1 / 3))
    assert scores[2] == pytest.approx((0.1 * 2.0 * 90.0) ** (1 / 3))


def test_choose_smoothing_prefers_smoothing_on_noisy_runs(kcs, protocol_runs, seed):
    train = protocol_runs["train"]
    rms = {c: np.sqrt(np.mean(np.concatenate([r[c] for r in train]) ** 2)) for c in "uvr"}
    std = {c: 0.03 * rms[c] for c in "uvr"} | {"psi": NOISE["psi"], "x": 0.5, "y": 0.5}
    noisy = [add_noise(r, std, seed=seed + k) for k, r in enumerate(train)]
    best, table = choose_smoothing(noisy, kcs, ["none", "rts:41"], n_jobs=2)
    assert list(table["setting"]) == ["none", "rts 41 s"]
    assert table["chosen"].sum() == 1
    assert table.loc[table["chosen"], "setting"].item() == best.label == "rts 41 s"
    assert {r.name for r in train} <= set(table.columns)
    # measured: score 2.62 L without smoothing, 0.87 L with the Kalman smoother
    assert table.loc[0, "score_L"] > 2.0 * table.loc[1, "score_L"]
    with pytest.raises(SindyshipInputError, match="at least two training records"):
        choose_smoothing(noisy[:1], kcs)


def test_a_savgol_window_longer_than_the_record_or_too_short_is_refused(kcs):
    """A window longer than the record had been cut to the record and one too short for the
    polynomial widened, both silently (a 5000 s window over 3200 s records gave N'_r > 0);
    the smoother and the derivative now refuse both, naming the record."""
    from sindyship.identify import fit

    runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=300),
                               Manoeuvre("zigzag", rudder=10, check=10, duration=300)])
    with pytest.raises(SindyshipInputError, match=r"^zz20_20: smoothing: a Savitzky-Golay "
                       r"window of 5000 s is longer than the record \(299 s\); give a window "
                       r"shorter than the record\.$"):
        smooth_records(runs, SmoothingSetting("savgol", 5000.0))
    with pytest.raises(SindyshipInputError, match=r"^zz20_20: smoothing: a Savitzky-Golay "
                       r"window of 1 s holds 1 sample at 1 s, too few for a polynomial of "
                       r"order 3; give a window of 4 s or more\.$"):
        smooth_records(runs, SmoothingSetting("savgol", 1.0))
    with pytest.raises(SindyshipInputError, match=r"^zz20_20: the derivative \(--window\): a "
                       r"Savitzky-Golay window of 600 s is longer than the record"):
        fit(runs, kcs, derivative="savgol", window=600.0)
    assert smooth_records(runs, SmoothingSetting("savgol", 299.0))[0].n_samples == 300


def test_automatic_smoothing_leaves_out_windows_the_records_cannot_hold(kcs, monkeypatch):
    """The default candidates a record is too short for are not tried (they had been cut to
    the record), and the candidates' fits use the fit's own derivative and rudder signal."""
    import sindyship.identify as identify

    runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=60),
                               Manoeuvre("zigzag", rudder=10, check=10, duration=60)])
    seen, fit = [], identify.fit

    def watched(*args, **kwargs):
        seen.append({k: kwargs[k] for k in ("derivative", "window", "rudder_signal")})
        return fit(*args, **kwargs)

    monkeypatch.setattr(identify, "fit", watched)
    best, table = choose_smoothing(runs, kcs, derivative="savgol", window=11.0,
                                   rudder_signal="commanded", n_jobs=1)
    # no 81 s window in records of 59 s
    assert table["window_s"].dropna().tolist() == [11.2, 21.0, 41.0, 21.0, 41.0]
    assert seen and all(s == {"derivative": "savgol", "window": 11.0,
                              "rudder_signal": "commanded"} for s in seen)


@pytest.mark.parametrize("text, fragment", [
    ("auto:21", "gives auto a window; write auto alone"),
    ("none:5", "gives none a window; write none alone"),
    ("rts:21:3", "gives the RTS smoother an order, which only the Savitzky-Golay filter has"),
])
def test_a_smoothing_setting_with_parts_its_method_does_not_take_is_refused(text, fragment):
    """Parts a method does not take had been dropped silently (rts:21:3 smoothed as rts:21)."""
    with pytest.raises(SindyshipInputError, match=fragment):
        SmoothingSetting.parse(text)


def test_fit_says_which_automatic_windows_it_left_out(kcs, tmp_path, capsys):
    from sindyship.cli import main
    from sindyship.measurements import write_csv

    runs = fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=60),
                               Manoeuvre("zigzag", rudder=10, check=10, duration=60)])
    paths = []
    for run in runs:
        write_csv(run, tmp_path / f"{run.name}.csv")
        paths.append(str(tmp_path / f"{run.name}.csv"))
    assert main(["fit", *paths, "--ship", "kcs", "--optimizer", "ls", "--smoothing", "auto",
                 "--no-identifiability", "--out", str(tmp_path / "m.json")]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert ("--smoothing auto left out savgol 81 s: a window longer than a record, or holding "
            "too few of its samples") in err
    chosen = json.loads((tmp_path / "m.json").read_text())["info"]["smoothing"]
    said = ("not smoothing the records: --smoothing auto chose them as they are"
            if chosen["method"] == "none" else
            f"smoothing the records before differencing: {chosen['method']} ")
    assert said in err

"""Fits streamed from record files (one record at a time, reduced to triangular factors and
merged as a tree) give the in-memory fit's coefficients: in this process, on a two-worker
Dask LocalCluster, and through ``sindyship fit --stream`` with a glob of Parquet files."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sindyship.cli import main
from sindyship.cli._records import read_records
from sindyship.identify import design, fit, resolve_library
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.measurements import write_csv
from sindyship.mmg import MMGModel
from sindyship.model import AbkowitzModel
from sindyship.optimizers import LeastSquares, RowFactor, tree_factor
from sindyship.optimizers._base import _FitData
from sindyship.optimizers._factored import _FactorData
from sindyship.smoothing import smooth_records
from sindyship.streaming import fit_files, reduce_files, stream_settings
from sindyship.trajectory import Trajectory

PLAN = [Manoeuvre("turning-circle", rudder=35, duration=500),
        Manoeuvre("turning-circle", rudder=-35, duration=500),
        Manoeuvre("zigzag", rudder=20, check=20, duration=500),
        Manoeuvre("zigzag", rudder=10, check=10, duration=500)]

#: The streamed coefficients equal the in-memory ones to this fraction of the largest
#: coefficient of their equation.
RTOL = 1e-10


@pytest.fixture(scope="module")
def files(kcs, tmp_path_factory):
    """The plan's records as measurement CSVs and as Parquet files (with unit headers)."""
    folder = tmp_path_factory.mktemp("fleet")
    runs = fly(MMGModel(kcs), PLAN)
    csv, parquet = [], []
    for k, run in enumerate(runs):
        csv.append(write_csv(run, folder / f"run{k}.csv"))
        frame = run.data.copy()
        frame["psi"] = np.degrees(frame["psi"])
        frame["r"] = np.degrees(frame["r"])
        frame = frame.rename(columns={"psi": "psi [deg]", "r": "r [deg/s]"})
        path = folder / f"run{k}.parquet"
        frame.to_parquet(path, index=False)
        parquet.append(path)
    return {"folder": folder, "csv": csv, "parquet": parquet}


@pytest.fixture(scope="module")
def records(files, kcs):
    return read_records(files["csv"], ship=kcs)


def gap(a, b) -> float:
    """Largest coefficient difference over the largest coefficient, worst equation."""
    out = 0.0
    for dof in ("X", "Y", "N"):
        x = np.array(list(a.coefficients[dof].values()))
        y = np.array(list(b.coefficients[dof].values()))
        assert np.array_equal(x == 0, y == 0)
        out = max(out, float(np.max(np.abs(x - y)) / np.max(np.abs(x))))
    return out


@pytest.mark.parametrize("optimizer", ["ls", "stlsq", "lasso", "prior"])
def test_streamed_coefficients_equal_the_in_memory_fit(files, records, kcs, optimizer):
    direct = fit(records, kcs, optimizer=optimizer)
    streamed = fit_files(files["csv"], kcs, optimizer=optimizer)
    assert gap(direct, streamed) <= RTOL
    saved, same = streamed.to_dict(), direct.to_dict()
    for key in ("ship", "library", "optimizer", "rudder_signal", "nondim"):
        assert saved[key] == same[key]
    for key in ("training", "n_samples", "derivative", "envelope"):
        assert saved["info"][key] == same["info"][key]
    assert saved["info"]["streamed"]["records"] == len(records)
    if optimizer == "prior":
        assert saved["info"]["prior"] == same["info"]["prior"]
        assert saved["info"]["straight_run"] == same["info"]["straight_run"]


def test_a_streamed_fit_on_the_actual_rudder_refuses_a_record_without_it(files, kcs, tmp_path):
    """In memory such records are fitted on the command; streamed, each record is read on its
    own, so one without ``delta`` is refused with the option that fits it."""
    from sindyship.errors import SindyshipInputError
    from sindyship.measurements import read_csv

    bare = tmp_path / "bare.csv"
    write_csv(Trajectory(read_csv(files["csv"][0]).data.drop(columns=["delta"]), "bare"), bare)
    with pytest.raises(SindyshipInputError, match="bare.csv: has no actual rudder angle"):
        fit_files([bare, *files["csv"][1:]], kcs)
    commanded = fit_files([bare, *files["csv"][1:]], kcs, rudder_signal="commanded")
    assert commanded.rudder_signal == "commanded"


def test_smoothing_effects_and_savgol_derivatives_stream_as_in_memory(files, records, kcs):
    options = {"effects": ["asymmetry"], "derivative": "savgol", "window": 31.0}
    smoothed = smooth_records(records, "rts:21")
    direct = fit(smoothed, kcs, **options)
    streamed = fit_files(files["csv"], kcs, smoothing="rts:21", **options)
    assert gap(direct, streamed) <= RTOL
    assert streamed.info["smoothing"] == {"method": "rts", "window_s": 21.0}


def test_leave_one_record_out_folds_are_the_direct_fold_fits(records, kcs):
    library = resolve_library("abkowitz")
    problems = design(records, kcs, library)["N"]
    per_record = [design([r], kcs, library)["N"] for r in records]
    factors = [RowFactor.of_rows(p.features, p.target) for p in per_record]
    X, Y = problems.features, problems.target.reshape(-1, 1)
    splits = [(np.flatnonzero(problems.groups != k), np.flatnonzero(problems.groups == k))
              for k in range(len(records))]
    rows = _FitData(X, Y, splits)
    streamed = _FactorData(factors, None, cross_validate=True)
    assert len(list(streamed.folds())) == len(records)
    for (f, fold, Rf, Zf, error), (_, fold_s, Rs, Zs, error_s) in zip(
            rows.folds(), streamed.folds(), strict=True):
        w = fold.physical(np.linalg.lstsq(Rf, Zf[:, 0], rcond=None)[0], 0.0, 0, X.shape[1])
        w_s = fold_s.physical(np.linalg.lstsq(Rs, Zs[:, 0], rcond=None)[0], 0.0, 0, X.shape[1])
        assert np.max(np.abs(w - w_s)) <= RTOL * np.max(np.abs(w))
        held_out = error(w[:, None], 0)[0]
        assert error_s(w[:, None], 0)[0] == pytest.approx(held_out, rel=1e-9)
        # the fold is the fit on all the other records, read directly from their rows
        train = splits[f][0]
        direct = LeastSquares().fit(X[train], Y[train, 0]).coef_[0]
        others = tree_factor([factors[k] for k in range(len(records)) if k != f])
        assert np.max(np.abs(LeastSquares().fit_factors([], others).coef_[0] - direct)) <= (
            RTOL * np.max(np.abs(direct)))


def test_parquet_with_unit_headers_fits_as_the_csv(files, kcs):
    from_csv = fit_files(files["csv"], kcs)
    from_parquet = fit_files(files["parquet"], kcs)
    assert gap(from_csv, from_parquet) <= RTOL


def test_svr_and_the_automatic_smoothing_are_refused_before_any_work(files, kcs):
    from sindyship.errors import SindyshipInputError

    with pytest.raises(SindyshipInputError, match="needs every sample"):
        fit_files(files["csv"], kcs, optimizer="svr")
    with pytest.raises(SindyshipInputError, match="fixed setting"):
        stream_settings(kcs, smoothing="auto")


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    with distributed.Client(cluster) as connected:
        yield connected
    cluster.close()


def test_the_cluster_reduces_the_records_as_this_process_does(files, kcs, client):
    settings = stream_settings(kcs)
    local, local_records = reduce_files(files["parquet"], settings, keep_records=True)
    from distributed import get_task_stream

    with get_task_stream(client) as stream:
        remote, remote_records = reduce_files(files["parquet"], settings, client=client,
                                              keep_records=True)
    # one task per record file and a binary tree of three merges
    assert len(stream.data) >= len(files["parquet"]) + 3
    assert remote.names == local.names and remote.samples == local.samples
    for dof in ("X", "Y", "N"):
        np.testing.assert_allclose(np.abs(remote.factors[dof].R), np.abs(local.factors[dof].R),
                                   rtol=1e-12, atol=1e-12 * np.abs(local.factors[dof].R).max())
    assert [r.names for r in remote_records] == [r.names for r in local_records]


def test_fit_stream_reads_the_rudder_signal_from_the_headers(files, client, tmp_path, capsys):
    """Streamed, the records are read one at a time on the cluster: the command line reads the
    files' headers first, so records without ``delta`` are fitted on the command with the
    in-memory note (and a mix is refused), as in memory."""
    from sindyship.measurements import read_csv
    from sindyship.records import record_columns

    assert {"t", "psi", "r", "delta"} <= record_columns(files["parquet"][0])  # unit headers
    bare = []
    for k, path in enumerate(files["csv"]):
        bare.append(tmp_path / f"bare{k}.csv")
        write_csv(Trajectory(read_csv(path).data.drop(columns=["delta"]), f"bare{k}"), bare[-1])
    assert "delta" not in record_columns(bare[0])
    out = tmp_path / "commanded.json"
    code = main(["fit", *map(str, bare), "--stream", "--scheduler", client.scheduler.address,
                 "--optimizer", "ls", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "note: the records have no actual rudder angle (delta)" in err
    assert AbkowitzModel.load(out).rudder_signal == "commanded"
    code = main(["fit", str(bare[0]), *map(str, files["csv"][1:]), "--stream", "--scheduler",
                 client.scheduler.address, "--out", str(tmp_path / "mixed.json")])
    assert code == 2 and "bare0 has no actual rudder angle" in capsys.readouterr().err


def test_fit_stream_takes_a_glob_and_writes_the_in_memory_model(files, records, kcs, client,
                                                                  tmp_path, capsys):
    out = tmp_path / "model.json"
    pattern = str(files["folder"] / "*.parquet")
    code = main(["fit", pattern, "--stream", "--scheduler", client.scheduler.address,
                 "--optimizer", "stlsq", "--out", str(out), "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    document = json.loads(captured.out)
    assert document["streamed"]["records"] == len(files["parquet"])
    assert document["streamed"]["samples"] == sum(r.n_samples for r in records)
    assert gap(fit(records, kcs, optimizer="stlsq"), AbkowitzModel.load(out)) <= RTOL


def test_a_streamed_fit_too_large_to_refine_is_saved_as_fitted(files, records, kcs, client,
                                                                tmp_path, capsys, monkeypatch):
    """The refinement (on by default for the prior fit) flies every record from memory: where
    they would take more than half of it, the streamed fit is saved unrefined with a notice and
    the records are never read into this process; where they fit, the notice says they are."""
    import sindyship.cli._common as common
    import sindyship.cli.fit as fit_verb

    def never(*args, **kwargs):
        raise AssertionError("the records were read into memory")

    out = tmp_path / "model.json"
    scheduler = ["--stream", "--scheduler", client.scheduler.address]
    monkeypatch.setattr(common, "physical_memory", lambda: 1_000_000)  # 1 MB
    monkeypatch.setattr(fit_verb, "read_records", never)
    assert main(["fit", str(files["folder"] / "*.parquet"), *scheduler, "--out", str(out)]) == 0
    err = " ".join(capsys.readouterr().err.split())
    assert (f"not refined: the refinement flies the records from memory, "
            f"{sum(r.n_samples for r in records):.3g} samples with the sensitivities of 61 "
            "coefficients") in err
    assert "the streamed fit is saved as fitted" in err
    saved = AbkowitzModel.load(out)
    assert "refined" not in saved.info
    assert gap(fit(records, kcs, library=saved.library, optimizer="prior"), saved) <= RTOL
    monkeypatch.undo()
    assert main(["fit", str(files["folder"] / "*.parquet"), *scheduler, "--refine", "2",
                 "--out", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    assert "the streamed fit; the refinement reads the records into memory" in captured.err
    assert AbkowitzModel.load(out).info["refined"]["records"]
    # having read them, it flies its training records as the fit in memory does
    assert "training flights (mean distance [L]" in captured.err
    flights = json.loads(captured.out)["training_flights"]
    assert len(flights) == len(records)
    assert all(f["diverged_at_s"] is None and f["mean_distance_L"] < 1.0
               for f in flights.values())


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert err and err[-1].startswith("sindyship fit: error: ")
    assert "Traceback" not in "\n".join(err)
    return err[-1]


def test_bad_inputs_of_a_streamed_fit_are_one_line_errors(files, client, tmp_path, capsys,
                                                          monkeypatch):
    scheduler = ["--stream", "--scheduler", client.scheduler.address]
    out = str(tmp_path / "model.json")
    assert main(["fit", str(tmp_path / "nothing" / "*.parquet"), *scheduler, "--out", out]) == 2
    assert "no files match" in one_line_error(capsys)

    wrong = pd.read_parquet(files["parquet"][0])
    wrong["delta"] = np.degrees(wrong["delta"])  # degrees under a radian header
    bad = tmp_path / "bad.parquet"
    wrong.to_parquet(bad, index=False)
    assert main(["fit", str(files["parquet"][1]), str(bad), *scheduler, "--out", out]) == 2
    line = one_line_error(capsys)
    assert "bad.parquet" in line and "'delta'" in line and "degrees" in line

    unknown = tmp_path / "unknown.csv"
    unknown.write_text(files["csv"][0].read_text().replace("r,", "r [furlong/s],", 1))
    assert main(["fit", str(unknown), str(files["csv"][1]), *scheduler, "--out", out]) == 2
    assert "unknown.csv" in one_line_error(capsys)

    assert main(["fit", str(files["csv"][0]), *scheduler, "--optimizer", "svr",
                 "--out", out]) == 2
    assert "needs every sample" in one_line_error(capsys)
    assert not (tmp_path / "model.json").exists()

    monkeypatch.setitem(sys.modules, "distributed", None)  # Dask not installed
    assert main(["fit", str(files["csv"][0]), "--stream", "--out", out]) == 2
    assert 'pip install "sindyship[cluster]"' in one_line_error(capsys)


def test_fit_stream_without_a_scheduler_starts_a_local_cluster(files, records, kcs, tmp_path,
                                                               capsys):
    pytest.importorskip("distributed")
    out = tmp_path / "model.json"
    pattern = str(files["folder"] / "run*.csv")
    assert main(["fit", pattern, "--stream", "--n-jobs", "1", "--optimizer", "ls", "--out",
                 str(out)]) == 0
    assert "on 1 Dask workers (local cluster)" in capsys.readouterr().err
    assert gap(fit(records, kcs), AbkowitzModel.load(out)) <= RTOL


def test_a_streamed_fit_notes_coarse_sampling_as_the_fit_in_memory_does(files, client,
                                                                         tmp_path, capsys):
    """Every 3 s, the KCS's records are sampled at 0.16 L/U0, coarser than eight samples per
    L/U0: both fits say so in the same line (the streamed one from its records' reductions)."""
    common = [*map(str, files["csv"]), "--resample", "3", "--optimizer", "ls"]
    assert main(["fit", *common, "--out", str(tmp_path / "memory.json")]) == 0
    in_memory = [line for line in capsys.readouterr().err.splitlines()
                 if "L/U0" in line and line.startswith("note:")]
    assert main(["fit", *common, "--stream", "--scheduler", client.scheduler.address,
                 "--out", str(tmp_path / "streamed.json")]) == 0
    streamed = [line for line in capsys.readouterr().err.splitlines()
                if "L/U0" in line and line.startswith("note:")]
    assert len(in_memory) == 1 and streamed == in_memory
    assert "0.16" in in_memory[0]


def test_a_streamed_fit_notes_records_slower_than_the_ships_speed_as_in_memory(
        files, client, tmp_path, capsys):
    """The KCS's records given a ship whose U0 is 1.6 times theirs never reach 0.7 U0: both
    fits say so in the same line (the streamed one from each record's highest speed); given
    twice their U0 they never reach 0.6 U0, and both refuse them in the same line."""
    from pathlib import Path

    import sindyship

    source = (Path(sindyship.__file__).parent / "ships" / "kcs.toml").read_text()
    ship = tmp_path / "fast.toml"
    ship.write_text(source.replace('name = "kcs"', 'name = "fast"').replace(
        "U0 = 12.348 ", "U0 = 24.696 "))
    common = [*map(str, files["csv"]), "--ship", str(ship), "--optimizer", "ls"]
    refusals = []
    for stream in ((), ("--stream", "--scheduler", client.scheduler.address)):
        assert main(["fit", *common, *stream, "--out", str(tmp_path / "m.json")]) == 2
        refusals.append(capsys.readouterr().err.strip().splitlines()[-1])
    assert refusals[0] == refusals[1] and "0.50 times the design speed U0 = 24.7 m/s" in \
        refusals[0] and not (tmp_path / "m.json").exists()
    ship.write_text(source.replace('name = "kcs"', 'name = "fast"').replace(
        "U0 = 12.348 ", "U0 = 19.7568 "))
    assert main(["fit", *common, "--out", str(tmp_path / "memory.json")]) == 0
    in_memory = [line for line in capsys.readouterr().err.splitlines()
                 if line.startswith("note: no record reaches")]
    assert main(["fit", *common, "--stream", "--scheduler", client.scheduler.address,
                 "--out", str(tmp_path / "streamed.json")]) == 0
    streamed = [line for line in capsys.readouterr().err.splitlines()
                if line.startswith("note: no record reaches")]
    assert len(in_memory) == 1 and streamed == in_memory
    assert "0.63 times the design speed U0 = 19.76 m/s of ship fast" in in_memory[0]


def test_a_parquet_timestamp_column_is_read_as_seconds_from_the_first_sample(tmp_path, kcs):
    pytest.importorskip("pyarrow")
    from sindyship.streaming import read_record

    (run,) = fly(MMGModel(kcs), [Manoeuvre("turning-circle", rudder=20, duration=120)])
    frame = run.data.copy()
    frame["t"] = pd.Timestamp("2026-01-01 08:00") + pd.to_timedelta(frame["t"], unit="s")
    frame.to_parquet(tmp_path / "logged.parquet")
    record, _, _ = read_record(tmp_path / "logged.parquet", time_range="all")
    np.testing.assert_allclose(record.t, run.t - run.t[0])
    np.testing.assert_allclose(record["u"], run["u"])


def test_a_streamed_fit_sends_the_workers_absolute_paths(files, kcs, monkeypatch):
    import sindyship.streaming._cluster as cluster

    seen = []

    def reduce_record(path, name, settings):
        seen.append(path)
        return original(path, name, settings)

    original = cluster.reduce_record
    monkeypatch.setattr(cluster, "reduce_record", reduce_record)
    first, second = (Path(f) for f in files["csv"][:2])
    monkeypatch.chdir(first.parent)
    reduce_files([first.name, second.name], stream_settings(kcs))
    assert seen == [str(first.resolve()), str(second.resolve())]


@pytest.mark.parametrize("answer", [None, b"\xff" * 64])
def test_a_server_that_is_no_dask_scheduler_ends_in_one_line_within_the_timeout(
        answer, monkeypatch):
    """A port that takes the connection and never answers (Dask's own timeout does not cover
    its handshake) and one that answers with garbage: both end in one line, in time."""
    import socket
    import threading
    import time

    pytest.importorskip("distributed")
    from sindyship.errors import SindyshipInputError
    from sindyship.streaming import _cluster, connect

    monkeypatch.setattr(_cluster, "CONNECT_TIMEOUT_S", 2)
    server = socket.create_server(("127.0.0.1", 0))
    held = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            held.append(conn)
            if answer is not None:
                conn.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    start = time.perf_counter()
    try:
        with pytest.raises(SindyshipInputError, match="127.0.0.1") as raised:
            with connect(address):
                pass
    finally:
        server.close()
        for conn in held:
            conn.close()
    assert time.perf_counter() - start < 2 + 3
    assert "\n" not in str(raised.value)
    if answer is None:
        assert "did not answer as a Dask scheduler within 2 s" in str(raised.value)


@pytest.mark.parametrize("address, fragment", [
    ("", "empty"), ("ucx://h:1", "ucx://"), ("h", "port"), ("h:0", "port"),
    ("h:\u00b2", "port"), ("h:\u0668\u0667", "port"), ("::1:8786", "brackets"),
    ("tcp:/h:8786", "host"), ("tcp://a b:1", "host"), ("[abc]:1", "host"),
    ("h:1:2", "host")])
def test_a_scheduler_address_that_cannot_be_used_is_refused_before_connecting(address,
                                                                              fragment):
    from sindyship.errors import SindyshipInputError
    from sindyship.streaming import check_scheduler_address

    with pytest.raises(SindyshipInputError, match=fragment):
        check_scheduler_address(address)


def test_a_scheduler_address_is_given_its_tcp_scheme():
    from sindyship.streaming import check_scheduler_address

    assert check_scheduler_address("sched-01.example.org:8786") == \
        "tcp://sched-01.example.org:8786"
    assert check_scheduler_address("tcp://[::1]:8786") == "tcp://[::1]:8786"
    assert check_scheduler_address(" 10.0.0.1:8786 ") == "tcp://10.0.0.1:8786"

"""Ensembles, the smoothing choice, the refinement, the diagnosis and discovery on a Dask
cluster (a LocalCluster of two worker processes through joblib's dask backend): the work runs
on the cluster and gives the same numbers as on one process."""

from __future__ import annotations

import joblib
import numpy as np
import pandas as pd
import pytest

from sindyship.diagnose import diagnose, discover
from sindyship.effects import parse_effects, simulate_with_effects
from sindyship.manoeuvres import Manoeuvre
from sindyship.smoothing import choose_smoothing
from sindyship.uncertainty import ensemble

distributed = pytest.importorskip("distributed")

PLAN = [Manoeuvre("turning-circle", rudder=35, duration=500),
        Manoeuvre("turning-circle", rudder=-35, duration=500),
        Manoeuvre("zigzag", rudder=20, check=20, duration=500),
        Manoeuvre("zigzag", rudder=10, check=10, duration=500)]


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    with distributed.Client(cluster) as connected:
        yield connected
    cluster.close()


@pytest.fixture(scope="module")
def lagged(kcs):
    ship = kcs.with_rudder(gamma_R_stbd=0.415, gamma_R_port=0.415)
    return ship, simulate_with_effects(ship, PLAN, parse_effects(["rudder_lag=4"]))


def on_cluster(client, work):
    """Run ``work()`` with joblib's dask backend; the result and the tasks the cluster ran."""
    with distributed.get_task_stream(client) as stream, \
            joblib.parallel_config(backend="dask", n_jobs=-1):
        result = work()
    return result, len(stream.data)


def test_an_ensemble_on_the_cluster_equals_the_local_one(client, kcs, lagged):
    _, runs = lagged
    local = ensemble(runs, kcs, n_models=4, seed=3, n_jobs=1)
    remote, tasks = on_cluster(client, lambda: ensemble(runs, kcs, n_models=4, seed=3))
    assert tasks > 0
    assert remote.members == local.members
    for dof, values in local.coefficients.items():
        np.testing.assert_array_equal(remote.coefficients[dof], values)


def test_the_smoothing_choice_on_the_cluster_equals_the_local_one(client, kcs):
    noisy = [simulate_with_effects(kcs, [m], parse_effects(["noise=0.01", f"seed={k + 1}"]))[0]
             for k, m in enumerate(PLAN)]
    candidates = ["none", "savgol:21", "rts:21"]
    local, table = choose_smoothing(noisy, kcs, candidates, n_jobs=1)
    (remote, remote_table), tasks = on_cluster(
        client, lambda: choose_smoothing(noisy, kcs, candidates))
    assert tasks > 0
    assert remote == local
    pd.testing.assert_frame_equal(remote_table, table)


def test_a_diagnosis_and_a_discovery_on_the_cluster_equal_the_local_ones(client, lagged):
    ship, runs = lagged
    local = diagnose(runs, ship, effects=["asymmetry", "environment"], confirm=1, n_jobs=1)
    remote, tasks = on_cluster(client, lambda: diagnose(
        runs, ship, effects=["asymmetry", "environment"], confirm=1, n_jobs=2))
    assert tasks > 0
    assert remote.to_json()["errors"] == local.to_json()["errors"]
    assert remote.discovery.to_json()["accepted"] == local.discovery.to_json()["accepted"]
    found, tasks = on_cluster(client, lambda: discover(runs, ship, check_catalogue=False,
                                                       n_jobs=None))
    assert tasks > 0
    assert found.best.delays == local.discovery.best.delays


def test_a_refinement_on_the_cluster_equals_the_local_one(client, kcs, lagged):
    """The refinement's segments fly on the workers (n_jobs=None takes the dask backend) with
    the same coefficients as on one process, to rounding (a worker may fly the numpy
    reference where this process runs compiled code)."""
    from sindyship.identify import fit
    from sindyship.refine import refine

    _, runs = lagged
    prior = fit(runs, kcs, library="abkowitz-vr", optimizer="prior")
    local = refine(prior, runs, max_evaluations=4, n_jobs=1)
    remote, tasks = on_cluster(client, lambda: refine(prior, runs, max_evaluations=4,
                                                      n_jobs=None))
    assert tasks > 0
    for dof, terms in local.coefficients.items():
        for term, value in terms.items():
            assert remote.coefficients[dof][term] == pytest.approx(value, rel=1e-8, abs=1e-15)
    assert remote.info["refined"]["cost_after"] == pytest.approx(
        local.info["refined"]["cost_after"], rel=1e-8)


#: Put before the README's example: its process, and the workers it starts, on one core.
ONE_CORE = ("import os\n"
            "if hasattr(os, 'sched_setaffinity'):\n"
            "    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})\n")


def test_the_readme_cluster_example_runs(tmp_path):
    """As written, in a new interpreter held to one core (:data:`ONE_CORE` first), where
    ``Client()`` starts a one-worker LocalCluster (the two-worker equalities are the other
    tests'): a worker process per core would only wait on a machine the suite keeps busy."""
    import os
    import re
    import subprocess
    import sys
    from pathlib import Path

    readme = (Path(__file__).parents[1] / "README.md").read_text()
    (code,) = [block for block in re.findall(r"```python\n(.*?)```", readme, re.S)
               if "parallel_config" in block]
    done = subprocess.run([sys.executable, "-c", ONE_CORE + code], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.startswith("8 members;")


def test_diagnose_and_discover_take_a_glob_and_a_scheduler(client, lagged, tmp_path, capsys):
    """The command line: quoted glob patterns for the records, and --scheduler runs the work
    on the cluster with the numbers of a run on this machine."""
    import json

    from sindyship.cli import main
    from sindyship.measurements import write_csv

    _, runs = lagged
    folder = tmp_path / "records"
    folder.mkdir()
    for k, run in enumerate(runs):
        write_csv(run, folder / f"run{k}.csv")
    pattern = str(folder / "run[0-2].csv")
    common = [pattern, "--test", str(folder / "run3*.csv"), "--ship", "kcs",
              "--candidates", "asymmetry,environment", "--confirm", "1", "--json"]
    assert main(["diagnose", *common]) == 0
    local = json.loads(capsys.readouterr().out)
    with distributed.get_task_stream(client) as stream:
        assert main(["diagnose", *common, "--scheduler", client.scheduler.address]) == 0
    assert len(stream.data) > 0  # the work ran on the cluster
    captured = capsys.readouterr()
    remote = json.loads(captured.out)
    assert f"running on the Dask cluster at {client.scheduler.address}" in captured.err
    assert remote["errors"] == local["errors"]
    assert [r["effect"] for r in remote["ranking"]] == [r["effect"] for r in local["ranking"]]
    assert main(["discover", str(folder / "*.csv"), "--ship", "kcs", "--json",
                 "--scheduler", client.scheduler.address]) == 0
    found = json.loads(capsys.readouterr().out)
    assert found["accepted"]

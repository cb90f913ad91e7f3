"""The MARIN-data rule of conftest.py, run both ways in a separate pytest process.

A copy of ``tests/conftest.py`` and ``tests/test_marin.py`` goes into ``project/tests`` in a
temporary folder, with or without a ``shared/data`` folder beside ``project``, and
``SINDYSHIP_MARIN_DIR`` points at a folder that does not exist, so the MARIN files are absent.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
SELECTION = "test_port_turn_is_the_tighter_one or test_short_names"


def run_copy(root: Path, *, shared: bool, ci: str | None) -> subprocess.CompletedProcess:
    """pytest on the copied MARIN tests: one ``marin`` test and one that needs no data."""
    project = root / "project"
    (project / "tests").mkdir(parents=True)
    for name in ("conftest.py", "test_marin.py"):
        shutil.copy(TESTS / name, project / "tests" / name)
    if shared:
        (root / "shared" / "data").mkdir(parents=True)
    env = {key: value for key, value in os.environ.items() if key != "CI"}
    env["SINDYSHIP_MARIN_DIR"] = str(root / "nowhere")
    env["PYTHONPATH"] = os.pathsep.join([str(TESTS.parent), env.get("PYTHONPATH", "")])
    if ci is not None:
        env["CI"] = ci
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-k", SELECTION,
         "tests/test_marin.py"],
        cwd=project, env=env, capture_output=True, text=True, timeout=300,
    )


def test_on_ci_with_shared_data_a_marin_skip_fails(tmp_path):
    result = run_copy(tmp_path, shared=True, ci="true")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "MARIN test skipped on CI" in result.stdout
    assert "MARIN KVLCC2 data folder absent" in result.stdout  # the skip's reason is kept
    assert "1 passed" in result.stdout  # the test that needs no data still passes
    assert "skipped" not in result.stdout.splitlines()[-1]


@pytest.mark.parametrize(("shared", "ci"), [(False, "true"), (True, None), (True, "0"),
                                            (False, None)])
def test_elsewhere_a_marin_test_skips_cleanly(tmp_path, shared, ci):
    result = run_copy(tmp_path, shared=shared, ci=ci)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 passed, 1 skipped" in result.stdout.splitlines()[-1]

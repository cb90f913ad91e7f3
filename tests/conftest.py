"""Shared fixtures and the MARIN-data rule.

The protocol's KCS records are simulated once per test session.

Tests that read the MARIN KVLCC2 measurements carry the ``marin`` marker and skip when the
files are absent (a fresh clone without ``../shared``).  Where the data are meant to be
present, that skip would hide a broken path: when the environment variable ``CI`` is set
(and not ``0``/``false``) and the folder ``shared/data`` beside the project folder exists, a
skipped ``marin`` test is reported as a failure instead.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from sindyship.manoeuvres import fly, protocol_manoeuvres
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship


@pytest.fixture(scope="session")
def kcs():
    return load_ship("kcs")


@pytest.fixture(scope="session")
def protocol_runs(kcs):
    """The 8 training and 3 held-out KCS manoeuvres of the protocol, flown by the MMG model."""
    plan = protocol_manoeuvres()
    mmg = MMGModel(kcs)
    return {"train": fly(mmg, plan["train"]), "test": fly(mmg, plan["test"])}


@pytest.fixture
def seed():
    """The one seed tests use for randomness (numpy.random.default_rng(seed))."""
    return 20261121


#: The shared data folder beside the project folder (``../shared/data`` from the repository).
SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def marin_skip_is_failure() -> bool:
    """Whether a skipped ``marin`` test fails: on CI, with the shared data folder present."""
    ci = os.environ.get("CI", "").strip().lower()
    return ci not in ("", "0", "false", "no") and SHARED_DATA.is_dir()


def pytest_configure(config):
    config.addinivalue_line(
        "markers",
        "marin: reads the MARIN KVLCC2 measurements; skips without them, except on CI when "
        "../shared/data exists (then a skip is a failure)",
    )


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.skipped and item.get_closest_marker("marin") and marin_skip_is_failure():
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = (
            f"MARIN test skipped on CI although {SHARED_DATA} exists ({reason}); check that "
            "shared/data/kvlcc2-marin holds the six files, or that SINDYSHIP_MARIN_DIR points "
            "at them."
        )

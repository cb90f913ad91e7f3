"""Shared fixtures: the protocol's KCS records are simulated once per test session."""

from __future__ import annotations

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

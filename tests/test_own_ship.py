"""A ship file made for identification only: particulars, mass and inertia, nothing of the MMG."""

from __future__ import annotations

import numpy as np
import pytest

from sindyship.errors import SindyshipInputError
from sindyship.evaluation import evaluate
from sindyship.identify import fit
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship

KCS_PARTICULARS = """
name = "my-kcs"
[particulars]
L = 230.0
B = 32.2
d = 10.8
displacement = 52030.0
rho = 1025.0
U0 = 12.348
x_G = -3.404
[mass]
k_zz = 0.25
"""

TABLE_6 = """
[abkowitz]
X_udot = -29.4e-5
Y_vdot = -732e-5
Y_rdot = -21e-5
N_vdot = -21e-5
N_rdot = -43e-5
[servo]
T_R = 1.0
rate_max = 5.0
delta_max = 35.0
"""


@pytest.fixture
def own_ship(tmp_path):
    def make(text: str):
        path = tmp_path / "ship.toml"
        path.write_text(text, encoding="utf-8")
        return load_ship(path)

    return make


def test_an_identification_ship_with_table_6_fits_as_the_built_in_kcs(own_ship, kcs,
                                                                      protocol_runs):
    # the paper's Table 2 mass and inertia instead of the displacement and k_zz
    ship = own_ship(KCS_PARTICULARS.replace("k_zz = 0.25", "m = 0.182280\nI_zz = 0.011432")
                    + TABLE_6)
    assert not ship.has_mmg
    ours = fit(protocol_runs["train"], ship)
    builtin = fit(protocol_runs["train"], kcs)
    for dof in "XYN":
        a = np.array(list(ours.coefficients[dof].values()))
        b = np.array(list(builtin.coefficients[dof].values()))
        assert np.allclose(a, b, rtol=1e-9, atol=1e-15), dof
    errors = evaluate(ours, protocol_runs["test"])
    assert max(e["mean_distance_L"] for e in errors.values()) < 1.0
    assert all(e["completed"] for e in errors.values())


def test_added_masses_are_estimated_when_absent(own_ship, kcs, protocol_runs):
    ship = own_ship(KCS_PARTICULARS)
    estimated, table = ship.prime_i_inertia(), kcs.prime_i_inertia()
    for key in ("Y_vdot", "N_rdot"):  # Clarke (1983) within 15 % of the paper's Table 6
        assert estimated[key] == pytest.approx(table[key], rel=0.15)
    assert ship.servo.T_R == 0.1 and ship.servo.delta_max == 35.0
    model = fit(protocol_runs["train"], ship)
    errors = evaluate(model, protocol_runs["test"])
    assert all(e["completed"] for e in errors.values())


def test_an_identification_ship_cannot_be_simulated(own_ship):
    with pytest.raises(SindyshipInputError, match="no MMG hull"):
        MMGModel(own_ship(KCS_PARTICULARS))


def test_an_identification_ship_needs_its_inertia(own_ship):
    with pytest.raises(SindyshipInputError, match="I_zz or k_zz"):
        own_ship(KCS_PARTICULARS.replace("k_zz = 0.25", ""))

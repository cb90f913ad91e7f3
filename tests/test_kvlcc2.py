"""KVLCC2: the simulator's 35 deg turning circles beside the MARIN free-running measurements."""

from __future__ import annotations

import dataclasses

import pytest

from sindyship.manoeuvres import Manoeuvre, fly, turning_figures
from sindyship.marin import MARIN_FILES, default_marin_dir, read_marin
from sindyship.mmg import MMGModel
from sindyship.ships import load_ship


def simulated_turns(revolutions: float | None = None):
    ship = load_ship("kvlcc2")
    if revolutions is not None:
        ship = dataclasses.replace(ship, propeller=dataclasses.replace(ship.propeller,
                                                                       n_P=revolutions))
    runs = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=35, duration=300, dt=0.1),
                                Manoeuvre("turning-circle", rudder=-35, duration=300, dt=0.1)])
    return {r.name: turning_figures(r, ship.L) for r in runs}


def test_kvlcc2_turns_from_the_yasukawa_yoshimura_condition():
    figures = simulated_turns()
    # port is tighter (gamma_R is smaller for beta_R < 0)
    assert figures["tc35_port"]["tactical_diameter_L"] < figures["tc35_stbd"]["tactical_diameter_L"]
    assert figures["tc35_stbd"]["advance_L"] == pytest.approx(2.60, abs=0.02)
    assert figures["tc35_stbd"]["tactical_diameter_L"] == pytest.approx(2.76, abs=0.02)


def test_a_froude_scaled_ship_flies_the_same_turn_in_ship_lengths():
    """Froude scaling keeps every non-dimensional force, so the scaled ship turns as the
    model does, in ship lengths; the rudder area (m^2) scales with the square of the scale."""
    model = load_ship("kvlcc2")
    full = model.scaled(45.7)
    assert full.rudder.A_R == pytest.approx(model.rudder.A_R * 45.7**2)
    figures = []
    for ship in (model, full):
        dt = 0.1 * ship.L / model.L * (model.U0 / ship.U0)
        (run,) = fly(MMGModel(ship), [Manoeuvre("turning-circle", rudder=35,
                                                duration=3000 * dt, dt=dt)])
        figures.append(turning_figures(run, ship.L))
    for key in ("advance_L", "tactical_diameter_L"):
        assert figures[1][key] == pytest.approx(figures[0][key], rel=1e-6), key


@pytest.mark.marin
@pytest.mark.skipif(default_marin_dir() is None, reason="the MARIN measurements are not here")
def test_kvlcc2_turns_beside_marin_measurements():
    folder = default_marin_dir()
    # MARIN's positive rudder turns to port: tc_35 is a port turn in our convention
    measured = {"tc35_port": read_marin(folder / MARIN_FILES["tc_35"]),
                "tc35_stbd": read_marin(folder / MARIN_FILES["tc_-35"])}
    marin = {k: turning_figures(v, 320.0) for k, v in measured.items()}
    assert marin["tc35_port"]["tactical_diameter_L"] == pytest.approx(3.07, abs=0.02)
    assert marin["tc35_stbd"]["tactical_diameter_L"] == pytest.approx(3.33, abs=0.02)
    # Froude-scaled MARIN revolutions (91.7 rpm full scale -> 10.33 rps on the 7 m model)
    model_n = float(measured["tc35_port"]["n"][0]) * 45.7**0.5
    sim = simulated_turns(model_n)
    for side in ("tc35_port", "tc35_stbd"):
        for key in ("advance_L", "tactical_diameter_L"):
            assert sim[side][key] == pytest.approx(marin[side][key], rel=0.15), (side, key)
    assert marin["tc35_port"]["tactical_diameter_L"] < marin["tc35_stbd"]["tactical_diameter_L"]


def test_at_its_published_revolutions_the_kvlcc2_speeds_up_and_the_kcs_holds_u0():
    """As docs/command-line.md (simulate) says: the KVLCC2's 17.95 rps give 2.6 times its
    resistance at U0, and its straight run settles at 1.51 U0; the KCS holds U0."""
    from sindyship.mmg import force_components

    kvlcc2, kcs = load_ship("kvlcc2"), load_ship("kcs")
    parts = force_components(kvlcc2, 1.0, 0.0, 0.0, 0.0)
    assert float(parts["propeller"][0]) / -float(parts["hull"][0]) == pytest.approx(2.65, abs=0.05)
    for ship, settles in ((kvlcc2, 1.51), (kcs, 1.0)):
        (run,) = fly(MMGModel(ship), [Manoeuvre("straight", duration=3200)])
        assert run["u"][-1] / ship.U0 == pytest.approx(settles, abs=0.01)

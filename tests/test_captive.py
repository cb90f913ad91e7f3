"""Virtual captive tests of the MMG model, the captive CSV and the two command-line verbs."""

from __future__ import annotations

import argparse
import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from sindyship.captive import (
    captive_tests,
    classify_tests,
    force_scales,
    read_captive_csv,
    rigid_body_forces,
    write_captive_csv,
)
from sindyship.cli import captive as captive_verb
from sindyship.cli import forces as forces_verb
from sindyship.errors import SindyshipInputError
from sindyship.model import paper_model
from sindyship.ships import load_ship
from sindyship.taylor import TaylorSeries, taylor_reference


def _slope(frame, x, dof, scale):
    return float(np.polyfit(x, frame[dof].to_numpy() / scale, 1)[0])


def test_static_drift_changes_sign_and_matches_the_mmg_linear_derivative(kcs):
    frame = captive_tests(kcs, "static-drift", points=21)
    beta = np.degrees(np.arctan2(-frame.v, frame.u))
    assert beta.min() == pytest.approx(-20.0) and beta.max() == pytest.approx(20.0)
    assert np.all(np.sign(frame.Y) == np.sign(beta))  # Y has the sign of beta (Y_v < 0)
    assert np.all(frame.X[beta != 0] < 0)  # drift adds resistance
    # the MMG's own derivative dY'/dv' (Prime II), by Taylor arithmetic through the one
    # force function, at the mean gamma_R that a central difference sees
    from sindyship.mmg import force_components

    g = kcs.rudder.gamma_R_mean
    ship = kcs.with_rudder(gamma_R_stbd=g, gamma_R_port=g)
    du, v, r, d = (TaylorSeries.variable(k, 4, 1) for k in range(4))
    parts = force_components(ship, 1.0 + du, v, r, d, starboard=True)
    dY_dv = sum(p[1] for p in parts.values()).coefficient((0, 1, 0, 0))
    small = captive_tests(kcs, "static-drift", points=3, beta_max=0.1)
    slope = _slope(small, small.v / kcs.U0, "Y", force_scales(kcs, "prime-II")[1])
    assert slope == pytest.approx(dY_dv, rel=1e-3)
    assert dY_dv == pytest.approx(-0.2252 - 0.0185, abs=0.01)  # -Y'_beta plus the rudder


def test_captive_derivatives_are_the_abkowitz_ones_plus_added_mass_coriolis(kcs):
    # With the identification's inertia equal to the MMG's (no Table-6 overrides) an exact
    # Abkowitz fit is the Taylor reference, and captive slopes = reference + C'_added terms.
    ship = replace(kcs, abkowitz={})
    p = ship.prime_i_inertia()
    reference = taylor_reference(ship)
    scale = force_scales(ship, "prime-I")
    drift = captive_tests(ship, "static-drift", points=3, beta_max=0.01)
    yaw = captive_tests(ship, "pure-yaw", points=3, r_max=1e-4)
    v, r = drift.v / ship.U0, yaw.r * ship.L / ship.U0
    assert _slope(drift, v, "Y", scale[1]) == pytest.approx(reference["Y"]["v"], rel=2e-3)
    assert _slope(drift, v, "N", scale[2]) == pytest.approx(
        reference["N"]["v"] + p["Y_vdot"] - p["X_udot"], rel=2e-3)  # the Munk moment
    assert _slope(yaw, r, "Y", scale[1]) == pytest.approx(reference["Y"]["r"] + p["X_udot"],
                                                          rel=2e-3)
    assert _slope(yaw, r, "N", scale[2]) == pytest.approx(reference["N"]["r"] + p["Y_rdot"],
                                                          rel=2e-3)
    # the paper's KCS (Table 6 with Y'_rdot = N'_vdot = -21e-5) differs by the inertia mismatch
    kcs_drift = captive_tests(kcs, "static-drift", points=3, beta_max=0.01)
    kcs_ref = taylor_reference(kcs)
    assert _slope(kcs_drift, v, "Y", scale[1]) / kcs_ref["Y"]["v"] == pytest.approx(0.921,
                                                                                   abs=0.005)


def test_rigid_body_part_and_test_grids(kcs):
    mass = kcs.particulars.rho * kcs.particulars.displacement
    X, Y, N = rigid_body_forces(kcs, 12.0, 1.0, 0.01)
    assert float(Y) == pytest.approx(-mass * 12.0 * 0.01, rel=1e-3)
    assert float(X) == pytest.approx(mass * (0.01 + kcs.particulars.x_G * 1e-4), rel=1e-3)
    frame = captive_tests(kcs, "all", points=5)
    counts = pd.Series(classify_tests(frame, kcs)).value_counts().to_dict()
    # the 5 x 5 drift-yaw grid holds a static-drift and a pure-yaw line too
    assert counts == {"drift-yaw": 16, "static-drift": 8, "rudder": 4, "pure-yaw": 8,
                      "straight": 4}
    yaw = captive_tests(kcs, "pure-yaw", points=5)
    assert yaw.r.max() * kcs.L / kcs.U0 == pytest.approx(0.6)
    assert np.all(yaw.v == 0.0) and np.all(yaw.n == kcs.propeller.n_P)
    rudder = captive_tests(kcs, "rudder", points=5)
    assert np.degrees(rudder.delta.max()) == pytest.approx(35.0)
    assert rudder.Y.iloc[-1] < 0 < rudder.N.iloc[-1]  # starboard rudder turns to starboard
    with pytest.raises(SindyshipInputError, match="unknown captive test 'zigzag'"):
        captive_tests(kcs, "zigzag")


def test_captive_csv_round_trip_and_units(kcs, tmp_path):
    frame = captive_tests(kcs, "drift-yaw", points=4)
    path = write_captive_csv(frame, tmp_path / "captive.csv")
    assert path.read_text().splitlines()[0] == "u,v,r,delta,n,X,Y,N"
    again = read_captive_csv(path)
    pd.testing.assert_frame_equal(again, frame[again.columns].reset_index(drop=True))
    text = ("u [kn],v,r [deg/s],delta [deg],X [kN],Y [N],N [kNm]\n"
            "24,0.5,0.2,10,-100,2000,3\n")
    (tmp_path / "units.csv").write_text(text)
    units = read_captive_csv(tmp_path / "units.csv")
    assert units.iloc[0].to_dict() == pytest.approx(
        {"u": 24 * 1852 / 3600, "v": 0.5, "r": np.radians(0.2), "delta": np.radians(10.0),
         "X": -1e5, "Y": 2000.0, "N": 3000.0})


@pytest.mark.parametrize("text, message", [
    ("u,v,r,delta,X,Y\n1,0,0,0,1,2\n", "captive.csv: missing column 'N'"),
    ("u,v,r,delta,X,Y,N\n", "captive.csv: has no data rows"),
    ("u,v,r,delta,X,Y,N\n1,0,0,zero,1,2,3\n",
     "captive.csv: column 'delta' has the text 'zero' in row 2"),
    ("u,v,r,delta,X,Y,N\n1,0,0,0,1,nan,3\n", "captive.csv: column 'Y' has no finite value in "
     "row 2"),
    ("u,v,r,delta,X,Y,N\n1,0,0,0,1,2,3\n1,0,0,20,1,2,3\n",
     "captive.csv: column 'delta' reaches 20 in row 3"),
    ("u,v,r,delta,X [m],Y,N\n1,0,0,0,1,2,3\n", "captive.csv: column 'X \\[m\\]' needs a unit of "
     "force"),
    ("u,v,r [furlong],delta,X,Y,N\n1,0,0,0,1,2,3\n", "captive.csv: column 'r \\[furlong\\]' has "
     "the unknown unit"),
])
def test_bad_captive_csv_gives_one_line(tmp_path, text, message):
    path = tmp_path / "captive.csv"
    path.write_text(text)
    with pytest.raises(SindyshipInputError, match=message) as error:
        read_captive_csv(path)
    assert "\n" not in str(error.value) and str(path) in str(error.value)


def _parser():
    parser = argparse.ArgumentParser(prog="sindyship")
    sub = parser.add_subparsers(dest="verb")
    captive_verb.add_parser(sub)
    forces_verb.add_parser(sub)
    return parser


def test_captive_and_forces_commands(kcs, tmp_path, capsys):
    parser = _parser()
    out = tmp_path / "captive.csv"
    args = parser.parse_args(["captive", "--ship", "kcs", "--test", "rudder", "--points", "7",
                              "--out", str(out)])
    assert captive_verb.run(args) == 0
    assert len(read_captive_csv(out)) == 7
    model_path = tmp_path / "paper.json"
    paper_model(kcs, "LS").save(model_path)
    capsys.readouterr()
    args = parser.parse_args(["forces", str(model_path), str(out), "--json", "--out",
                              str(tmp_path / "report")])
    assert forces_verb.run(args) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["n_conditions"] == 7 and document["envelope"] is None
    assert document["by_test"]["rudder"]["Y"]["correlation"] > 0.99
    assert (tmp_path / "report" / "captive-forces.png").stat().st_size > 0
    assert json.loads((tmp_path / "report" / "forces.json").read_text()) == document
    args = parser.parse_args(["forces", str(model_path), str(out)])
    assert forces_verb.run(args) == 0
    assert capsys.readouterr().out.splitlines()[0].startswith("conditions")
    help_text = parser._subparsers._group_actions[0].choices["captive"].format_help()
    assert "default: 21" in help_text and "[m/s]" in help_text


def test_captive_tests_at_the_revolutions_of_the_trials(tmp_path, capsys):
    """The KVLCC2 model tested at the MARIN trials' 10.3 rps instead of its own 17.95: less
    thrust ahead (the surge force at straight running falls), a weaker rudder (less race), the
    hull's forces in pure drift as they were; the revolutions are written in the n column, and
    revolutions in rpm are refused in one sentence."""
    from sindyship.cli import main

    kvlcc2 = load_ship("kvlcc2")
    own = captive_tests(kvlcc2, "rudder", points=5)
    trials = captive_tests(kvlcc2, "rudder", points=5, revolutions=10.34)
    assert np.all(own["n"] == kvlcc2.propeller.n_P) and np.all(trials["n"] == 10.34)
    straight = int(np.flatnonzero(own["delta"] == 0.0)[0])
    assert trials["X"][straight] < own["X"][straight]  # less thrust against the same resistance
    assert abs(trials["Y"].iloc[-1]) < 0.8 * abs(own["Y"].iloc[-1])  # less race over the rudder
    pd.testing.assert_frame_equal(captive_tests(kvlcc2, "rudder", points=5,
                                                revolutions=kvlcc2.propeller.n_P), own)
    out = tmp_path / "trials.csv"
    assert main(["captive", "--ship", "kvlcc2", "--test", "static-drift", "--points", "3",
                 "--revolutions", "10.34", "--out", str(out)]) == 0
    assert np.all(read_captive_csv(out)["n"] == 10.34)
    capsys.readouterr()
    assert main(["captive", "--ship", "kvlcc2", "--revolutions", "620", "--out",
                 str(tmp_path / "rpm.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "at most 5 times the ship's 17.95 rps (rps, not rpm)" in err
    assert not (tmp_path / "rpm.csv").exists()


def test_forces_refuses_careless_input_in_one_sentence(kcs, tmp_path, capsys):
    """Files given the wrong way round, captive tests of another ship's scale, a captive table
    given as a training record, an output folder that is an input: each refused before any
    output is written, in one sentence that says what to do."""
    from sindyship.cli import main

    captive = tmp_path / "captive.csv"
    other = tmp_path / "kvlcc2.csv"
    assert main(["captive", "--ship", "kcs", "--test", "rudder", "--points", "5",
                 "--out", str(captive)]) == 0
    assert main(["captive", "--ship", "kvlcc2", "--test", "rudder", "--points", "5",
                 "--out", str(other)]) == 0
    model = tmp_path / "paper.json"
    paper_model(kcs, "LS").save(model)
    capsys.readouterr()
    cases = [
        (["forces", str(captive), str(model)], "the saved model (JSON) comes first and the "
         "captive CSV second"),
        (["forces", str(model), str(other)], "kvlcc2.csv: the captive tests run at 1.18 m/s "
         "(median), far from the design speed 12.3 m/s of the model's ship 'kcs'"),
        (["forces", str(model), str(captive), "--training", str(captive)],
         "captive.csv: this is a captive-test table"),
        (["forces", str(model), str(captive), "--out", str(captive)], f"--out {captive}"),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and message in err, err
    assert not (tmp_path / "forces.json").exists()
    # an output folder of a previous run is replaced; any other non-empty folder is refused
    report = tmp_path / "report"
    assert main(["forces", str(model), str(captive), "--out", str(report)]) == 0
    assert main(["forces", str(model), str(captive), "--out", str(report)]) == 0
    assert main(["forces", str(model), str(captive), "--out", str(tmp_path)]) == 2
    assert sorted(p.name for p in report.iterdir()) == [".sindyship-output",
                                                          "captive-forces.png", "forces.json"]
    # a file of the user's in a previous output folder is never deleted with it
    (report / "notes.txt").write_text("mine", encoding="utf-8")
    capsys.readouterr()
    assert main(["forces", str(model), str(captive), "--out", str(report)]) == 2
    assert "also holds 'notes.txt', which this command did not write" in capsys.readouterr().err
    assert (report / "notes.txt").read_text(encoding="utf-8") == "mine"

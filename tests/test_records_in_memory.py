"""Records built in memory are checked as a measurement CSV is, before they are fitted or flown.

A :class:`~sindyship.trajectory.Trajectory` made by hand has no headers to name its units and
nothing checks it when it is made.  Before these checks, ``fit`` turned a rudder in degrees
into N'_delta 2.44e-5 instead of 1.40e-3 (a turn then flew 19.4 L off instead of 0.003 L),
shuffled rows into N'_v 8.6e-3 instead of 1.57e-3, and ``evaluate`` scored another ship's
records in its own ship lengths, all without a word.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

import sindyship as ss
from sindyship.diagnose import before_after, compare, diagnose, discover
from sindyship.manoeuvres import Manoeuvre, fly
from sindyship.measurements import PlausibilityNote, read_csv, write_csv
from sindyship.mmg import MMGModel
from sindyship.model import paper_model
from sindyship.trajectory import Trajectory

IN_MEMORY = "record 'zz20_20' (a Trajectory, in SI units; "


@pytest.fixture(scope="module")
def runs(kcs):
    return fly(MMGModel(kcs), [Manoeuvre("zigzag", rudder=20, check=20, duration=800),
                               Manoeuvre("turning-circle", rudder=35, duration=800),
                               Manoeuvre("zigzag", rudder=10, check=10, duration=800)])


def spoilt(record: Trajectory, **changes) -> Trajectory:
    """The record's channels changed as a hand-made table would have them (no meta)."""
    data = record.data.assign(**{name: change(record.data) for name, change in changes.items()})
    return Trajectory(data.reset_index(drop=True), record.name)


SPOILT = {
    "rudder in degrees": ({"delta": lambda d: np.degrees(d.delta),
                           "delta_c": lambda d: np.degrees(d.delta_c)},
                          "column 'delta' reaches 19.9454 in the row with index label 281, beyond "
                          "any rudder angle (1 rad = 57 deg); the values look like degrees, so "
                          "write the header as 'delta [deg]'"),
    "yaw rate in deg/s": ({"r": lambda d: np.degrees(d.r)}, "write the header as 'r [deg/s]'"),
    "time in milliseconds": ({"t": lambda d: 1000 * d.t},
                             "the times look like milliseconds"),
    "speeds in knots": ({"u": lambda d: d.u / 0.5144, "v": lambda d: d.v / 0.5144},
                        "u and v look like knots"),
    "sway positive to port": ({"v": lambda d: -d.v}, "v looks positive to port"),
    "rudder positive to port": ({"delta": lambda d: -d.delta, "delta_c": lambda d: -d.delta_c},
                                "the rudder-sign check refuses the record"),
    "heading in degrees": ({"psi": lambda d: np.degrees(d.psi)},
                           "the heading looks like degrees, so write the header as 'psi [deg]'"),
}


@pytest.mark.parametrize("case", sorted(SPOILT))
def test_fit_refuses_a_spoilt_record_as_read_csv_would(runs, kcs, case):
    changes, fragment = SPOILT[case]
    with pytest.raises(ss.SindyshipInputError) as caught:
        ss.fit([spoilt(runs[0], **changes), *runs[1:]], kcs)
    message = str(caught.value)
    assert message.startswith(IN_MEMORY) and fragment in message
    assert "read a table with other units, or with the options named here, by " \
        "sindyship.measurements.trajectory_from_frame): " in message


@pytest.mark.parametrize("rows, fragment", [
    (lambda d: d.sample(frac=1.0, random_state=0), "time in column 't' goes back in the "
                                                   "row with index label 2"),
    (lambda d: d.drop(index=range(100, 130)), "the sampling is irregular: the time step into "
                                              "the row with index label 100 is 31 s"),
    (lambda d: pd.concat([d.iloc[:50], d.iloc[49:]]), "time in column 't' repeats in the "
                                                      "row with index label 50"),
])
def test_fit_refuses_shuffled_missing_or_repeated_rows(runs, kcs, rows, fragment):
    record = Trajectory(rows(runs[0].data).reset_index(drop=True), runs[0].name)
    with pytest.raises(ss.SindyshipInputError) as caught:
        ss.fit([record, *runs[1:]], kcs)
    assert str(caught.value).startswith(IN_MEMORY) and fragment in str(caught.value)


def test_every_function_that_takes_records_checks_them(runs, kcs):
    bad = spoilt(runs[0], delta=lambda d: np.degrees(d.delta),
                 delta_c=lambda d: np.degrees(d.delta_c))
    model = paper_model(kcs)
    calls = {
        "fit": lambda: ss.fit([bad, *runs[1:]], kcs),
        "evaluate": lambda: ss.evaluate(model, [bad]),
        "refine": lambda: ss.refine(model, [bad, *runs[1:]], max_evaluations=2),
        "compare": lambda: compare(model, [bad]),
        "diagnose": lambda: diagnose([bad, *runs[1:]], kcs),
        "diagnose held-out": lambda: diagnose(list(runs[1:]), kcs, test=[bad]),
        "diagnose_iteratively": lambda: ss.diagnose_iteratively([bad, *runs[1:]], kcs),
        "discover": lambda: discover([bad, *runs[1:]], kcs),
        "before_after": lambda: before_after(list(runs[1:]), kcs, effects=["asymmetry"],
                                             test=[bad]),
    }
    for name, call in calls.items():
        with pytest.raises(ss.SindyshipInputError) as caught:
            call()
        assert str(caught.value).startswith(IN_MEMORY), name


def test_a_sound_record_built_in_memory_fits_exactly_as_the_simulated_one(runs, kcs):
    plain = [Trajectory(r.data.copy(), r.name) for r in runs]
    assert all("checks" not in r.meta for r in plain)
    assert runs[0].meta["checks"] == {"ship": ["kcs", 230.0, 12.348], "skipped": [],
                                      "rudder_check": True}
    ours, theirs = ss.fit(plain, kcs), ss.fit(runs, kcs)
    for dof in ("X", "Y", "N"):
        assert ours.coefficients[dof] == theirs.coefficients[dof]


def test_a_wrapped_heading_in_memory_is_unwrapped_with_a_note(runs, kcs):
    turn = runs[1]
    wrapped = Trajectory(turn.data.assign(psi=np.angle(np.exp(1j * turn.data.psi))), turn.name)
    with pytest.warns(PlausibilityNote, match="jumps by a full turn"):
        model = ss.fit([runs[0], wrapped, runs[2]], kcs)
    assert model.coefficients == ss.fit(runs, kcs).coefficients


def test_checks_skipped_on_reading_stay_skipped_and_the_ship_is_checked_later(runs, kcs,
                                                                              tmp_path):
    flipped = Trajectory(runs[0].data.assign(delta=-runs[0].data.delta,
                                             delta_c=-runs[0].data.delta_c), "flipped")
    path = write_csv(flipped, tmp_path / "flipped.csv")
    with pytest.raises(ss.SindyshipInputError, match="rudder-sign check"):
        read_csv(path)
    record = read_csv(path, skip_checks=["rudder-sign"])  # no ship: the ship's checks wait
    assert record.meta["checks"] == {"ship": None, "skipped": ["rudder-sign"],
                                     "rudder_check": True}
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityNote)
        ss.fit([record, *runs[1:]], kcs)  # the skipped check is not run again
    spinning = Trajectory(runs[1].data.assign(n=10.0 * kcs.propeller.n_P), "spinning")
    unscaled = read_csv(write_csv(spinning, tmp_path / "spinning.csv"))  # n needs the ship
    assert unscaled.meta["checks"]["ship"] is None
    with pytest.raises(ss.SindyshipInputError, match=(
            r"^.*spinning\.csv: the revolutions check refuses the record")):  # named as read
        ss.fit([runs[0], unscaled], kcs)


def test_records_of_another_ship_or_scale_are_refused_by_every_verb(runs, kcs):
    kvlcc2 = ss.load_ship("kvlcc2")
    (model_scale,) = fly(MMGModel(kvlcc2), [Manoeuvre("zigzag", rudder=20, check=20,
                                                      duration=200)])
    kcs_model = paper_model(kcs)
    for call in (lambda: ss.evaluate(kcs_model, [model_scale]),
                 lambda: ss.refine(kcs_model, [model_scale], max_evaluations=2),
                 lambda: ss.fit([model_scale], kcs)):
        with pytest.raises(ss.SindyshipInputError, match=(
                r"^records: zz20_20 never goes faster than 1\.\d+ m/s, 0\.1\d* times the "
                r"design speed U0 = 12\.35 m/s of ship 'kcs', and is no record of it under "
                r"way; give the ship \(and scale\)")):
            call()
    with pytest.raises(ss.SindyshipInputError, match=(
            r"^records: zz20_20 reaches 12\.\d+ m/s, 10\.\d times the design speed U0 = "
            r"1\.179 m/s of ship 'kvlcc2'")):
        ss.evaluate(paper_model(kcs).__class__(kvlcc2, kcs_model.library,
                                               kcs_model.coefficients), [runs[0]])


def test_a_missing_rudder_angle_is_named_as_such(runs, kcs):
    data = runs[0].data.copy()
    data.loc[100, "delta"] = np.nan
    with pytest.raises(ss.SindyshipInputError, match=(
            r"^records: zz20_20 has a missing or infinite delta at t = 100 s; give records "
            r"with every sample of u, v, r, x, y, psi and the rudder angle\.$")):
        ss.fit([Trajectory(data, runs[0].name), *runs[1:]], kcs)


def test_wrong_arguments_to_the_python_functions_are_named(runs, kcs, tmp_path):
    """Each had failed deep inside: an AttributeError on a str or a dict, an
    IsADirectoryError on the atomic rename, scikit-learn's InvalidParameterError at fit."""
    from sindyship.export import equations_latex, generate_python

    with pytest.raises(TypeError, match=r"^records must be a list of Trajectory \(or of "
                       r"measurement CSV paths\), not a dict; pass list\(records\.values\(\)\)\.$"):
        ss.evaluate(paper_model(kcs), {run.name: run for run in runs})  # keys read as paths
    mmg = ss.MMGModel("kcs")  # a ship's name, as fit takes it
    assert mmg.ship == kcs
    with pytest.raises(TypeError, match=r"^ship must be a Ship, a built-in ship name"):
        ss.MMGModel(230.0)
    model = paper_model(kcs)
    for call in (lambda: generate_python(mmg), lambda: equations_latex(model.to_dict())):
        with pytest.raises(TypeError, match=r"^model must be an identified AbkowitzModel "
                           r"\(sindyship\.fit makes one, AbkowitzModel\.load reads one\)"):
            call()
    with pytest.raises(TypeError, match=r"AbkowitzModel\.from_dict\(it\)\), not dict\.$"):
        equations_latex(model.to_dict())
    with pytest.raises(ss.SindyshipInputError, match=r" is a folder; give the model a file "
                       r"name, such as .*model\.json\.$"):
        model.save(tmp_path)
    for optimizer, params, message in (
            ("lasso", {"cv": "loo"}, r"^optimizer 'lasso' refuses its parameters \(\{'cv': "
                                     r"'loo'\}\): The 'cv' parameter of LassoCV must be"),
            ("stlsq", {"threshold": -1}, r"^optimizer 'stlsq' refuses its parameters \(\{"
                                         r"'threshold': -1\}\): The 'threshold' parameter")):
        with pytest.raises(ss.SindyshipInputError, match=message):
            ss.fit(runs, kcs, optimizer=optimizer, params=params)


def test_channels_no_check_reads_pass_unread(runs, kcs):
    """A text label or a NaN in a channel nothing reads had been refused ("delete the row")
    once records in memory were checked; they pass as they did, and stay in the record."""
    labelled = [Trajectory(r.data.assign(label="trial 3", wind_speed=np.nan), r.name)
                for r in runs]
    model = ss.fit(labelled, kcs)
    assert model.coefficients == ss.fit(runs, kcs).coefficients
    from sindyship.measurements import check_trajectory

    checked = check_trajectory(labelled[0], kcs)
    assert list(checked.data["label"].unique()) == ["trial 3"]
    assert checked.data["wind_speed"].isna().all()


def test_python_fit_refuses_a_training_set_never_near_the_ships_speed(runs, kcs):
    """As the command line does: a U0 in knots (24 for 12.35 m/s) leaves every record at 0.51
    of it; a fit on part of a set (left out one by one) is not judged alone."""
    from dataclasses import replace

    knots = replace(kcs, particulars=replace(kcs.particulars, U0=24.0))
    with pytest.raises(ss.SindyshipInputError, match=(
            r"^no training record goes faster than 12\.\d+ m/s, 0\.51 times the design speed "
            r"U0 = 24 m/s of ship 'kcs'; give the ship the records are of, with its "
            r"approach speed U0 in m/s\.$")):
        ss.fit(runs, knots)
    assert ss.fit(runs, knots, part_of_set=True).ship is knots


def test_the_simulators_slow_records_of_the_ship_are_flown(kcs):
    """A zig-zag the simulator flew at 0.22 U0 with the ship's own model had been refused as
    "no record of it under way": records flown for the ship are that ship's."""
    slow = ss.simulate_with_effects(
        kcs, [Manoeuvre("zigzag", rudder=20, check=20, duration=1500)],
        ss.parse_effects(["rps=0.22"]), state0=np.array([0.22 * kcs.U0, 0, 0, 0, 0, 0, 0]))
    assert max(slow[0]["u"]) < 0.25 * kcs.U0
    errors = ss.evaluate(paper_model(kcs), slow)
    assert errors["zz20_20"]["mean_distance_L"] > 0.0

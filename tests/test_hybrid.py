"""Hybrid identification: trajectories and captive tests in one regression (fit --captive)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from cli_in_process import run_sindyship

from sindyship.captive import captive_tests, write_captive_csv
from sindyship.errors import SindyshipInputError
from sindyship.evaluation import distance_errors
from sindyship.flights import fly_like_batch
from sindyship.hybrid import (
    CAPTIVE_SHARE,
    captive_design,
    fit_hybrid,
    fitted_again,
    model_design,
    with_captive,
)
from sindyship.identify import design, fit, resolve_library
from sindyship.measurements import write_csv
from sindyship.model import AbkowitzModel
from sindyship.optimizers import ALWAYS_TRAINED
from sindyship.reproduce import captive_agreement

#: A small towing-tank programme: three sweeps of five conditions (no drift and yaw combined).
PROGRAMME = ("static-drift", "rudder", "pure-yaw")


@pytest.fixture(scope="module")
def programme(kcs):
    return pd.concat([captive_tests(kcs, test, points=5) for test in PROGRAMME],
                     ignore_index=True)


@pytest.fixture(scope="module")
def zigzags(protocol_runs):
    return [r for r in protocol_runs["train"] if r.name.startswith("zz")]


def lowest_correlation(model, ship) -> float:
    """The lowest correlation of X, Y, N with the MMG's captive tests, over all four tests
    (drift and yaw combined among them, which the programme does not hold)."""
    agreement = captive_agreement({"model": model}, ship)["model"]
    return min(f["correlation"] for test in agreement.values() for f in test.values()
               if f["correlation"] is not None)


def held_out(model, protocol_runs, ship) -> list[float]:
    flown = fly_like_batch(model.dynamics(), protocol_runs["test"])
    errors = [distance_errors(f, r, ship.L) for f, r in zip(flown, protocol_runs["test"],
                                                             strict=True)]
    assert all(e["diverged_at_s"] is None for e in errors)
    return [e["mean_distance_L"] for e in errors]


def test_captive_rows_are_the_inverse_of_the_forces_a_model_predicts(kcs):
    """A model's predicted captive forces, made into rows of eq. 16, are fitted by that model's
    own coefficients exactly (the instantaneous speed form too, with its (U/U0)^2)."""
    from sindyship.forces import model_captive_forces

    tests, runs = captive_tests(kcs, "all", points=5), manoeuvres(kcs)
    for speed in ("design", "instantaneous"):
        model = fit(runs, kcs, library=resolve_library("abkowitz-vr", (), speed),
                    optimizer="prior")  # forces of the right sign: they pass the table's checks
        measured = tests.assign(**model_captive_forces(model, tests))
        rows = captive_design(measured, kcs, model.library)
        for dof, problem in rows.items():
            coefficients = np.array([model.coefficients[dof][t] for t in problem.terms])
            assert np.allclose(problem.features @ coefficients, problem.target,
                               rtol=1e-9, atol=1e-12 * np.abs(problem.target).max())
        assert set(rows["Y"].groups) == {ALWAYS_TRAINED}  # never a fold of their own


def manoeuvres(ship):
    from sindyship.manoeuvres import Manoeuvre, fly
    from sindyship.mmg import MMGModel

    return fly(MMGModel(ship), [Manoeuvre("zigzag", rudder=20, check=20, duration=800),
                                Manoeuvre("turning-circle", rudder=-35, duration=800)])


def test_the_captive_rows_carry_their_share_of_the_weight(kcs, zigzags, programme):
    library = resolve_library("abkowitz-vr")
    problems = design(zigzags, kcs, library)
    rows = captive_design(programme, kcs, library)
    for share in (0.01, 0.5):
        stacked = with_captive(problems, rows, share)
        n = len(problems["Y"].target)
        weight = np.sum(stacked["Y"].features[n:] ** 2) / np.sum(rows["Y"].features ** 2)
        assert weight == pytest.approx(share / (1 - share) * n / len(programme))
        assert np.allclose(stacked["Y"].target[n:], np.sqrt(weight) * rows["Y"].target)
        assert np.array_equal(stacked["Y"].features[:n], problems["Y"].features)
        assert list(np.unique(stacked["Y"].groups)) == [ALWAYS_TRAINED, 0, 1, 2]
    with pytest.raises(SindyshipInputError, match="between 0 and 1"):
        with_captive(problems, rows, 1.0)


def test_a_small_programme_fixes_the_forces_the_zigzags_leave_free(kcs, zigzags, programme,
                                                                   protocol_runs):
    """On the three KCS zig-zags the prior fit's forces correlate 0.97 at worst with the
    captive tests; with 15 conditions of static drift, rudder and pure yaw at the default
    share, at least 0.99 in every test and force, drift and yaw combined among them (which
    the programme does not hold), and the held-out flights are each closer."""
    library = resolve_library("abkowitz-vr")
    prior = fit(zigzags, kcs, library=library, optimizer="prior")
    hybrid = fit_hybrid(zigzags, kcs, programme, library=library, optimizer="prior")
    assert 0.95 < lowest_correlation(prior, kcs) < 0.98
    assert lowest_correlation(hybrid, kcs) > 0.99
    before, after = held_out(prior, protocol_runs, kcs), held_out(hybrid, protocol_runs, kcs)
    assert before == pytest.approx([2.454, 1.266, 0.405], abs=0.01)
    assert after == pytest.approx([2.370, 1.086, 0.186], abs=0.01)
    kept = hybrid.info["captive"]
    assert kept["share"] == CAPTIVE_SHARE and kept["rows"] == 15
    assert kept["tests"] == {"static-drift": 4, "straight": 3, "rudder": 4, "pure-yaw": 4}
    assert hybrid.info["n_samples"] == sum(r.n_samples for r in zigzags)


def test_tests_at_half_speed_tell_how_the_forces_fall_and_move_them_at_the_design_speed(
        kcs, zigzags, protocol_runs):
    """The same programme run at half the design speed with the design revolutions: in the
    design speed form the held-out turns (which lose speed) fly closer and the yaw moment in
    pure yaw at U0 moves; in the instantaneous form the surge force in pure yaw at U0 takes
    the wrong sign (the propeller loaded at the design revolutions), as the docs say."""
    slow = pd.concat([captive_tests(kcs, test, points=5, speed=0.5 * kcs.U0)
                      for test in PROGRAMME], ignore_index=True)
    design_form = fit_hybrid(zigzags, kcs, slow, library="abkowitz-vr", optimizer="prior")
    assert held_out(design_form, protocol_runs, kcs) == pytest.approx([1.268, 0.087, 0.156],
                                                                      abs=0.01)
    agreement = captive_agreement({"model": design_form}, kcs)["model"]
    assert agreement["pure-yaw"]["N"]["relative_rms"] == pytest.approx(0.41, abs=0.02)
    assert lowest_correlation(design_form, kcs) > 0.98
    instantaneous = fit_hybrid(zigzags, kcs, slow, optimizer="prior",
                               library=resolve_library("abkowitz-vr", speed="instantaneous"))
    agreement = captive_agreement({"model": instantaneous}, kcs)["model"]
    assert agreement["pure-yaw"]["X"]["correlation"] < -0.99


def test_a_saved_hybrid_model_is_refined_and_refitted_with_its_captive_rows(kcs, zigzags,
                                                                          programme, tmp_path):
    """The refinement's penalty (the fit's own objective) and its check on half of the
    records fit the same captive rows: the model keeps them, through save and load."""
    model = fit_hybrid(zigzags, kcs, programme, library="abkowitz-vr", optimizer="prior")
    model.save(tmp_path / "m.json")
    loaded = AbkowitzModel.load(tmp_path / "m.json", ship=kcs)
    rows = model_design(loaded, zigzags)
    n = sum(r.n_samples for r in zigzags)
    assert len(rows["N"].target) == n + len(programme)
    assert len(model_design(loaded, zigzags, captive=False)["N"].target) == n
    from sindyship.export import generate_python

    assert ("Captive tests fitted beside them: static-drift 4, straight 3, rudder 4, pure-yaw "
            "4") in " ".join(generate_python(loaded).split())
    again = fitted_again(loaded, zigzags)
    assert again.info["captive"]["rows"] == len(programme)
    for dof in ("X", "Y", "N"):
        assert again.coefficients[dof] == pytest.approx(model.coefficients[dof], rel=1e-6,
                                                        abs=1e-12)


def test_fit_takes_captive_tests_beside_the_records(kcs, zigzags, programme, tmp_path):
    paths = []
    for record in zigzags:
        paths.append(tmp_path / f"{record.name}.csv")
        write_csv(record, paths[-1])
    captive = tmp_path / "captive.csv"
    write_captive_csv(programme, captive)
    code, out, err = run_sindyship("fit", *paths, "--ship", "kcs", "--captive", captive,
                                   "--refine", "0", "--out", tmp_path / "m.json", "--json")
    assert code == 0, err
    assert ("captive tests: 15 conditions (static-drift 4, straight 3, rudder 4, pure-yaw 4) "
            "fitted beside the records, carrying 0.01 of the regression's weight") in err
    assert ("terms these records cannot separate; the captive static-drift, rudder, pure-yaw "
            "tests given decide what they hold (--captive); the ship's prior decides the "
            "rest)") in err
    saved = json.loads((tmp_path / "m.json").read_text())
    assert saved["info"]["captive"]["conditions"]["u"][0] == pytest.approx(programme["u"][0])
    document = json.loads(out)
    assert document["training_flights"]["zz20_20"]["diverged_at_s"] is None
    # the saved model against the tests it was given, as forces compares them
    given = document["captive_agreement"]
    assert set(given) == {"static-drift", "rudder", "pure-yaw", "straight"}
    assert min(given[t][f]["correlation"] for t in ("static-drift", "rudder", "pure-yaw")
               for f in "YN") > 0.99
    assert "the saved model against the captive tests given (correlation of X / Y / N" in err


@pytest.mark.parametrize(("extra", "message"), [
    (["--captive-share", "0.1"], "--captive-share weighs the captive tests of --captive"),
    (["--captive", "{captive}", "--stream"], "--captive goes with a fit in memory"),
    (["--captive", "{kilo}"], "the measured Y is 0.00"),
    (["--captive", "{surge}"], "the measured X is 7.29e-05 times the size of the measured Y"),
    (["--captive", "{flipped}"], "the measured Y correlates -0.9"),
    (["--captive", "{astern}"], "has 15 conditions going astern"),
    (["--captive", "{port_rudder}"], "rudder angle, where a rudder aft gives Y negative and N "
                                     "positive for a positive angle in sindyship's convention "
                                     "(delta positive turns the bow to starboard): negate the "
                                     "column delta."),
    (["--captive", "{flipped_n}"], "the measured N of the rudder tests correlates -1.00 with the "
                                   "rudder angle"),
    (["--captive", "{other}"], "far from the design speed 12.3 m/s of the ship 'kcs'"),
    (["--captive", "{captive}", "--captive-share", "1"], "--captive-share"),
])
def test_fit_refuses_captive_tests_it_cannot_use(kcs, zigzags, programme, tmp_path, extra,
                                                  message):
    record = tmp_path / "zz.csv"
    write_csv(zigzags[0], record)
    files = {"captive": tmp_path / "captive.csv", "kilo": tmp_path / "kilo.csv",
             "other": tmp_path / "other.csv"}
    write_captive_csv(programme, files["captive"])
    write_captive_csv(programme.assign(X=programme["X"] / 1000.0, Y=programme["Y"] / 1000.0,
                                       N=programme["N"] / 1000.0), files["kilo"])
    write_captive_csv(programme.assign(u=programme["u"] / 10.0, v=programme["v"] / 10.0),
                      files["other"])
    files.update(surge=tmp_path / "surge.csv", flipped=tmp_path / "flipped.csv",
                 astern=tmp_path / "astern.csv", port_rudder=tmp_path / "port_rudder.csv",
                 flipped_n=tmp_path / "flipped_n.csv")
    write_captive_csv(programme.assign(X=programme["X"] / 1000.0), files["surge"])
    write_captive_csv(programme.assign(Y=-programme["Y"], N=-programme["N"]), files["flipped"])
    write_captive_csv(pd.concat([programme, programme.assign(u=-programme["u"])]),
                      files["astern"])
    rudder = programme[programme["delta"] != 0.0]  # a positive angle to port: not sindyship's
    write_captive_csv(rudder.assign(delta=-rudder["delta"]), files["port_rudder"])
    write_captive_csv(rudder.assign(N=-rudder["N"]), files["flipped_n"])
    argv = [word.format(**files) for word in extra]
    code, _, err = run_sindyship("fit", record, "--ship", "kcs", *argv, "--out",
                                 tmp_path / "m.json")
    assert code == 2 and message in err, err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "m.json").exists()
    if extra[0] == "--captive" and len(extra) == 2 and "{captive}" not in extra[1]:
        assert f"{files[extra[1][1:-1]]}: " in err  # the table's own refusals name the file


def test_captive_rows_are_never_a_fold_of_the_cross_validation(kcs, zigzags, programme):
    """Held out as folds of their own, the test types made STLSQ's cross-validation keep 2
    of 16 surge terms and fly its own zig-zags 2 to 5 L off; always trained on, it keeps as
    many terms as without them."""
    library = resolve_library("abkowitz")
    alone = fit(zigzags, kcs, library=library, optimizer="stlsq")
    hybrid = fit_hybrid(zigzags, kcs, programme, library=library, optimizer="stlsq")
    assert hybrid.n_active()["X"] >= alone.n_active()["X"] - 2
    assert hybrid.n_active()["N"] >= alone.n_active()["N"] - 2
    flown = fly_like_batch(hybrid.dynamics(), zigzags)
    assert max(distance_errors(f, r, kcs.L)["mean_distance_L"]
               for f, r in zip(flown, zigzags, strict=True)) < 0.5

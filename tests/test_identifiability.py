"""Which terms the records cannot separate (VIF, sign flips, collinear groups, remedies)."""

from __future__ import annotations

import json

import pytest
from cli_in_process import run_sindyship

from sindyship.identifiability import VIF_BOUND, identifiability


@pytest.fixture(scope="module")
def zigzag_report(kcs, protocol_runs):
    zigzags = [r for r in protocol_runs["train"] if r.name.startswith("zz")]
    return identifiability(zigzags, kcs)


def test_zigzags_flag_the_cubic_v_r_terms(zigzag_report):
    report = zigzag_report
    for dof in "YN":
        assert {"v^3", "r^2 v", "v^2 r", "r^3", "v r delta"} <= set(report.high_vif[dof])
        assert "v" not in report.high_vif[dof] and "delta" not in report.high_vif[dof]
        assert report.vif[dof]["r^2 v"] == pytest.approx(1.21e7, rel=0.05)
    assert report.high_vif["X"] == []
    # X_vv and X_rr are fitted with either sign depending on which zig-zag is left out
    assert {"v^2", "r^2", "r delta"} <= set(report.sign_flips["X"])
    assert set(report.sign_flips["Y"]) == {"du", "du^2", "du^2 v"}
    assert report.relative_residual["Y"] == pytest.approx(0.0091, abs=0.001)


def test_groups_name_the_tie_and_the_test_that_separates(zigzag_report):
    cubic = [g for g in zigzag_report.groups if g.dof == "Y" and "v^3" in g.terms]
    assert len(cubic) == 1
    group = cubic[0]
    assert {"v^3", "r^2 v", "v^2 r", "r^3"} <= set(group.terms)
    assert group.max_vif > VIF_BOUND
    assert group.ties[0]["pair"] == ["v", "r"] and group.ties[0]["r2"] == pytest.approx(0.96,
                                                                                      abs=0.01)
    captive = next(r for r in group.remedies if r["captive"])
    best_free = next(r for r in group.remedies if not r["captive"])
    assert captive["factor"] > 50 > 3 > best_free["factor"] > 1.5
    assert group.remedies[0]["captive"]  # captive tests separate them best
    line = group.text()
    assert line.startswith("Y: v^3") and "v' moves with r' (R^2 0.96)" in line
    assert "\n" not in line and "captive" in line


def test_report_serialises_and_reads(zigzag_report):
    document = json.loads(zigzag_report.to_json())
    assert document["records"] == ["zz35_10", "zz20_20", "zz15_15"]
    assert document["bounds"]["vif"] == VIF_BOUND
    lines = zigzag_report.text().splitlines()
    flip_lines = sum(bool(zigzag_report.sign_flips[d]) for d in "XYN")
    # sway and yaw share their terms: their identical groups make one line
    distinct = {(g.terms, g.max_vif) for g in zigzag_report.groups}
    assert len(lines) == len(distinct) + flip_lines
    assert "X: v^2, r^2" in zigzag_report.text()


def test_the_full_training_set_still_cannot_separate_v_and_r(kcs, protocol_runs):
    report = identifiability(protocol_runs["train"], kcs, remedies=False)
    assert {"v^3", "r^2 v", "v^2 r"} <= set(report.high_vif["Y"])
    assert all(group.remedies == [] for group in report.groups)
    # no sign flip is not a right sign: X_vv keeps one sign here, the wrong one
    assert "v^2" not in report.sign_flips["X"]
    assert report.vif["X"]["v^2"] < VIF_BOUND


def test_fit_on_the_three_zigzags_warns_of_the_collinear_terms(protocol_runs, tmp_path):
    from sindyship.measurements import write_csv

    paths = [write_csv(r, tmp_path / f"{r.name}.csv") for r in protocol_runs["train"]
             if r.name.startswith("zz")]
    # the warning does not depend on the refinement, which is left out
    code, out, err = run_sindyship("fit", *paths, "--ship", "kcs", "--refine", "0", "--out",
                                   tmp_path / "m.json", "--json")
    assert code == 0, err
    assert "Identifiability" in err
    assert "Y and N: v^3, r^3, v^2 r" in err and "v' moves with r'" in err
    document = json.loads(out)
    flagged = {term for g in document["identifiability"]["groups"] for term in g["terms"]}
    assert {"v^3", "r^2 v", "v^2 r"} <= flagged


def test_fit_with_the_prior_says_the_prior_decides_the_collinear_terms(protocol_runs,
                                                                        tmp_path):
    from sindyship.measurements import write_csv

    paths = [write_csv(r, tmp_path / f"{r.name}.csv") for r in protocol_runs["train"]
             if r.name.startswith("zz")]
    code, _, err = run_sindyship("fit", *paths, "--ship", "kcs", "--optimizer", "prior",
                                 "--refine", "0", "--out", tmp_path / "m.json")
    assert code == 0, err
    assert "the ship's prior decides what the records cannot" in err
    saved = json.loads((tmp_path / "m.json").read_text())
    assert saved["optimizer"]["name"] == "prior"
    assert saved["info"]["straight_run"]["stable"] is True


def test_a_remedy_from_exact_collinearity_reads_as_making_the_vif_finite():
    """Exactly collinear terms have no finite VIF, so a remedy's factor is None (null in
    JSON): the text says the remedy makes the VIF finite, or that it leaves it infinite when
    the remedy's own VIF is None too, instead of failing to format it."""
    from sindyship.identifiability import CollinearGroup

    def group(free):
        return CollinearGroup("Y", ("v", "r"), float("inf"), float("inf"), ("v", "r"),
                              [{"pair": ["v", "r"], "r2": 1.0}],
                              [free, {"test": "captive pure-yaw tests", "captive": True,
                                      "max_vif": 1.2, "factor": 40.0}])

    finite = group({"test": "turning circles", "captive": False, "max_vif": 3.0,
                    "factor": None})
    assert finite.text() == (
        "Y: v, r cannot be separated (VIF up to inf): v' moves with r' (R^2 1.00); adding "
        "turning circles lowers it to a finite VIF, captive pure-yaw tests would lower it "
        "40-fold (give them to fit with --captive, or check the model's forces against them "
        "with sindyship forces).")
    assert finite.to_dict()["remedies"][0]["factor"] is None
    infinite = group({"test": "turning circles", "captive": False, "max_vif": None,
                      "factor": None})
    assert infinite.text().endswith("adding turning circles leaves it infinite, captive "
                                    "pure-yaw tests would lower it 40-fold (give them to "
                                    "fit with --captive, or check the model's forces "
                                    "against them with sindyship forces).")

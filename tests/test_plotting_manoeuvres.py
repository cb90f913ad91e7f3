"""The standard manoeuvre figures show the numbers the manoeuvre functions compute."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sindyship.manoeuvres import imo_criteria, turning_figures, zigzag_figures
from sindyship.plotting import plot_turning_circle, plot_zigzag

GOLDEN = json.loads((Path(__file__).parent / "golden" / "kcs.json").read_text())


def test_the_zigzag_figure_marks_the_overshoots_and_the_imo_criteria(kcs, protocol_runs):
    record = next(r for r in protocol_runs["test"] if r.name == "zz10_10")
    figures = zigzag_figures(record)
    fig = plot_zigzag(record, L=kcs.L, U=kcs.U0)
    axis = fig.axes[0]
    texts = " ".join(t.get_text() for t in axis.texts)
    assert f"overshoot 1: {figures['first_overshoot_deg']:.1f} deg" in texts
    assert f"overshoot 2: {figures['second_overshoot_deg']:.1f} deg" in texts
    assert f"period {figures['period_s']:.0f} s" in texts
    limits = imo_criteria("zigzag", kcs.L / kcs.U0, rudder=10, check=10)
    assert limits["first_overshoot_deg"] == pytest.approx(5 + 0.5 * kcs.L / kcs.U0)
    assert f"IMO <= {limits['first_overshoot_deg']:.3g} deg: meets" in texts
    assert "[s]" in axis.get_xlabel() and "[deg]" in axis.get_ylabel()
    assert axis.get_legend() is not None and axis.get_title().startswith("Zig-zag 10/10")


def test_the_turning_figure_marks_advance_and_tactical_diameter(kcs, protocol_runs):
    record = next(r for r in protocol_runs["train"] if r.name == "tc35_stbd")
    figures = turning_figures(record, kcs.L)
    golden = GOLDEN["turning"]["tc35_stbd"]
    fig = plot_turning_circle(record, L=kcs.L)
    axis = fig.axes[0]
    texts = " ".join(t.get_text() for t in axis.texts)
    assert f"advance {figures['advance_L']:.2f} L" in texts
    assert f"tactical diameter {figures['tactical_diameter_L']:.2f} L" in texts
    assert "IMO <= 4.5 L: meets" in texts and "IMO <= 5 L: meets" in texts
    tolerance = GOLDEN["tolerance_rel"]
    assert figures["advance_L"] == pytest.approx(golden["advance_L"], rel=tolerance)
    assert figures["tactical_diameter_L"] == pytest.approx(golden["tactical_diameter_L"],
                                                           rel=tolerance)
    labels = [line.get_label() for line in axis.get_lines()]
    assert "start (rudder execute)" in labels and "record, first 360 deg" in labels
    assert "north" in axis.get_ylabel() and "east" in axis.get_xlabel()

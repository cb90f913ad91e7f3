"""The text tables of flights for people: a saved model's flights (``sindyship evaluate``)
and the paper-reproduction table (``sindyship reproduce``).  The diagnoses' are in
:mod:`sindyship.reports`.
"""

from __future__ import annotations

import math

__all__ = ["evaluation_report", "reproduce_report"]


def _flown_as_text(err: dict) -> str:
    """How a record was flown, and from which time (its rudder execute, or its first row)."""
    kind = err.get("flown_as")
    how = {"replay-commanded": "replaying its commanded rudder through the servo",
           "replay-actual": "replaying its recorded rudder angle"}.get(kind, "")
    if kind == "zigzag":
        how = (f"flown closed loop as a {err['amplitude_deg']:g}/{err['check_deg']:g} "
               "zig-zag")
    reason = err.get("start_reason") or ""
    if how and err.get("start_s") is not None:  # a zig-zag is flown from its execute
        at = "its execute at " if kind == "zigzag" or "execute" in reason else ""
        how += f" from {at}t = {err['start_s']:.6g} s"
    if kind in ("replay-commanded", "replay-actual") and "(as a zig-zag: " in reason:
        how += "; " + reason.split(": flown from")[0]  # why a zig-zag-like record is none
    return how


def evaluation_report(errors: dict) -> str:
    """The text ``sindyship evaluate`` prints: one line per record with how it was flown (from
    where, and why there), its mean and maximum distance in ship lengths (a diverged flight
    has FAILED; its mean covers the time before), and a line of a turn's or zig-zag's figures,
    flown against recorded.

    Parameters
    ----------
    errors : dict
        What :func:`sindyship.evaluation.evaluate` returns.

    Returns
    -------
    str

    Examples
    --------
    >>> import sindyship as ss
    >>> ship = ss.load_ship("kcs")
    >>> runs = ss.fly(ss.MMGModel(ship), [ss.Manoeuvre("zigzag", rudder=20, check=20,
    ...                                                duration=600)])
    >>> report = ss.evaluation_report(ss.evaluate(ss.fit(runs, ship), runs))
    >>> report.splitlines()[0].startswith("zz20_20: mean ")
    True
    """
    lines = []
    for name, err in errors.items():
        how = _flown_as_text(err)
        cell = (f"mean {err['mean_distance_L']:.4f} L, max {err['max_distance_L']:.4f} L"
                if math.isfinite(err["mean_distance_L"]) else "no distance")
        if err["diverged_at_s"] is not None:
            cell = (f"FAILED: diverged at {err['diverged_at_s']:.0f} s; before it {cell}")
        lines.append(f"{name}: {cell}" + (f" ({how})" if how else ""))
        if err.get("turn") is not None:
            lines.append(_turn_line(err["turn"]))
        if err.get("zigzag") is not None:
            lines.append(_figures_line("zig-zag", err["zigzag"], (
                ("first overshoot", "first_overshoot_deg", " deg", 1),
                ("second overshoot", "second_overshoot_deg", " deg", 1),
                ("period", "period_s", " s", 0))))
    return "\n".join(lines)


def _turn_line(turn: dict) -> str:
    """A turn's side and figures flown, with the recorded ones in brackets."""
    flown, recorded = turn["flown"] or {}, turn["recorded"] or {}
    sides = (flown.get("side"), recorded.get("side"))
    if None not in sides and sides[0] != sides[1]:
        return f"  turn flown to {sides[0]}, recorded to {sides[1]}: no figures to compare"
    side = sides[1] or sides[0]
    return _figures_line("turn" + (f" to {side}" if side else ""), turn, (
        ("advance", "advance_L", " L", 2), ("tactical diameter", "tactical_diameter_L", " L", 2),
        ("steady diameter", "steady_diameter_L", " L", 2), ("speed loss", "speed_loss", "", 2)))


def _figures_line(what: str, figures: dict, rows) -> str:
    """A manoeuvre's figures flown, with the recorded ones in brackets (n/a where missing)."""
    flown, recorded = figures["flown"] or {}, figures["recorded"] or {}

    def value(values, key, unit, digits):
        number = values.get(key)
        return "n/a" if number is None else f"{number:.{digits}f}{unit}"

    return f"  {what} flown: " + ", ".join(
        f"{label} {value(flown, key, unit, digits)} (recorded "
        f"{value(recorded, key, unit, digits)})" for label, key, unit, digits in rows)


def reproduce_report(output: dict) -> str:
    """Plain-text report: Table 10 beside the paper, and the LS agreement check."""
    lines = ["Held-out mean distance [ship lengths] (paper Table 10 in brackets; +effect: the",
             "least-squares model with the terms of effects the diagnosis found missing;",
             "refined: its coefficients refined by the error of its training flights)", ""]
    names = list(output["results"][0]["errors"]) if output["results"] else []
    header = f"{'method':34s}" + "".join(f"{n:>22s}" for n in names)
    lines.append(header)
    for res in output["results"]:
        cells = []
        for name in names:
            err = res["errors"][name]
            value = f"{err['mean_distance_L']:.4f}"
            if err["diverged_at_s"] is not None:
                value += f" (div {err['diverged_at_s']:.0f}s)"
            paper_row = output.get("paper_table_10", {}).get(res["method"], {})
            paper = None if res["effects"] else paper_row.get(name)
            cells.append(f"{value} [{paper:.4f}]" if paper is not None else value)
        label = res["method"] + "".join(f"+{e}" for e in res["effects"])
        base = res.get("library", "abkowitz").split("+")[0]
        if base != "abkowitz":  # the physics-consistent fit's library with v r
            label += f" on {base}"
        if res.get("refined"):
            label += ", refined"
        lines.append(f"{label:34s}" + "".join(f"{c:>22s}" for c in cells))
    if output.get("diagnosis"):
        lines.append("")
        lines.append("Missing-effect diagnosis (share of the force error each effect explains on "
                     "manoeuvres left out):")
        lines.extend("  " + line for line in output["diagnosis"]["report"].splitlines()[:4])
    paper_flown = output.get("paper_ls_flown")
    if paper_flown:
        lines.append("")
        lines.append("The paper's own LS coefficients flown here: " + ", ".join(
            f"{k} {v['mean_distance_L']:.3f} L" for k, v in paper_flown.items()))
    agreement = output.get("paper_ls_agreement")
    if agreement:
        lines.append(
            f"LS coefficients vs paper Tables 7-9: median relative deviation "
            f"{agreement['median_rel_dev']:.3f}, "
            f"same sign {100 * agreement['sign_agreement']:.1f} %"
            f" ({agreement['n_coefficients']} non-zero coefficients)")
    captive = output.get("captive")
    if captive:
        lines.append("")
        lines.extend(_captive_lines(captive))
    linear = output.get("linear_derivatives")
    if linear:
        lines.append("")
        lines.append("Linear derivatives x 1e-5: the MMG's Taylor reference beside the fits")
        methods = [k for k in linear[0] if k not in ("name", "MMG_Taylor", "paper_LS")]
        widths = [max(10, len(m) + 2) for m in methods]
        lines.append(f"{'':8s}{'MMG':>10s}{'paper LS':>10s}" + "".join(
            f"{m.upper():>{w}s}" for m, w in zip(methods, widths, strict=True)))
        for row in linear:
            lines.append(f"{row['name']:8s}{row['MMG_Taylor']:10.1f}{row['paper_LS']:10.1f}"
                         + "".join(f"{row[m]:{w}.1f}"
                                   for m, w in zip(methods, widths, strict=True)))
        lines.append("(all coefficients: coefficients.csv in the output folder)")
    lines.append(f"Finished in {output['seconds']:.1f} s.")
    return "\n".join(lines)


def _captive_lines(captive: dict) -> list[str]:
    """Correlation of X, Y, N with the MMG's captive forces, per model and test."""
    tests = list(next(iter(captive.values())))
    lines = ["Forces against the MMG's virtual captive tests: correlation of X Y N (1 is "
             "perfect; a negative value is a force of the wrong sign)",
             f"{'model':34s}" + "".join(f"{t:>20s}" for t in tests)]
    for key, by_test in captive.items():
        cells = []
        for test in tests:
            values = [by_test[test][f]["correlation"] for f in "XYN"]
            cells.append(" ".join("  n/a" if v is None else f"{v:+.2f}" for v in values))
        lines.append(f"{key:34s}" + "".join(f"{c:>20s}" for c in cells))
    return lines

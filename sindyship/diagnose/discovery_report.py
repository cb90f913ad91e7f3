"""The text report of :func:`sindyship.diagnose.discover`: the findings beyond the catalogue,
what they mean, and what was discovered (or why nothing was)."""

from __future__ import annotations

from ..reports import DOF_NAMES, wrapped_text
from ._words import shape_words

__all__ = ["discovery_report"]


def _finding_lines(k: int, finding) -> list[str]:
    mark = "meaningful" if finding.meaningful else "not meaningful"
    what = (", ".join(f"{c} read {d:+.2f} s later" + (
                f" (95 % interval {finding.intervals[c][0]:+.2f} to "
                f"{finding.intervals[c][1]:+.2f} s when the manoeuvres are resampled)"
                if c in getattr(finding, "intervals", {}) else "")
                      for c, d in finding.delays.items())
            if finding.delays else
            "; ".join(f"{dof}: {', '.join(ts)}" for dof, ts in finding.terms.items() if ts))
    line = shape_words(finding.variables, getattr(finding, "intervals", {}))
    if line:
        what = f"{line}. {what}"
    shares = ", ".join(f"{dof} {finding.signal_by_dof[dof]:.0%}"
                       + ("" if finding.significant[dof] else " (not significant)")
                       for dof in DOF_NAMES)
    return [f"  {k}. {finding.family}: explains {finding.explained_signal:.1%} of the error "
            f"above the noise floor ({mark}; {shares})",
            wrapped_text(f"{what}. Usually: {finding.hint}.", indent="     ", subsequent="     ")]


def discovery_report(discovery, effect_file: str | None = None) -> str:
    """Text report of :func:`sindyship.diagnose.discover`: the findings and what they mean;
    ``effect_file`` is where the discovery was written, if it was."""
    smoothing = ("" if discovery.smoothing is None else
                 f", records smoothed with {discovery.smoothing['method']} over "
                 f"{discovery.smoothing.get('window_s')} s")
    lines = [f"Not in the catalogue: searched the residual of {discovery.library.name} on "
             f"{len(discovery.records)} records ({discovery.seconds:.1f} s{smoothing})."]
    named = ", ".join(f"{name} ({share:.0%})" for name, share in discovery.catalogue.items())
    if discovery.catalogue and discovery.contests:
        lines.append(wrapped_text(
            f"Catalogued effects meaningful here: {named}. A family below can stand in for "
            "them and they for it, so the best finding competes with each in flights: each "
            "fitted leaving one manoeuvre out, flying the manoeuvre left out.",
            indent="", subsequent=""))
    elif discovery.catalogue:
        lines.append(wrapped_text(f"Catalogued effects meaningful here: {named}.", indent="",
                                  subsequent=""))
    if any(c.catalogued == "none" for c in discovery.contests):
        lines.append(wrapped_text(
            "A line of a shape is chosen among hundreds, so a shape's finding must also fly "
            "the manoeuvres left out better than the library alone.", indent="",
            subsequent=""))
    for contest in discovery.contests:
        lines.append(wrapped_text(contest.sentence(), indent="", subsequent=""))
    if discovery.unnamed_channels:
        listed = ", ".join(repr(c) for c in discovery.unnamed_channels)
        lines.append(wrapped_text(
            f"Not searched: the columns {listed}, whose names no term can use; rename them "
            "with lower-case letters, digits and single underscores (heel, wave_height) to "
            "search them.", indent="", subsequent=""))
    lines += [wrapped_text(note, indent="", subsequent="")
              for note in getattr(discovery, "notes", [])]
    floor = ", ".join(f"{dof} {share:.0%}" for dof, share in discovery.noise_floor.items())
    lines.append(f"Noise floor (share of the leave-one-manoeuvre-out error): {floor}.")
    if not discovery.findings:
        lines.append("No candidate explains any of the error.")
    for k, finding in enumerate(discovery.findings[:5], start=1):
        lines += _finding_lines(k, finding)
    for r, found in enumerate(discovery.rounds[1:], start=2):
        added = ", ".join(f.family for f in discovery.accepted[: r - 1])
        best = next((f for f in found if f.meaningful), found[0] if found else None)
        if best is None:
            lines.append(f"Round {r}, with {added} added: no candidate explains any error.")
            continue
        lines.append(f"Round {r}, with {added} added, the "
                     + ("discovery:" if best.meaningful else "best candidate:"))
        lines += _finding_lines(1, best)
    lines.append(_discovery_verdict(discovery, effect_file))
    return "\n".join(lines)


def _discovery_verdict(discovery, effect_file: str | None) -> str:
    """The last line of :func:`discovery_report`: what was discovered, or why nothing was."""
    if discovery.contests and not discovery.accepted:
        last = discovery.contests[-1]
        why = ("flies better than" if last.winner == "catalogued" else
               "flies as well as")
        if last.catalogued == "none":
            return wrapped_text(
                f"Nothing was discovered: the library alone {why} the best finding "
                f"({last.finding}), which is then a chance fit of the residual.",
                indent="", subsequent="")
        return wrapped_text(
            f"Nothing was discovered: the catalogued {last.catalogued} {why} the best finding; "
            "add it (--effects) and search again.", indent="", subsequent="")
    if discovery.catalogue and not discovery.accepted:
        return "Nothing was discovered: add the catalogued effects above and search again."
    if not discovery.accepted:
        return wrapped_text(
            f"No finding is meaningful (explaining {discovery.threshold:.0%} of the error above "
            "the noise floor, with a gain significant in at least two of X, Y and N): no "
            "missing effect was discovered.", indent="", subsequent="")
    found = " and ".join(f.family for f in discovery.accepted)
    target = effect_file or "effect.toml"
    written = f"Written to {effect_file}" if effect_file else "Write it with --out effect.toml"
    return f"Discovered: {found}. {written}; refit with --effects {target} to see the error fall."

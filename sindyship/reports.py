"""The text tables of diagnoses: results hold numbers, this module turns them into text for
people (a captive comparison's is :func:`sindyship.forces.forces_report`, the flights' of
``evaluate`` and ``reproduce`` are in :mod:`sindyship.flight_reports`).

The command line prints these; notebooks call them (or a result's ``report()`` method, which
calls them).
"""

from __future__ import annotations

import math
import shlex
import textwrap
from pathlib import Path

from ._diagnosis_thresholds import MEANINGFUL_SHARE
from .errors import SindyshipInputError
from .library import DOFS, PAPER_LIBRARY, read_from_builtin
from .targets import is_under_resolved

__all__ = ["DOF_NAMES", "SETS", "before_after_report", "diagnosis_report", "error_cell",
           "iteration_report"]

#: The equations by name, for text.
DOF_NAMES = {"X": "surge force X", "Y": "sway force Y", "N": "yaw moment N"}
#: The two sets a flown record belongs to.
SETS = ("training", "held-out")


def _common_cell(row: dict) -> str:
    """The comparison over the window both flights cover: gain, or which one diverged."""
    common = row["common"]
    b, a = common["before_mean_L"], common["after_mean_L"]
    if row["before"]["diverged_at_s"] != row["after"]["diverged_at_s"]:
        return f"{common['worse']} diverged first; over {common['window_s']:.0f} s " + (
            f"{b:.3f} -> {a:.3f}" if math.isfinite(a) and math.isfinite(b) else "n/a")
    if a > 0 and math.isfinite(a) and math.isfinite(b):
        return f"{b / a:6.1f}x"
    return ""


def before_after_report(change) -> str:
    """A plain-text table of the errors before and after.

    Distances are mean / max in ship lengths; a diverged flight shows its divergence time
    beside its mean.  The last column compares the two flights over the window both cover
    (docs/protocol.md): the gain before/after, or which one diverged first.
    """
    w = max([16, *(len(row["manoeuvre"]) for row in change.rows)])
    lines = [
        f"Before/after: {change.before} -> {change.after} (mean / max distance in ship "
        "lengths; div = the flight diverged at that time and has failed)",
        f"  {'manoeuvre':{w}s} {'set':9s} {'before':>22s} {'after':>22s}  common window",
    ]
    for row in change.rows:
        cells = [error_cell(row[when]) for when in ("before", "after")]
        lines.append(
            f"  {row['manoeuvre']:{w}s} {row['set']:9s} {cells[0]:>22s} "
            f"{cells[1]:>22s}  {_common_cell(row)}"
        )
    for kind in SETS:
        ratio = change.ratio(kind)
        if math.isfinite(ratio):
            before, after = change.divergences(kind)
            lines.append(
                f"  {kind}: error x {ratio:.2f} (geometric mean over the windows both "
                f"flights cover); diverged flights {before} -> {after}"
            )
    return "\n".join(lines)


def error_cell(err: dict) -> str:
    """Mean / max distance, with the divergence time of a failed flight."""
    mean, peak = err["mean_distance_L"], err["max_distance_L"]
    cell = (f"{mean:.3f} / {peak:.3f}" if math.isfinite(mean) else "n/a")
    if err["diverged_at_s"] is not None:
        cell += f" div {err['diverged_at_s']:.0f}s"
    return cell



def _ship_argument(ship) -> str:
    """The ``--ship`` argument that loads ``ship``: its name if built in, else a placeholder."""
    from .ships import load_ship

    try:
        return ship.name if load_ship(ship.name) == ship else "SHIP.toml"
    except SindyshipInputError:
        return "SHIP.toml"


def _file_or_name(item, default_folder) -> str:
    """The command-line argument that loads a library or effect: its built-in name, the path
    of the file it was read from, or a placeholder."""
    source = getattr(item, "source", None)
    if source is None:
        return f"{item.name.upper()}.toml"
    if Path(source).parent.resolve() == Path(str(default_folder)).resolve():
        return Path(source).stem
    return str(source)


def _fit_options(diagnosis, ship_argument: str | None, effects, *,
                 optimizer: bool = True) -> str:
    """The ``fit`` options that repeat the diagnosis's own settings with ``effects`` (effect
    objects) added: the ship, how the records were read (``settings["read_options"]``), the
    library unless it is the diagnosis's default (``fit`` then takes its recommended one), the
    speed form unless it is the ship's, the derivative, the rudder signal, the smoothing and,
    with ``optimizer``, the optimizer unless it is least squares (``fit`` then takes its
    recommended ``prior``; ``discover`` takes none)."""
    from .library import builtin_library_dir

    library, settings = diagnosis.library, diagnosis.settings
    base = _file_or_name(library, builtin_library_dir())
    options = [f"--ship {shlex.quote(ship_argument or _ship_argument(diagnosis.ship))}",
               *settings.get("read_options", ())]  # resampling, checks skipped, time range
    if not read_from_builtin(library, PAPER_LIBRARY):
        options.append(f"--library {shlex.quote(base)}")
    if library.speed != diagnosis.ship.speed_reference:
        options.append(f"--speed {library.speed}")
    if settings.get("derivative") == "savgol":
        options.append(f"--derivative savgol --window {settings['window']:g}")
    if settings.get("rudder_signal") == "commanded":
        options.append("--rudder-signal commanded")
    smoothing = settings.get("smoothing") or {}
    if smoothing.get("method", "none") != "none":  # the setting chosen, also when 'auto' chose
        options.append(f"--smoothing {smoothing['method']}:{smoothing['window_s']:g}")
    if effects:
        folder = builtin_library_dir() / "effects"
        options.append("--effects " + shlex.quote(",".join(
            e if isinstance(e, str) else _file_or_name(e, folder) for e in effects)))
    if optimizer and settings.get("optimizer", "ls") != "ls":
        options.append(f"--optimizer {settings['optimizer']}")
    return " ".join(options)


def _ratio_parts(change, label: str, missing: str) -> list[str]:
    """Per set flown (training, held-out): its after/before ratio and divergences, named by
    ``label`` (``{kind}`` the set), ``missing`` where no window compares them."""
    parts = []
    for kind in SETS:
        if not any(row["set"] == kind for row in change.rows):
            continue
        ratio = change.ratio(kind)
        before, after = change.divergences(kind)
        name = label.format(kind=kind)
        text = f"{name} x {ratio:.2f}" if math.isfinite(ratio) else f"{name} {missing}"
        parts.append(text + (f" (diverged flights {before} -> {after})" if before or after
                             else ""))
    return parts


def _confirmation_text(change) -> str:
    parts = _ratio_parts(change, "{kind} error", "n/a")
    verdict = {True: "confirmed", False: "not confirmed", None: "flown"}[change.confirmed]
    judged = "" if change.confirmed is None else " (judged on the training flights)"
    disagree = {True: "; the held-out flights agree", None: "",
                False: "; the held-out flights do not agree"}[change.held_out_supports]
    return (
        f"{verdict} by refitting and re-flying{judged}: "
        + ", ".join(parts)
        + " (geometric mean of after/before mean distance over the windows both flights cover)"
        + disagree
    )



def wrapped_text(text: str, indent: str = "    ", subsequent: str = "      ") -> str:
    """``text`` wrapped at 96 characters, its first line indented by ``indent`` and the others
    by ``subsequent``."""
    return textwrap.fill(text, width=96, initial_indent=indent, subsequent_indent=subsequent)


def _compare_lines(comparisons) -> list[str]:
    if not comparisons:
        return []
    w = max([16, *(len(c.name) for c in comparisons)])
    lines = [
        "Compare: the identified model flown like each record",
        f"  {'manoeuvre':{w}s} {'set':9s} {'mean L':>8s} {'max L':>8s} "
        f"{'heading deg':>12s} {'speed m/s':>10s}  diverged",
    ]
    for c in comparisons:
        e = c.errors
        div = "-" if e["diverged_at_s"] is None else f"at {e['diverged_at_s']:.0f} s"
        lines.append(
            f"  {c.name:{w}s} {c.set:9s} {e['mean_distance_L']:8.3f} "
            f"{e['max_distance_L']:8.3f} {e['rms_heading_deg']:12.2f} "
            f"{e['rms_speed_m_s']:10.3f}  {div}"
        )
    return [*lines, ""]


def _residual_lines(diagnosis) -> list[str]:
    summary = diagnosis.residuals.summary()
    worst = diagnosis.residuals.worst_bins()
    lines = [
        "Where it fails: force residual (measured - model), RMS over the RMS "
        "measured force; the bin of the largest RMS"
    ]
    for dof in DOFS:
        floor = diagnosis.noise_floor.get(dof)
        noise = "" if floor is None else f"   noise {100 * min(floor, 1.0):3.0f} % of it"
        lines.append(
            f"  {DOF_NAMES[dof]:13s} {100 * summary[dof]['relative']:7.2f} %   "
            f"cross-validated {100 * diagnosis.force_error[dof]:7.2f} %{noise}   worst at "
            f"{worst[dof]}"
        )
    level = diagnosis.noise_level
    if level:
        coarse = [is_under_resolved(step) for step in diagnosis.sampling.values()]
        lines.append(
            "  noise in the records (rough part over one L/U0"
            + ("; the records are under-resolved, so mostly motion between samples: see the "
               "caution below" if coarse and all(coarse) else
               "; some records are under-resolved, so part of it may be motion between "
               "samples: see the caution below" if any(coarse) else "")
            + f"): u {100 * level['u']:.2g} %, "
            f"v {100 * level['v']:.2g} %, r {100 * level['r']:.2g} % of their RMS, heading "
            f"{level['psi_deg']:.2g} deg"
        )
    return [*lines, ""]


def _score_lines(k: int, score) -> list[str]:
    by = ", ".join(f"{d} {100 * score.explained_by_dof[d]:.0f} %"
                   + ("" if score.significant.get(d, True) else "?") for d in DOFS)
    mark = "" if score.meaningful else "  (not meaningful)"
    signal = ""
    if f"{100 * score.explained_signal:.1f}" != f"{100 * score.explained:.1f}":  # judged on it
        signal = f"; {100 * score.explained_signal:.1f} % of the error above noise"
    lines = [
        f" {k}. {score.effect.name} - {score.effect.title}: explains "
        f"{100 * score.explained:.1f} % ({by}){signal}{mark}"
    ]
    if score.meaningful:
        lines.append(wrapped_text(f"where: {score.regime}"))
        if score.confirmation is not None:
            lines.append(wrapped_text(_confirmation_text(score.confirmation)))
        lines.append(wrapped_text(f"physics: {score.effect.physics}"))
    return lines


def _ranking_lines(diagnosis) -> list[str]:
    lines = [
        f"Which effect is missing: share of the leave-one-manoeuvre-out force "
        f"error each effect explains (meaningful from {100 * diagnosis.threshold:.0f} % of the "
        "error above the noise floor, counting equations whose gain holds when the "
        "manoeuvres are resampled; ? marks one that does not)"
    ]
    if not diagnosis.ranking:
        lines.append("  (no testable effect)")
    for k, score in enumerate(diagnosis.ranking, 1):
        lines += _score_lines(k, score)
    if diagnosis.not_testable:
        lines += ["", "Not testable with these data (record the channel named):"]
        for item in diagnosis.not_testable:
            lines.append(wrapped_text(
                f"- {item.effect.name} ({item.effect.title}): {item.reason}", "  ", "    "))
    if diagnosis.in_library:
        lines.append(f"Already in the library: {', '.join(diagnosis.in_library)}.")
    return [*lines, ""]


def _stability_text(diagnosis) -> str:
    stability = diagnosis.stability
    if stability is None:
        return "the straight-run stability could not be evaluated"
    values = ", ".join(f"{z.real:.3g}" + (f"{z.imag:+.3g}i" if z.imag else "")
                       for z in stability.eigenvalues)
    if stability.stable:
        return f"straight-run eigenvalues {values} (per L/U0): stable on a straight course"
    doubling = stability.doubling_time_L_over_U
    return (f"straight-run eigenvalues {values} (per L/U0): unstable, a disturbance doubles "
            f"in {doubling:.2g} L/U0")


def _collinear_text(diagnosis) -> str:
    groups: dict[tuple, list[str]] = {}
    for dof, terms in diagnosis.collinear.items():
        if terms:
            groups.setdefault(tuple(terms.items()), []).append(DOF_NAMES[dof])
    parts = [" and ".join(names) + ": " + ", ".join(f"{term} (VIF {vif:.1e})"
                                                    for term, vif in terms)
             for terms, names in groups.items()]
    if not parts:
        return ""
    return "; terms the data cannot separate, " + "; ".join(parts)


_REMEDIES = (
    "what can help: another optimizer (--optimizer lasso or stlsq keeps fewer collinear "
    "terms), smoothing noisy records (--smoothing auto), manoeuvres that separate the terms "
    "(turning circles at several rudder angles, pull-outs, spirals), or terms beyond the "
    "catalogue"
)


def _closer(score) -> str:
    """What re-flying the training records with an effect does: how much closer it flies
    them, as a factor, or that it cures a divergence (the others no farther off)."""
    ratio = score.confirmation.ratio("training")
    if not 0.0 < ratio < 1.0:
        return "cures a divergence of the training flights without flying the others farther"
    return f"brings them {1.0 / ratio:.2g} times closer"


def _held_out_refutation(change) -> str:
    """How the held-out flights refute an effect: their error ratio and divergences."""
    before, after = change.divergences("held-out")
    diverged = f", diverged flights {before} -> {after}" if before or after else ""
    ratio = change.ratio("held-out")
    error = f"held-out error x {ratio:.2f}" if math.isfinite(ratio) else "held-out error n/a"
    return error + diverged


def _diagnosis_fit(diagnosis) -> str:
    """The fit the report's confirmations re-fly: the diagnosis's own, on its library."""
    optimizer = diagnosis.settings.get("optimizer", "ls")
    what = {"ls": "least squares", "prior": "the prior fit, unrefined"}.get(optimizer, optimizer)
    return f"{what} on {diagnosis.library.name}"


def _command_flights(change) -> str:
    """How the command's model flies the records with the effect, against without it."""
    return " and ".join(_ratio_parts(change, "the {kind} records", "(no window to compare)"))


def _other_fit(diagnosis) -> str:
    """What the command's model does with the effect, when the command fits another model than
    the one the ratios above describe (a diagnosis by ``ls`` names ``fit``'s recommended
    ``prior`` fit, refined; one by ``prior`` its refinement)."""
    change = diagnosis.command
    if change is None:
        if diagnosis.settings.get("optimizer", "ls") != "ls":
            return ""
        return (f" (The flights above are {_diagnosis_fit(diagnosis)}; the command fits the "
                "recommended prior and refines it: judge that model with sindyship evaluate on "
                "records it was not fitted on.)")
    return (f" (The flights above are {_diagnosis_fit(diagnosis)}; the command's model, the "
            f"prior on {change.after} refined by its flights, flies "
            f"{_command_flights(change)} as far off as without {', '.join(change.added)}.)")


def _given_effects(diagnosis, effect_arguments: list[str] | None) -> list:
    """The effects a ``fit`` command repeats: as given on the command line
    (``effect_arguments``), else the diagnosed library's."""
    return list(diagnosis.library.effects if effect_arguments is None else effect_arguments)


def _verdict_lines(diagnosis, ship_argument: str | None = None,
                   effect_arguments: list[str] | None = None) -> list[str]:
    lines = [textwrap.fill(f"Caution: {warning}.", width=96, subsequent_indent="  ")
             for warning in diagnosis.warnings]
    verdict = diagnosis.verdict
    given = _given_effects(diagnosis, effect_arguments)
    if verdict == "complete":
        flown = [s.effect.name for s in diagnosis.ranking if s.confirmation is not None]
        checked = (f", re-flying the training records with {', '.join(flown)} brings them no "
                   "clearly closer" if flown else "")
        why = (diagnosis.no_catalogued_effect if diagnosis.refuted else "no catalogued effect "
               f"explains {100 * diagnosis.threshold:.0f} % or more of the remaining force error"
               f"{checked}")
        text = (f"Verdict: complete - {why}, every training flight completed and the library "
                "predicts most of every force.")
    elif verdict == "add-effect":
        top = diagnosis.top
        why = "" if top.meaningful else (
            f" (its share of the force error is below the threshold, but re-flying the training "
            f"records with it {_closer(top)})")
        first = diagnosis.first_unrefuted or top
        if first is not top:
            why = (f" (rather than {first.effect.name}, which explains more of the force error: "
                   f"re-flying the training records with {top.effect.name} {_closer(top)}, "
                   f"with {first.effect.name} {_closer(first).removeprefix('brings them ')})")
        options = _fit_options(diagnosis, ship_argument, [*given, top.effect])
        text = (f"Verdict: add {top.effect.name}{why}: sindyship fit DATA.csv... {options}; then "
                "diagnose again with the same --effects." + _other_fit(diagnosis))
    elif verdict == "contested" and not diagnosis.top.refuted_by_held_out:
        # the command's model contests it
        top, command = diagnosis.top, diagnosis.command
        without = _fit_options(diagnosis, ship_argument, given)
        options = _fit_options(diagnosis, ship_argument, [*given, top.effect])
        text = (f"Verdict: contested - re-flying the training records favours {top.effect.name} "
                f"({_diagnosis_fit(diagnosis)}), but the model "
                f"the command to add it fits, the prior on {command.after} refined by its "
                f"flights, flies {_command_flights(command)} as far off as without it, so it "
                "is not named to add.  "
                f"Fit without it (sindyship fit DATA.csv... {without}), or, to see it anyway, "
                f"sindyship fit DATA.csv... {options} and sindyship evaluate it on records it "
                "was not fitted on.")
    elif verdict == "contested":
        top = diagnosis.top
        change = top.confirmation
        options = _fit_options(diagnosis, ship_argument, [*given, top.effect])
        ratio = change.ratio("training")
        training = (f"training error x {ratio:.2f}" if math.isfinite(ratio) else
                    "it cures a divergence" if change.divergences()[0] > change.divergences()[1]
                    else "no training flights to compare")
        text = (f"Verdict: contested - re-flying the training records favours {top.effect.name} "
                f"({training}), but the held-out flights "
                f"given refute it ({_held_out_refutation(change)}): on the training manoeuvres "
                "its terms may stand in for something else, so it is not named to add.  What "
                "can help: training records of manoeuvres like the held-out ones, or logging "
                "what the effect describes (its 'To test it' above); to see it anyway, "
                f"sindyship fit DATA.csv... {options} and sindyship evaluate it on the "
                "held-out records.")
    elif verdict == "add-discovered":
        found = " and ".join(f.family for f in diagnosis.discovery.accepted)
        options = _fit_options(diagnosis, ship_argument, given, optimizer=False)
        if diagnosis.threshold != MEANINGFUL_SHARE:  # the search the diagnosis ran
            options += f" --threshold {diagnosis.threshold:g}"
        effects = ",".join(e if isinstance(e, str) else e.name for e in [*given, "effect.toml"])
        text = (f"Verdict: {diagnosis.no_catalogued_effect}, but {found} was discovered "
                f"beyond the catalogue (above): sindyship discover DATA.csv... {options} "
                f"--out effect.toml, then fit and diagnose with --effects {shlex.quote(effects)}.")
    elif verdict == "unstable":
        flights = ", ".join(f"{name} at {when:.0f} s" for name, when in diagnosis.diverged.items())
        text = (f"Verdict: the model fails - its training flights diverged ({flights}) and no "
                f"catalogued effect is meaningful; {_stability_text(diagnosis)}"
                f"{_collinear_text(diagnosis)}; {_REMEDIES}.")
    else:
        share = ", ".join(f"{DOF_NAMES[dof]} {100 * (1 - diagnosis.force_error[dof] ** 2):.0f} %"
                          for dof in diagnosis.unexplained)
        text = (f"Verdict: the model is wrong - on held-out manoeuvres the library predicts "
                f"only {share} of the measured force (variance explained), and no catalogued "
                f"effect explains the rest; {_REMEDIES}.")
    lines.append(textwrap.fill(text, width=96, subsequent_indent="  ", break_long_words=False,
                               break_on_hyphens=False))  # a command stays whole to copy
    return lines


def diagnosis_report(diagnosis, ship_argument: str | None = None,
                     effect_arguments: list[str] | None = None) -> str:
    """The diagnosis as text a person reads, best effect first.

    Parameters
    ----------
    diagnosis : sindyship.diagnose.Diagnosis
    ship_argument : str, optional
        The ``--ship`` argument the verdict's command names (default: the ship's name if it
        is built in, else a placeholder).
    effect_arguments : list of str, optional
        The ``--effects`` arguments of the library's effects, as given (an effect file by its
        path; default: their names).

    Returns
    -------
    str
    """
    n_terms = sum(len(diagnosis.library.terms[d]) for d in DOFS)
    held_out = sum(c.set == "held-out" for c in diagnosis.comparisons)
    lines = [
        f"sindyship diagnose: ship {diagnosis.ship.name}, library {diagnosis.library.name} "
        f"({n_terms} terms), {len(diagnosis.residuals.names)} training records"
        + (f", {held_out} held-out" if held_out else ""),
        "",
    ]
    lines += _compare_lines(diagnosis.comparisons)
    lines += _residual_lines(diagnosis)
    lines += _ranking_lines(diagnosis)
    if diagnosis.discovery is not None:
        lines += ["", diagnosis.discovery.report(), ""]
    if getattr(diagnosis, "speed", None) is not None:
        lines += [textwrap.fill(diagnosis.speed.text(), width=96, subsequent_indent="  "), ""]
    lines += _verdict_lines(diagnosis, ship_argument, effect_arguments)
    return "\n".join(lines)


def _why_added(diagnosis) -> str:
    """Why a round adds another effect than the first: those re-flying refutes, its flights."""
    top = diagnosis.top
    if top is None:  # a discovered effect: its own report says why
        return ""
    refuted = [s.effect.name for s in diagnosis.refuted]
    parts = ([f"re-flying refutes {', '.join(refuted)}"] if refuted else []) + (
        [] if top.meaningful else [f"with {top.effect.name} the training flights: {_closer(top)}"])
    return f" ({'; '.join(parts)})" if top is not diagnosis.ranking[0] and parts else ""


def round_line(k: int, rnd) -> str:
    """One line on round ``k`` of an iterative diagnosis: its library, the shares its first
    four effects explain, and the effect it adds (and why, when not the first)."""
    d = rnd.diagnosis
    top = ", ".join(f"{s.effect.name} {100 * s.explained:.1f} %" for s in d.ranking[:4])
    return (f"Round {k}: library {d.library.name}: {top or 'no testable effect'}"
            + (f" -> add {rnd.added}{_why_added(d)}" if rnd.added else ""))


def iteration_report(iterative, ship_argument: str | None = None,
                     effect_arguments: list[str] | None = None) -> str:
    """One paragraph per round, the mean distance of every flight with every library (a
    diverged flight marked with the time it diverged) and the ``fit`` command of the library
    the rounds end with (the arguments as :func:`diagnosis_report`'s)."""
    lines = [round_line(k, rnd) for k, rnd in enumerate(iterative.rounds, 1)]
    lines.append(f"Stopped: {iterative.stopped}")
    table = iterative.table
    if not table.empty:
        lines.append("")
        lines.append("Mean distance [ship lengths] per manoeuvre and library:")
        table = table.assign(cell=[
            f"{mean:.3f}" + ("" if diverged is None or math.isnan(diverged)
                             else f" (diverged at {diverged:.0f} s)")
            for mean, diverged in zip(table["mean_distance_L"], table["diverged_at_s"],
                                      strict=True)])
        pivot = table.pivot(index=["set", "manoeuvre"], columns="round", values="cell")
        order = list(dict.fromkeys(zip(table["set"], table["manoeuvre"], strict=True)))
        lines.append(pivot.reindex(order).fillna("-").to_string())
    added = [rnd.diagnosis.top.effect for rnd in iterative.rounds if rnd.added]
    if added:
        first = iterative.rounds[0].diagnosis
        given = _given_effects(first, effect_arguments)
        lines += ["", textwrap.fill(
            f"The library the rounds end with: sindyship fit DATA.csv... "
            f"{_fit_options(first, ship_argument, [*given, *added])}", width=96,
            subsequent_indent="  ", break_long_words=False, break_on_hyphens=False)]
    return "\n".join(lines)

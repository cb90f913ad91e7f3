"""The README stays true: its generated blocks, its shell blocks and its pinned numbers."""

from __future__ import annotations

import contextlib
import glob
import importlib.util
import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from cli_in_process import run_sindyship

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
NUMBERS = json.loads((ROOT / "docs" / "readme-numbers.json").read_text(encoding="utf-8"))


def _script():
    path = ROOT / "scripts" / "make_readme.py"
    spec = importlib.util.spec_from_file_location("make_readme", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_blocks_are_what_the_saved_numbers_render_to():
    assert _script().render(README, NUMBERS) == README, (
        "README.md and docs/readme-numbers.json disagree: run python scripts/make_readme.py"
    )


def test_the_saved_numbers_of_the_benchmarks_are_the_benchmarks_own():
    """The README's speed, campaign and zig-zag captive figures come from what the benchmarks
    saved, so a rerun of a benchmark without ``make_readme.py`` fails here."""
    script = _script()
    for key, saved in (("speed", script._saved_speed), ("campaign", script._saved_campaign),
                       ("captive_bench", script._saved_captive_bench)):
        assert NUMBERS[key] == json.loads(json.dumps(script.clean_json(saved()))), key


def _shell_blocks() -> list[str]:
    first_hour = README.split("## Your first hour", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```bash\n(.*?)```", first_hour, re.S)


#: A word of a command the test runs in process: letters, digits and ``_./*=:,+-`` (no quote,
#: operator, variable, comment or escape, whose meaning is bash's to give).
PLAIN_WORD = re.compile(r"[A-Za-z0-9_./*=:,+-]+")


def _plain_commands(block: str) -> list[list[str]] | None:
    """The block's commands, each a list of words without ``sindyship``, when every command
    is ``sindyship`` with plain words; None when any is not (bash runs that block)."""
    commands = []
    for line in block.replace("\\\n", "").splitlines():
        words = line.split()
        if not words:
            continue
        if words[0] != "sindyship" or not all(PLAIN_WORD.fullmatch(w) for w in words):
            return None
        commands.append(words[1:])
    return commands


def _expanded(words: list[str]) -> list[str]:
    """Words with their ``*`` patterns expanded as bash does (sorted; kept when none match)."""
    out = []
    for word in words:
        matches = sorted(glob.glob(word)) if "*" in word else []
        out.extend(matches or [word])
    return out


def test_the_first_hour_runs_as_written(tmp_path, monkeypatch):
    """Every block of the README's first hour, in order, in one folder.  A block of
    ``sindyship`` commands with plain words runs in this process through
    :func:`sindyship.cli.main`, each command with the README's arguments and its globs
    expanded as bash does (a new interpreter would add a second per command); any other block
    runs as a whole with ``bash -e``, through the installed ``sindyship``."""
    blocks = _shell_blocks()
    assert len(blocks) >= 4
    env = {**os.environ, "MPLBACKEND": "Agg", "PATH": f"{Path(sys.executable).parent}:"
           + os.environ.get("PATH", "")}
    monkeypatch.chdir(tmp_path)
    through_bash, notes = [], {}
    for block in blocks:
        commands = _plain_commands(block)
        if commands is None:
            done = subprocess.run(["bash", "-e", "-c", block], cwd=tmp_path, env=env,
                                  capture_output=True, text=True, timeout=600)
            assert done.returncode == 0, f"{block}\n{done.stderr[-2000:]}"
            through_bash.append(block)
            continue
        for words in commands:
            code, _, err = run_sindyship(*_expanded(words))
            assert code == 0, f"sindyship {' '.join(words)}\n{err[-2000:]}"
            if words[0] == "fit":
                notes[words[-1]] = err
    assert any("sindyship " in block for block in through_bash)  # the console script runs
    assert (tmp_path / "equations.tex").exists() and (tmp_path / "kcs_model.py").exists()
    forces = json.loads((tmp_path / "forces" / "forces.json").read_text())
    assert min(forces["by_test"][t]["Y"]["correlation"] for t in forces["by_test"]
               if t != "straight" and forces["by_test"][t]["Y"]["correlation"] is not None) > 0.9
    assert len(list((tmp_path / "diagnosis").glob("*.png"))) > 10
    # a pure-yaw test at five yaw rates beside the records: least squares' pure-yaw forces
    # right, its static drift (which they do not hold) as wrong as without them
    hybrid = json.loads((tmp_path / "forces-yaw" / "forces.json").read_text())["by_test"]
    assert min(hybrid["pure-yaw"][f]["correlation"] for f in "YN") > 0.99
    assert hybrid["static-drift"]["N"]["correlation"] < -0.5
    # fit flies its training records and names those it misses: the default model the
    # straight run, the model with the asymmetry none
    assert "flies more than 1 L off, records it was fitted on: straight (33.2 L);" \
        in notes["model.json"]
    assert "training flights" in notes["model-asymmetry.json"]
    assert "records it was fitted on" not in notes["model-asymmetry.json"]


def test_a_readme_block_with_more_than_plain_sindyship_commands_goes_to_bash():
    assert _plain_commands("sindyship fit data/*.csv --ship kcs \\\n    --out m.json\n") == [
        ["fit", "data/*.csv", "--ship", "kcs", "--out", "m.json"]]
    for block in ("sindyship fit d.csv --ship kcs#typo\n", "sindyship fit 'a b.csv'\n",
                  "sindyship fit d.csv > log\n", "sindyship fit $DATA\n",
                  "sindyship fit d.csv;\n", "sindyship evaluate m.json d.csv 2>&1\n",
                  "sindyship fit d.csv\npython3 -c 'print(1)'\n", "cd data\n"):
        assert _plain_commands(block) is None, block


def test_the_python_example_runs(tmp_path, monkeypatch):
    """The README's Python example, run in this process in a namespace of its own."""
    (code,) = [block for block in re.findall(r"```python\n(.*?)```", README, re.S)
               if "ss.evaluate(" in block]
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {"__name__": "__main__"})
    assert "Verdict: add asymmetry" in out.getvalue()
    assert re.search(r"^zz10_10: mean [\d.]+ L, max [\d.]+ L \(flown closed loop", out.getvalue(),
                     re.M)


def test_the_python_recipe_of_the_recommended_model_is_the_default_fit(kcs, protocol_runs,
                                                                       tmp_path):
    """The README: ``ss.refine(ss.fit(train, ship, optimizer="prior", library="abkowitz-vr"),
    train)`` is the model of ``sindyship fit`` without options, coefficient for coefficient."""
    import sindyship as ss
    from sindyship.measurements import write_csv

    assert 'ss.refine(ss.fit(train, ship, optimizer="prior", library="abkowitz-vr"),\ntrain)' \
        in README
    train = protocol_runs["train"][2:6]
    paths = [str(write_csv(r, tmp_path / f"{r.name}.csv")) for r in train]
    status, _, err = run_sindyship("fit", *paths, "--ship", "kcs", "--out",
                                   str(tmp_path / "m.json"))
    assert status == 0, err
    cli = ss.AbkowitzModel.load(tmp_path / "m.json")
    ours = ss.refine(ss.fit(train, kcs, optimizer="prior", library="abkowitz-vr"), train)
    for dof in ("X", "Y", "N"):
        assert ours.coefficients[dof] == pytest.approx(cli.coefficients[dof], rel=1e-9,
                                                       abs=1e-15), dof


# ------------------------------------------------------------------ numbers pinned to the code
def _row(method: str, effects=()):
    return next(r for r in NUMBERS["table10"]
                if r["method"] == method and r["effects"] == list(effects))


@pytest.mark.parametrize("method", ["ls", "stlsq", "lasso", "svr", "prior"])
def test_table_10_rows_are_pinned(method, kcs, protocol_runs):
    from sindyship.evaluation import evaluate
    from sindyship.identify import fit
    from sindyship.reproduce import METHOD_LIBRARIES

    model = fit(protocol_runs["train"], kcs, optimizer=method,
                library=METHOD_LIBRARIES.get(method, "abkowitz"))
    errors = evaluate(model, protocol_runs["test"])
    for name, saved in _row(method)["errors"].items():
        assert errors[name]["mean_distance_L"] == pytest.approx(saved["mean_distance_L"],
                                                                rel=1e-6), name
        assert errors[name]["completed"]


def test_the_default_fit_on_the_paper_records_keeps_the_prior_row(kcs, protocol_runs):
    """The first hour: on the paper's records the default fit's last check refuses its
    refinement (refined on half of the records, it flies the other half worse), so
    ``evaluate`` shows the table's ``prior`` row."""
    from sindyship.identify import fit, recommended_library
    from sindyship.refine import refine

    model = fit(protocol_runs["train"], kcs, optimizer="prior",
                library=recommended_library("design"))
    refined = refine(model, protocol_runs["train"])
    report = refined.info["refined"]
    assert report["refused_validation"] and report["validation"]["ratio"] > 1.0
    assert refined.coefficients == model.coefficients


def test_the_diagnosed_rows_are_pinned(kcs, protocol_runs):
    from sindyship.evaluation import evaluate
    from sindyship.identify import fit

    for effects in (["asymmetry"], ["asymmetry", "higher_order"]):
        model = fit(protocol_runs["train"], kcs, effects=effects)
        errors = evaluate(model, protocol_runs["test"])
        for name, saved in _row("ls", effects)["errors"].items():
            assert errors[name]["mean_distance_L"] == pytest.approx(saved["mean_distance_L"],
                                                                    rel=1e-6), (effects, name)


def test_the_captive_correlations_are_pinned(kcs, protocol_runs):
    from sindyship.identify import fit
    from sindyship.reproduce import captive_agreement

    models = {"ls": fit(protocol_runs["train"], kcs),
              "prior": fit(protocol_runs["train"], kcs, optimizer="prior",
                           library="abkowitz-vr"),
              "ls+asymmetry+higher_order": fit(protocol_runs["train"], kcs,
                                               effects=["asymmetry", "higher_order"])}
    fresh = captive_agreement(models, kcs)
    for key, by_test in fresh.items():
        for test, forces in by_test.items():
            for dof, stats in forces.items():
                saved = NUMBERS["captive"][key][test][dof]
                assert stats["correlation"] == pytest.approx(saved["correlation"], abs=1e-6)
                assert stats["relative_rms"] == pytest.approx(saved["relative_rms"], rel=1e-6)


def test_the_paper_agreement_is_pinned(kcs, protocol_runs):
    from sindyship.identify import fit
    from sindyship.paper import ls_agreement

    agreement = ls_agreement(fit(protocol_runs["train"], kcs).coefficients)
    saved = NUMBERS["paper_ls_agreement"]
    assert agreement["median_rel_dev"] == pytest.approx(saved["median_rel_dev"], rel=1e-6)
    assert agreement["sign_agreement"] == saved["sign_agreement"]


def test_the_diagnosis_shares_are_pinned(kcs, protocol_runs):
    from sindyship.diagnose import diagnose

    result = diagnose(protocol_runs["train"], kcs, fly_training=False, confirm=0)
    saved = {s["effect"]: s["explained"] for s in NUMBERS["diagnosis"][0]["ranking"]}
    assert {s.effect.name: s.explained for s in result.ranking} == pytest.approx(saved,
                                                                                 abs=1e-6)


def test_the_kvlcc2_turns_are_pinned():
    script = _script()
    fresh = script._kvlcc2_turns()
    for side, figures in NUMBERS["kvlcc2_turns_yy"].items():
        for key in ("advance_L", "tactical_diameter_L"):
            assert fresh[side][key] == pytest.approx(figures[key], rel=1e-6), (side, key)


def _numbers_in(value) -> list[float]:
    """Every number of a nested JSON value, in order (booleans and None left out)."""
    if isinstance(value, dict):
        return [x for key in sorted(value) for x in _numbers_in(value[key])]
    if isinstance(value, list):
        return [x for item in value for x in _numbers_in(item)]
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return []
    return [float(value)]


def test_the_marin_numbers_are_pinned():
    """The KVLCC2 measurements' block (skipped without the shared data folder)."""
    from sindyship.marin import default_marin_dir

    if default_marin_dir() is None or NUMBERS["marin"] is None:
        pytest.skip("the MARIN measurements are not here (SINDYSHIP_MARIN_DIR)")
    fresh = json.loads(json.dumps(_script()._marin()))
    saved = dict(NUMBERS["marin"])
    assert fresh["top"] == saved["top"] and fresh["confirmed"] == saved["confirmed"]
    assert fresh["not_testable"] == saved["not_testable"]
    # the default fit's refinement is an iterative search: pinned at a tolerance
    default_fresh, default_saved = fresh.pop("default_fit"), saved.pop("default_fit")
    assert _numbers_in(default_fresh) == pytest.approx(_numbers_in(default_saved), rel=1e-3,
                                                       abs=1e-9)
    assert _numbers_in(fresh) == pytest.approx(_numbers_in(saved), rel=1e-6, abs=1e-12)
    # identified on the zig-zags, the default fit (with cross-flow drag in the instantaneous
    # speed form) flies both 35 deg turns as recorded without diverging, advance and tactical
    # diameter within 10 % of the measured, speed loss within 0.1; without the cross-flow
    # drag the speed loss misses by up to 0.2
    misses = _script().marin_misses
    assert default_fresh["default"]["library"] == "abkowitz-vr-crossflow"
    chosen = misses(default_fresh["default"], fresh["measured_turns"])
    assert chosen["figures"] < 0.10 and chosen["speed_loss"] < 0.10
    polynomial = misses(default_fresh["abkowitz-vr"], fresh["measured_turns"])
    assert polynomial["figures"] < 0.10 and polynomial["speed_loss"] < 0.20


def test_the_marin_block_flies_the_turns_the_readme_states(tmp_path, monkeypatch):
    """The MARIN section's commands, with the data folder in place of the README's path
    (skipped without it): the turns ``evaluate`` flies and the figures it reports as recorded
    are the README's default fit's and measured ones, to the README's two decimals."""
    from sindyship.marin import default_marin_dir
    from sindyship.marin import main as write_marin

    folder = default_marin_dir()
    if folder is None or NUMBERS["marin"] is None:
        pytest.skip("the MARIN measurements are not here (SINDYSHIP_MARIN_DIR)")
    section = README.split("### Real measurements: the KVLCC2 at MARIN", 1)[1]
    (block,) = re.findall(r"```bash\n(.*?)```", section.split("<!-- BEGIN marin", 1)[0], re.S)
    lines = block.strip().splitlines()
    assert lines[0] == "python3 -m sindyship.marin marin --data /path/to/kvlcc2"
    monkeypatch.chdir(tmp_path)
    assert write_marin(["marin", "--data", str(folder)]) == 0
    for line in lines[1:]:
        code, out, err = run_sindyship(*_expanded(line.split()[1:]), "--json")
        assert code == 0, f"{line}\n{err[-2000:]}"
    turns = json.loads(out)["errors"]
    stated = NUMBERS["marin"]["default_fit"]["default"]["turns"]
    measured = NUMBERS["marin"]["measured_turns"]
    for name, side in (("tc_35", "port"), ("tc_-35", "stbd")):
        assert turns[name]["completed"], name
        assert turns[name]["mean_distance_L"] == pytest.approx(  # over the whole record
            stated[name]["mean_distance_L"], rel=1e-3)
        figures = turns[name]["turn"]
        for key in ("advance_L", "tactical_diameter_L", "speed_loss"):
            flown, recorded = figures["flown"][key], figures["recorded"][key]
            assert flown == pytest.approx(stated[name][key], abs=0.005), (name, key)
            assert recorded == pytest.approx(measured[side][key], abs=1e-9), (name, key)
    # the diagnosis the section's paragraph states, by the command it names
    (command,) = re.findall(r"`sindyship (diagnose marin/[^`]*)`", section)
    code, out, err = run_sindyship(*_expanded(command.split()), "--json")
    assert code == 0, err
    ranking = {row["effect"]: row for row in json.loads(out)["ranking"]}
    for effect, saved in NUMBERS["marin"]["ranking"].items():
        assert ranking[effect]["explained"] == pytest.approx(saved["explained"], abs=1e-6)
        assert ranking[effect]["explained_signal"] == pytest.approx(saved["signal"], abs=1e-6)


def test_the_noise_ratios_are_pinned(kcs, protocol_runs):
    """1 % noise (seed 1), 21 s Savitzky-Golay smoothing, least squares: the held-out error
    over the clean one, as scripts/regenerate_golden.py computes it (tests/golden/kcs.json)."""
    path = ROOT / "scripts" / "regenerate_golden.py"
    spec = importlib.util.spec_from_file_location("regenerate_golden", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    runs = {r.name: r for r in protocol_runs["train"] + protocol_runs["test"]}
    ratios = module.noise_ratios(kcs, runs, protocol_runs["test"])
    golden = json.loads((ROOT / "tests" / "golden" / "kcs.json").read_text())
    assert ratios == pytest.approx(golden["noise_one_percent"], rel=1e-6)
    assert max(ratios.values()) < 1.5  # 1 % noise costs at most half the clean accuracy

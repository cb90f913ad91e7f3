"""The command line contract: verbs, exit status, one-line errors, --json on stdout only."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from cli_in_process import run_sindyship

from sindyship.cli import main
from sindyship.measurements import read_csv


def run_in_subprocess(*args):
    """``python -m sindyship.cli ARGS`` in a new interpreter: (exit status, stdout, stderr);
    for what only a real process shows (its streams as a shell sees them)."""
    proc = subprocess.run([sys.executable, "-m", "sindyship.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=600)
    return proc.returncode, proc.stdout, proc.stderr


def test_help_lists_the_verbs():
    code, out, _ = run_in_subprocess("--help")
    assert code == 0
    for verb in ("simulate", "fit", "evaluate", "reproduce"):
        assert verb in out


def test_python_m_sindyship_is_the_command_line():
    proc = subprocess.run([sys.executable, "-m", "sindyship", "--version"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0 and proc.stdout.startswith("sindyship ")


def test_the_parsers_optimizer_names_are_the_registrys():
    from sindyship.cli._common import OPTIMIZER_NAMES
    from sindyship.optimizers import OPTIMIZERS

    assert sorted(OPTIMIZER_NAMES) == sorted(OPTIMIZERS)


def test_help_simulate_a_read_record_and_refused_fits_import_no_scikit_learn(tmp_path):
    """The parser of a verb builds that verb's options alone: ``--help``, ``simulate``,
    reading a record and a ``fit``, ``diagnose`` or ``discover`` refused for its ship file
    or library, and a ``diagnose`` or ``discover`` refused for one training record or an
    unknown effect, import neither scikit-learn, pysindy, sympy nor scipy.integrate (seconds
    of every command), and every verb's full help still lists the same options as the parser
    of every verb."""
    (tmp_path / "ship.toml").write_text("[particulars]\nL = -1\n")
    script = (
        "import sys\n"
        "from sindyship.cli import build_parser, _verb_of, main\n"
        "for argv in (['--help'], ['simulate', '--help'], ['effects']):\n"
        "    build_parser({_verb_of(argv)})\n"
        "status = main(['simulate', '--manoeuvre', 'zigzag', '--rudder', '20', '--duration',\n"
        "               '100', '--out', sys.argv[1]])\n"
        "from sindyship.measurements import read_csv\n"
        "read_csv(sys.argv[1])  # every check of a record runs\n"
        "refused = [main([verb, sys.argv[1], *bad, '--out', sys.argv[3] + end])\n"
        "           for bad in (['--ship', sys.argv[2]], ['--library', 'no_such_library'])\n"
        "           for verb, end in (('fit', '.json'), ('diagnose', ''), ('discover', '.toml'))]\n"
        "refused += [main([verb, sys.argv[1], '--out', sys.argv[3] + end])\n"
        "            for verb, end in (('diagnose', ''), ('discover', '.toml'))]\n"
        "import shutil\n"
        "two = [sys.argv[1], shutil.copy(sys.argv[1], sys.argv[4])]\n"
        "refused += [main(['diagnose', *two, '--candidates', 'no_such_effect', '--out',\n"
        "                  sys.argv[3]]),\n"
        "            main(['discover', *two, '--effects', 'no_such_effect', '--out',\n"
        "                  sys.argv[3] + '.toml'])]\n"
        "heavy = ('sklearn', 'pysindy', 'sympy', 'scipy.integrate')\n"
        "print(status, refused, sorted(m for m in heavy if m in sys.modules))\n")
    out = subprocess.run([sys.executable, "-c", script, str(tmp_path / "zz.csv"),
                          str(tmp_path / "ship.toml"), str(tmp_path / "m"),
                          str(tmp_path / "zz2.csv")],
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip().split("\n")[-1] == "0 [2, 2, 2, 2, 2, 2, 2, 2, 2, 2] []"
    assert out.stderr.count("ship.toml") == 3  # refused for the ship file
    assert out.stderr.count("no_such_library") == 3  # and for the library
    assert out.stderr.count("needs at least two training records") == 2  # one record
    assert out.stderr.count('no built-in effect named "no_such_effect"') == 2
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith("m")]
    assert (tmp_path / "zz.csv").exists()
    from sindyship.cli import VERBS, build_parser

    everything = build_parser()._subparsers._group_actions[0].choices
    for verb in VERBS:
        alone = build_parser({verb})._subparsers._group_actions[0].choices[verb]
        assert alone.format_help() == everything[verb].format_help()


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    folder = tmp_path_factory.mktemp("records")
    specs = {
        "tc35": ["--manoeuvre", "turning-circle", "--rudder", "35"],
        "tc-35": ["--manoeuvre", "turning-circle", "--rudder", "-35"],
        "zz20": ["--manoeuvre", "zigzag", "--rudder", "20", "--check", "20"],
        "spiral": ["--manoeuvre", "spiral", "--rudder", "35"],
    }
    paths = {}
    for name, spec in specs.items():
        path = folder / f"{name}.csv"
        assert main(["simulate", "--ship", "kcs", *spec, "--duration", "1200",
                     "--out", str(path)]) == 0
        paths[name] = path
    return paths


def test_simulate_writes_the_measurement_csv(records):
    record = read_csv(records["zz20"])
    assert record.n_samples == 1200
    assert list(record.data.columns[:9]) == ["t", "u", "v", "r", "x", "y", "psi", "delta",
                                             "delta_c"]
    assert np.degrees(np.abs(record["delta_c"])).max() == pytest.approx(20.0)


def test_simulate_with_effects_changes_the_record(tmp_path):
    plain, drifted = tmp_path / "a.csv", tmp_path / "b.csv"
    base = ["simulate", "--manoeuvre", "straight", "--duration", "100"]
    assert main([*base, "--out", str(plain)]) == 0
    assert main([*base, "--effect", "current=1", "--effect", "current_dir=90",
                 "--out", str(drifted)]) == 0
    assert read_csv(drifted)["y"][-1] - read_csv(plain)["y"][-1] == pytest.approx(99.0)


def test_fit_then_evaluate_json(records, tmp_path):
    model = tmp_path / "model.json"
    train = [records[k] for k in ("tc35", "tc-35", "zz20", "spiral")]
    # a real process: --json writes one document on stdout and nothing else does
    code, out, err = run_in_subprocess("fit", *train, "--ship", "kcs", "--optimizer", "ls",
                                       "--out", model, "--json")
    assert code == 0, err
    assert json.loads(out)["active_terms"]["Y"] == 22
    saved = json.loads(model.read_text())
    assert saved["optimizer"]["name"] == "ls" and saved["rudder_signal"] == "actual"
    code, out, err = run_in_subprocess("evaluate", model, records["zz20"], records["tc35"],
                                       "--json")
    assert code == 0, err
    errors = json.loads(out)["errors"]
    assert set(errors) == {"zz20", "tc35"}
    assert errors["tc35"]["mean_distance_L"] < 0.05  # a training record flies back closely
    assert errors["zz20"]["diverged_at_s"] is None
    # a turn's figures, flown and recorded: a training record's agree closely
    turn = errors["tc35"]["turn"]
    assert set(turn["flown"]) == {"side", "advance_L", "tactical_diameter_L",
                                  "steady_diameter_L", "speed_loss"}
    assert turn["flown"]["side"] == turn["recorded"]["side"] == "starboard"
    for key, recorded in turn["recorded"].items():
        if key != "side":
            assert turn["flown"][key] == pytest.approx(recorded, abs=0.05), key
    assert 2.5 < turn["recorded"]["tactical_diameter_L"] < 4.0
    # the steady circle is smaller than the tactical diameter (the turn tightens as it slows)
    assert 2.0 < turn["recorded"]["steady_diameter_L"] < turn["recorded"]["tactical_diameter_L"]
    assert "turn" not in errors["zz20"]
    # a zig-zag's overshoots and period, flown and recorded: a training record's agree closely
    zigzag = errors["zz20"]["zigzag"]
    for key, recorded in zigzag["recorded"].items():
        assert zigzag["flown"][key] == pytest.approx(recorded, rel=0.15), key
    assert 5.0 < zigzag["recorded"]["first_overshoot_deg"] < 20.0
    # the text says how and from where each record was flown
    code, out, err = run_sindyship("evaluate", model, records["zz20"])
    assert code == 0, err
    assert out.strip().splitlines()[-2] == (
        f"zz20: mean {errors['zz20']['mean_distance_L']:.4f} L, max "
        f"{errors['zz20']['max_distance_L']:.4f} L (flown closed loop as a 20/20 zig-zag "
        f"from its execute at t = {errors['zz20']['start_s']:.6g} s)")
    assert out.strip().splitlines()[-1].startswith("  zig-zag flown: first overshoot ")


def test_evaluate_writes_its_report_and_a_figure_per_record_to_a_folder(records, tmp_path):
    """--out: evaluate.json (the --json document) and compare-<name>.png of the flight against
    its record; a folder holding anything else is refused before any work, a previous output
    is replaced."""
    from PIL import Image

    model = tmp_path / "model.json"
    assert run_sindyship("fit", records["zz20"], records["tc35"], "--ship", "kcs",
                         "--optimizer", "ls", "--out", model)[0] == 0
    out = tmp_path / "evaluation"
    code, text, err = run_sindyship("evaluate", model, records["zz20"], records["tc35"],
                                    "--out", out)
    assert code == 0, err
    assert f"wrote evaluate.json and 2 figures (compare-<record>.png) to {out}/" in err
    code, document, _ = run_sindyship("evaluate", model, records["zz20"], records["tc35"],
                                      "--json")
    assert json.loads((out / "evaluate.json").read_text()) == json.loads(document)
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "compare-tc35.png", "compare-zz20.png", "evaluate.json"]
    with Image.open(out / "compare-tc35.png") as image:
        assert image.size[0] > 1000 and image.size[1] > 500
    code, _, _ = run_sindyship("evaluate", model, records["zz20"], "--out", out)
    assert code == 0 and not (out / "compare-tc35.png").exists()  # replaced as a whole
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    code, _, err = run_sindyship("evaluate", model, records["zz20"], "--out", other)
    assert code == 2 and "--out" in err and err.count("\n") == 1
    assert (other / "notes.txt").read_text() == "mine"


def test_evaluate_with_a_record_where_the_model_belongs_says_the_model_comes_first(records):
    code, out, err = run_sindyship("evaluate", records["zz20"], records["tc35"])
    assert code == 2 and out == ""
    assert err == (f"sindyship evaluate: error: {records['zz20']} is a record, not a saved "
                   "model; give the model first: sindyship evaluate MODEL.json DATA.csv...\n")


def test_a_model_where_records_belong_and_a_record_where_a_model_belongs_are_named(
        records, tmp_path):
    """fit and diagnose given a saved model, export given a record: the message says which
    file is which, instead of a CSV parser's or a JSON parser's complaint."""
    model = str(tmp_path / "m.json")
    assert run_sindyship("fit", records["zz20"], records["tc35"], "--ship", "kcs",
                         "--refine", "0", "--out", model)[0] == 0
    for verb in (("fit", model, "--ship", "kcs", "--out", str(tmp_path / "q.json")),
                 ("diagnose", records["zz20"], records["tc35"], "--ship", "kcs", "--test",
                  model)):
        code, _, err = run_sindyship(*verb)
        assert code == 2 and err == (f"sindyship {verb[0]}: error: {model} is a saved model "
                                     "(JSON), not a record; give measurement CSV or Parquet "
                                     "files here.\n")
    code, _, err = run_sindyship("export", records["zz20"], "--latex", str(tmp_path / "e.tex"))
    assert code == 2 and f"{records['zz20']} is a record, not a saved model" in err


def test_a_fit_on_one_record_says_what_it_could_not_check(records, tmp_path):
    code, _, err = run_sindyship("fit", records["zz20"], "--ship", "kcs", "--refine", "3",
                                 "--out", str(tmp_path / "one.json"))
    assert code == 0, err
    assert "note: with 1 record the refinement is not checked on records it was not refined on" \
        in err
    assert "note: no identifiability report from one record" in err


def test_evaluate_notes_a_flight_that_starts_far_from_the_design_speed(kcs, capsys):
    """A record of another ship, or at another speed, is flown without complaint; a flight
    starting outside 0.7 to 1.3 U0 of the model's ship gets a note."""
    import pandas as pd

    from sindyship.cli.evaluate import _note_speeds
    from sindyship.trajectory import Trajectory

    frame = pd.DataFrame({"t": [0.0, 1.0, 2.0], "u": kcs.U0 * np.array([0.5, 0.9, 0.9]),
                          "v": 0.0, "r": 0.0, "x": 0.0, "y": 0.0, "psi": 0.0, "delta": 0.0})
    record = Trajectory(frame, "slow")
    _note_speeds([record], {"slow": {"start_s": 0.0}}, kcs)
    assert "note: slow starts at 0.50 times the design speed U0" in capsys.readouterr().err
    _note_speeds([record], {"slow": {"start_s": 1.0}}, kcs)
    assert capsys.readouterr().err == ""


def test_usage_errors_are_one_line_that_names_the_verb():
    code, out, err = run_sindyship("export", "m.json", "--bogus")
    assert (code, out) == (2, "")
    assert err == ("sindyship export: error: unrecognized arguments: --bogus (see sindyship "
                   "export --help)\n")
    code, _, err = run_sindyship("fit", "d.csv", "--optimizer", "foo", "--out", "m.json")
    assert code == 2 and err.startswith("sindyship fit: error: argument --optimizer: invalid "
                                        "choice: 'foo'") and err.count("\n") == 1
    assert "did you mean" not in err  # nothing is close to foo
    # a misspelt option, choice or verb: the close one is named
    _, _, err = run_sindyship("fit", "d.csv", "--out", "m.json", "--optimiser", "prior")
    assert err.endswith("unrecognized arguments: --optimiser prior; did you mean --optimizer? "
                        "(see sindyship fit --help)\n")
    _, _, err = run_sindyship("fit", "d.csv", "--optimizer", "priors", "--out", "m.json")
    assert re.search(r"(did you mean|maybe you meant) '?prior'?\?", err)  # argparse's own
    code, _, err = run_sindyship("fitt", "d.csv")                        # in newer Pythons
    assert code == 2 and re.search(r"(did you mean|maybe you meant) '?fit'?\?", err)
    assert err.count("\n") == 1 and err.endswith("(see sindyship --help)\n")


def test_the_evaluation_report_names_where_a_flight_started_and_a_divergence():
    from sindyship.flight_reports import evaluation_report

    errors = {"tc_35": {"mean_distance_L": 0.25, "max_distance_L": 1.5, "diverged_at_s": None,
                        "flown_as": "replay-commanded", "start_s": 214.2,
                        "start_reason": "a turn with -35 deg rudder, flown from its execute at "
                                        "t = 214.2 s",
                        "turn": {"flown": {"side": "port", "advance_L": 3.012,
                                           "tactical_diameter_L": 3.284, "speed_loss": 0.555},
                                 "recorded": {"side": "port", "advance_L": 3.02,
                                              "tactical_diameter_L": None, "speed_loss": 0.64}}},
              "tc_-35": {"mean_distance_L": 4.0, "max_distance_L": 8.0, "diverged_at_s": None,
                         "flown_as": "replay-actual", "start_s": 3.0,
                         "turn": {"flown": {"side": "port", "advance_L": None,
                                            "tactical_diameter_L": None, "speed_loss": None},
                                  "recorded": {"side": "starboard", "advance_L": 3.1,
                                               "tactical_diameter_L": 3.3,
                                               "speed_loss": 0.6}}},
              "zz_20": {"mean_distance_L": 3.0, "max_distance_L": 9.0, "diverged_at_s": 401.4,
                        "flown_as": "zigzag", "amplitude_deg": 20.0, "check_deg": 20.0,
                        "start_s": 7.04,
                        "zigzag": {"flown": None, "recorded": {"first_overshoot_deg": 5.24,
                                                               "second_overshoot_deg": None,
                                                               "period_s": 98.6}}}}
    assert evaluation_report(errors).splitlines() == [
        "tc_35: mean 0.2500 L, max 1.5000 L (replaying its commanded rudder through the servo "
        "from its execute at t = 214.2 s)",
        "  turn to port flown: advance 3.01 L (recorded 3.02 L), tactical diameter 3.28 L "
        "(recorded n/a), steady diameter n/a (recorded n/a), speed loss 0.56 (recorded 0.64)",
        "tc_-35: mean 4.0000 L, max 8.0000 L (replaying its recorded rudder angle from t = 3 s)",
        "  turn flown to port, recorded to starboard: no figures to compare",
        "zz_20: FAILED: diverged at 401 s; before it mean 3.0000 L, max 9.0000 L (flown closed "
        "loop as a 20/20 zig-zag from its execute at t = 7.04 s)",
        "  zig-zag flown: first overshoot n/a (recorded 5.2 deg), second overshoot n/a (recorded "
        "n/a), period n/a (recorded 99 s)"]


GOOD_HEADER = "t,u,v,r,x,y,psi,delta"
GOOD_ROWS = [f"{k},12.3,0,0,{12.3 * k},0,0,0" for k in range(10)]

BAD_CSVS = {
    "missing column": ("t,u,v,r,x,y,delta\n" + "\n".join(r.rsplit(",", 2)[0] + ",0"
                                                        for r in GOOD_ROWS), "psi"),
    "nan": (GOOD_HEADER + "\n" + "\n".join(GOOD_ROWS[:4] + ["4,nan,0,0,49.2,0,0,0"]
                                           + GOOD_ROWS[5:]), "u"),
    "inf": (GOOD_HEADER + "\n" + "\n".join(GOOD_ROWS[:4] + ["4,12.3,inf,0,49.2,0,0,0"]
                                           + GOOD_ROWS[5:]), "v"),
    "text": (GOOD_HEADER + "\n" + "\n".join(GOOD_ROWS[:4] + ["4,12.3,0,abc,49.2,0,0,0"]
                                            + GOOD_ROWS[5:]), "r"),
    "time not increasing": (GOOD_HEADER + "\n" + "\n".join(GOOD_ROWS[:5] + ["3,12.3,0,0,0,0,0,0"]
                                                           + GOOD_ROWS[6:]), "row"),
    "irregular sampling": (GOOD_HEADER + "\n" + "\n".join(GOOD_ROWS[:5] + ["4.5,12.3,0,0,0,0,0,0"]
                                                          + GOOD_ROWS[5:]), "resample"),
    "degrees in a radian column": (GOOD_HEADER + "\n" + "\n".join(
        r.rsplit(",", 1)[0] + ",35" for r in GOOD_ROWS), "delta"),
    "heading under another name": (GOOD_HEADER.replace("psi", "heading") + "\n"
                                   + "\n".join(GOOD_ROWS),
                                   "(is 'heading' the channel psi? rename the column psi)"),
    "empty": ("", "empty"),
    "one row": (GOOD_HEADER + "\n" + GOOD_ROWS[0], "row"),
    "unknown unit": (GOOD_HEADER.replace("psi", "psi [furlong]") + "\n" + "\n".join(GOOD_ROWS),
                     "psi"),
}


@pytest.mark.parametrize("kind", sorted(BAD_CSVS))
def test_bad_csv_exits_2_with_one_line_naming_file_and_place(tmp_path, kind):
    text, place = BAD_CSVS[kind]
    path = tmp_path / "bad_input.csv"
    path.write_text(text)
    out_model = tmp_path / "model.json"
    code, out, err = run_sindyship("fit", path, "--ship", "kcs", "--out", out_model, "--json")
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert "bad_input.csv" in lines[0]
    assert place.lower() in lines[0].lower()
    assert not out_model.exists()
    assert not list(tmp_path.glob(".model.json*"))


def test_unknown_ship_and_model_errors_exit_2(tmp_path, records):
    code, _, err = run_sindyship("fit", records["tc35"], "--ship", "titanic", "--out",
                                 tmp_path / "m")
    assert code == 2 and "titanic" in err
    bad = tmp_path / "truncated.json"
    bad.write_text('{"format_version": 1, "ship": "kcs", "coeff')
    code, _, err = run_sindyship("evaluate", bad, records["tc35"])
    assert code == 2 and "truncated.json" in err and len(err.strip().splitlines()) == 1
    newer = tmp_path / "newer.json"
    newer.write_text(json.dumps({"format_version": 99, "ship": "kcs"}))
    code, _, err = run_sindyship("evaluate", newer, records["tc35"])
    assert code == 2 and "newer" in err


def test_records_fitted_without_a_ship_are_named_as_the_kcs_in_a_note(tmp_path, records):
    """Records are made non-dimensional with their ship's length and speed, so another ship's
    records fitted as the KCS's fit without an error and fly wrong: a fit given no --ship says
    which ship it took; given one, it says nothing of it."""
    code, _, err = run_sindyship("fit", records["zz20"], records["tc35"], "--optimizer", "ls",
                                 "--out", tmp_path / "m.json")
    assert code == 0, err
    assert "no --ship given: the records are taken as the KCS's (L = 230 m, U0 = 12.35 m/s)" \
        in err
    code, _, err = run_sindyship("fit", records["zz20"], records["tc35"], "--optimizer", "ls",
                                 "--ship", "kcs", "--out", tmp_path / "k.json")
    assert code == 0 and "--ship" not in err, err
    assert json.loads((tmp_path / "m.json").read_text())["ship"] == "kcs"


@pytest.mark.parametrize("option", [["--dt", "0.1"], ["--duration", "600"], ["--rudder", "20"],
                                    ["--first", "port"], ["--check", "10"]])
def test_manoeuvre_options_are_refused_with_the_protocol(tmp_path, option):
    """The protocol's plan fixes its manoeuvres, their length and sampling: an option that
    would not apply is refused before anything is flown (it was silently dropped)."""
    code, _, err = run_sindyship("simulate", "--protocol", *option, "--out", tmp_path / "p")
    assert code == 2 and f"{option[0]} does not apply to --protocol" in err, err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "p").exists()


def test_the_protocol_of_another_ship_is_sampled_in_its_own_time_scale(tmp_path):
    """The KVLCC2 model (L/U0 5.94 s) had flown the KCS's 3200 s at 1 Hz: records its own fit
    called too coarse to resolve the accelerations (0.168 L/U0), and a fit on them flew its
    held-out zig-zag 7.9 L off.  Scaled by L/U0, 3200 samples every 0.319 s."""
    from sindyship.records import read_record
    from sindyship.ships import load_ship
    from sindyship.targets import sampling_steps, under_resolved

    code, _, err = run_sindyship("simulate", "--protocol", "--ship", "kvlcc2", "--out",
                                 tmp_path / "p")
    assert code == 0, err
    assert "sampled every 0.319 s" in err
    ship = load_ship("kvlcc2")
    paths = sorted((tmp_path / "p").rglob("*.csv"))
    assert len(paths) == 11
    assert {len(path.read_text().splitlines()) for path in paths} == {3201}  # and a header
    records = [read_record(path, ship=ship)[0] for path in paths]
    steps = sampling_steps(records, ship)
    assert max(steps.values()) == pytest.approx(0.319 / ship.time_scale)
    assert under_resolved(steps, ship) == ""
    code, _, err = run_sindyship("simulate", "--protocol", "--out", tmp_path / "kcs")
    assert code == 0 and "sampled every" not in err, err  # the KCS's plan as the paper's
    kcs = (tmp_path / "kcs" / "test" / "zz10_10.csv").read_text().splitlines()
    assert len(kcs) == 3201 and kcs[2].startswith("1.0,")


def test_reproduce_json_contract(tmp_path):
    code, out, err = run_sindyship("reproduce", "--out", tmp_path / "rep", "--json")
    assert code == 0, err
    doc = json.loads(out)
    methods = [r["method"] for r in doc["results"]]
    assert methods[:4] == ["ls", "stlsq", "lasso", "svr"]
    for result in doc["results"]:
        assert set(result["errors"]) >= {"tc15_port", "tc15_stbd", "zz10_10"}
        for err_row in result["errors"].values():
            assert set(err_row) >= {"mean_distance_L", "max_distance_L", "diverged_at_s"}
    agreement = doc["paper_ls_agreement"]
    assert agreement["median_rel_dev"] < 0.15 and agreement["sign_agreement"] >= 0.95
    # the physics-consistent fit runs on the library with v r, and the report says so
    prior = next(r for r in doc["results"] if r["method"] == "prior")
    assert prior["library"] == "abkowitz-vr"
    from sindyship.flight_reports import reproduce_report

    assert "prior on abkowitz-vr " in reproduce_report(doc)
    # the default fit (the prior) with the first diagnosed effect, refined by its training
    # flights, is the last row
    refined = doc["results"][-1]
    first_added = doc["diagnosis"]["rounds"][0]["added"]
    assert refined["refined"] is True and refined["method"] == "prior"
    assert refined["effects"] == [first_added] and refined["library"].startswith("abkowitz-vr")
    assert refined["refinement"]["records"] == ["straight", "tc35_stbd", "tc35_port", "zz35_10",
                                                "zz20_20", "zz15_15", "spiral_stbd",
                                                "spiral_port"]
    assert ", refined " in reproduce_report(doc)
    # the README's refined row is what reproduce flies (docs/readme-numbers.json, made by
    # scripts/make_readme.py); the refinement's path may round differently on another machine
    readme = json.loads((Path(__file__).resolve().parents[1] / "docs" / "readme-numbers.json")
                        .read_text(encoding="utf-8"))
    (saved,) = [r for r in readme["table10"] if r.get("refined")]
    for name, error in refined["errors"].items():
        assert error["completed"], name
        assert error["mean_distance_L"] == pytest.approx(saved["errors"][name]["mean_distance_L"],
                                                         rel=1e-3), name
    assert (tmp_path / "rep" / f"model-prior+{first_added}+refined.json").exists()
    assert (tmp_path / "rep" / "results.json").exists()
    assert (tmp_path / "rep" / "trajectory-zz10_10.png").exists()
    # every generated simulator has a name import takes (the refined row's had '+' in it)
    import importlib.util

    simulators = sorted((tmp_path / "rep").glob("simulator*.py"))
    assert len(simulators) == len(doc["results"])
    name = f"simulator_prior_{first_added}_refined"
    assert all(path.stem.isidentifier() for path in simulators)
    spec = importlib.util.spec_from_file_location(name, tmp_path / "rep" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.zigzag(np.arange(0.0, 60.0), 10, 10).diverged_at is None


def test_fit_with_smoothing_records_the_setting(records, tmp_path, capsys):
    model = tmp_path / "smoothed.json"
    train = [records[k] for k in ("tc35", "tc-35", "zz20", "spiral")]
    assert main(["fit", *map(str, train), "--ship", "kcs", "--smoothing", "savgol:21",
                 "--refine", "0", "--out", str(model)]) == 0
    info = json.loads(model.read_text())["info"]
    assert info["smoothing"] == {"method": "savgol", "window_s": 21.0, "order": 3}
    # said in words, not as the Python dictionary it is saved as
    assert "smoothing the records before differencing: savgol 21 s\n" in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:  # refused as the command line is read
        main(["fit", str(train[0]), "--ship", "kcs", "--smoothing", "bogus:x", "--out",
              str(tmp_path / "x.json")])
    assert stop.value.code == 2


def test_fit_default_library_follows_the_speed_form(records, tmp_path, capsys):
    """The recommended fit adds cross-flow drag in the instantaneous speed form only; a
    --library given is kept in either form."""
    train = [str(records[k]) for k in ("tc35", "zz20")]
    libraries = {}
    for label, options in (("instantaneous", ["--speed", "instantaneous"]),
                           ("design", ["--speed", "design"]),
                           ("given", ["--speed", "instantaneous", "--library", "abkowitz-vr"])):
        model = tmp_path / f"{label}.json"
        assert main(["fit", *train, "--ship", "kcs", *options, "--refine", "0",
                     "--no-identifiability", "--out", str(model), "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        saved = json.loads(model.read_text())
        assert saved["library"]["name"] == out["library"]
        libraries[label] = (out["library"], out["speed"])
    assert libraries == {"instantaneous": ("abkowitz-vr-crossflow", "instantaneous"),
                         "design": ("abkowitz-vr", "design"),
                         "given": ("abkowitz-vr", "instantaneous")}
    saved = json.loads((tmp_path / "instantaneous.json").read_text())
    crossflow = {"abs(v) v", "abs(r) r", "abs(v) r", "v abs(r)"}
    assert crossflow <= set(saved["coefficients"]["N"]) and crossflow <= set(
        saved["coefficients"]["Y"])
    design = json.loads((tmp_path / "design.json").read_text())
    assert not crossflow & set(design["coefficients"]["N"])


def test_fit_refine_flies_the_records_and_says_what_it_did(records, tmp_path, capsys):
    model = tmp_path / "refined.json"
    train = [str(records[k]) for k in ("tc35", "zz20")]
    assert main(["fit", *train, "--ship", "kcs", "--refine", "8", "--no-identifiability",
                 "--out", str(model), "--json"]) == 0
    out, err = capsys.readouterr()
    saved = json.loads(model.read_text())
    refined = saved["info"]["refined"]
    assert saved["optimizer"]["name"] == "prior" and saved["library"]["name"] == "abkowitz-vr"
    assert refined["records"] == ["tc35", "zz20"] and refined["method"] == "multiple shooting"
    assert refined["jacobians"] >= 1 and refined["evaluations"] <= 8
    assert refined["flight_rms_after"] < refined["flight_rms_before"]
    assert json.loads(out)["refined"]["cost_after"] == pytest.approx(refined["cost_after"])
    assert "refined: flight error" in err
    assert re.search(r"refining by flights \([\d.]+ s segments\): step 1,", err)
    # the paper's least squares is one option away, and not refined unless asked
    assert main(["fit", *train, "--ship", "kcs", "--optimizer", "ls", "--no-identifiability",
                 "--out", str(tmp_path / "ls.json")]) == 0
    assert "refined" not in json.loads((tmp_path / "ls.json").read_text())["info"]
    assert main(["fit", *train, "--ship", "kcs", "--optimizer", "ls", "--segment", "100",
                 "--out", str(tmp_path / "x.json")]) == 2
    assert "--segment sets the refinement, which is off" in capsys.readouterr().err


def test_diagnose_rounds_log_a_line_each_where_no_bar_is_drawn(records, capsys):
    """Written to a log (stderr no terminal), diagnose --rounds had printed its first line and
    then nothing for minutes; each round now ends with its summary line and the time."""
    import re

    paths = [str(records[name]) for name in ("tc35", "tc-35", "zz20")]
    assert main(["diagnose", *paths, "--rounds", "3", "--threshold", "0.95", "--confirm",
                 "0"]) == 0
    captured = capsys.readouterr()
    logged = [line for line in captured.err.splitlines() if line.startswith("Round ")]
    assert len(logged) == 1 and re.fullmatch(r"Round 1: library abkowitz: .+ \(\d+ s\)",
                                              logged[0])
    assert logged[0].rsplit(" (", 1)[0] in captured.out  # the report's own line


def test_a_single_diagnosis_logs_each_long_step_where_no_bar_is_drawn(records, capsys):
    """Written to a log, a diagnosis without --rounds had printed its header and then nothing
    until its report; each long step now writes what ended and the seconds so far."""
    import re

    paths = [str(records[name]) for name in ("tc35", "tc-35", "zz20")]
    assert main(["diagnose", *paths, "--confirm", "1"]) == 0
    err = capsys.readouterr().err.splitlines()
    steps = [line for line in err if re.fullmatch(r".+ \(\d+ s\)", line)]
    assert steps[0].startswith("fitted abkowitz and scored ")
    assert steps[1].startswith("flew the model on 3 records ")
    assert steps[2].startswith("re-flew the model with ")
    seconds = [int(re.search(r"\((\d+) s\)$", line).group(1)) for line in steps]
    assert seconds == sorted(seconds)


def test_fit_says_when_n_jobs_is_not_used(records, tmp_path, capsys):
    """--n-jobs sets the workers of --smoothing auto and --stream; elsewhere it had been
    ignored without a word (the refinement flies on numba's threads already)."""
    train = [str(records[k]) for k in ("tc35", "zz20")]
    for given, said in ((["--n-jobs", "-1"], True), ([], False)):
        assert main(["fit", *train, "--ship", "kcs", "--refine", "0", "--no-identifiability",
                     *given, "--out", str(tmp_path / "m.json")]) == 0
        err = " ".join(capsys.readouterr().err.split())
        assert ("note: --n-jobs -1 is not used: it sets the workers of --smoothing auto and "
                "--stream" in err) is said


def test_the_in_process_runner_shows_what_a_fresh_process_would(monkeypatch):
    """The tests' in-process runner: warnings on stderr where they are raised (a library's
    DeprecationWarning hidden, as Python hides it), exit status of SystemExit as a process's."""
    import warnings

    import sindyship.cli

    def warns(argv):
        print("before", file=sys.stderr)
        warnings.warn("shown", UserWarning, stacklevel=1)
        warnings.warn("hidden", DeprecationWarning, stacklevel=1)
        print("after", file=sys.stderr)
        return 0

    monkeypatch.setattr(sindyship.cli, "main", warns)
    code, out, err = run_sindyship("fit")
    assert code == 0 and out == ""
    lines = err.splitlines()
    assert lines[0] == "before" and "UserWarning: shown" in lines[1] and lines[-1] == "after"
    assert "hidden" not in err
    for status, expected in ((None, 0), ("refused", 1), (2, 2)):
        def stops(argv, status=status):
            raise SystemExit(status)

        monkeypatch.setattr(sindyship.cli, "main", stops)
        code, _, err = run_sindyship("fit")
        assert code == expected and (status != "refused" or err == "refused\n")


def test_fit_flies_its_training_records_and_names_those_it_misses(tmp_path, records):
    """A fit can match every force within a few per cent and still not fly the records it
    was fitted on: least squares on the paper's library diverges in both 35 deg turns it was
    fitted on, beside a straight run and a zig-zag.  fit flies the saved model like each
    training record (as evaluate flies it), prints the distances and names those records."""
    straight = tmp_path / "straight.csv"
    assert main(["simulate", "--ship", "kcs", "--manoeuvre", "straight", "--duration", "1200",
                 "--out", str(straight)]) == 0
    data = [records["tc35"], records["tc-35"], records["zz20"], straight]
    model = tmp_path / "m.json"
    code, out, err = run_sindyship("fit", *data, "--ship", "kcs", "--optimizer", "ls",
                                   "--out", model, "--json")
    assert code == 0, err
    flights = json.loads(out)["training_flights"]
    assert flights["tc35"]["diverged_at_s"] is not None
    assert flights["tc-35"]["diverged_at_s"] is not None
    assert flights["zz20"]["diverged_at_s"] is None
    assert flights["zz20"]["mean_distance_L"] < 0.5
    assert "training flights (mean distance [L], flown as sindyship evaluate flies them): " \
        f"tc35 diverged at {flights['tc35']['diverged_at_s']:g} s" in err
    assert ("note: the model diverges on, or flies more than 1 L off, records it was fitted "
            f"on: tc35 (diverged at {flights['tc35']['diverged_at_s']:g} s), tc-35 (diverged "
            f"at {flights['tc-35']['diverged_at_s']:g} s); physics the library lacks") in err
    code, out, err = run_sindyship("evaluate", model, *data, "--json")
    assert code == 0, err
    evaluated = json.loads(out)["errors"]
    for name, flight in flights.items():
        assert flight["mean_distance_L"] == pytest.approx(
            evaluated[name]["mean_distance_L"], rel=1e-9, nan_ok=True)
    code, _, err = run_sindyship("fit", *data, "--ship", "kcs", "--out", tmp_path / "p.json")
    assert code == 0 and "note: the model diverges on" not in err, err  # the prior flies them


def test_a_refinement_refused_for_a_lost_hard_over_turn_names_the_way_out(tmp_path,
                                                                          protocol_runs):
    """Refined by the flights of the three KCS zig-zags alone, the default fit loses the
    hard-over turn to starboard (its symmetric library cannot hold the KCS's asymmetric
    rudder inflow, so the flights pull other terms) and the refinement is refused; the note
    names the ways out, and one of them, the effect diagnose ranks first on the same records,
    makes the refinement kept."""
    from sindyship.measurements import write_csv

    zigzags = [write_csv(run, tmp_path / f"{run.name}.csv") for run in protocol_runs["train"]
               if run.name.startswith("zz")]
    assert len(zigzags) == 3
    code, out, err = run_sindyship("diagnose", *zigzags, "--ship", "kcs", "--json")
    assert code == 0, err
    first = json.loads(out)["ranking"][0]["effect"]
    assert first == "asymmetry"
    code, _, err = run_sindyship("fit", *zigzags, "--ship", "kcs", "--out", tmp_path / "m.json")
    assert code == 0, err
    assert ("not refined: the refined model diverges in a hard-over turn to starboard, which "
            "the fit it started from flies") in err
    assert "fit with the effect sindyship diagnose names on the same records" in err
    code, _, err = run_sindyship("fit", *zigzags, "--ship", "kcs", "--effects", first,
                                 "--out", tmp_path / "a.json")
    assert code == 0, err
    assert "refined: flight error" in err and "not refined:" not in err


def test_an_unstable_refined_prior_fit_is_not_told_to_refine_a_prior_fit(monkeypatch, capsys):
    """A prior fit that its prior could not make stable in straight running (a course-unstable
    ship) and whose refinement is kept: the warning says it started unstable, and does not
    send the user to the prior fit it already is."""
    import importlib
    from types import SimpleNamespace

    from sindyship.cli.fit import _refined

    done = {"refused_unstable": False, "refused_validation": False, "refused_turning": None,
            "cost_before": 1.0, "cost_after": 0.5, "flight_rms_before": 0.2,
            "flight_rms_after": 0.1, "evaluations": 9, "jacobians": 8, "converged": True,
            "stopped": "the cost stopped falling", "straight_run_stable": False,
            "largest_change": {"coefficient": "N[r]", "relative": 0.1},
            "force_change": {"X": 0.01, "Y": 0.02, "N": 0.03}, "validation": {}}
    args = SimpleNamespace(refine=10, segment=None, refine_weight=None)
    refining = importlib.import_module("sindyship.refine")
    for info, says in (({"refined": done, "straight_run": {"stable": False}}, "as the prior fit"),
                       ({"refined": done}, "refine a --optimizer prior fit")):
        monkeypatch.setattr(refining, "refine", lambda *a, info=info, **k: SimpleNamespace(
            info=info))
        _refined(None, [], args)
        warning = capsys.readouterr().err.splitlines()[-1]
        assert warning.startswith("warning: the refined model is unstable") and says in warning

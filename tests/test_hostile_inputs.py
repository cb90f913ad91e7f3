"""A corpus of hostile or mistaken command lines, as data, over every verb.

Each case names the command line, the files to lay out in a fresh folder (the command runs
there), the exit status it must end with and a fragment of its message.  Every case checks:
the exit status; for a refusal, exactly one line on stderr (no traceback) holding the fragment
and nothing on stdout; every input byte-identical afterwards (links still links, pipes still
pipes); no file left behind but the named outputs; no child process left running.  Cases
that could hang or eat memory if refused late (pipes, devices, servo constants that shrink
the integration step) run in a subprocess with a 20 s timeout; the others run ``main()`` in
this process.

File specs: text is written as is; ``@csv`` is a valid 120 s zig-zag record, ``@model`` a model
fitted on it, ``@ship:SECTION.KEY=VALUE`` the KCS ship file with one value edited; ``fifo:``,
``sock:`` and ``dir:`` make a named pipe, a socket or a folder; ``link:T`` a symbolic link to
T, ``hard:T`` a hard link to T.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from cli_in_process import run_sindyship

import sindyship
from sindyship.cli import main

ROOT = Path(__file__).resolve().parents[1]
KCS_TOML = (Path(sindyship.__file__).parent / "ships" / "kcs.toml").read_text()
AS_ROOT = hasattr(os, "geteuid") and os.geteuid() == 0
CASE_TIMEOUT = 20.0

HEADER = "t,u,v,r,x,y,psi,delta"
ROWS = [f"{k},12.3,0,0,{12.3 * k:.1f},0,0,0" for k in range(10)]
GOOD_SMALL = HEADER + "\n" + "\n".join(ROWS) + "\n"


def ship_edit(section: str, key: str, value: str) -> str:
    """``@ship:`` spec: the KCS file with [section] key set to value."""
    return f"@ship:{section}.{key}={value}"


# ---------------------------------------------------------------------------------------------
# the corpus
# ---------------------------------------------------------------------------------------------
def case(group, argv, code=2, message="", files=None, *, sub=False, outputs=(), xfail=None,
         skip_root=False):
    return {"group": group, "argv": argv, "code": code, "message": message,
            "files": files or {}, "sub": sub, "outputs": tuple(outputs), "xfail": xfail,
            "skip_root": skip_root}


SIM = ["simulate", "--manoeuvre", "turning-circle", "--duration", "60"]
FIT = ["fit", "data.csv"]
DATA = {"data.csv": "@csv"}
MODEL = {"model.json": "@model", "data.csv": "@csv"}
DIAG = ["diagnose", "data.csv", "other.csv"]
DIAG_FILES = {"data.csv": "@csv", "other.csv": "@csv"}
CAPTIVE = ["captive", "--test", "rudder", "--points", "3", "--out"]
FORCES = ["forces", "model.json", "captive.csv"]
FORCES_FILES = {**MODEL, "captive.csv": "u,v,r,delta,X,Y,N\n12.3,0,0,0.1,-1e4,2e5,-3e7\n"
                "12.3,0,0,-0.1,-1e4,-2e5,3e7\n12.3,0,0,0,0,0,0\n"}

# Output targets that are not a plain new file: (files, target, fragment).
BAD_FILE_TARGETS = [
    ({"real.txt": "keep me\n", "out": "link:real.txt"}, "out", "symbolic link"),
    ({"out": "link:nowhere.txt"}, "out", "symbolic link"),
    ({"out": "fifo:"}, "out", "FIFO"),
    ({"out": "sock:"}, "out", "socket"),
    ({}, "/dev/null", "device"),
    ({}, "/dev/full", "device"),
    ({"out": "dir:"}, "out", "is a folder"),
    ({}, ".", "is a folder"),
    ({}, "out.csv/", "ends with '/'"),
    ({"plain.txt": "a file\n"}, "plain.txt/out.csv", "not a folder"),
    ({}, "/sys/sindyship-out.csv", "cannot write"),
    ({}, "", "empty"),
]


def _output_cases() -> list[dict]:
    cases = []
    verbs = {
        "simulate": (SIM + ["--out"], {}),
        "fit": (FIT + ["--out"], DATA),
        "export --latex": (["export", "model.json", "--latex"], MODEL),
        "export --python": (["export", "model.json", "--python"], MODEL),
        "captive": (CAPTIVE, {}),
        "discover": (["discover", "data.csv", "other.csv", "--out"], DIAG_FILES),
    }
    for verb, (argv, base) in verbs.items():
        for files, target, fragment in BAD_FILE_TARGETS:
            cases.append(case(f"output target: {verb}", argv + [target], 2, fragment,
                              {**base, **files}))
    # the output is one of the inputs: the file itself, a hard link, a symbolic link
    same = [
        (FIT + ["--out", "data.csv"], DATA, "also an input"),
        (FIT + ["--out", "twin.csv"], {**DATA, "twin.csv": "hard:data.csv"}, "also an input"),
        (FIT + ["--out", "ship.toml", "--ship", "ship.toml"],
         {**DATA, "ship.toml": ship_edit("servo", "T_R", "1.0")}, "also an input"),
        (FIT + ["--out", "lib.toml", "--library", "lib.toml"],
         {**DATA, "lib.toml": (ROOT / "libraries" / "abkowitz.toml").read_text()},
         "also an input"),
        (FIT + ["--out", "./data.csv"], DATA, "also an input"),
        (["simulate", "--manoeuvre", "straight", "--ship", "ship.toml", "--out", "ship.toml"],
         {"ship.toml": ship_edit("servo", "T_R", "1.0")}, "also an input"),
        (["export", "model.json", "--latex", "model.json"], MODEL, "also an input"),
        (["export", "model.json", "--python", "model.json"], MODEL, "also an input"),
        (["export", "model.json", "--python", "alias.json"],
         {**MODEL, "alias.json": "hard:model.json"}, "also an input"),
        (["export", "model.json", "--latex", "same.tex", "--python", "same.tex"], MODEL,
         "two different files"),
        (["captive", "--ship", "ship.toml", "--out", "ship.toml"],
         {"ship.toml": ship_edit("servo", "T_R", "1.0")}, "also an input"),
        (["discover", "data.csv", "other.csv", "--out", "other.csv"], DIAG_FILES,
         "also an input"),
        (FORCES + ["--out", "captive.csv"], FORCES_FILES, "is a file"),
        (FORCES + ["--out", "."], FORCES_FILES, "holds the input"),
    ]
    cases += [case("output is an input", argv, 2, fragment, files)
                  for argv, files, fragment in same]
    # an output named as another kind of file: a user's table is not overwritten with code
    other_kind = [
        (FIT + ["--out", "other.csv"], {**DATA, "other.csv": "@csv"}, "ends in .csv"),
        (["export", "model.json", "--python", "data.csv"], MODEL, "ends in .csv"),
        (["export", "model.json", "--latex", "notes.py"], {**MODEL, "notes.py": "x = 1\n"},
         "ends in .py"),
        (SIM + ["--out", "model.json"], MODEL, "ends in .json"),
        (CAPTIVE + ["model.json"], MODEL, "ends in .json"),
        (["discover", "data.csv", "other.csv", "--out", "lib.py"], DIAG_FILES, "ends in .py"),
    ]
    cases += [case("output of another kind", argv, 2, fragment, files)
              for argv, files, fragment in other_kind]
    # folder outputs
    folders = [
        ({"out": "link:real", "real": "dir:"}, "out", "symbolic link"),
        ({"out": "x\n"}, "out", "is a file"),
        ({"out": "fifo:"}, "out", "FIFO"),
        ({}, "/dev/null", "device"),
        ({}, ".", "current folder"),
        ({"plain.txt": "a file\n"}, "plain.txt/sub", "not a folder"),
        ({}, "/sys/sindyship-out", "cannot write"),
        ({"keep/notes.txt": "mine\n"}, "keep", "holds other files"),
        ({}, "", "empty"),
    ]
    for files, target, fragment in folders:
        cases.append(case("output folder: reproduce", ["reproduce", "--out", target], 2,
                          fragment, files))
        if target != ".":  # holds the inputs first: the cases above and below
            cases.append(case("output folder: diagnose", DIAG + ["--out", target], 2,
                              fragment, {**DIAG_FILES, **files}))
            cases.append(case("output folder: forces", FORCES + ["--out", target], 2,
                              fragment, {**FORCES_FILES, **files}))
    cases.append(case("output folder: diagnose", ["diagnose", "d/data.csv", "d/other.csv",
                                                   "--out", "d"], 2, "holds the input",
                      {"d/data.csv": "@csv", "d/other.csv": "@csv"}))
    cases.append(case("output folder: diagnose", DIAG + ["--out", "."], 2, "holds the input",
                      DIAG_FILES))
    cases.append(case("output target: unwritable folder", FIT + ["--out", "ro/m.json"], 2,
                      "cannot write", {**DATA, "ro": "dir:0555"}, skip_root=True))
    cases.append(case("output target: unwritable folder", ["reproduce", "--out", "ro/out"],
                      2, "cannot write", {"ro": "dir:0555"}, skip_root=True))
    return cases


def _number_cases() -> list[dict]:
    simulate = {
        "--duration": ["inf", "nan", "0", "-1", "1e9", "abc", "-inf"],
        "--dt": ["inf", "nan", "0", "-1", "1e-9", "1e9"],
        "--rudder": ["inf", "nan", "0", "90", "1e9", "-1e9", "46", "-inf"],
        "--check": ["inf", "nan", "0", "90", "-50"],
        "--seed": ["-1", "1.5", "1e30", "abc"],
    }
    cases = []
    for option, values in simulate.items():
        for value in values:
            cases.append(case(f"number: simulate {option}", SIM + [option, value, "--out",
                                                                     "o.csv"], 2, option))
    cases += [
        case("number: simulate cross-checks", ["simulate", "--manoeuvre", "straight",
             "--duration", "1e6", "--dt", "0.001", "--out", "o.csv"], 2, "samples"),
        case("number: simulate cross-checks", ["simulate", "--manoeuvre", "turning-circle",
             "--rudder", "40", "--out", "o.csv"], 2, "rudder limit"),
        case("number: simulate cross-checks", ["simulate", "--manoeuvre", "zigzag",
             "--rudder", "20", "--check", "-20", "--out", "o.csv"], 2, "check"),
        case("number: simulate cross-checks", ["simulate", "--manoeuvre", "straight",
             "--duration", "0.5", "--out", "o.csv"], 2, "two samples"),
    ]
    effects = ["load=1e30", "load=inf", "load=nan", "current=1e9", "noise=-1", "noise=5",
               "quantise=-1", "quantise=2.5", "crossflow=-1", "rudder_offset=90", "bogus=1",
               "load", "load=abc", "seed=-1", "load_arm=1e9", "current_dir=1e9"]
    cases += [case("number: simulate --effect", SIM + ["--effect", e, "--out", "o.csv"], 2,
                   "effect") for e in effects]
    fit = {
        "--window": ["0", "-1", "inf", "nan", "1e9"],
        "--resample": ["0", "-1", "1e-9", "inf", "nan"],
        "--n-jobs": ["0", "-2", "-10000", "abc"],
        "--seed": ["-1", "nan"],
    }
    for option, values in fit.items():
        for value in values:
            cases.append(case(f"number: fit {option}", FIT + [option, value, "--out", "m.json"],
                              2, option, DATA))
    diagnose = {
        "--threshold": ["0", "1", "-0.5", "2", "nan", "inf"],
        "--rounds": ["0", "-1", "1e9", "1.5"],
        "--confirm": ["-1", "1000000"],
        "--n-jobs": ["0", "-2"],
        "--window": ["inf"],
        "--resample": ["0"],
    }
    for option, values in diagnose.items():
        for value in values:
            cases.append(case(f"number: diagnose {option}", DIAG + [option, value], 2, option,
                              DIAG_FILES))
    cases += [case("number: evaluate --resample", ["evaluate", "model.json", "data.csv",
                                                   "--resample", v], 2, "--resample", MODEL)
              for v in ("0", "1e-9", "nan")]
    cases += [case("number: export --precision", ["export", "model.json", "--precision", v],
                   2, "--precision", MODEL) for v in ("0", "-1", "18", "1e9", "abc")]
    # accepted: more workers than cores is capped with a notice, not refused
    cases.append(case("number: accepted", FIT + ["--n-jobs", "10000", "--out", "m.json"], 0,
                      "using", DATA, outputs=["m.json"]))
    return cases


def _ship_cases() -> list[dict]:
    edits = [
        ("servo", "T_R", "0"), ("servo", "T_R", "-1"), ("servo", "T_R", "1e-7"),
        ("servo", "T_R", "1e9"), ("servo", "T_R", "nan"), ("servo", "rate_max", "0"),
        ("servo", "rate_max", "-5"), ("servo", "rate_max", "1e-9"),
        ("servo", "delta_max", "0"), ("servo", "delta_max", "90"),
        ("servo", "delta_max", "180"), ("servo", "delta_max", "-35"),
        ("particulars", "U0", "0"), ("particulars", "U0", "1e9"),
        ("particulars", "L", "1e-9"), ("particulars", "L", "1e9"),
        ("particulars", "rho", "1"), ("particulars", "U0", "49"),
    ]
    cases = []
    for section, key, value in edits:
        files = {"ship.toml": ship_edit(section, key, value)}
        cases.append(case("ship file: simulate", ["simulate", "--manoeuvre", "zigzag",
                          "--rudder", "20", "--check", "20", "--ship", "ship.toml", "--out",
                          "o.csv"], 2, key if key != "U0" or value != "49" else "Froude",
                          files, sub=section == "servo" and key == "T_R"))
    for section, key, value in edits[:3]:
        files = {**DATA, "ship.toml": ship_edit(section, key, value)}
        cases.append(case("ship file: fit", FIT + ["--ship", "ship.toml", "--out", "m.json"],
                          2, "T_R", files, sub=True))
        cases.append(case("ship file: evaluate", ["evaluate", "model.json", "data.csv",
                          "--ship", "ship.toml"], 2, "T_R", {**MODEL, **files}, sub=True))
        cases.append(case("ship file: diagnose", DIAG + ["--ship", "ship.toml"], 2, "T_R",
                          {**DIAG_FILES, **files}, sub=True))
    cases.append(case("ship file: export", ["export", "model.json", "--ship", "ship.toml"], 2,
                      "T_R", {**MODEL, "ship.toml": ship_edit("servo", "T_R", "0")}, sub=True))
    return cases


BAD_CSVS = {
    "decimal commas": ("t;u;v;r;x;y;psi;delta\n" + "\n".join(
        f"{k};12,3;0;0;{k * 12},3;0;0;0" for k in range(10)) + "\n", "column"),
    "text in numbers": (HEADER + "\n" + "\n".join(ROWS[:4] + ["4,fast,0,0,49.2,0,0,0"]
                                                  + ROWS[5:]) + "\n", "u"),
    "empty": ("", "empty"),
    "header only": (HEADER + "\n", "row"),
    "one row": (HEADER + "\n" + ROWS[0] + "\n", "row"),
    "binary junk": ("\x00\x01\x02\xff" * 40, "data.csv"),
    "nan": (HEADER + "\n" + "\n".join(ROWS[:4] + ["4,nan,0,0,49.2,0,0,0"] + ROWS[5:]) + "\n",
            "u"),
    "degrees as radians": (HEADER + "\n" + "\n".join(r.rsplit(",", 1)[0] + ",35" for r in ROWS)
                           + "\n", "delta"),
    "time goes back": (HEADER + "\n" + "\n".join(ROWS[:5] + ["3,12.3,0,0,0,0,0,0"] + ROWS[6:])
                       + "\n", "time"),
}


def _input_cases() -> list[dict]:
    cases = []
    for kind, (text, fragment) in BAD_CSVS.items():
        files = {"data.csv": text, "good.csv": GOOD_SMALL}
        cases.append(case(f"bad CSV: fit ({kind})", ["fit", "data.csv", "--out", "m.json"],
                          2, fragment, files))
        cases.append(case(f"bad CSV: evaluate ({kind})", ["evaluate", "model.json",
                          "data.csv"], 2, fragment, {**files, "model.json": "@model"}))
    cases.append(case("bad CSV: diagnose", ["diagnose", "good.csv", "data.csv"], 2, "empty",
                      {"good.csv": "@csv", "data.csv": ""}))
    cases.append(case("bad CSV: diagnose", ["diagnose", "good.csv", "--test", "data.csv"], 2,
                      "data.csv", {"good.csv": "@csv", "data.csv": BAD_CSVS["text in numbers"][0]}))
    special = [
        ({"data.csv": "fifo:"}, "FIFO"),
        ({"data.csv": "link:/dev/zero"}, "device"),
        ({"data.csv": "sock:"}, "socket"),
        ({"data.csv": "dir:"}, "folder"),
        ({}, "not found"),
    ]
    for files, fragment in special:
        cases.append(case("special input: fit", ["fit", "data.csv", "--out", "m.json"], 2,
                          fragment, files, sub=fragment in ("FIFO", "device")))
        cases.append(case("special input: evaluate", ["evaluate", "model.json", "data.csv"], 2,
                          fragment, {**files, "model.json": "@model"},
                          sub=fragment in ("FIFO", "device")))
    for name, spec, fragment in [("model.json", "fifo:", "FIFO"),
                                 ("model.json", "link:/dev/zero", "device")]:
        cases.append(case("special input: evaluate", ["evaluate", name, "data.csv"], 2,
                          fragment, {name: spec, "data.csv": "@csv"}, sub=True))
        cases.append(case("special input: export", ["export", name], 2, fragment, {name: spec},
                          sub=True))
    cases.append(case("special input: simulate", ["simulate", "--manoeuvre", "straight",
                      "--ship", "ship.toml", "--out", "o.csv"], 2, "ship", {"ship.toml": "fifo:"},
                      sub=True))
    cases.append(case("special input: diagnose", ["diagnose", "data.csv", "--test", "t.csv"],
                      2, "FIFO", {"data.csv": "@csv", "t.csv": "fifo:"}, sub=True))
    # the same record given twice
    twice = [
        (["fit", "data.csv", "data.csv", "--out", "m.json"], DATA),
        (["fit", "data.csv", "./data.csv", "--out", "m.json"], DATA),
        (["fit", "data.csv", "alias.csv", "--out", "m.json"], {**DATA, "alias.csv":
                                                               "link:data.csv"}),
        (["evaluate", "model.json", "data.csv", "data.csv"], MODEL),
        (["evaluate", "model.json", "data.csv", "twin.csv"], {**MODEL, "twin.csv":
                                                              "hard:data.csv"}),
        (["diagnose", "data.csv", "data.csv"], DATA),
        (["diagnose", "data.csv", "other.csv", "--test", "data.csv"], DIAG_FILES),
    ]
    cases += [case("duplicated inputs", argv, 2, "twice", files) for argv, files in twice]
    return cases


def _model_cases() -> list[dict]:
    models = [
        ("truncated", '{"format_version": 1, "ship": "kcs", "coeff', "model.json", None),
        ("empty", "", "model.json", None),
        ("not JSON", "coefficients: 1\n", "model.json", None),
        ("a list", "[1, 2, 3]\n", "model.json", None),
        ("deeply nested", '{"a": ' * 100_000 + "1" + "}" * 100_000, "model.json", None),
        ("duplicated keys", "@model:dupkeys", "model.json", None),
        ("1e30 coefficient", "@model:huge", "model.json", None),
        ("format_version 0", "@model:version=0", "format", None),
        ("format_version -1", "@model:version=-1", "format", None),
        ("format_version text", '@model:version="1"', "format", None),
        ("NaN coefficient", "@model:nan", "model.json", None),
        ("a folder", "dir:", "model.json", None),
    ]
    cases = []
    for kind, spec, fragment, xfail in models:
        files = {"model.json": spec, "data.csv": "@csv"}
        cases.append(case(f"bad model: evaluate ({kind})", ["evaluate", "model.json",
                          "data.csv"], 2, fragment, files, xfail=xfail))
        cases.append(case(f"bad model: export ({kind})", ["export", "model.json"], 2, fragment,
                          files, xfail=xfail))
    return cases


HUGE = "1" * 5000  # an integer no float holds
#: Ship values outside any physical range: (section, key, value).
SHIP_RANGES = [
    ("particulars", "x_G", "-3.404\nscale = 0"), ("particulars", "x_G", "-3.404\nscale = -1"),
    ("particulars", "B", "1e300"), ("particulars", "d", "1e-300"),
    ("particulars", "B", "500"), ("particulars", "x_G", "1e200"), ("mass", "m", "1e200"),
    ("mass", "I_zz", "1e200"), ("mass", "m_y", "1e300"), ("particulars", "displacement", "1e-300"),
    ("particulars", "L", HUGE),
]
IDENTIFICATION_SHIP = ('name = "mine"\n[particulars]\nL = 100.0\nB = 16.0\nd = 6.0\n'
                       'displacement = 6000.0\nrho = 1025.0\nU0 = 7.0\nx_G = 0.0\n'
                       '[mass]\nk_zz = 0.25\n')


def _trust_cases() -> list[dict]:
    """What a fresh user met: huge integers, ship values with no range, unbounded options,
    special files given to forces, over-long output names, glob patterns that match nothing."""
    cases = []
    for section, key, value in SHIP_RANGES:
        ship = {"ship.toml": ship_edit(section, key, value)}
        fragment = "ship.toml"
        cases.append(case("ship range: simulate", ["simulate", "--manoeuvre", "straight",
                          "--duration", "30", "--ship", "ship.toml", "--out", "o.csv"], 2,
                          fragment, ship))
        cases.append(case("ship range: fit", FIT + ["--ship", "ship.toml", "--out", "m.json"],
                          2, fragment, {**DATA, **ship}))
        cases.append(case("ship range: evaluate", ["evaluate", "model.json", "data.csv",
                          "--ship", "ship.toml"], 2, fragment, {**MODEL, **ship}))
        cases.append(case("ship range: diagnose", DIAG + ["--ship", "ship.toml"], 2, fragment,
                          {**DIAG_FILES, **ship}))
    for option in ("rts:1e300", "savgol:1e300", "rts:0", "rts:-5", "rts:nan", "savgol:21:9",
                   "kalman:21", "savgol:21:3:1"):
        cases.append(case("number: fit --smoothing", FIT + ["--smoothing", option, "--out",
                          "m.json"], 2, "smoothing", DATA))
        cases.append(case("number: diagnose --smoothing", DIAG + ["--smoothing", option], 2,
                          "smoothing", DIAG_FILES))
    for value in ("100000", "1", "0", "nan", "2.5"):
        cases.append(case("number: captive --points", ["captive", "--test", "rudder",
                          "--points", value, "--out", "c.csv"], 2, "--points"))
    for value in ("1e300", "-1", "0", "nan", "inf"):
        cases.append(case("number: captive --speed", ["captive", "--test", "rudder",
                          "--points", "3", "--speed", value, "--out", "c.csv"], 2, "--speed"))
    refine_options = [("--refine", "-1"), ("--refine", "1e9"), ("--refine", "nan"),
                      ("--segment", "-1"), ("--segment", "0"), ("--segment", "1e9"),
                      ("--refine-weight", "-1"), ("--refine-weight", "nan"),
                      ("--prior-strength", "2")]
    for option, value in refine_options:
        cases.append(case(f"number: fit {option}", FIT + [option, value, "--out", "m.json"],
                          2, option, DATA))
    long_name = "m" * 251 + ".json"  # 256 bytes
    for argv in (FIT + ["--out", long_name], ["export", "model.json", "--latex", long_name],
                 ["simulate", "--manoeuvre", "straight", "--duration", "30", "--out",
                  long_name], CAPTIVE + [long_name], ["discover", "data.csv", "--out", long_name]):
        cases.append(case(f"output name: {argv[0]}", argv, 2, "name", MODEL))
    for files, fragment in (({**MODEL, "model.json": "fifo:"}, "FIFO"),
                            ({**FORCES_FILES, "captive.csv": "fifo:"}, "FIFO"),
                            ({**FORCES_FILES, "captive.csv": "link:/dev/zero"}, "device"),
                            ({**FORCES_FILES, "captive.csv": "dir:"}, "folder")):
        cases.append(case("special input: forces", FORCES, 2, fragment,
                          {**FORCES_FILES, **files}, sub=True))
    for verb, argv in (("fit", ["fit", "none-*.csv", "--out", "m.json"]),
                       ("evaluate", ["evaluate", "model.json", "none-*.csv"]),
                       ("diagnose", ["diagnose", "none-*.csv"])):
        cases.append(case(f"glob matching nothing: {verb}", argv, 2, "none-*.csv", MODEL))
    cases.append(case("huge integer: fit --library", FIT + ["--library", "lib.toml", "--out",
                      "m.json"], 2, "lib.toml", {**DATA, "lib.toml":
                      f'name = "x"\n[terms]\nX = ["du"]\nY = ["v"]\nN = ["r"]\nscale = {HUGE}\n'}))
    cases.append(case("huge integer: diagnose --library", DIAG + ["--library", "lib.toml"], 2,
                      "lib.toml", {**DIAG_FILES, "lib.toml":
                      f'name = "x"\n[terms]\nX = ["du"]\nY = ["v"]\nN = ["r"]\nscale = {HUGE}\n'}))
    cases.append(case("huge integer: fit --effects", FIT + ["--effects", "eff.toml", "--out",
                      "m.json"], 2, "eff.toml", {**DATA, "eff.toml":
                      f'name = "x"\ntitle = "x"\n[terms]\nY = ["v"]\nscale = {HUGE}\n'}))
    cases.append(case("huge integer: export --ship", ["export", "model.json", "--ship",
                      "ship.toml"], 2, "ship.toml",
                      {**MODEL, "ship.toml": ship_edit("particulars", "L", HUGE)}))
    for verb in ("evaluate", "export", "forces"):
        argv = {"evaluate": ["evaluate", "model.json", "data.csv"],
                "export": ["export", "model.json"], "forces": FORCES}[verb]
        cases.append(case(f"huge integer: {verb} model", argv, 2, "model.json",
                          {**FORCES_FILES, "model.json": f"@model:version={HUGE}"}))
    cases.append(case("identification ship: captive", ["captive", "--ship", "mine.toml",
                      "--out", "c.csv"], 2, "no MMG", {"mine.toml": IDENTIFICATION_SHIP}))
    cases.append(case("identification ship: simulate", ["simulate", "--manoeuvre", "straight",
                      "--duration", "30", "--ship", "mine.toml", "--out", "o.csv"], 2, "no MMG",
                      {"mine.toml": IDENTIFICATION_SHIP}))
    return cases


def _scheduler_and_channel_cases() -> list[dict]:
    """Scheduler addresses no Dask client can use or reach, and recorded channels so large
    that a term of them overflows the fit."""
    cases = []
    for address, fragment in (("", "empty"), ("ucx://h:1", "ucx://"), ("tls://h:8786", "tls://"),
                              ("tcp://h", "port"), ("h:99999", "port"),
                              ("tcp://127.0.0.1:1", "cannot reach")):
        for verb, argv, files in (("fit", FIT + ["--stream", "--out", "m.json"], DATA),
                                  ("diagnose", DIAG, DIAG_FILES),
                                  ("discover", ["discover", "data.csv", "other.csv"],
                                   DIAG_FILES)):
            cases.append(case(f"scheduler: {verb}", argv + ["--scheduler", address], 2,
                              fragment, files))
    heel = ('name = "heel"\ntitle = "heel"\nphysics = "heel"\nchannels = ["heel"]\n'
            '[terms]\nY = ["heel v", "heel^2"]\nN = ["heel"]\n')
    for scale in ("1e300", "1e120", "1e60"):
        files = {"data.csv": f"@csv:heel={scale}", "other.csv": f"@csv:heel={scale}",
                 "heel.toml": heel}
        cases.append(case("huge channel: fit", FIT + ["--effects", "heel.toml", "--out",
                          "m.json"], 2, "heel", files))
        cases.append(case("huge channel: diagnose", DIAG + ["--candidates", "heel.toml"], 2,
                          "heel", files))
    return cases


CASES = (_output_cases() + _number_cases() + _ship_cases() + _input_cases() + _model_cases()
         + _trust_cases() + _scheduler_and_channel_cases())


# ---------------------------------------------------------------------------------------------
# laying out files and running a case
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def kit(tmp_path_factory) -> dict:
    """The valid record and model the file specs refer to."""
    folder = tmp_path_factory.mktemp("kit")
    csv, model = folder / "zz.csv", folder / "m.json"
    assert main(["simulate", "--manoeuvre", "zigzag", "--rudder", "20", "--check", "20",
                 "--duration", "120", "--out", str(csv)]) == 0
    assert main(["fit", str(csv), "--out", str(model)]) == 0
    return {"csv": csv.read_text(), "model": model.read_text()}


def _model_variant(text: str, variant: str) -> str:
    document = json.loads(text)
    if variant == "dupkeys":
        return '{"ship": "kvlcc2", ' + text.lstrip()[1:]
    if variant == "huge":
        document["coefficients"]["Y"]["v"] = 1e30
    elif variant == "nan":
        return text.replace(json.dumps(document["coefficients"]["Y"]["v"]), "NaN", 1)
    elif variant.startswith("version="):
        value = variant.split("=", 1)[1]
        if value.isdigit():  # written as it is: a JSON integer of any length
            document["format_version"] = "@version@"
            return json.dumps(document, indent=2).replace('"@version@"', value)
        document["format_version"] = json.loads(value)
    return json.dumps(document, indent=2)


def _content(spec: str, kit: dict) -> str:
    if spec == "@csv":
        return kit["csv"]
    if spec == "@model":
        return kit["model"]
    if spec.startswith("@model:"):
        return _model_variant(kit["model"], spec.split(":", 1)[1])
    if spec.startswith("@csv:"):  # an extra channel: @csv:name=scale, varying about scale
        name, scale = spec[len("@csv:"):].split("=")
        header, *rows = kit["csv"].strip().splitlines()
        rows = [f"{row},{float(scale) * (1 + 0.01 * (i % 7))!r}" for i, row in enumerate(rows)]
        return "\n".join([f"{header},{name}", *rows]) + "\n"
    if spec.startswith("@ship:"):
        target, value = spec[len("@ship:"):].split("=", 1)
        section, key = target.split(".")
        lines, current = [], None
        for line in KCS_TOML.splitlines():
            if line.startswith("["):
                current = line.split("]")[0].strip("[")
            elif current == section and line.split("=")[0].strip() == key:
                line = f"{key} = {value}"
            lines.append(line)
        return "\n".join(lines) + "\n"
    return spec


def lay_out(folder: Path, files: dict, kit: dict) -> list:
    """Make the files; return the sockets to close afterwards."""
    keep = []
    for name, spec in files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if spec == "fifo:":
            os.mkfifo(path)
        elif spec == "sock:":
            server = socket.socket(socket.AF_UNIX)
            server.bind(str(path))
            keep.append(server)
        elif spec.startswith("dir:"):
            path.mkdir(exist_ok=True)
            if spec[4:]:
                path.chmod(int(spec[4:], 8))
        elif spec.startswith("link:"):
            os.symlink(spec[5:], path)
        elif spec.startswith("hard:"):
            os.link(folder / spec[5:], path)
        else:
            path.write_bytes(_content(spec, kit).encode("utf-8", "surrogateescape"))
    return keep


def snapshot(folder: Path) -> dict:
    """Every entry below ``folder``: its kind and its bytes (files) or target (links)."""
    state = {}
    for root, dirs, names in os.walk(folder):
        for name in dirs + names:
            path = Path(root) / name
            rel = str(path.relative_to(folder))
            if path.is_symlink():
                state[rel] = ("link", os.readlink(path))
            elif path.is_dir():
                state[rel] = ("dir", None)
            elif path.is_file():
                state[rel] = ("file", path.read_bytes())
            else:
                state[rel] = ("special", oct(path.lstat().st_mode))
    return state


def _children(pid: int) -> set[int]:
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.add(int(entry.name))
    return found


def _session_members(sid: int) -> set[int]:
    found = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[3]) == sid:
                found.add(int(entry.name))
    return found


def run_subprocess(argv: list[str], folder: Path) -> tuple[int, str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    proc = subprocess.Popen([sys.executable, "-m", "sindyship.cli", *argv], cwd=folder,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=CASE_TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        pytest.fail(f"sindyship {' '.join(argv)} ran longer than {CASE_TIMEOUT:g} s")
    left = _session_members(proc.pid)
    for pid in left:
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)
    assert not left, f"processes left running: {sorted(left)}"
    return proc.returncode, out, err


def run_in_process(argv: list[str], folder: Path, monkeypatch) -> tuple[int, str, str]:
    monkeypatch.chdir(folder)
    before = _children(os.getpid())
    result = run_sindyship(*argv)
    assert _children(os.getpid()) <= before, "child processes left running"
    return result


def _case_id(c: dict) -> str:
    return re.sub(r"\s+", "_", f"{CASES.index(c):03d}:{c['group']}:{' '.join(c['argv'][1:])}"
                  )[:100]


def _params():
    out = []
    for c in CASES:
        marks = []
        if c["xfail"]:
            marks.append(pytest.mark.xfail(reason=c["xfail"], strict=True))
        if c["skip_root"] and AS_ROOT:
            marks.append(pytest.mark.skip(reason="root writes in any folder"))
        out.append(pytest.param(c, id=_case_id(c), marks=marks))
    return out


def test_the_corpus_covers_every_verb_with_enough_cases():
    verbs = {c["argv"][0] for c in CASES}
    assert verbs == {"simulate", "fit", "evaluate", "reproduce", "diagnose", "export",
                     "captive", "discover", "forces"}
    assert len(CASES) >= 400
    assert len({json.dumps(c, sort_keys=True) for c in CASES}) == len(CASES)  # no repeats


@pytest.mark.parametrize("c", _params())
def test_hostile_input(c, kit, tmp_path, monkeypatch):
    folder = tmp_path / "case"
    folder.mkdir()
    sockets = lay_out(folder, c["files"], kit)
    try:
        before = snapshot(folder)
        if c["sub"]:
            code, out, err = run_subprocess(c["argv"], folder)
        else:
            code, out, err = run_in_process(c["argv"], folder, monkeypatch)
        after = snapshot(folder)
    finally:
        for server in sockets:
            server.close()
        for name, spec in c["files"].items():
            if spec.startswith("dir:0"):
                (folder / name).chmod(0o755)
    assert code == c["code"], err
    assert "Traceback" not in err
    if c["code"] == 2:
        assert out == "", out
        assert err.endswith("\n") and err.count("\n") == 1, err
        assert err.startswith("sindyship "), err
    fragment = c["message"]
    assert fragment.lower() in err.lower(), (fragment, err)
    for name in c["outputs"]:
        assert name in after, name
    assert {k: v for k, v in after.items() if k not in c["outputs"]} == before


# ---------------------------------------------------------------------------------------------
# results never merge; folder outputs replace the previous folder only at the end
# ---------------------------------------------------------------------------------------------
def test_records_with_one_stem_are_reported_apart(kit, tmp_path, monkeypatch):
    lay_out(tmp_path, {"a/run.csv": "@csv", "b/run.csv": "@csv", "model.json": "@model"}, kit)
    code, out, err = run_in_process(["evaluate", "model.json", "a/run.csv", "b/run.csv",
                                     "--json"], tmp_path, monkeypatch)
    assert code == 0, err
    errors = json.loads(out)["errors"]
    assert sorted(errors) == ["a/run", "b/run"]
    assert errors["a/run"]["mean_distance_L"] == errors["b/run"]["mean_distance_L"]


def test_a_failed_folder_output_leaves_the_previous_folder_whole(tmp_path):
    from sindyship._io import output_folder

    previous = tmp_path / "out"
    previous.mkdir()
    (previous / "results.json").write_text("old\n")
    with pytest.raises(RuntimeError), output_folder(previous) as tmp:
        (tmp / "results.json").write_text("half\n")
        raise RuntimeError("killed half way")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert (previous / "results.json").read_text() == "old\n"
    with output_folder(previous) as tmp:
        (tmp / "results.json").write_text("new\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert sorted(p.name for p in previous.iterdir()) == [".sindyship-output", "results.json"]
    assert (previous / ".sindyship-output").read_text() == "results.json\n"
    assert (previous / "results.json").read_text() == "new\n"


def test_a_killed_folder_output_leaves_the_previous_folder_whole(tmp_path):
    previous = tmp_path / "out"
    previous.mkdir()
    (previous / "results.json").write_text("old\n")
    script = ("import sys, time\nfrom pathlib import Path\n"
              "from sindyship._io import output_folder\n"
              "with output_folder(sys.argv[1]) as tmp:\n"
              "    (tmp / 'results.json').write_text('half')\n"
              "    print('writing', flush=True)\n"
              "    time.sleep(60)\n")
    proc = subprocess.Popen([sys.executable, "-c", script, str(previous)],
                            env={**os.environ, "PYTHONPATH": str(ROOT)},
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline() == "writing\n"
    finally:
        proc.kill()
        proc.wait(timeout=CASE_TIMEOUT)
    assert [p.name for p in previous.iterdir()] == ["results.json"]
    assert (previous / "results.json").read_text() == "old\n"


def test_a_folder_given_for_a_file_output_suggests_a_name_of_the_right_kind(tmp_path):
    from sindyship._io import check_output
    from sindyship.errors import SindyshipInputError

    for suffixes, example in (((".json",), "out.json"), ((), "out.csv")):
        with pytest.raises(SindyshipInputError) as caught:
            check_output(tmp_path, suffixes=suffixes)
        assert str(caught.value).endswith(f"is a folder; give the name of a file to write (e.g. "
                                          f"{tmp_path}/{example}).")

"""The command line run in the test's process.

A new interpreter costs about a second per command (imports, numba's cache), more than most
commands take on a test's small records, so the tests run ``sindyship ARGS`` through
:func:`sindyship.cli.main` here.  Tests of the installed command, of a command that could hang
(behind a timeout) or of what a fresh process sees still start one through ``subprocess``.
"""

from __future__ import annotations

import contextlib
import io
import os


def run_sindyship(*args, cwd=None) -> tuple[int, str, str]:
    """``sindyship ARGS`` in this process, in ``cwd`` when given: (exit status, stdout,
    stderr); a refusal while the command line is read (argparse's ``SystemExit``) gives its
    status like any other."""
    from sindyship.cli import main

    out, err = io.StringIO(), io.StringIO()
    previous = os.getcwd()
    if cwd is not None:
        os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main([str(a) for a in args])
            except SystemExit as exc:
                code = exc.code
    finally:
        os.chdir(previous)
    return code, out.getvalue(), err.getvalue()

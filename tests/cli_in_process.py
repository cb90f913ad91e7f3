"""The command line run in the test's process.

A new interpreter costs about a second per command (imports, numba's cache), more than most
commands take on a test's small records, so the tests run ``sindyship ARGS`` through
:func:`sindyship.cli.main` here.  Tests of the installed command, of a command that could hang
(behind a timeout) or of what a fresh process prints beyond Python's own streams still start
one through ``subprocess``.
"""

from __future__ import annotations

import contextlib
import io
import warnings

#: The warning filters of a fresh interpreter (Python's defaults; pytest installs its own).
FRESH_FILTERS = (("default", DeprecationWarning, "__main__"), ("ignore", DeprecationWarning, ""),
                 ("ignore", PendingDeprecationWarning, ""), ("ignore", ImportWarning, ""),
                 ("ignore", ResourceWarning, ""))


def run_sindyship(*args) -> tuple[int, str, str]:
    """``sindyship ARGS`` in this process: (exit status, stdout, stderr).

    Warnings reach stderr as they would in a fresh process, where they are raised (Python's
    default filters, each formatted by :func:`warnings.formatwarning`), and the exit status of
    a ``SystemExit`` (argparse's refusals) is what the process would return: 0 for ``None``,
    1 for a message.
    """
    from sindyship.cli import main

    out, err = io.StringIO(), io.StringIO()

    def show(message, category, filename, lineno, file=None, line=None):
        err.write(warnings.formatwarning(message, category, filename, lineno, line))

    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        warnings.resetwarnings()
        warnings.simplefilter("default")
        for action, category, module in reversed(FRESH_FILTERS):
            warnings.filterwarnings(action, category=category, module=module)
        warnings.showwarning = show
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if isinstance(exc.code, str):
                print(exc.code, file=err)
    return code, out.getvalue(), err.getvalue()

"""Exceptions that sindyship raises for problems a user can fix."""

from __future__ import annotations


class SindyshipInputError(ValueError):
    """Bad input handed to sindyship by a user (a file, an option, an argument).

    The message is one sentence that names the file and the column, row or term at fault and
    says how to fix it.  The command line prints it on one line and exits with status 2.
    """

"""A measurement CSV's text as rows of strings: the file's encoding, its quoting, its
separators and decimal commas (:func:`sindyship.measurements.read_csv` turns the rows into
numbers).  Rows are numbered as a spreadsheet numbers them: the header is row 1."""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import pandas as pd

from sindyship.errors import SindyshipInputError

__all__ = ["DECIMAL_COMMA", "FILE_ROW", "REQUIRED_TEXT", "parse_csv_text", "read_text"]

#: The name of the index of a parsed file: its rows as a spreadsheet numbers them.
FILE_ROW = "spreadsheet row"
#: The columns a measurement CSV needs, for messages.
REQUIRED_TEXT = "t, u, v, r, x, y, psi and delta and/or delta_c"
#: A number written with a decimal comma (``12,5``).
DECIMAL_COMMA = re.compile(r"(?<![\d.])-?\d+,\d+(?:[eE][-+]?\d+)?(?![\d.,])")


def read_text(path: Path, source: str) -> str:
    try:
        return path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        problem = "file not found; check the path and the file name"
    except IsADirectoryError:
        problem = "is a folder, not a file; give the path of a CSV file"
    except PermissionError:
        problem = "cannot be read (permission denied); check the file's permissions"
    except UnicodeDecodeError:
        problem = "is not UTF-8 text; save it as a UTF-8 (or plain ASCII) CSV file"
    except OSError as error:
        problem = f"cannot be read ({error.strerror or error}); check the path"
    raise SindyshipInputError(f"{source}: {problem}.")


def parse_csv_text(text: str, source: str) -> pd.DataFrame:
    """Split CSV text into a frame of strings indexed by spreadsheet row number."""
    reader = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    rows: list[list[str]] = []
    numbers: list[int] = []
    try:
        for record in reader:
            if not any(cell.strip() for cell in record):
                continue  # a blank row carries no sample
            if header is None:
                header = record
                continue
            _refuse_open_quote(record, reader.line_num, source)
            if len(record) != len(header):
                _refuse_decimal_commas(header, record, reader.line_num, source)
                raise SindyshipInputError(
                    f"{source}: row {reader.line_num} (counting the header as row 1) has "
                    f"{len(record)} values but the header names {len(header)} columns; "
                    "give every row one value per column."
                )
            rows.append(record)
            numbers.append(reader.line_num)
    except csv.Error as error:
        raise SindyshipInputError(
            f"{source}: row {reader.line_num} is not valid CSV ({error}); fix the quoting."
        ) from error
    if header is None:
        raise SindyshipInputError(
            f"{source}: the file is empty; a measurement CSV needs a header row "
            f"({REQUIRED_TEXT}) and at least two rows of samples."
        )
    if len(header) == 1 and (";" in header[0] or "\t" in header[0]):
        if rows:
            _refuse_decimal_commas(header, rows[0], numbers[0], source)
        raise SindyshipInputError(
            f"{source}: the header has a single column '{header[0].strip()}'; "
            "separate the columns with commas, not semicolons or tabs."
        )
    index = pd.Index(numbers, name=FILE_ROW)
    return pd.DataFrame(rows, columns=header, index=index, dtype=object)


def _refuse_decimal_commas(header: list[str], record: list[str], line: int, source: str) -> None:
    """Refuse a row written with decimal commas (``0,5``), which a column count would hide.

    A row has decimal commas when it splits into more cells than the header names and its
    text holds numbers like ``12,5``, or when the header is one semicolon-separated cell and
    the row's cells hold such numbers.
    """
    if len(header) == 1:
        example = DECIMAL_COMMA.search(",".join(record).replace(";", " ").replace("\t", " "))
        if example is None:
            return
        found = f"(e.g. '{example.group(0)}') and semicolons between the columns"
    elif len(record) > len(header) and DECIMAL_COMMA.search(",".join(record)):
        found = f"({len(record)} comma-separated values for {len(header)} columns)"
    else:
        return
    raise SindyshipInputError(
        f"{source}: row {line} (counting the header as row 1) looks written with decimal "
        f"commas {found}; save the file with decimal points and commas between the columns "
        "(e.g. '12.5,0.3')."
    )


def _refuse_open_quote(record: list[str], line: int, source: str) -> None:
    """Refuse a row whose quote is never closed: the reader takes every row after it into one
    cell, and the row a column count names would be the file's last."""
    swallowed = sum(cell.rstrip("\r\n").count("\n") for cell in record)
    if swallowed or any("\n" in cell for cell in record):
        raise SindyshipInputError(
            f"{source}: row {line - swallowed} (counting the header as row 1) opens a quote "
            "(\") that is never closed, so the rows after it read as one value; remove the "
            "stray quote.")

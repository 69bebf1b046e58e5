"""The CSV of vpcontact's tables (history.csv, contact.csv, adapt.csv, study.csv): cells as Python's
``csv.writer`` writes them, floats as their repr (every digit, so that ``pandas.read_csv`` reads the
numbers of the run to the last bit), rows ended by CRLF; read back as text by column."""

from __future__ import annotations

import csv
import io
import os

import numpy as np


def read_table(path: str | os.PathLike) -> list[dict[str, str]]:
    """The rows of a CSV table vpcontact writes (contact.csv, adapt.csv, study.csv, ...), each a dict of
    its cells as text by column."""
    with open(path, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def joined(*columns: np.ndarray, nan: str = "nan") -> list[str]:
    """The cells of ``columns`` (arrays of one length) as the text of each row, comma-separated."""
    return [",".join(cells) for cells in zip(*(texts(column, nan) for column in columns))]


def texts(values: np.ndarray, nan: str = "nan") -> list[str]:
    """The cells of a CSV column as csv.writer writes them: integers as str, floats as repr (NaN as ``nan``),
    text quoted where it holds a comma, a quote or a line break."""
    if values.dtype.kind == "f":
        cells = list(map(repr, values.tolist()))
        return cells if nan == "nan" else [nan if cell == "nan" else cell for cell in cells]
    if values.dtype.kind in "iub":
        return list(map(str, values.tolist()))
    quoted = {text: _quoted(text) for text in set(values.tolist())}
    return [quoted[text] for text in values.tolist()]


def _quoted(text: str) -> str:
    """One text cell as csv.writer writes it."""
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="").writerow([text])
    return buffer.getvalue()

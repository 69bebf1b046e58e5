"""history.csv: one row per converged time level (sub-steps of a cut step included), the columns of
``result.columns`` (:mod:`vpcontact.results.columns`), floats as their repr. Also refreshed at every
checkpoint of a run in progress. Read back with ``pandas.read_csv`` (the numbers of ``result.history``
to the last bit) or :func:`vpcontact.io.csv_format.read_table`."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .files import replacing

FILES = ("history.csv",)


def wanted(result) -> bool:
    """Every run has its history."""
    return True


def write(result, out: Path) -> None:
    """history.csv of ``result`` in the run directory ``out``."""
    with replacing(Path(out) / "history.csv") as temporary, temporary.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=result.columns)
        writer.writeheader()
        for row in result.rows:
            writer.writerow({k: (repr(float(v)) if isinstance(v, (float, np.floating)) else v) for k, v in row.items()})

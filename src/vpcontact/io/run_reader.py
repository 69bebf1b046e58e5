"""Reading a run directory (the files :mod:`vpcontact.io.writers` writes): its summary, its resolved case,
its tables and its solution arrays, parsed in this one place for the studies, resume
(:mod:`vpcontact.drivers.rundir`) and the figures of the reproduction.

Which rows of contact.csv are the steps t_n is the rule of :func:`vpcontact.results.steps.step_ends`, the
one a run in memory follows too. A file that is missing or damaged reads as nothing (None, an empty
table, no snapshots): the callers decide whether that is an error.
"""

from __future__ import annotations

import csv
import json
import os
import zipfile
from collections.abc import Collection
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..case.schema import Case, load_case
from ..laws.contact import STATUS_NAMES
from ..results.columns import CONTACT_ARRAYS
from ..results.steps import step_ends
from ..fem.space import CELLS, coordinates

if TYPE_CHECKING:
    from ..results.norms import Snapshot

SOLUTION_ARRAYS = ("steps", "times", "points", "displacement", "stress")
"""The arrays of solution.npz a comparison reads (besides the elements, and the Lamé parameters when
the run wrote them): see :func:`vpcontact.io.writers.write_solution`."""


def read_summary(folder: str | os.PathLike) -> dict | None:
    """summary.json of the run in ``folder``; None when there is none or it is not a readable JSON object (a
    run in progress or killed, or not a run)."""
    try:
        summary = json.loads((Path(folder) / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return summary if isinstance(summary, dict) else None


def read_case(folder: str | os.PathLike) -> Case:
    """case.resolved.toml of the run in ``folder`` (CaseError when it is missing or not a case)."""
    return load_case(Path(folder) / "case.resolved.toml")


def read_table(path: str | os.PathLike) -> list[dict[str, str]]:
    """The rows of a CSV table vpcontact writes (contact.csv, adapt.csv, study.csv, ...), each a dict of
    its cells as text by column."""
    with open(path, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def read_contact(folder: str | os.PathLike, step: int | None = None) -> dict[str, np.ndarray]:
    """The contact.csv rows of the run in ``folder`` at t_n of step n = ``step`` (default: the last step
    reached, summary.json's "steps"), one array per contact node and column: ``node`` (mesh index),
    ``coordinates`` and ``normals`` (d, m), ``weight``, the per-node arrays of
    :data:`vpcontact.results.columns.CONTACT_ARRAYS` (``status`` as its index in STATUS_NAMES) and ``t``.
    KeyError when the step was not reached."""
    folder = Path(folder)
    completed = int((read_summary(folder) or {}).get("steps", 0))
    step = completed if step is None else step
    rows = read_table(folder / "contact.csv")
    m = len({row["node"] for row in rows}) or 1
    blocks = [rows[i:i + m] for i in range(0, len(rows), m)]  # one block of m nodes per history row
    ends = step_ends([int(block[0]["step"]) for block in blocks], completed)
    chosen = [block for block, end in zip(blocks, ends) if end and int(block[0]["step"]) == step]
    if not chosen:
        raise KeyError(f"step {step} was not reached by the run in '{folder}' ({completed} steps reached)")
    (block,) = chosen
    column = lambda name: np.array([float(row[name]) for row in block])  # noqa: E731
    axes = coordinates(len([name for name in block[0] if name.startswith("normal_")]))
    return {"node": np.array([int(row["node"]) for row in block]), "t": column("t"),
            "coordinates": np.vstack([column(c) for c in axes]),
            "normals": np.vstack([column(f"normal_{c}") for c in axes]), "weight": column("weight"),
            **{name: column(name) for name in CONTACT_ARRAYS if name != "status"},
            "status": np.array([STATUS_NAMES.index(row["status"]) for row in block])}


def read_solution(folder: str | os.PathLike) -> dict[str, np.ndarray] | None:
    """The arrays of solution.npz of the run in ``folder`` a comparison or a figure reads: SOLUTION_ARRAYS,
    ``elements`` (triangles or tetrahedra) and ``lame`` (None for runs of earlier versions, which lack
    it); None when it is missing or damaged."""
    try:
        with np.load(Path(folder) / "solution.npz") as solution:
            data = {key: solution[key] for key in SOLUTION_ARRAYS}
            data["elements"] = solution[CELLS[data["points"].shape[0]][2]]
            data["lame"] = solution["lame"] if "lame" in solution else None
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile):
        return None
    return data


def snapshots_at(folder: str | os.PathLike, times: Collection[float]) -> dict[float, Snapshot]:
    """The fields of the run in ``folder`` at those of ``times`` its solution.npz holds (none if it is
    missing or damaged), for :func:`vpcontact.results.norms.differences` (loaded here: a run needs no norms)."""
    from ..results.norms import Snapshot

    data = read_solution(folder)
    if data is None:
        return {}
    found = {}
    for t in times:
        index = np.flatnonzero(np.isclose(data["times"], t, rtol=1e-9, atol=1e-12))
        if index.size:
            i = index[0]
            found[t] = Snapshot(data["points"], data["elements"], data["displacement"][i], data["stress"][i],
                                data["lame"])
    return found

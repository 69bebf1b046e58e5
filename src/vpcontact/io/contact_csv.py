"""contact.csv: one row per contact node and converged time level: ``step``, ``t``, the node (its index
in the mesh), its coordinates, normal and weight, the contact arrays (:mod:`vpcontact.results.columns`;
``status`` by its name), ``substep``, and the local layer parameters
(:func:`vpcontact.results.frames.layer_columns`). Written in blocks of rows (the memory it takes is the
same however long the run), read back at one step by :func:`read_contact`."""

from __future__ import annotations

import csv
import itertools
import os
from pathlib import Path

import numpy as np

from ..mesh.cells import coordinates
from ..laws.contact import STATUS_NAMES
from ..results.columns import CONTACT_ARRAYS
from ..results.frames import layer_columns
from ..results.steps import step_ends
from .csv_format import joined, read_table, texts
from .files import replacing
from .summary import read_summary

FILES = ("contact.csv",)
#: Values of each column of contact.csv turned into text at once: the memory the writer adds to the run's
#: stays the same however many rows the run has.
CONTACT_BLOCK = 2**14


def wanted(result) -> bool:
    """Every run has its contact table (a header alone without contact)."""
    return True


def write(result, out: Path) -> None:
    """contact.csv of ``result`` in the run directory ``out``, in blocks of rows: each number turned into text
    once (the columns of a node, such as its coordinates, once for all the steps; those of a row, such as t,
    once for all its nodes), as csv.writer writes it (floats as repr, an empty cell for None or a NaN layer
    parameter, text quoted if need be)."""
    surface = result.discretization.surface
    rows, m = len(result.rows), surface.size
    steps, substeps, times = result.series("step").astype(int), result.series("substep").astype(int), result.times
    axes = coordinates(result.dim)
    layer = layer_columns(result.discretization)
    names = ["step", "t", "node", *axes, *(f"normal_{c}" for c in axes), "weight", *CONTACT_ARRAYS, "substep",
             *layer]
    node_cells = joined(surface.nodes, *surface.coordinates, *surface.normals, surface.weights)
    layer_cells = joined(*layer.values(), nan="") if layer else None  # a parameter a node's law has not: empty
    status_names = np.asarray(STATUS_NAMES)
    block = max(1, CONTACT_BLOCK // max(m, 1))
    with replacing(Path(out) / "contact.csv") as temporary, temporary.open("w", newline="") as handle:
        csv.writer(handle).writerow(names)
        for start in range(0, rows, block):
            chosen = slice(start, min(rows, start + block))
            count = chosen.stop - start
            row_cells = joined(steps[chosen], times[chosen])  # step and t
            columns = [itertools.chain.from_iterable(itertools.repeat(cells, m) for cells in row_cells),
                       node_cells * count]
            columns += [texts(np.array(result.contact[name][chosen]).ravel()) for name in CONTACT_ARRAYS[:-1]]
            columns.append(status_names[np.array(result.contact["status"][chosen]).ravel().astype(int)].tolist())
            columns.append(texts(np.repeat(substeps[chosen], m)))
            if layer_cells is not None:
                columns.append(layer_cells * count)
            handle.writelines(",".join(cells) + "\r\n" for cells in zip(*columns))


def read_contact(folder: str | os.PathLike, step: int | None = None) -> dict[str, np.ndarray]:
    """The contact.csv rows of the run in ``folder`` at t_n of step n = ``step`` (default: the last step
    reached, summary.json's "steps"), one array per contact node and column: ``node`` (mesh index),
    ``coordinates`` and ``normals`` (d, m), ``weight``, the per-node arrays of
    :data:`vpcontact.results.columns.CONTACT_ARRAYS` (``status`` as its index in STATUS_NAMES) and ``t``.
    Which rows are the steps t_n is the rule of :func:`vpcontact.results.steps.step_ends`, the one a run in
    memory follows too. KeyError when the step was not reached."""
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

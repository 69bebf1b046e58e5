"""The outputs of a run directory, written through one interface, :func:`write_outputs` (by ``vpcontact
run`` at its end and its checkpoints, by an adaptive run for each cycle, by :func:`vpcontact.io.run.write_run`).

Each output is a module of :mod:`vpcontact.io`, a plug-in with

- ``FILES``: the files it writes, as glob patterns below the run directory (what ``--overwrite``
  removes, where a symbolic link is refused before a run starts: :mod:`vpcontact.io.run`);
- ``wanted(result)``: does this run have it (every run has a history; the field files need kept
  fields, XDMF and figures are asked for in ``[output]``);
- ``write(result, out)``: write it into the run directory ``out``, each file atomically
  (:mod:`vpcontact.io.files`).

WRITERS lists them in the order they are written, summary.json last: a directory whose summary.json
says ``"status": "complete"`` holds a complete run. A new output format is one module and one entry
there.
"""

from __future__ import annotations

from pathlib import Path

from . import contact_csv, figures, history_csv, solution, summary, vtu, xdmf

#: The outputs of a run, in the order they are written: history.csv, contact.csv, fields/*.vtu and
#: *.pvd, solution.npz, fields/*.xdmf and *.h5, figures/*.png, summary.json.
WRITERS = (history_csv, contact_csv, vtu, solution, xdmf, figures, summary)
FILES = tuple(pattern for writer in (summary, *(w for w in WRITERS if w is not summary)) for pattern in writer.FILES)
"""The files of one run, as glob patterns, summary.json first (removed first: it must never describe
files that are gone)."""


def write_outputs(result, out: str | Path, *, history_only: bool = False) -> None:
    """Every output of ``result`` it has (WRITERS' ``wanted``) into the run directory ``out``, in the order
    of WRITERS, summary.json last; ``history_only``: history.csv alone (refreshed at the checkpoints of a
    run in progress)."""
    for writer in (history_csv,) if history_only else WRITERS:
        if writer.wanted(result):
            writer.write(result, Path(out))

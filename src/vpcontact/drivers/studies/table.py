"""DIR/study.csv: a row per run of a study, its overrides, status and summary values, and the difference norms
against the reference run at the compared times (the norms of
:data:`vpcontact.results.norms.COMPARED`, NaN where a run has no fields at a compared time; "energy" needs the
reference's Lamé parameters)."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Collection
from pathlib import Path

from ...mesh.cells import COORDINATES
from ...io.files import replacing
from ...io.solution import snapshots_at
from ...io.summary import read_summary
from ...results.norms import COMPARED, Snapshot, differences, norm_column
from .file import RunSpec, Study

#: The vectors of summary.json's ``final``, one column per component (``contact_force_x``, ...).
VECTORS = ("contact_force", "reaction", "applied_force", "balance_residual")


def write_study_table(study: Study, out: Path, errors: dict[str, str] | None = None,
                      interrupted: Collection[str] = ()) -> list[dict]:
    """DIR/study.csv: per run its overrides, status, wall time, summary values and difference norms
    (``errors``: why runs that wrote nothing failed; ``interrupted``: runs a stopped study did not
    finish)."""
    rows = []
    reference = _snapshots(study, study.reference) if study.reference else {}
    for spec in study.runs:
        row = {"id": spec.id, **{k: _cell(v) for k, v in spec.overrides.items() if k != "output.field_steps"}}
        summary = _summary(spec, (errors or {}).get(spec.id), spec.id in interrupted)
        row.update({"status": summary.get("status"), "message": summary.get("message", ""),
                    "wall_time_s": summary.get("wall_time_s"), "dofs": summary.get("dofs"),
                    "contact_nodes": summary.get("contact_nodes"), "steps": summary.get("steps"),
                    "newton_iterations": summary.get("newton_iterations")})
        final = dict(summary.get("final") or {})
        vectors = {name: final.pop(name, [None, None]) for name in VECTORS}
        row.update(final)
        row.update({f"{name}_{c}": value for name, vector in vectors.items() for c, value in zip(COORDINATES, vector)})
        if reference:
            mine = _snapshots(study, spec.id) if summary.get("status") == "complete" else {}
            for t in study.times:
                norms = differences(mine[t], reference[t]) if t in mine and t in reference else {}
                row.update({norm_column(norm, t): norms.get(norm, math.nan) for norm in COMPARED})
        rows.append(row)
    columns = list(dict.fromkeys(key for row in rows for key in row))
    with replacing(out / "study.csv") as temporary, temporary.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    return rows


def _summary(spec: RunSpec, error: str | None, interrupted: bool) -> dict:
    """The run's summary.json; for a run that ended with an exception, or that a stopped study did not
    finish, what happened instead (a summary.json there is an earlier run's)."""
    if error is not None:
        return {"status": "error", "message": error}
    if interrupted:
        return {"status": "interrupted", "message": "the study was stopped before this run finished; rerun the "
                                                    "study to do it"}
    return read_summary(spec.out) or {"status": "missing", "message": ""}


def _cell(value):
    return json.dumps(value) if isinstance(value, (dict, list)) else value


def _snapshots(study: Study, run_id: str) -> dict[float, Snapshot]:
    """The run's fields at the compared times, from its solution.npz."""
    spec = next(s for s in study.runs if s.id == run_id)
    return snapshots_at(spec.out, study.times)

"""summary.json, the last file a run writes: its status and message, sizes, the step solver and its
work, the wall time and its parts, the final values of the history and the installed versions. A run
directory whose summary.json says ``"status": "complete"`` holds a complete run; without one a run is in
progress or was killed (``vpcontact run --resume`` continues it from its checkpoint)."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from .files import write_text
from .versions import versions

FILES = ("summary.json",)


def wanted(result) -> bool:
    """Every run has its summary."""
    return True


def write(result, out: Path) -> None:
    """summary.json of ``result`` (:meth:`~vpcontact.results.result.Result.summary` and the versions) in the
    run directory ``out``."""
    summary = {**result.summary(), "versions": versions()}
    write_text(Path(out) / "summary.json", json.dumps(json_safe(summary), indent=2) + "\n")


def json_safe(value):
    """Plain JSON values: NumPy scalars as Python ones, NaN and inf as null, keys as strings."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def read_summary(folder: str | os.PathLike) -> dict | None:
    """summary.json of the run in ``folder``; None when there is none or it is not a readable JSON object (a
    run in progress or killed, or not a run)."""
    try:
        summary = json.loads((Path(folder) / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return summary if isinstance(summary, dict) else None

"""A run of a study solved on several MPI ranks: ``vpcontact study STUDY --out DIR --ranks N`` launches each run as
``mpiexec -n N python -m vpcontact run BASE --set KEY=VALUE ... --out DIR/runs/ID --overwrite`` from the worker
that has it (a process of the local pool, or a Dask worker: mpiexec is then the one on that worker's machine, and
its ranks go where that machine's MPI puts them, a hostfile or a batch allocation; docs/mpi.md). The run writes its
own directory as ``vpcontact run`` does; the study reads its summary.json.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import tomli_w

from ...io.summary import read_summary
from .file import RunSpec

#: The MPI launcher of the runs (its path is looked up on the worker's PATH).
LAUNCHER = "mpiexec"


def toml_value(value) -> str:
    """``value`` as a TOML value on one line, as ``--set KEY=VALUE`` reads it (a table inline)."""
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(key)} = {toml_value(item)}" for key, item in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    return tomli_w.dumps({"v": value})[len("v = "):].strip()


def command(spec: RunSpec) -> list[str]:
    """The command that solves ``spec`` on its ranks: the base case with the run's overrides as ``--set`` values."""
    overrides = [item for key, value in spec.overrides.items() for item in ("--set", f"{key}={toml_value(value)}")]
    launcher = shutil.which(LAUNCHER) or LAUNCHER
    return [launcher, "-n", str(spec.ranks), sys.executable, "-m", "vpcontact", "run", str(spec.base), *overrides,
            "--out", str(spec.out), "--overwrite", "--quiet"]


def execute_on_ranks(spec: RunSpec) -> dict:
    """Solve ``spec`` on its MPI ranks and write its directory; its summary (status "error", with the launch's last
    line, when it wrote none: the launcher is missing, or the run was refused or killed)."""
    try:
        done = subprocess.run(command(spec), capture_output=True, text=True, env=os.environ.copy())
    except OSError as error:
        return {"status": "error", "message": f"{LAUNCHER} cannot be started ({error}): install MPI (docs/mpi.md)"}
    summary = read_summary(spec.out)
    if summary is None:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        return {"status": "error", "message": f"{LAUNCHER} -n {spec.ranks} exited with status {done.returncode}: "
                                              f"{lines[-1] if lines else 'no message'}"}
    return summary

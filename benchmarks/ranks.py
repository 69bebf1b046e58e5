"""Strong scaling of one solve on MPI ranks: the quarter ball of examples/quarter_ball.toml by the iterative method
(CG with PETSc's GAMG) in one process and on N ranks (``mpiexec -n N vpcontact run``), each a fresh launch.

For each count of ranks: the whole launch's wall time (median of ``--repeats``), the run's own timings (build, the
partition, the multigrid's set-up, the time loop), its Newton and CG iterations, each rank's peak resident memory
and its share of the solve (free dofs, ghost dofs received at each exchange, contact nodes) from summary.json; and
the projection of docs/mpi.md from them (per-rank costs and message volumes for larger meshes on more ranks).

    python benchmarks/ranks.py --h 0.042 --steps 100 --ranks 1 2      # the 300k-dof rung, 100 steps
    python benchmarks/ranks.py --h 0.0218 --steps 10 --ranks 1 2      # the 2M-dof rung, 10 steps
    python benchmarks/ranks.py --quick                                # 9k dofs, 3 steps (the tests)
    python benchmarks/ranks.py --h 0.042 --steps 10 --viscoplastic    # a Perzyna body: each rank's element history

prints one JSON document. Needs mpiexec, mpi4py, petsc4py and pymetis (README: scripts/install-mpi.sh).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"


#: A Perzyna body (--viscoplastic): yield at a fifth of the elastic peak, relaxation time 5 steps of the default grid.
PERZYNA = ["--set", 'material.viscoplastic.law="perzyna"', "--set", "material.viscoplastic.eta=0.5",
           "--set", "material.viscoplastic.yield_stress=1.0"]


def launch(ranks: int, h: float, steps: int, viscoplastic: bool = False) -> dict:
    """One run of the quarter ball (``viscoplastic``: of a Perzyna body) on ``ranks`` ranks (1: a process alone):
    its record."""
    with tempfile.TemporaryDirectory() as folder:
        command = [sys.executable, "-m", "vpcontact", "run", str(EXAMPLE), "--quiet", "--out", folder,
                   "--set", f"mesh.h={h}", "--set", f"time.steps={steps}", "--set", 'solver.method="iterative"',
                   "--set", 'solver.multigrid="petsc"', "--set", 'output.field_steps="none"',
                   "--set", "output.figures=false", *(PERZYNA if viscoplastic else [])]
        if ranks > 1:
            command = [shutil.which("mpiexec"), "-n", str(ranks), *command]
        environment = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
                       "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
        started = time.perf_counter()
        done = subprocess.run(command, env=environment, capture_output=True, text=True)
        wall = time.perf_counter() - started
        if done.returncode != 0:
            return {"ranks": ranks, "status": "error", "message": done.stderr[-2000:]}
        summary = json.loads((Path(folder) / "summary.json").read_text())
    return {"ranks": ranks, "status": summary["status"], "process_s": wall, "dofs": summary["dofs"],
            "contact_nodes": summary["contact_nodes"], "timings_s": summary["timings_s"],
            "newton_iterations": summary["newton_iterations"], "cg_iterations": summary["krylov_iterations"],
            "peak_memory_bytes": summary["peak_memory_bytes"], "shares": summary["ranks_detail"]}


def median_record(records: list[dict]) -> dict:
    """The record of the median wall time, with every repeat's wall time."""
    done = [record for record in records if record["status"] == "complete"]
    if not done:
        return records[0]
    ordered = sorted(done, key=lambda record: record["process_s"])
    return {**ordered[len(ordered) // 2], "process_s_all": [record["process_s"] for record in done],
            "process_s": statistics.median(record["process_s"] for record in done)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, default=0.1)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="h = 0.15, 3 steps, 1 and 2 ranks")
    parser.add_argument("--viscoplastic", action="store_true", help="a Perzyna body (eta = 0.5, yield stress 1)")
    args = parser.parse_args()
    h, steps = (0.15, 3) if args.quick else (args.h, args.steps)
    records = [median_record([launch(ranks, h, steps, args.viscoplastic) for _ in range(args.repeats)])
               for ranks in args.ranks]
    base = records[0]
    for record in records:
        if record["status"] == "complete" and base["status"] == "complete":
            record["speedup"] = base["process_s"] / record["process_s"]
            record["loop_speedup"] = base["timings_s"]["time_loop"] / record["timings_s"]["time_loop"]
            record["largest_rank_memory_over_one_process"] = max(record["peak_memory_bytes"]) / max(
                base["peak_memory_bytes"])
    print(json.dumps({"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                                  "load_average": os.getloadavg()}, "h": h, "steps": steps,
                      "viscoplastic": args.viscoplastic, "runs": records},
                     indent=2))


if __name__ == "__main__":
    main()

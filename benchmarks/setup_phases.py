"""The set-up of the quarter ball at large sizes, phase by phase, with its peak memory: prints JSON.

For each mesh size h, one fresh process (watched: its resident memory sampled every 0.2 s, stopped past a
memory or time limit) builds the problem of ``examples/quarter_ball.toml`` (``vpcontact.build_problem``) and
times its phases: the mesh (``mesh_s``: the shape's nodes and tetrahedra, their orientation check, then the
scikit-fem mesh with its facet tables and the parts), the displacement space, the stiffness (its element
geometry included), the load vector, the contact surface, and the rest of the build (the Dirichlet conditions,
the checks of rigid motions, the initial state and its strains); its peak resident memory after the build
(getrusage), and with ``--steps N`` the peak of the whole process once ``vpcontact.solve`` has run N steps of
``--method`` (the ladder's rung "ball2M" is ``--h 0.0218 --steps 10``). The record names the processor, the
cores and the load average before and after.

    python benchmarks/setup_phases.py                      # h = 0.042: 300k dofs, the build only
    python benchmarks/setup_phases.py --h 0.0218 --steps 10  # 2M dofs, the build then 10 iterative steps
    python benchmarks/setup_phases.py --quick              # h = 0.3: seconds
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time
from pathlib import Path

from startup import processor  # noqa: E402 - this folder's module (the script runs from here)
from watched import watched  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"
QUICK = 0.3
#: (module, function) of vpcontact timed as one phase each, in the order the build calls them.
PHASES = {"mesh_tetrahedra": ("vpcontact.mesh.ball", "structured_tetrahedra"),
          "mesh_wrap": ("vpcontact.mesh.shapes", "_wrap"),
          "space": ("vpcontact.problem.build", "displacement_space"),
          "stiffness": ("vpcontact.problem.build", "stiffness"), "loads": ("vpcontact.problem.build", "LoadVector"),
          "contact_surface": ("vpcontact.problem.build", "contact_surface")}


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def timing(seconds: dict, name: str, function):
    """``function``, adding the seconds each call takes to ``seconds[name]``."""

    def timed(*args, **kwargs):
        started = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - started

    return timed


def run_inline(h: float, steps: int, method: str) -> dict:
    """Build (and with ``steps``, solve) the quarter ball at ``h`` in this process: its record."""
    import importlib

    import vpcontact

    seconds: dict[str, float] = {}
    for name, (module_name, attribute) in PHASES.items():
        module = importlib.import_module(module_name)
        setattr(module, attribute, timing(seconds, name, getattr(module, attribute)))
    overrides = {"mesh.h": h, "time.steps": max(steps, 1), "solver.method": method, "output.field_steps": "none",
                 "output.figures": False}
    case = vpcontact.load_case(EXAMPLE, overrides)
    problem = vpcontact.build_problem(case)
    built = time.perf_counter()
    timings = problem.timings  # the build's own, without importing it
    record = {"h": h, "dofs": int(problem.basis.N), "tetrahedra": int(problem.mesh.mesh.t.shape[1]),
              "contact_nodes": int(problem.surface.size), "stiffness_entries": int(problem.A.nnz),
              "build_s": timings["build"], "mesh_s": timings["mesh"], "assembly_s": timings["assembly"],
              "phases_s": seconds, "rest_of_build_s": timings["build"] - sum(seconds.values()),
              "build_peak_rss_mb": peak_rss_mb()}
    if steps:
        result = vpcontact.solve(problem, output={"field_steps": "none", "progress": False})
        record.update(steps=steps, method=result.method, status=result.status, solve_s=time.perf_counter() - built,
                      krylov_iterations=result.krylov_iterations,
                      timings_s={key: float(value) for key, value in result.timings.items()},
                      run_peak_rss_mb=peak_rss_mb())
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, nargs="+", default=[0.042], help="element edges (default: 0.042)")
    parser.add_argument("--quick", action="store_true", help=f"h = {QUICK} only")
    parser.add_argument("--steps", type=int, default=0, help="time steps solved after the build (default: none)")
    parser.add_argument("--method", default="iterative", help="solver.method of the steps (default: iterative)")
    parser.add_argument("--time-limit", type=float, default=3600.0, help="seconds before a run is stopped")
    parser.add_argument("--memory-limit", type=float, help="MB of resident memory before a run is stopped "
                        "(default: 80 %% of the memory available at its start)")
    parser.add_argument("--inline", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    levels = [QUICK] if args.quick else args.h
    if args.inline:
        print(json.dumps(run_inline(levels[0], args.steps, args.method)))
        return
    from vpcontact.memory import available_memory

    records = []
    for h in levels:
        limit = args.memory_limit or 0.8 * available_memory() / 2**20
        load = os.getloadavg()
        command = [sys.executable, __file__, "--inline", "--h", str(h), "--steps", str(args.steps),
                   "--method", args.method]
        status, stdout, stderr, stopped, wall, largest = watched(command, limit, args.time_limit, interval_s=0.2)
        record = {"h": h, "process_s": wall, "sampled_peak_rss_mb": largest, "processor": processor(),
                  "cores": os.cpu_count(), "load_average_before": load, "load_average_after": os.getloadavg()}
        if stopped or status != 0:
            record.update(status="stopped" if stopped else "error", message=stopped or stderr[-2000:])
        else:
            record.update(json.loads(stdout), status="complete")
        records.append(record)
        print(json.dumps(record), file=sys.stderr, flush=True)
    print(json.dumps(records, indent=1))


if __name__ == "__main__":
    main()

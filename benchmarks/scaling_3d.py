"""Sizes and speed in 3D: the quarter ball (examples/quarter_ball.toml) on a ladder of meshes, timed: prints JSON.

A sibling of scaling.py rather than a ``--dim 3`` of it: the 2D script runs the paper's h = k
sequence (steps grow with the level, mesh edge √2·h), this one keeps the example's load and its 11
steps and varies the mesh only, and records what decides how far 3D goes (contact dofs, the memory
guard's estimate against the measured peak, PARDISO's fill) and why a level stopped.

Each level and method runs in a fresh process (its peak memory is its own) watched by this one: a
run is stopped when its resident memory passes --memory-limit (default 80 % of the memory available
when it starts) or its wall time passes --time-limit (default 900 s); a method is not tried on finer
levels once a level of it did not complete. One record per level and method: DOFs, tetrahedra,
contact nodes and dofs, the setup stages (mesh, assembly, factorization, condensation), the time
loop, the solver's total and the whole process's wall time, Newton iterations (and the GMRES
iterations and LU factorizations of their systems), the peak RSS (after
building the problem, after the solver's setup, at the end), the condensed method's memory estimate
(``condensed_memory``), the size of the sparse factor (``factor_size``), status and message. With
--repeat R each completed run is repeated R times and the times and peak RSS are medians.

    python benchmarks/scaling_3d.py                        # every level; condensed, and full while it completes
    python benchmarks/scaling_3d.py --h 0.035 --method condensed --profile level.prof
    python benchmarks/scaling_3d.py --quick                # h = 0.3, both methods (seconds)
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import sys
from pathlib import Path

from watched import watched  # noqa: E402 - this folder's module (the script runs from here)

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"
#: Element edges of the ladder: 12 n³ tetrahedra with n = ceil(1.5 / h) (7.6k DOFs at 0.15, 1.5M at 0.025).
LEVELS = (0.15, 0.1, 0.07, 0.05, 0.035, 0.025)
QUICK = 0.3
METHODS = ("condensed", "iterative", "full")
STAGES = ("mesh", "assembly", "factorization", "condensation")


def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def run_level(h: float, method: str, steps: int | None = None, beta: float = 1.0) -> dict:
    """Solve the example on the mesh of edge h with ``method`` (``steps`` steps over its time span, the
    layer's β) in this process and return its record."""
    import vpcontact
    from vpcontact import build_problem
    from vpcontact.case.translate import output_options
    from vpcontact.solvers.condensed import condensed_memory
    from vpcontact.timeloop.loop import TimeLoop

    overrides = {"mesh.h": h, "solver.method": method, "output.field_steps": "none", "output.figures": False,
                 "contact.stiffness.beta": beta}
    case = vpcontact.load_case(EXAMPLE, {**overrides, **({"time.steps": steps} if steps else {})})
    problem = build_problem(case)
    rss_problem = peak_rss_mb()
    free = problem.free
    A, N = problem.A[free][:, free].tocsr(), problem.surface.operator[:, free].tocsr()
    record = {"h": h, "method": method, "beta": beta, "dofs": int(problem.basis.N), "free_dofs": int(free.size),
              "tetrahedra": int(problem.mesh.mesh.t.shape[1]), "contact_nodes": int(N.shape[0]),
              "contact_dofs": len(set(N.indices)), "steps": case.time.steps,
              "condensed_memory_mb": condensed_memory(N, A.shape[0]) / 2**20}
    try:
        loop = TimeLoop(problem, output_options(case.output))
    except vpcontact.CaseError as error:  # the memory guard, or a factorization that fails
        return {**record, "status": "refused", "message": str(error), "peak_rss_mb": peak_rss_mb()}
    rss_setup = peak_rss_mb()
    result = loop.run()
    timings = result.timings
    record.update({
        "status": result.status, "message": result.message,
        "setup_s": {k: timings.get(k, 0.0) for k in STAGES},
        "setup_total_s": timings["total"] - timings["time_loop"], "time_loop_s": timings["time_loop"],
        "total_s": timings["total"], "newton_iterations": int(result.series("newton_iterations").sum()),
        "linear_solves": int(result.linear_solves), "krylov_iterations": result.krylov_iterations,
        "newton_factorizations": result.newton_factorizations,
        "peak_rss_mb": peak_rss_mb(), "rss_after_problem_mb": rss_problem, "rss_after_setup_mb": rss_setup,
    })
    record["factor"] = factor_size(loop.solver, A)
    return record


def factor_size(solver, A) -> dict:
    """What the method's linear algebra holds: the condensed method's factor of A0 = A + Nᵀ r N in
    Schur mode on the contact dofs (PARDISO's supernodal storage, or SuperLU's L + U), the full
    method's factor of its Newton matrix (PARDISO's storage), or the iterative method's multigrid
    hierarchy (levels, operator complexity, hierarchies built)."""
    if solver.name == "iterative":
        amg = solver.linear
        return {"backend": amg.name, "matrix_nonzeros": int(A.nnz), "levels": amg.levels,
                "most_cg_iterations_per_solve": amg.most_iterations,
                "operator_complexity": amg.operator_complexity, "setups": amg.setups, "setup_s": amg.setup_time}
    if solver.name == "condensed":
        nonzeros, backend = solver.factorization.factor_nonzeros, solver.factorization.name
    else:
        backend = solver.linear.name
        nonzeros = solver.linear._pardiso.factor_nonzeros if backend == "pardiso" else \
            solver.linear._lu.L.nnz + solver.linear._lu.U.nnz
    return {"backend": backend, "matrix_nonzeros": int(A.nnz), "factor_nonzeros": int(nonzeros),
            "fill": nonzeros / A.nnz, "factor_mb": 8 * nonzeros / 2**20}


def in_subprocess(h: float, method: str, memory_limit_mb: float, time_limit_s: float, profile: str | None,
                  steps: int | None = None, beta: float = 1.0) -> dict:
    """One run of a level in a fresh process, with the whole process's wall time."""
    command = [sys.executable, __file__, "--h", str(h), "--method", method, "--beta", str(beta), "--inline"]
    command += ["--steps", str(steps)] if steps else []
    command += ["--profile", profile] if profile else []
    status, stdout, stderr, stopped, wall, _ = watched(command, memory_limit_mb, time_limit_s, interval_s=0.2)
    if stopped:
        return {"h": h, "method": method, "status": "stopped", "message": stopped, "process_s": wall}
    if status != 0:
        return {"h": h, "method": method, "status": "error", "message": stderr[-2000:], "process_s": wall}
    return {**json.loads(stdout), "process_s": wall}


def median_of(runs: list[dict]) -> dict:
    """The first run's record with its times and peak RSS replaced by the medians over ``runs``."""
    record = dict(runs[0])
    for key in ("setup_total_s", "time_loop_s", "total_s", "process_s", "peak_rss_mb"):
        record[key] = statistics.median(r[key] for r in runs)
    record["setup_s"] = {k: statistics.median(r["setup_s"][k] for r in runs) for k in STAGES}
    record["process_s_runs"] = [r["process_s"] for r in runs]
    record["repeats"] = len(runs)
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, help="one level: the element edge h (default: the ladder)")
    parser.add_argument("--quick", action="store_true", help=f"the level h = {QUICK} only (about 1,000 DOFs)")
    parser.add_argument("--method", choices=(*METHODS, "all"), default="all")
    parser.add_argument("--steps", type=int, help="time steps over the example's time span (default: its 11)")
    parser.add_argument("--beta", type=float, default=1.0, help="the layer's beta (default 1)")
    parser.add_argument("--full-up-to", type=float, default=0.0, help="coarsest h not run with the full method "
                        "(default 0: run it until a level does not complete)")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each completed level (medians reported)")
    parser.add_argument("--time-limit", type=float, default=900.0, help="seconds before a run is stopped")
    parser.add_argument("--memory-limit", type=float, help="MB of resident memory before a run is stopped "
                        "(default: 80 %% of the memory available at its start)")
    parser.add_argument("--profile", help="write the run's cProfile statistics to this file (one level)")
    parser.add_argument("--inline", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.inline:
        if args.profile:
            import cProfile

            profiler = cProfile.Profile()
            record = profiler.runcall(run_level, args.h, args.method, args.steps, args.beta)
            profiler.dump_stats(args.profile)
        else:
            record = run_level(args.h, args.method, args.steps, args.beta)
        print(json.dumps(record))
        return
    from vpcontact.memory import available_memory

    levels = [QUICK] if args.quick else [args.h] if args.h else list(LEVELS)
    methods = list(METHODS) if args.method == "all" else [args.method]
    given_up: dict[str, str] = {}
    records = []
    for h in levels:
        for method in methods:
            if method == "full" and h < args.full_up_to:
                continue
            if method in given_up:
                records.append({"h": h, "method": method, "status": "skipped", "message": given_up[method]})
                continue
            limit = args.memory_limit or 0.8 * available_memory() / 2**20
            run = (h, method, limit, args.time_limit)
            runs = [in_subprocess(*run, args.profile, args.steps, args.beta)]
            if runs[0]["status"] == "complete":
                runs += [in_subprocess(*run, None, args.steps, args.beta) for _ in range(args.repeat - 1)]
                runs = [r for r in runs if r["status"] == "complete"]
                record = median_of(runs)
            else:
                record = runs[0]
                given_up[method] = f"not run: h = {h} did not complete ({record['status']})"
            record["load_average"] = os.getloadavg()
            records.append(record)
            print(json.dumps(record), file=sys.stderr, flush=True)
    print(json.dumps(records, indent=1))


if __name__ == "__main__":
    main()

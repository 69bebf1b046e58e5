"""The 3D ladder of the "3D at the sizes users bring" issue: each rung by each method, against the cost model.

Rungs: the quarter ball of examples/quarter_ball.toml (24k, 71k, 300k dofs × 100 steps; 2M dofs × 10 steps) and
the user's punch of benchmarks/punch.py (a filleted steel cylinder made in gmsh, displacement-controlled cycles
that lift off the layer and press again: 30k dofs with 1.9k contact nodes and 136k with 5.2k, 60 steps). Each
run is a fresh process, watched for memory and time (watched.py); it records the sizes, the plan of the run
(``vpcontact check``'s prediction for every method, the method "auto" chooses and why, the predicted peak
memory), and what was measured: set-up stages, time loop, total, Newton/CG/GMRES iterations, peak resident
memory. The summary of a rung: the fastest method, the one "auto" chose and its time over the fastest, the
check's time (build, set-up and time loop: the run's ``timings_s.total``) and memory over the measured ones.

"auto" plans (its choice costs the rates' probe and, where a direct method may win, PARDISO's symbolic analysis:
the ``plan_s`` recorded) and then runs the method it chose, whose run by name is in the record: by default its time
is that run's plus ``plan_s``. It may switch method during the run (vpcontact.solvers.switch); ``--auto-runs`` runs
it for real, and its own time, its method at the end and its switch (``method_switch``) are the rung's.

    python benchmarks/ladder.py                          # every rung (hours)
    python benchmarks/ladder.py --rungs ball24k punch30k --repeats 3
    python benchmarks/ladder.py --rungs punch136k --auto-runs     # auto run for real, beside the named methods
    python benchmarks/ladder.py --quick                  # the punch at 7k dofs, 3 steps (the tests)

prints one JSON document: the machine and its load, one record per run, one summary per rung.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from watched import watched  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"
#: name -> (kind, size, steps): the quarter ball's element edge h, the punch's size name (punch.SIZES)
RUNGS = {
    "ball24k": ("ball", 0.1, 100), "ball71k": ("ball", 0.07, 100), "ball300k": ("ball", 0.042, 100),
    "punch30k": ("punch", "30k", 60), "punch136k": ("punch", "136k", 60), "ball2M": ("ball", 0.0218, 10),
}
QUICK = {"punch-quick": ("punch", "7k", 3)}
METHODS = ("condensed", "iterative")


def problem_of(kind: str, size, steps: int, method: str):
    """The composed problem of a rung for ``method``."""
    import vpcontact

    if kind == "ball":
        case = vpcontact.load_case(EXAMPLE, {"mesh.h": size, "time.steps": steps, "solver.method": method,
                                             "output.field_steps": "none", "output.figures": False})
        return vpcontact.build_problem(case)
    import punch

    return punch.punch_problem(*punch.SIZES[size], method=method, steps=steps, cycles=max(1, round(steps / 20)))[0]


def run_inline(kind: str, size, steps: int, method: str, solve: bool = True) -> dict:
    """One run in this process: its record (``solve`` False: the plan alone)."""
    import vpcontact
    from vpcontact.results.output_options import OutputOptions
    from vpcontact.timeloop.plan import free_operators, plan_run

    started = time.perf_counter()
    problem = problem_of(kind, size, steps, method)
    built = time.perf_counter()
    output = OutputOptions(field_steps="none")
    A, N = free_operators(problem)
    plan = plan_run(problem, output, A, N)  # what the run will plan (for "auto": its choice, timed)
    planned = time.perf_counter()
    sizes = {"kind": kind, "size": size, "steps": steps, "asked": method, "dofs": int(problem.basis.N),
             "free_dofs": int(problem.free.size), "contact_nodes": int(problem.surface.size),
             "build_s": built - started, "plan_s": planned - built, "predicted": plan.predicted,
             "predicted_time_s": plan.time_seconds, "predicted_peak_bytes": plan.memory_peak_bytes}
    if not solve:
        return {**sizes, "method": plan.method, "reason": plan.method_reason, "status": "planned"}
    result = vpcontact.solve(problem, output={"field_steps": "none", "progress": False})
    done = time.perf_counter()
    timings = {key: float(value) for key, value in result.timings.items()}
    return {**sizes, "method": result.method, "reason": result.method_reason, "method_switch": result.method_switch,
            "status": result.status, "solve_s": done - planned, "timings_s": timings,
            "newton_iterations": int(result.history["newton_iterations"].sum()),
            "linear_solves": result.linear_solves, "krylov_iterations": result.krylov_iterations,
            "newton_factorizations": result.newton_factorizations, "step_cuts": result.step_cuts,
            "peak_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}


def run(kind: str, size, steps: int, method: str, memory_limit_mb: float, time_limit_s: float,
        solve: bool = True) -> dict:
    """One run in a fresh process, watched (``solve`` False: the plan alone)."""
    command = [sys.executable, __file__, "--inline", kind, str(size), str(steps), method, "solve" if solve else "plan"]
    status, stdout, stderr, stopped, wall, largest = watched(command, memory_limit_mb, time_limit_s, interval_s=0.5)
    if stopped or status != 0:
        return {"kind": kind, "size": size, "steps": steps, "asked": method,
                "status": "stopped" if stopped else "error",
                "message": stopped or stderr[-2000:], "process_s": wall, "largest_rss_mb": largest}
    return {**json.loads(stdout), "process_s": wall, "largest_rss_mb": largest}


def median_run(records: list[dict]) -> dict:
    """The first record, its times the medians of ``records``'."""
    record = dict(records[0])
    if all(r["status"] == "complete" for r in records):
        record["solve_s"] = statistics.median(r["solve_s"] for r in records)
        record["process_s"] = statistics.median(r["process_s"] for r in records)
        record["process_s_runs"] = [r["process_s"] for r in records]
    record["repeats"] = len(records)
    return record


def summary(name: str, records: list[dict]) -> dict:
    """The rung's fastest method, auto's choice and its time over the fastest, the check's estimates over the
    measured."""
    done = {r["method"]: r for r in records if r.get("status") == "complete" and r["asked"] != "auto"}
    if not done:
        return {"rung": name, "fastest": None}
    fastest = min(done.values(), key=lambda r: r["process_s"])
    out = {"rung": name, "dofs": fastest["dofs"], "contact_nodes": fastest["contact_nodes"],
           "fastest": fastest["method"], "fastest_s": fastest["process_s"],
           "seconds": {method: r["process_s"] for method, r in done.items()}}
    auto = next((r for r in records if r["asked"] == "auto" and r.get("status") in ("complete", "planned")), None)
    if auto is not None and auto["status"] == "complete":  # run for real: its own time, switch included
        out.update(auto=auto["method"], auto_ran=True, auto_switch=auto["method_switch"],
                   auto_over_fastest=auto["process_s"] / fastest["process_s"])
    elif auto is not None and auto["method"] in done:  # planned: the run of the method it chose, plus the plan
        out.update(auto=auto["method"], auto_ran=False,
                   auto_over_fastest=(done[auto["method"]]["process_s"] + auto["plan_s"]) / fastest["process_s"])
    out["check_time_over_measured"] = {m: r["predicted_time_s"]["total"] / r["timings_s"]["total"]
                                       for m, r in done.items()}
    out["check_memory_over_peak"] = {m: r["predicted_peak_bytes"] / r["peak_rss_bytes"] for m, r in done.items()}
    return out


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--inline":
        kind, size, steps, method, mode = sys.argv[2:7]
        print(json.dumps(run_inline(kind, float(size) if kind == "ball" else size, int(steps), method, mode == "solve"),
                         default=float))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rungs", nargs="+", choices=sorted(RUNGS), default=list(RUNGS))
    parser.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS))
    parser.add_argument("--repeats", type=int, default=1, help="runs per method (the median is kept)")
    parser.add_argument("--memory-limit-mb", type=float, default=0.8 * os.sysconf("SC_PAGE_SIZE")
                        * os.sysconf("SC_PHYS_PAGES") / 2**20)
    parser.add_argument("--time-limit-s", type=float, default=1800.0)
    parser.add_argument("--quick", action="store_true", help="the punch at 7k dofs, 3 steps")
    parser.add_argument("--auto-runs", action="store_true", help="run auto for real (by default it only plans)")
    args = parser.parse_args()
    rungs = QUICK if args.quick else {name: RUNGS[name] for name in args.rungs}
    records, summaries = [], []
    for name, (kind, size, steps) in rungs.items():
        rung = []
        for method in (*args.methods, "auto"):
            repeats = 1 if method == "auto" else args.repeats
            solve = method != "auto" or args.auto_runs
            rung.append(median_run([run(kind, size, steps, method, args.memory_limit_mb, args.time_limit_s, solve)
                                    for _ in range(repeats)]))
            print(json.dumps({"rung": name, **rung[-1]}, default=float), file=sys.stderr)
        records += [{"rung": name, **r} for r in rung]
        summaries.append(summary(name, rung))
    print(json.dumps({"machine": {"platform": platform.platform(), "processor": platform.processor(),
                                  "cores": os.cpu_count(), "load_average": os.getloadavg()},
                      "runs": records, "summaries": summaries}, indent=1, default=float))


if __name__ == "__main__":
    main()

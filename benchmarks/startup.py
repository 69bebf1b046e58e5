"""Start-up and outputs, timed from outside: prints JSON.

- ``vpcontact --help`` and ``vpcontact run`` of a tiny case (examples/paper_ball.toml with mesh.h = 0.25,
  11 steps), whole processes: the median wall time of ``--repeat`` runs (and of ``python -c pass``, the
  interpreter alone);
- the paper's example at about 30,000 DOFs (mesh.h = 0.011, 141 steps, β = 0, the example's four field
  steps), built in and read from a gmsh 2.2 file (written once by ``vpcontact.mesh.gmsh.write_mesh``):
  the median wall time of whole ``vpcontact run`` processes, and of each phase of such a run in a
  child process: importing what ``run`` imports, the case, the mesh, the assembly, the factorization
  and condensation, the time loop, then each output (case.resolved.toml, history.csv, contact.csv, the
  VTU files with their PVD, solution.npz, summary.json), and what a run writes only when asked or due:
  the figures (``output.figures``, matplotlib's import included) and one checkpoint.

The record names the processor (/proc/cpuinfo), the cores and the load average before and after.

    python benchmarks/startup.py [--repeat 5] [--quick]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_ball.toml"
TINY = {"mesh.h": 0.25, "time.steps": 11}
LARGE = {"mesh.h": 0.011, "time.steps": 141, "contact.stiffness.beta": 0}
QUICK_LARGE = {"mesh.h": 0.1, "time.steps": 11, "contact.stiffness.beta": 0}


def processor() -> str:
    """The model name of the first processor in /proc/cpuinfo (else what platform says)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


#: The environment of the timed processes: Python may cache the bytecode it compiles, as it has for an
#: installed package (with PYTHONDONTWRITEBYTECODE set, every run would compile vpcontact again: 0.3 s).
ENVIRONMENT = {name: value for name, value in os.environ.items() if name != "PYTHONDONTWRITEBYTECODE"}


def wall(command: list[str], repeat: int) -> dict:
    """Median, min and max wall seconds of ``repeat`` runs of ``command`` (each must exit 0), after one run
    that is not timed (it compiles what Python had not cached)."""
    subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                   env=ENVIRONMENT)
    times = []
    for _ in range(repeat):
        started = time.perf_counter()
        done = subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              env=ENVIRONMENT)
        times.append(time.perf_counter() - started)
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(command)} exited {done.returncode}: {done.stderr.decode()[-2000:]}")
    return {"median_s": statistics.median(times), "min_s": min(times), "max_s": max(times), "runs": repeat}


def run_command(case: Path, overrides: dict, out: Path) -> list[str]:
    """``vpcontact run case --set ... --out out --overwrite --quiet``."""
    sets = [item for key, value in overrides.items() for item in ("--set", f"{key}={value}")]
    return [sys.executable, "-m", "vpcontact.cli", "run", str(case), *sets, "--out", str(out), "--overwrite", "--quiet"]


def phases(case_path: str, overrides: dict, out: Path) -> dict:
    """The phases of one run of the case, in this process (seconds)."""
    started = time.perf_counter()
    import vpcontact.cli  # noqa: F401  (what `vpcontact run` imports)
    from vpcontact.io import checkpoint, contact_csv, figures, history_csv, solution, summary, vtu
    from vpcontact.io.run import write_resolved_case
    from vpcontact.case.load import load_case
    from vpcontact import build_problem
    from vpcontact.case.translate import output_options
    from vpcontact.drivers.rundir import run  # noqa: F401
    from vpcontact.timeloop.loop import TimeLoop

    seconds = {"import": time.perf_counter() - started}

    def timed(name, action):
        begun = time.perf_counter()
        value = action()
        seconds[name] = time.perf_counter() - begun
        return value

    case = timed("case", lambda: load_case(case_path, overrides))
    problem = build_problem(case)
    seconds |= {"mesh": problem.timings["mesh"], "assembly": problem.timings["assembly"]}
    loop = TimeLoop(problem, output_options(case.output))
    result = loop.run(progress=False)
    seconds |= {name: result.timings.get(name, 0.0) for name in ("factorization", "condensation", "time_loop")}
    out.mkdir(parents=True, exist_ok=True)
    timed("case.resolved.toml", lambda: write_resolved_case(case.to_toml(), out))
    timed("history.csv", lambda: history_csv.write(result, out))
    timed("contact.csv", lambda: contact_csv.write(result, out))
    timed("fields", lambda: vtu.write(result, out))  # the VTU and PVD files
    timed("solution.npz", lambda: solution.write(result, out))
    timed("summary.json", lambda: summary.write(result, out))
    seconds["outputs"] = sum(seconds[name] for name in ("case.resolved.toml", "history.csv", "contact.csv", "fields",
                                                        "solution.npz", "summary.json"))
    timed("figures (if asked for)", lambda: figures.write(result, out))
    timed("checkpoint (if due)", lambda: checkpoint.save(loop, out))
    return {"dofs": int(result.dofs), "contact_nodes": int(result.contact_nodes), "steps": result.steps,
            "field_steps": len(result.fields), "seconds": seconds}


def phase_medians(case: Path, overrides: dict, repeat: int, folder: Path) -> dict:
    """``phases`` in ``repeat`` child processes; the median of each phase."""
    records = []
    for k in range(repeat):
        command = [sys.executable, __file__, "--phases-of", str(case), json.dumps(overrides), str(folder / f"p{k}")]
        done = subprocess.run(command, capture_output=True, text=True, env=ENVIRONMENT)
        if done.returncode != 0:
            raise SystemExit(f"phases of {case}: {done.stderr[-2000:]}")
        records.append(json.loads(done.stdout))
    names = records[0]["seconds"]
    return {**{key: records[0][key] for key in ("dofs", "contact_nodes", "steps", "field_steps")},
            "phases_s": {name: statistics.median(r["seconds"][name] for r in records) for name in names}}


def gmsh_case(folder: Path, overrides: dict) -> tuple[Path, dict]:
    """The example's case with its half disc written to a gmsh 2.2 file (mesh.file), and its overrides."""
    import tomllib

    import tomli_w

    from vpcontact.mesh import half_disc
    from vpcontact.mesh.gmsh import write_mesh

    write_mesh(half_disc(overrides["mesh.h"]), folder / "half_disc.msh")
    case = tomllib.loads(EXAMPLE.read_text())
    case["mesh"] = {"file": str(folder / "half_disc.msh")}
    (folder / "case.toml").write_text(tomli_w.dumps(case))
    return folder / "case.toml", {key: value for key, value in overrides.items() if not key.startswith("mesh.")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs of each command (the median is reported)")
    parser.add_argument("--quick", action="store_true", help="one run of each, the large case at mesh.h = 0.1")
    parser.add_argument("--phases-of", nargs=3, metavar=("CASE", "OVERRIDES", "OUT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.phases_of:
        case, overrides, out = args.phases_of
        print(json.dumps(phases(case, json.loads(overrides), Path(out))))
        return
    repeat, large = (1, QUICK_LARGE) if args.quick else (args.repeat, LARGE)
    record = {"processor": processor(), "cores": os.cpu_count(), "load_average_before": os.getloadavg(),
              "python": platform.python_version(), "repeat": repeat}
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        record["python_pass_s"] = wall([sys.executable, "-c", "pass"], repeat)
        record["help_s"] = wall([sys.executable, "-m", "vpcontact.cli", "--help"], repeat)
        record["tiny_run"] = {"case": str(EXAMPLE.name), "overrides": TINY,
                              **wall(run_command(EXAMPLE, TINY, folder / "tiny"), repeat)}
        from_file, file_overrides = gmsh_case(folder, large)
        for name, case, overrides in (("built_in_mesh", EXAMPLE, large), ("gmsh_file", from_file, file_overrides)):
            record[name] = {"case": str(case.name), "overrides": overrides,
                            "whole_run": wall(run_command(case, overrides, folder / name), repeat),
                            **phase_medians(case, overrides, repeat, folder / f"{name}-phases")}
    record["load_average_after"] = os.getloadavg()
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()

"""The speed targets of "fast to the physical limit", measured on this machine: prints JSON.

Each target is measured by the benchmark that owns it, in fresh processes, and compared with its
limit; the record names the machine (platform, processor, cores, memory, versions) and the load
average before and after, since a loaded machine makes every time longer.

| target | measured by |
|---|---|
| `vpcontact --help` ≤ 0.3 s, `vpcontact run` of a tiny case ≤ 0.8 s | startup.py (medians of whole processes) |
| writing the outputs ≤ the solve (30k DOFs, 141 steps) | startup.py (the phases of that run) |
| the finest level 1/512, β = ±1: end to end ≤ 10 s, time loop ≤ 3 s | scaling.py --level 512 (medians) |
| assembly ≤ 1 s at 475k triangles | scaling.py's assembly stage at 1/512 (470,252 triangles) |
| the finest level, viscoplastic ≤ 60 s | scaling.py --level 512 --viscoplastic |
| ≥ 50× GetFEM end to end (1/128, 141 steps) | peer_getfem.py (when GetFEM is installed) |
| `vpcontact reproduce` ≤ 60 s, `--quick` ≤ 12 s | whole processes |

    python benchmarks/targets.py [--runs 3] [--skip NAME ...]   # about 12 minutes with GetFEM
    python benchmarks/targets.py --quick    # every measurement at a small size, no verdicts (the tests)

``--quick`` runs each benchmark at a coarse level (1/32, the tiny start-up case, GetFEM's peer at 1/32,
no reproduction): the record has the same shape, with ``met`` null, since the limits are for the full
sizes.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: The measurements, in the order they run; ``--skip`` takes these names.
MEASUREMENTS = ("startup", "finest", "viscoplastic", "peer", "reproduce")


def script(name: str, *arguments: str) -> object:
    """The JSON a benchmark script of this folder prints (its last stdout document)."""
    done = subprocess.run([sys.executable, str(HERE / name), *arguments], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"benchmarks/{name} {' '.join(arguments)} failed:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout)


def target(name: str, measured: float | None, limit: float, *, at_least: bool = False, unit: str = "s",
           command: str, quick: bool, note: str = "") -> dict:
    """One target's record: the measured value against its limit (≤, or ≥ with ``at_least``)."""
    met = None
    if measured is not None and not quick:
        met = bool(measured >= limit) if at_least else bool(measured <= limit)
    return {"target": name, "limit": limit, "relation": ">=" if at_least else "<=", "unit": unit,
            "measured": measured, "met": met, "command": command, **({"note": note} if note else {})}


def startup_targets(runs: int, quick: bool) -> tuple[list[dict], dict]:
    record = script("startup.py", *(["--quick"] if quick else ["--repeat", str(runs)]))
    phases = record["built_in_mesh"]["phases_s"]
    solve = sum(phases[name] for name in ("mesh", "assembly", "factorization", "condensation", "time_loop"))
    command = "python benchmarks/startup.py"
    return [
        target("vpcontact --help", record["help_s"]["median_s"], 0.3, command=command, quick=quick),
        target("vpcontact run of a tiny case", record["tiny_run"]["median_s"], 0.8, command=command, quick=quick),
        target("writing the outputs over the solve (30k DOFs, 141 steps)", phases["outputs"] / solve, 1.0,
               unit="ratio", command=command, quick=quick,
               note=f"outputs {phases['outputs']:.3f} s, solve {solve:.3f} s"),
    ], record


def scaling_runs(level: int, runs: int, *options: str) -> list[dict]:
    """``runs`` records of scaling.py at one level (condensed), each in a fresh process."""
    return [script("scaling.py", "--level", str(level), "--method", "condensed", *options)[0] for _ in range(runs)]


def median_of(records: list[dict], *keys: str) -> float:
    values = []
    for record in records:
        for key in keys:
            record = record[key]
        values.append(record)
    return statistics.median(values)


def finest_targets(runs: int, quick: bool) -> tuple[list[dict], dict]:
    level = 32 if quick else 512
    raw, targets = {}, []
    for beta in (1.0, -1.0):
        records = raw[f"beta={beta:g}"] = scaling_runs(level, runs, "--beta", str(beta))
        command = f"python benchmarks/scaling.py --level {level} --method condensed --beta {beta:g}"
        targets += [
            target(f"1/{level}, β = {beta:g}, end to end (mesh to the last step)", median_of(records, "total_s"), 10.0,
                   command=command, quick=quick),
            target(f"1/{level}, β = {beta:g}, time loop", median_of(records, "time_loop_s"), 3.0, command=command,
                   quick=quick),
        ]
    both = raw["beta=1"] + raw["beta=-1"]
    targets.append(target(f"assembly at 1/{level} ({both[0]['elements']:,} triangles)",
                          median_of(both, "setup_s", "assembly"), 1.0,
                          command=f"python benchmarks/scaling.py --level {level} --method condensed", quick=quick))
    return targets, raw


def viscoplastic_targets(runs: int, quick: bool) -> tuple[list[dict], dict]:
    level = 32 if quick else 512
    records = scaling_runs(level, runs, "--viscoplastic")
    command = f"python benchmarks/scaling.py --level {level} --method condensed --viscoplastic"
    return [target(f"1/{level}, viscoplastic, end to end (mesh to the last step)", median_of(records, "total_s"), 60.0, command=command,
                   quick=quick, note=f"{records[0]['linear_solves']} solves, {records[0]['steps']} steps")], records


def peer_targets(runs: int, quick: bool) -> tuple[list[dict], dict]:
    options = ["--level", "32", "--steps", "11", "--runs", "1"] if quick else ["--runs", str(runs)]
    record = script("peer_getfem.py", *options)
    note = "" if record["getfem"] is not None else "GetFEM is not installed here: vpcontact alone was timed"
    return [target(f"GetFEM / vpcontact end to end ({record['level']}, {record['steps']} steps)", record["ratio"],
                   50.0, at_least=True, unit="ratio", command="python benchmarks/peer_getfem.py", quick=quick,
                   note=note)], record


def reproduce_targets(runs: int, quick: bool) -> tuple[list[dict], dict]:
    """Whole `vpcontact reproduce` processes into fresh directories (one run each: they take minutes)."""
    if quick:
        return [], {"skipped": "--quick: the reproduction takes half a minute at least"}
    raw, targets = {}, []
    for name, options, limit in (("full", [], 60.0), ("quick", ["--quick"], 12.0)):
        with tempfile.TemporaryDirectory(prefix="targets_reproduce_") as scratch:
            command = [sys.executable, "-m", "vpcontact.cli", "reproduce", "--out", str(Path(scratch) / "out"),
                       *options]
            started = time.perf_counter()
            done = subprocess.run(command, capture_output=True, text=True)
            wall = time.perf_counter() - started
        if done.returncode != 0:
            raise SystemExit(f"vpcontact reproduce {' '.join(options)} failed:\n{done.stderr[-3000:]}")
        raw[name] = {"wall_s": wall}
        targets.append(target(f"vpcontact reproduce {' '.join(options)}".strip(), wall, limit,
                              command=f"vpcontact reproduce --out DIR {' '.join(options)}".strip(), quick=quick))
    return targets, raw


MEASURE = {"startup": startup_targets, "finest": finest_targets, "viscoplastic": viscoplastic_targets,
           "peer": peer_targets, "reproduce": reproduce_targets}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="processes per timing (medians; the viscoplastic run "
                                                            "and the reproductions run once)")
    parser.add_argument("--skip", nargs="+", choices=MEASUREMENTS, default=[], help="measurements left out")
    parser.add_argument("--quick", action="store_true", help="every measurement at a small size, no verdicts")
    args = parser.parse_args()
    from vpcontact.reproduction.machine import machine

    record = {"machine": machine(), "load_average_before": list(os.getloadavg()), "quick": args.quick,
              "targets": [], "measurements": {}}
    for name in MEASUREMENTS:
        if name in args.skip:
            continue
        runs = 1 if args.quick or name == "viscoplastic" else args.runs
        started = time.perf_counter()
        targets, raw = MEASURE[name](runs, args.quick)
        record["targets"] += targets
        record["measurements"][name] = {"seconds": time.perf_counter() - started, "records": raw}
        print(json.dumps(targets), file=sys.stderr, flush=True)
    record["load_average_after"] = list(os.getloadavg())
    verdicts = [t["met"] for t in record["targets"] if t["met"] is not None]
    record["met"] = f"{sum(verdicts)} of {len(verdicts)}"
    print(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()

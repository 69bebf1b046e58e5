"""How good is ``vpcontact check``'s time estimate? Each configuration is checked, then run, in a fresh
process; prints one JSON record per configuration: the sizes, the estimate by stage, the measured
stages (build = mesh + assembly + checks, solver setup, time loop, total) and estimate / measured. The
build measured is the check's: the first in its process, as a fresh ``vpcontact run``'s is (the run's own
build, a second one in the same process, is faster: "second build").

The same records are the data :mod:`vpcontact.solvers.time_estimate`'s constants were fitted to (its docstring).

    python benchmarks/check_estimate.py                 # every configuration (minutes)
    python benchmarks/check_estimate.py --only quarter_ball
    python benchmarks/check_estimate.py --fit records.jsonl ...   # the constants of vpcontact.solvers.time_estimate
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: (name, example, overrides): the examples on several meshes, with each method where it runs in seconds.
CONFIGURATIONS = [
    *[(f"paper_ball h={h} {method}", "paper_ball.toml", {"mesh.h": h, "solver.method": method})
      for method, sizes in (("condensed", (0.025, 0.0125, 0.00625, 0.003125)), ("full", (0.025, 0.0125, 0.00625)),
                            ("iterative", (0.0125, 0.00625)))
      for h in sizes],
    *[(f"viscoplastic_ball h={h} condensed", "viscoplastic_ball.toml", {"mesh.h": h, "solver.method": "condensed"})
      for h in (0.0125, 0.00625)],
    *[(f"quarter_ball h={h} {method}", "quarter_ball.toml", {"mesh.h": h, "solver.method": method})
      for method, sizes in (("condensed", (0.15, 0.1, 0.07)), ("iterative", (0.15, 0.1, 0.07)), ("full", (0.15, 0.1)))
      for h in sizes],
]
#: Configurations not in the fit, between its sizes: how good the estimate is (``--validation``).
VALIDATION = [
    ("paper_ball h=0.0044 auto", "paper_ball.toml", {"mesh.h": 0.0044}),
    ("viscoplastic_ball h=0.0088 auto", "viscoplastic_ball.toml", {"mesh.h": 0.0088}),
    ("quarter_ball h=0.085 auto", "quarter_ball.toml", {"mesh.h": 0.085}),
    ("quarter_ball h=0.085 iterative", "quarter_ball.toml", {"mesh.h": 0.085, "solver.method": "iterative"}),
    ("viscoplastic quarter_ball h=0.12 auto", "quarter_ball.toml",
     {"mesh.h": 0.12, "material.viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}}),
]
STAGES = ("build", "solver setup", "time loop", "total")


def measure(example: str, overrides: dict) -> dict:
    """Check, then solve, the example with ``overrides`` (no fields or figures written) in this process."""
    import vpcontact
    from vpcontact.drivers.check import check_case

    case = vpcontact.load_case(EXAMPLES / example, {**overrides, "output.figures": False})
    checked = check_case(case)
    result = vpcontact.solve(case)
    timings = result.timings
    # the build of a fresh process is the check's (the first in this process); the run's own is a second one
    build, setup = checked.time_seconds["build"], timings["total"] - timings["build"] - timings["time_loop"]
    measured = {"build": build, "solver setup": setup, "time loop": timings["time_loop"],
                "total": build + setup + timings["time_loop"], "second build": timings["build"]}
    history = "viscoplastic" in example or "material.viscoplastic" in overrides
    return {"dim": checked.dim, "history": history, "free_dofs": checked.free_dofs,
            "contact_nodes": checked.contact_nodes, "steps": checked.steps, "method": result.method,
            "estimate_s": checked.time_seconds, "measured_s": measured,
            "ratio": {stage: checked.time_seconds[stage] / measured[stage] for stage in STAGES},
            "newton_iterations": int(result.series("newton_iterations").sum()), "linear_solves": result.linear_solves,
            "load_average": os.getloadavg()[0]}


def fit(records: list[dict]) -> None:
    """Print the Rate of each (method, dimension) fitted to the elastic ``records`` (least squares of the logarithms
    of the setup and of the time loop per step, each over the run's build, against log(n / 10⁵), over the runs of
    at least MIN_FIT_DOFS free dofs) and the spread of the fit, and HISTORY_FACTOR: the geometric mean, over the
    viscoplastic records, of their time loop per step over the elastic condensed one's at the same size (each
    over its build)."""
    import numpy as np

    def build(r):
        return r["estimate_s"]["build"]  # the check's, measured

    def setup(r):
        return r["measured_s"]["solver setup"] / build(r)

    def per_step(r):
        return r["measured_s"]["time loop"] / r["steps"] / build(r)

    families = {}
    for r in records:
        if not r["history"] and r["free_dofs"] >= MIN_FIT_DOFS:
            families.setdefault((r["method"], r["dim"]), []).append(r)
    for (method, dim), runs in sorted(families.items()):
        x = np.log([r["free_dofs"] / 1e5 for r in runs])
        p, log_a = np.polyfit(x, np.log([setup(r) for r in runs]), 1)
        q, log_b = np.polyfit(x, np.log([per_step(r) for r in runs]), 1)
        fitted = [build(r) * (np.exp(log_a + p * xi) + r["steps"] * np.exp(log_b + q * xi)) for r, xi in zip(runs, x)]
        spread = [f / (r["measured_s"]["solver setup"] + r["measured_s"]["time loop"]) for f, r in zip(fitted, runs)]
        print(f'    ("{method}", {dim}): Rate(a={np.exp(log_a):.3g}, p={p:.2f}, b={np.exp(log_b):.3g}, q={q:.2f}),'
              f"  # {len(runs)} runs, {min(r['free_dofs'] for r in runs)}-{max(r['free_dofs'] for r in runs)} "
              f"free dofs; "
              f"fitted / measured setup + loop: {', '.join(f'{s:.2f}' for s in spread)}")
    elastic = {(r["dim"], r["free_dofs"]): r for r in records if not r["history"] and r["method"] == "condensed"}
    ratios = [per_step(r) / per_step(elastic[r["dim"], r["free_dofs"]]) for r in records
              if r["history"] and r["method"] == "condensed" and (r["dim"], r["free_dofs"]) in elastic]
    print(f"HISTORY_FACTOR = {np.exp(np.mean(np.log(ratios))):.2g}  # {len(ratios)} sizes: "
          f"{', '.join(f'{ratio:.2g}' for ratio in ratios)}")


#: The smallest runs fitted (below, fixed costs that the power laws do not describe dominate).
MIN_FIT_DOFS = 5000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="the configurations whose name contains this")
    parser.add_argument("--validation", action="store_true", help="the configurations not in the fit")
    parser.add_argument("--fit", nargs="+", metavar="RECORDS", help="fit the constants to these records (JSON lines)")
    parser.add_argument("--inline", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.fit:
        fit([json.loads(line) for name in args.fit for line in Path(name).read_text().splitlines()
             if "error" not in json.loads(line)])
        return
    if args.inline:
        print(json.dumps(measure(args.inline[0], json.loads(args.inline[1]))))
        return
    for name, example, overrides in VALIDATION if args.validation else CONFIGURATIONS:
        if args.only not in name:
            continue
        process = subprocess.run([sys.executable, __file__, "--inline", example, json.dumps(overrides)],
                                 capture_output=True, text=True)
        record = json.loads(process.stdout) if process.returncode == 0 else {"error": process.stderr[-1000:]}
        print(json.dumps({"name": name, **record}), flush=True)


if __name__ == "__main__":
    main()

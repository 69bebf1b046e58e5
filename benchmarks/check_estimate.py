"""How good is ``vpcontact check``'s time estimate? Each configuration is checked, then run, in a fresh
process; prints one JSON record per configuration: the sizes, the estimate by stage, the measured
stages (build = mesh + assembly + checks, solver setup, time loop, total) and estimate / measured. The
build measured is the check's: the first in its process, as a fresh ``vpcontact run``'s is (the run's own
build, a second one in the same process, is faster: "second build").

The estimate is the cost model's (:mod:`vpcontact.solvers.cost`); benchmarks/ladder.py checks it, and "auto", on the
3D sizes users bring, this script on the examples (2D and 3D, elastic and viscoplastic, every method).

    python benchmarks/check_estimate.py                 # every configuration (minutes)
    python benchmarks/check_estimate.py --only quarter_ball
    python benchmarks/check_estimate.py --validation    # the configurations between those sizes
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
#: More configurations, between those sizes and on a viscoplastic 3D body (``--validation``).
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="the configurations whose name contains this")
    parser.add_argument("--validation", action="store_true", help="the configurations not in the fit")
    parser.add_argument("--inline", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
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

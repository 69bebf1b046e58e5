"""The paper's convergence sequence h = k = 1/4, …, 1/512 (its Fig. 10), timed: prints JSON.

Each level runs examples/paper_ball.toml in a fresh process (so its peak memory is its own) with
the level rule of `vpcontact.reproduction.plan.level_overrides` (time.steps = round(1.1 / h), the
half disc meshed with element edge √2·h), which gives the paper's sizes (about 472,000 DOFs and
470,000 triangles at h = 1/512; an edge of h itself would give twice as many). One record per level
and method: DOFs, contact nodes, steps, the setup stages (mesh, assembly, factorization,
condensation), the time loop, the total, Newton iterations, the peak RSS, and the full/condensed time
ratio where both ran. ``--viscoplastic``: the same runs with the Perzyna law of
examples/viscoplastic_ball.toml (η = 0.5, yield stress 3), so that u is computed at every step (σ_n
feeds z_{n+1}).

    python benchmarks/scaling.py                      # every level, condensed; full up to 1/128
    python benchmarks/scaling.py --level 512 --beta -1 --method condensed
    python benchmarks/scaling.py --level 512 --method condensed --viscoplastic   # one solve per step
    python benchmarks/scaling.py --dim 3 [options]    # the 3D quarter-ball ladder: scaling_3d.py's options
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_ball.toml"
LEVELS = (4, 8, 16, 32, 64, 128, 256, 512)
#: The finest level at which the full method is run by default (it takes about 10 minutes there).
FULL_UP_TO = 128


#: The viscoplastic law of examples/viscoplastic_ball.toml (``--viscoplastic``).
PERZYNA = {"material.viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}}


def run_level(level: int, method: str, beta: float, viscoplastic: bool = False) -> dict:
    """Solve one level in this process and return its record."""
    import vpcontact
    from vpcontact.reproduction.plan import level_overrides

    h = 1.0 / level
    case = vpcontact.load_case(EXAMPLE, {
        **level_overrides(level), "solver.method": method,
        "contact.stiffness.beta": beta, "output.field_steps": "none", **(PERZYNA if viscoplastic else {})})
    result = vpcontact.solve(case)
    timings = result.timings
    setup = sum(timings.get(k, 0.0) for k in ("mesh", "assembly", "factorization", "condensation"))
    return {
        "level": f"1/{level}", "h": h, "k": 1.1 / case.time.steps, "method": result.method, "beta": beta,
        "viscoplastic": viscoplastic, "linear_solves": int(result.linear_solves),
        "krylov_iterations": int(result.krylov_iterations),
        "status": result.status, "dofs": int(result.dofs), "elements": int(result.elements),
        "contact_nodes": int(result.contact_nodes), "steps": result.steps,
        "setup_s": {k: timings.get(k, 0.0) for k in ("mesh", "assembly", "factorization", "condensation")},
        "setup_total_s": setup, "time_loop_s": timings["time_loop"], "total_s": timings["total"],
        "per_step_s": timings["time_loop"] / max(result.steps, 1),
        "newton_iterations": int(result.series("newton_iterations").sum()),
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "K_probe_final": float(result.series("K_probe")[-1]),
    }


def in_subprocess(level: int, method: str, beta: float, viscoplastic: bool) -> dict:
    command = [sys.executable, __file__, "--level", str(level), "--method", method, "--beta", str(beta), "--inline",
               *(["--viscoplastic"] if viscoplastic else [])]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        return {"level": f"1/{level}", "method": method, "beta": beta, "status": "error", "error": done.stderr[-2000:]}
    return json.loads(done.stdout)


def main() -> None:
    dimension = argparse.ArgumentParser(add_help=False)
    dimension.add_argument("--dim", type=int, choices=(2, 3), default=2)
    known, rest = dimension.parse_known_args()
    if known.dim == 3:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        import scaling_3d

        sys.argv = [scaling_3d.__file__, *rest]
        scaling_3d.main()
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dim", type=int, choices=(2,), default=2, help="2 (this ladder) or 3 (scaling_3d.py's)")
    parser.add_argument("--level", type=int, choices=LEVELS, help="one level 1/LEVEL (default: all)")
    parser.add_argument("--method", choices=("condensed", "full", "iterative", "both"), default="both")
    parser.add_argument("--beta", type=float, default=1.0)
    parser.add_argument("--full-up-to", type=int, default=FULL_UP_TO, help="finest level for the full method")
    parser.add_argument("--viscoplastic", action="store_true", help="with the Perzyna law of viscoplastic_ball.toml")
    parser.add_argument("--inline", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.inline:
        print(json.dumps(run_level(args.level, args.method, args.beta, args.viscoplastic)))
        return
    levels = [args.level] if args.level else LEVELS
    records = []
    for level in levels:
        methods = ["condensed", "full"] if args.method == "both" else [args.method]
        if args.method == "both" and args.level is None and level > args.full_up_to:
            methods = ["condensed"]
        pair = {m: in_subprocess(level, m, args.beta, args.viscoplastic) for m in methods}
        if {"condensed", "full"} <= set(pair) and all(r.get("status") == "complete" for r in pair.values()):
            pair["full"]["full_over_condensed"] = pair["full"]["total_s"] / pair["condensed"]["total_s"]
        records += list(pair.values())
        print(json.dumps(list(pair.values())), file=sys.stderr, flush=True)
    print(json.dumps(records, indent=1))


if __name__ == "__main__":
    main()

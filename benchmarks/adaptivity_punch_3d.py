"""Adapting during the run against uniform refinement on a 3D flat punch: prints JSON (docs/adaptivity.md,
"Adapting during the run, measured").

The block 1 × 1 × 1/2 on rollers at x = 0 and y = 0, pressed by the traction (0, 0, −20 t) on its top onto a flat
rigid punch under x < 1/2 of its bottom (initial gap (x − 1/2)⁺, a 45° chamfer; K ≡ 0, g = 10⁻³: Signorini's problem
with a thin gap), the paper's 11 steps: the 3D version of the punch of benchmarks/effectivity.py, whose pressure
grows like r^(−1/2) towards the punch's edge, here a line. It is solved on a uniform reference mesh (h = 1/64 by
default, four times finer than the finest uniform mesh compared), on the uniform meshes --levels, and in runs that
adapt during the run (adapt.mode = "run") from h = 1/4 with each of --tolerances. For each: the dofs, the energy
error E(t) = ‖I_ref u_h − u_ref‖_E at t = 0.5 and 1.1 on the reference mesh, and the wall time; for the adaptive
runs also that of one run on their last mesh, the ratio, and their smallest element edge at the punch's edge
(against the reference's h: a run finer there than the reference has its error there missed). Then the dofs
the adaptive runs need to reach each uniform mesh's E(1.1) (log–log interpolation between the two runs around
it) and their ratio to that mesh's dofs.

    python benchmarks/adaptivity_punch_3d.py                    # 1/4, 1/8, 1/16 against 1/64
    python benchmarks/adaptivity_punch_3d.py --levels 4 8 --reference 16 --tolerances 1.5 1   # seconds
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

import vpcontact
from vpcontact import adapt, build_problem
from vpcontact.mesh.simplex import longest_edges
from vpcontact.reproduction.records import dofs_reaching

from adaptivity import Reference, TIMES, complete, log


def punch(level: int):
    """The 3D punch on the block meshed with h = 1/level, its fields kept at the compared steps."""
    return vpcontact.load_case({
        "mesh": {"shape": "block", "h": 1.0 / level, "width": 1.0, "depth": 1.0, "height": 0.5},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}, {"part": "front", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", "-20*t"]}]},
        "contact": {"part": "bottom", "gap": "max(x - 0.5, 0)", "g": 1e-3, "normal": [0, 0, -1],
                    "stiffness": {"law": "constant", "value": 0.0}},
        "time": {"T": 1.1, "steps": 11},
        "output": {"field_steps": list(TIMES), "progress": False}})


def finest_at_the_edge(mesh) -> float:
    """The shortest longest-edge of the tetrahedra within 0.05 of the punch's edge (x = 1/2, z = 0)."""
    p, t = mesh.mesh.p, mesh.mesh.t
    x, _, z = p[:, t].mean(axis=1)
    near = np.hypot(x - 0.5, z) < 0.05
    return float(longest_edges(p, t[:, near]).min())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, nargs="+", default=[4, 8, 16], help="1/h of the uniform meshes")
    parser.add_argument("--reference", type=int, default=64, help="1/h of the uniform reference mesh")
    parser.add_argument("--tolerances", type=float, nargs="+", default=[1.5, 1.0, 0.7, 0.5],
                        help="adapt.tolerance of the runs that adapt during the run")
    args = parser.parse_args()
    started = time.perf_counter()
    run = complete(vpcontact.solve(punch(args.reference)))
    reference = Reference(run)
    found = {"reference": {"level": args.reference, "dofs": int(run.dofs), "solve_s": time.perf_counter() - started}}
    log(f"reference 1/{args.reference}: {run.dofs} dofs, {found['reference']['solve_s']:.1f} s")
    del run
    found["uniform"] = []
    for level in args.levels:
        started = time.perf_counter()
        result = complete(vpcontact.solve(punch(level)))
        found["uniform"].append({"level": level, "dofs": int(result.dofs), "errors": reference.errors(result),
                                 "wall_time_s": time.perf_counter() - started})
        log(f"  uniform 1/{level}: {result.dofs} dofs, E(1.1) {found['uniform'][-1]['errors']['E(1.1)']:.4g}")
    found["run_adaptive"] = []
    for tolerance in args.tolerances:
        case = punch(4)
        started = time.perf_counter()
        adaptation = adapt(build_problem(case), {"mode": "run", "tolerance": tolerance}, case.output)
        seconds = time.perf_counter() - started
        result = complete(adaptation.result)
        started = time.perf_counter()
        complete(vpcontact.solve(build_problem(case, mesh=adaptation.mesh), output=case.output))
        plain = time.perf_counter() - started
        row = {"tolerance": tolerance, "dofs": int(result.dofs), "refinements": adaptation.refinements,
               "refined_at_steps": sorted({r["step"] for r in adaptation.rows if r["refined"]}),
               "errors": reference.errors(result), "wall_time_s": seconds, "one_run_on_last_mesh_s": plain,
               "time_ratio": seconds / plain, "finest_edge_at_the_punch_edge": finest_at_the_edge(adaptation.mesh)}
        found["run_adaptive"].append(row)
        log(f"  run-adaptive, tolerance {tolerance:g}: {row['dofs']} dofs, E(1.1) {row['errors']['E(1.1)']:.4g}, "
            f"{seconds:.1f} s, {row['time_ratio']:.2f}× one run on its last mesh; finest edge at the punch's edge "
            f"{row['finest_edge_at_the_punch_edge']:.4f} (reference h {1 / args.reference:.4f})")
    passes = sorted(found["run_adaptive"], key=lambda r: r["dofs"])
    found["reach"] = []
    for uniform in found["uniform"]:
        target = uniform["errors"]["E(1.1)"]
        needed = dofs_reaching([r["dofs"] for r in passes], [r["errors"]["E(1.1)"] for r in passes], target)
        needed = None if math.isnan(needed) else needed
        found["reach"].append({"uniform_level": uniform["level"], "uniform_dofs": uniform["dofs"],
                               "uniform_error": target, "adaptive_dofs": needed,
                               "ratio": None if needed is None else needed / uniform["dofs"]})
    for name, rows in (("uniform", found["uniform"]), ("run_adaptive", passes)):
        if len(rows) > 1:
            x, y = np.log([r["dofs"] for r in rows]), np.log([r["errors"]["E(1.1)"] for r in rows])
            found[f"rate_{name}"] = float(np.polyfit(x, y, 1)[0])
    found["wall_time_s"] = sum(r["wall_time_s"] for r in found["uniform"] + found["run_adaptive"])
    print(json.dumps(found, indent=1))


if __name__ == "__main__":
    sys.exit(main())

"""The paper's example for a body from 1e-3 to 1e9 times as stiff as its layer, with both methods:
prints JSON (docs/accuracy.md).

E runs over 0.1, 1e3, 1e6, 1e9, 1e11 with the layer unchanged (c_v = 100, R = 1, so E/(c_v R) from
1e-3 to 1e9). One record per E: for each method the status, step cuts, Newton iterations, linear
solves, the penetration at the bottom point at t = T and the wall time; then the largest difference
between the methods over the whole contact history (penetration, ξ, K, compliance pressure) and over
the final displacement, each relative to its maximum.

    python benchmarks/stiffness_ratio.py               # the example's mesh, h = 0.0125 (46,410 DOFs)
    python benchmarks/stiffness_ratio.py --h 0.05
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "paper_ball.toml"
MODULI = (0.1, 1e3, 1e6, 1e9, 1e11)
METHODS = ("full", "condensed")
COMPARED = ("penetration", "xi", "K", "pressure_compliance")


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def record(E: float, h: float) -> dict:
    """Both methods at one E."""
    import vpcontact

    results, entry = {}, {"E": E}
    for method in METHODS:
        case = vpcontact.load_case(EXAMPLE, {"material.E": E, "solver.method": method, "mesh.h": h,
                                             "output.field_steps": "final"})
        started = time.perf_counter()
        result = vpcontact.solve(case)
        results[method] = result
        entry[method] = {"status": result.status, "step_cuts": result.step_cuts,
                         "newton_iterations": int(result.series("newton_iterations").sum()),
                         "linear_solves": result.linear_solves,
                         "penetration_probe": float(result.series("penetration_probe")[-1]) if result.rows else None,
                         "wall_time_s": time.perf_counter() - started}
    full, condensed = results["full"], results["condensed"]
    if full.status == condensed.status == "complete":
        entry["difference"] = {name: relative_difference(condensed.contact_history(name), full.contact_history(name))
                               for name in COMPARED}
        entry["difference"]["displacement"] = relative_difference(condensed.final.displacement,
                                                                  full.final.displacement)
    return entry


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, default=0.0125, help="mesh size (default: the example's)")
    args = parser.parse_args()
    records = [record(E, args.h) for E in MODULI]
    print(json.dumps({"h": args.h, "records": records}, indent=1))


if __name__ == "__main__":
    main()

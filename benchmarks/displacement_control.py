"""Displacement control against traction control on the same body: prints JSON.

A 3D block on rollers (every node of its bottom a contact node) pressed onto a hardening layer by its top, once
by a prescribed cyclic displacement (down to the rigid limit, lifted off the layer, down again: every reversal the
solvers meet) and once by the traction that presses it as far at the first peak, in each direct method. What a
prescribed displacement may cost: the right-hand side b − A_fh u_D(t) at every step (one sparse product), and for
the condensed method a load that no longer lies in the span of two (u_D and F both affine in t keep it there),
never a new factor. The record: sizes, wall times of the set-up and the time loop, Newton iterations, linear
solves, step cuts, per method and control.

    python benchmarks/displacement_control.py [--h 0.05] [--steps 60]
    python benchmarks/displacement_control.py --quick      # a coarse block, for the tests
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import vpcontact
from vpcontact import mesh as meshes

E, NU = 1000.0, 0.3
ROLLERS = {"left": "x", "right": "x", "front": "y", "back": "y"}
CONTACT = {"part": "bottom", "g": 0.004, "normal": [0, 0, -1],
           "stiffness": {"law": "power", "c_v": 2e3, "alpha": 50.0, "beta": 1.0}}
#: The top's displacement: 8 mm down at t = 1 (the limit), lifted 1 mm at t = 2, 10 mm down at t = 3.
TOP = "0.001 - 0.009*max(1 - abs(t - 1), 1.2*(t - 2))"
#: The traction that presses the block as far at the first peak (the uniaxial stress there, measured below).
TRACTION = "-{peak}*max(1 - abs(t - 1), 1.2*(t - 2))"


def run(body, control: str, method: str, steps: int, peak: float | None = None) -> dict:
    """One run of ``body`` under ``control`` ("displacement" or "traction") by ``method``: its record."""
    common = dict(material={"E": E, "nu": NU}, contact=CONTACT, time={"T": 3.0, "steps": steps},
                  solver={"method": method, "tolerance": 1e-10})
    started = time.perf_counter()
    if control == "displacement":
        problem = vpcontact.compose(body, dirichlet={**ROLLERS, "top": {"z": TOP}}, **common)
    else:
        problem = vpcontact.compose(body, dirichlet=ROLLERS, traction={"top": ["0", "0", TRACTION.format(peak=peak)]},
                                    **common)
    built = time.perf_counter()
    result = vpcontact.solve(problem)
    done = time.perf_counter()
    history = result.history
    return {"control": control, "method": method, "status": result.status, "dofs": int(problem.basis.N),
            "contact_nodes": int(problem.surface.size), "steps": steps, "build_s": built - started,
            "solve_s": done - built, "time_loop_s": result.timings["time_loop"],
            "newton_iterations": int(history["newton_iterations"].sum()), "linear_solves": result.linear_solves,
            "step_cuts": result.step_cuts, "largest_force_N": float(history["contact_force_z"].max()),
            "force_at_t1_N": float(history["contact_force_z"][(history["t"] - 1.0).abs().idxmin()]),
            "nodes_at_limit_max": int(history["nodes_at_limit"].max()),
            "nodes_separated_max": int(history["nodes_separated"].max())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, default=0.05, help="element size of the 1 × 1 × 0.5 block")
    parser.add_argument("--steps", type=int, default=60)
    parser.add_argument("--quick", action="store_true", help="h = 0.25, 12 steps")
    args = parser.parse_args()
    h, steps = (0.25, 12) if args.quick else (args.h, args.steps)
    body = meshes.block(1.0, 1.0, 0.5, h)
    records = []
    for method in ("condensed", "full"):
        pressed = run(body, "displacement", method, steps)
        records.append(pressed)
        # the traction of the same force at t = 1 (the block's top and bottom are 1 × 1: force = pressure)
        records.append(run(body, "traction", method, steps, peak=pressed["force_at_t1_N"]))
    print(json.dumps({"machine": {"platform": platform.platform(), "processor": platform.processor(),
                                  "python": platform.python_version()}, "h": h, "runs": records}, indent=1))


if __name__ == "__main__":
    main()

"""Adaptive against uniform refinement on the paper's example (docs/adaptivity.md, "Adaptive meshes").

Solves examples/paper_ball.toml on a fine uniform reference mesh, on the uniform meshes h = 1/8 ... 1/64
and in the adaptive cycles of [adapt] from h = 1/8 (recovery estimator), and prints for each the dofs,
the estimate (adaptive), the errors ‖ε(u_h − u_ref)‖ (V) at t = 0.5 and 1.1 and ‖σ_h − σ_ref‖ (Q) at
t = 1.1 against the reference (vpcontact.norms.differences), the wall time, and where the last adaptive
mesh is fine.

    python benchmarks/adaptivity.py --beta 1 --functional max --reference 256 --cycles 9
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import vpcontact
from vpcontact.adapt import adapt
from vpcontact.norms import differences
from vpcontact.problem import build_problem
from vpcontact.refinement import signed_measures

CASE = Path(__file__).resolve().parent.parent / "examples" / "paper_ball.toml"
STEPS = (5, 11)  # t = 0.5 and 1.1


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--beta", type=float, default=1.0)
    parser.add_argument("--functional", choices=("max", "l2"), default="max")
    parser.add_argument("--theta", type=float, default=0.5)
    parser.add_argument("--reference", type=int, default=256, help="1/h of the uniform reference mesh")
    parser.add_argument("--cycles", type=int, default=9)
    args = parser.parse_args()
    base = {"contact.stiffness.beta": args.beta, "output.field_steps": list(STEPS)}

    started = time.perf_counter()
    reference = vpcontact.solve(vpcontact.load_case(CASE, {**base, "mesh.h": 1 / args.reference}))
    print(f"reference h = 1/{args.reference}: {reference.dofs} dofs, {time.perf_counter() - started:.1f} s")
    snapshots = {step: reference.snapshot(step) for step in STEPS}

    def errors(result) -> str:
        found = {step: differences(result.snapshot(step), snapshots[step]) for step in STEPS}
        return f"V(0.5) = {found[5]['V']:.4g}  V(1.1) = {found[11]['V']:.4g}  Q(1.1) = {found[11]['Q']:.4g}"

    for n in (8, 16, 32, 64):
        started = time.perf_counter()
        result = vpcontact.solve(vpcontact.load_case(CASE, {**base, "mesh.h": 1 / n}))
        print(f"uniform h = 1/{n}: {result.dofs} dofs  {errors(result)}  {time.perf_counter() - started:.1f} s")

    case = vpcontact.load_case(CASE, {**base, "mesh.h": 1 / 8, "adapt.cycles": args.cycles,
                                      "adapt.theta": args.theta, "adapt.functional": args.functional})

    def report(cycle) -> None:
        print(f"cycle {cycle.number}: {cycle.result.dofs} dofs, {cycle.result.contact_nodes} contact nodes, "
              f"estimate {cycle.estimate:.4g}  {errors(cycle.result)}  {cycle.wall_time_s:.2f} s", flush=True)

    adaptation = adapt(build_problem(case), after_cycle=report)
    print(adaptation.message)
    mesh = adaptation.mesh
    size = np.sqrt(2.0 * np.abs(signed_measures(mesh.mesh.p, mesh.mesh.t)))  # about the edge length
    y = mesh.centroids[1]
    for low, high in ((0.0, 0.1), (0.1, 0.3), (0.3, 0.6), (0.6, 1.0), (1.0, 2.0)):
        inside = (y >= low) & (y < high)
        print(f"y in [{low}, {high}): {inside.sum()} triangles, size median {np.median(size[inside]):.4f}, "
              f"min {size[inside].min():.4f}")
    corner = np.hypot(mesh.centroids[0] - 1.0, y - 1.0) < 0.05
    print(f"within 0.05 of (1, 1), where Γ3 meets Γ2: {corner.sum()} triangles, size min {size[corner].min():.4f}")


if __name__ == "__main__":
    main()

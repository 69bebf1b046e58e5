"""Adaptive against uniform refinement in 3D, on the quarter ball: prints a table and JSON.

examples/quarter_ball.toml (elastic, β = 1, 11 steps; every run on the same time grid, so the errors
are spatial) is solved on a fine uniform reference mesh (mesh.h = 0.05, 176k dofs), on uniform meshes
(mesh.h = 0.3, 0.2, 0.15, 0.1) and in the adaptive cycles of [adapt] (residual estimator, Dörfler θ, time
functional "max") from the coarsest uniform mesh, up to half the reference's dofs. For each run, at
t = 0.5 and t = 1.1:

    error         ‖I_ref u_h − u_ref‖_E, the energy norm on the reference mesh (vpcontact.results.norms.differences;
                  u_h interpolated at the reference's nodes, extrapolated from the nearest element for the
                  nodes outside the run's inscribed polyhedron), and V = ‖ε(I_ref u_h − u_ref)‖;
    η(t)          the residual estimator of the run's solution (vpcontact.estimate.residual);
    effectivity   η(t) / error;

and for the adaptive cycles their estimate (the time functional's, adapt.csv's column). Then: the dofs
at which the cycles reach the finest uniform mesh's error at t = 1.1 (log–log interpolation between the
two cycles around it) and their ratio to that mesh's dofs, and where the last adaptive mesh and the
finest uniform one are fine (longest edge of the tetrahedra by distance from the bottom point, and at the
equator z = 1 where Γ3 meets the loaded Γ2).

With ``--run-tolerances``, also one run that adapts during the run (adapt.mode = "run") from the coarsest uniform
mesh for each tolerance: its dofs, refinements, errors at t = 0.5 and 1.1 (the fields of t = 0.5 as the run carried
them to its last mesh: the solution it computed then, on the mesh of then) and wall time, and the dofs at which
those runs reach the finest uniform mesh's error; ``--skip-cycles`` leaves the cycles out.

    python benchmarks/adaptivity_3d.py                 # h = 0.3 … 0.1 against 0.05, 12 cycles from 0.3
    python benchmarks/adaptivity_3d.py --quick         # h = 0.6, 0.4 against 0.2, 3 cycles (seconds)
    python benchmarks/adaptivity_3d.py --skip-cycles --run-tolerances 0.3 0.2 0.15 0.1
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

import vpcontact
from vpcontact import adapt
from vpcontact.estimate.indicators import Level
from vpcontact.results.norms import differences
from vpcontact import build_problem
from vpcontact.reproduction.records import dofs_reaching
from vpcontact.estimate.residual import ResidualEstimator

CASE = Path(__file__).resolve().parents[1] / "examples" / "quarter_ball.toml"
STEPS = {0.5: 5, 1.1: 11}
SETTINGS = {
    "full": {"levels": (0.3, 0.2, 0.15, 0.1), "reference": 0.05, "cycles": 12},
    "quick": {"levels": (0.6, 0.4), "reference": 0.2, "cycles": 3},
}
#: Shells around the bottom point (0, 0, 0) where the element sizes are reported.
SHELLS = ((0.0, 0.1), (0.1, 0.3), (0.3, 0.6), (0.6, 1.0), (1.0, 2.0))


def load(h: float, **overrides):
    """The example on the mesh of edge h, its fields kept at t = 0.5 and 1.1."""
    return vpcontact.load_case(CASE, {"mesh.h": h, "output.field_steps": sorted(STEPS.values()),
                                      "output.figures": False, "output.progress": False, **overrides})


def solved(case):
    """(problem, result) of a run of ``case`` that completes (else SystemExit)."""
    problem = build_problem(case)
    result = vpcontact.solve(problem, output=case.output)
    if result.status != "complete":
        raise SystemExit(f"the run failed: {result.message}")
    return problem, result


def with_lame(result, step: int):
    """The run's Snapshot at ``step`` with the Lamé parameters of its elements (for the energy norm)."""
    snapshot = result.snapshot(step)
    elements = snapshot.elements.shape[1]
    lame = np.array([np.broadcast_to(np.asarray(value, dtype=float), (elements,))
                     for value in result.discretization.elasticity.lame])
    return dataclasses.replace(snapshot, lame=lame)


def measured(problem, result, references: dict) -> dict:
    """dofs, contact nodes, and per time η(t), the energy error, V and the effectivity of one run of ``problem``."""
    estimator = ResidualEstimator(problem)
    row = {"dofs": int(result.dofs), "contact_nodes": int(result.contact_nodes),
           "elements": int(result.elements)}
    for t, step in STEPS.items():
        found = differences(result.snapshot(step), references[t])
        eta = float(estimator(Level.of(result, step, problem)).total)
        row[f"t={t:g}"] = {"estimate": eta, "error": found["energy"], "V": found["V"],
                           "effectivity": eta / found["energy"]}
    return row


def longest_edges(mesh) -> np.ndarray:
    """The longest edge of each tetrahedron."""
    p, t = mesh.p, mesh.t
    pairs = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
    return np.max([np.linalg.norm(p[:, t[a]] - p[:, t[b]], axis=0) for a, b in pairs], axis=0)


def sizes(mesh) -> dict:
    """Median and smallest longest edge of the tetrahedra in shells around the bottom point, and of those
    near the equator (the circle z = 1 on the sphere, where the contact part Γ3 meets the loaded part)."""
    edge = longest_edges(mesh)
    centroids = mesh.p[:, mesh.t].mean(axis=1)
    distance = np.linalg.norm(centroids, axis=0)
    zones = {f"r in [{low:g}, {high:g})": (distance >= low) & (distance < high) for low, high in SHELLS}
    to_sphere = 1.0 - np.linalg.norm(centroids - np.array([[0.0], [0.0], [1.0]]), axis=0)
    zones["equator (|z - 1| < 0.1, within 0.1 of the sphere)"] = (np.abs(centroids[2] - 1.0) < 0.1) & (to_sphere < 0.1)
    return {name: {"elements": int(inside.sum()), "median": float(np.median(edge[inside])),
                   "min": float(edge[inside].min())} for name, inside in zones.items() if inside.any()}


def crossing(cycles: list[dict], target: float, t: str) -> float | None:
    """The dofs at which the cycles' error at ``t`` falls to ``target`` (`vpcontact.reproduction.records.dofs_reaching`:
    log–log interpolation between the last cycle above it and the first at or below it); None when no
    cycle reaches it."""
    found = dofs_reaching([c["dofs"] for c in cycles], [c[t]["error"] for c in cycles], target)
    return None if math.isnan(found) else found


HEADER = (f"{'run':14} {'dofs':>7} {'Γ3 nodes':>8} {'estimate':>9} "
          + " ".join(f"{'η(' + t + ')':>9} {'err(' + t + ')':>10} {'eff':>5}" for t in ("0.5", "1.1")) + f" {'s':>6}")


def line(row: dict) -> str:
    """A run's line of the table (a uniform level or an adaptive cycle)."""
    name = f"h = {row['h']:g}" if "h" in row else f"cycle {row['cycle']}"
    estimate = f"{row['cycle_estimate']:9.4g}" if "cycle_estimate" in row else " " * 9
    return (f"{name:14} {row['dofs']:>7} {row['contact_nodes']:>8} {estimate} "
            + " ".join(f"{row[t]['estimate']:9.4g} {row[t]['error']:10.4g} {row[t]['effectivity']:5.2f}"
                       for t in ("t=0.5", "t=1.1"))
            + f" {row['wall_time_s']:6.1f}")


def adapted_during_run(h: float, tolerance: float, theta: float, max_dofs: int, references: dict) -> dict:
    """One run that adapts during the run from the mesh of edge h: its dofs, refinements, errors at t = 0.5 and 1.1
    against ``references`` and wall time."""
    case = load(h, **{"adapt.mode": "run", "adapt.tolerance": tolerance, "adapt.theta": theta,
                      "adapt.max_dofs": max_dofs})
    begun = time.perf_counter()
    adaptation = adapt(build_problem(case), case.adapt, case.output)
    seconds = time.perf_counter() - begun
    if adaptation.status != "complete":
        raise SystemExit(f"the run that adapts during the run failed: {adaptation.message}")
    result = adaptation.result
    row = {"tolerance": tolerance, "dofs": int(result.dofs), "contact_nodes": int(result.contact_nodes),
           "refinements": adaptation.refinements, "wall_time_s": seconds}
    for t, step in STEPS.items():
        found = differences(result.snapshot(step), references[t])
        row[f"t={t:g}"] = {"error": found["energy"], "V": found["V"]}
    print(f"during the run, tolerance {tolerance:g}: {row['dofs']} dofs, {row['refinements']} refinements, "
          f"E(0.5) = {row['t=0.5']['error']:.4g}, E(1.1) = {row['t=1.1']['error']:.4g}, {seconds:.1f} s",
          file=sys.stderr, flush=True)
    return row


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="coarse meshes (seconds)")
    parser.add_argument("--theta", type=float, default=0.5, help="Dörfler fraction")
    parser.add_argument("--cycles", type=int, help="adaptive cycles (default: 12, quick 3)")
    parser.add_argument("--out", type=Path, help="write the JSON there too (a file)")
    parser.add_argument("--run-tolerances", type=float, nargs="*", default=[],
                        help="adapt.tolerance of runs that adapt during the run (none by default)")
    parser.add_argument("--skip-cycles", action="store_true", help="leave the adaptive cycles out")
    arguments = parser.parse_args(argv)
    setting = SETTINGS["quick" if arguments.quick else "full"]
    levels, cycles = setting["levels"], arguments.cycles or setting["cycles"]
    started = time.perf_counter()

    _, reference = solved(load(setting["reference"], **{"solver.method": "condensed"}))
    references = {t: with_lame(reference, step) for t, step in STEPS.items()}
    reference_s = time.perf_counter() - started
    print(f"reference h = {setting['reference']:g}: {reference.dofs} dofs, {reference_s:.0f} s", file=sys.stderr)
    print(HEADER, file=sys.stderr)

    uniform = []
    for h in levels:
        begun = time.perf_counter()
        problem, result = solved(load(h))
        uniform.append({"h": h, **measured(problem, result, references), "wall_time_s": time.perf_counter() - begun})
        print(line(uniform[-1]), file=sys.stderr, flush=True)
    finest = result

    adaptive, adaptation = [], None

    def record(cycle) -> None:
        problem = start.on(cycle.result.discretization.mesh)  # the cycle's problem, built again on its mesh
        adaptive.append({"cycle": cycle.number, **measured(problem, cycle.result, references),
                         "cycle_estimate": cycle.estimate, "wall_time_s": cycle.wall_time_s})
        print(line(adaptive[-1]), file=sys.stderr, flush=True)

    if not arguments.skip_cycles:
        case = load(levels[0], **{"adapt.cycles": cycles, "adapt.theta": arguments.theta, "adapt.functional": "max",
                                  "adapt.max_dofs": int(reference.dofs) // 2})
        start = build_problem(case)
        adaptation = adapt(start, case.adapt, case.output, after_cycle=record)
        if adaptation.status != "complete":
            raise SystemExit(f"the adaptation failed: {adaptation.message}")
    during_run = [adapted_during_run(levels[0], tolerance, arguments.theta, int(reference.dofs) // 2, references)
                  for tolerance in arguments.run_tolerances]

    target = uniform[-1]
    reached = {t: crossing(adaptive, target[t]["error"], t) for t in ("t=0.5", "t=1.1")} if adaptive else None
    reached_run = {t: crossing(during_run, target[t]["error"], t) for t in ("t=0.5", "t=1.1")} if during_run else None
    report = {
        "case": "examples/quarter_ball.toml", "steps": 11, "theta": arguments.theta, "functional": "max",
        "reference": {"h": setting["reference"], "dofs": int(reference.dofs), "wall_time_s": reference_s},
        "uniform": uniform, "adaptive": adaptive, "during_run": during_run,
        "effectivity_uniform": {t: [row[t]["effectivity"] for row in uniform] for t in ("t=0.5", "t=1.1")},
        "finest_uniform": {"h": target["h"], "dofs": target["dofs"]},
        "adaptive_dofs_at_finest_uniform_error": reached,
        "dofs_ratio": None if reached is None else {t: None if dofs is None else dofs / target["dofs"]
                                                    for t, dofs in reached.items()},
        "during_run_dofs_at_finest_uniform_error": reached_run,
        "during_run_dofs_ratio": None if reached_run is None else {
            t: None if dofs is None else dofs / target["dofs"] for t, dofs in reached_run.items()},
        "wall_time_s": time.perf_counter() - started,
    }
    if adaptation is not None:
        bottom = adaptation.mesh.mesh.p[:, adaptation.mesh.nodes("bottom")]
        report.update({
            "contact_nodes_off_sphere": float(np.abs(np.linalg.norm(bottom - np.array([[0.0], [0.0], [1.0]]), axis=0)
                                                     - 1.0).max()),
            "sizes": {"last_cycle": sizes(adaptation.mesh.mesh),
                      "finest_uniform": sizes(finest.discretization.mesh.mesh)},
            "message": adaptation.message})
    print(f"adaptive reaches the h = {target['h']:g} error ({target['dofs']} dofs) at: cycles {reached}, "
          f"during the run {reached_run}", file=sys.stderr)
    text = json.dumps(report, indent=1)
    if arguments.out is not None:
        arguments.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The user's punch: a filleted steel cylinder made in gmsh, indented cyclically in displacement control.

The geometry and the load of the gallery's punch (docs/examples/plot_punch_cyclic.py): a quarter of a steel
cylinder (R = 5 mm, H = 10 mm, its bottom edge filleted by 1 mm; SI units) on rollers on its symmetry planes,
its top moved down into a soft layer (g = 0.5 mm, K(ξ) = c_v (1 + α ξ)^β), back up off the layer and down
again, 20 steps per cycle: every step of a lift-off separates all the contact nodes at once, and every step
back down brings them all into contact: the changes of state that monotone loads never make. Meshed finer at
the flat face (elements of ``h_contact`` there, growing linearly to ``h_far`` at the top) as a user resolving
the contact would.

    python benchmarks/punch.py --h-contact 0.1e-3 --h-far 0.5e-3 --method auto --steps 60
    python benchmarks/punch.py --size 30k --method condensed        # the sizes of the issue's user
    python benchmarks/punch.py --size 136k --method iterative

prints one JSON record: sizes, the method that ran and why, wall times (mesh, build, set-up, time loop),
Newton iterations, linear solves, GMRES/CG iterations, Newton-matrix factorizations, peak resident memory, and
``vpcontact check``'s estimates of the run for comparison. ``make_punch`` is the function the ladder
(benchmarks/ladder.py) imports.
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import time

import numpy as np

R, H, FILLET = 5e-3, 10e-3, 1e-3  # m
E, NU = 210e9, 0.3  # Pa
G, C_V, ALPHA = 0.5e-3, 2e10, 1e4  # m, Pa/m, 1/(m·s)
DEPTH, LIFT = 0.3e-3, 0.1e-3  # m: the deepest point of a cycle, and how high it lifts off the layer
DOWN, UP = 0.4, 0.8  # s: the deepest and the highest point of each 1 s cycle
PHASE = "(t - floor(t))"


def top_displacement(depth: float = DEPTH) -> str:
    """w(t), the top's vertical displacement: down to −depth at DOWN, up to +LIFT at UP, back to 0 at the cycle's
    end (a depth beyond G presses the flat face onto the rigid base: its nodes reach the limit)."""
    return (f"min({LIFT:g}*(1 - {PHASE})/{1 - UP:g}, max(-{depth:g}*{PHASE}/{DOWN:g}, "
            f"-{depth:g} + {depth + LIFT:g}*({PHASE} - {DOWN:g})/{UP - DOWN:g}))")
#: (h_contact, h_far) in m that give the sizes of the issue's user: about 30k dofs with 1.9k contact nodes, and
#: 136k dofs with 5.2k
SIZES = {"7k": (0.25e-3, 1.0e-3), "30k": (0.09e-3, 1.15e-3), "136k": (0.054e-3, 0.63e-3)}


def make_punch(h_contact: float, h_far: float):
    """Mesh the quarter punch in gmsh (an open model is left for ``vpcontact.compose``; the caller finalizes):
    physical groups ``sym_x``, ``sym_y`` (symmetry planes), ``contact`` (the flat bottom face), ``top`` and the
    volume ``punch``; elements of h_contact at z = 0 growing linearly to h_far at z = H."""
    import gmsh

    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("punch")
    occ = gmsh.model.occ
    cylinder = occ.addCylinder(0, 0, 0, 0, 0, H, R)
    occ.synchronize()
    bottom_edge = [tag for _, tag in gmsh.model.getEntities(1) if abs(occ.getCenterOfMass(1, tag)[2]) < 1e-9 * H]
    filleted = occ.fillet([cylinder], bottom_edge, [FILLET])
    quarter, _ = occ.intersect(filleted, [(3, occ.addBox(0, 0, 0, R, R, H))])
    occ.synchronize()
    faces = [tag for _, tag in gmsh.model.getBoundary(quarter, oriented=False)]

    def faces_at(axis: int, value: float) -> list[int]:
        return [face for face in faces if abs(occ.getCenterOfMass(2, face)[axis] - value) < 1e-9 * H]

    for name, tags in {"sym_x": faces_at(0, 0.0), "sym_y": faces_at(1, 0.0), "contact": faces_at(2, 0.0),
                       "top": faces_at(2, H)}.items():
        assert len(tags) == 1, (name, tags)
        gmsh.model.addPhysicalGroup(2, tags, name=name)
    gmsh.model.addPhysicalGroup(3, [tag for _, tag in quarter], name="punch")
    field = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(field, "F", f"{h_contact!r} + {h_far - h_contact!r} * z / {H!r}")
    gmsh.model.mesh.field.setAsBackgroundMesh(field)
    for option in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(option, 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.mesh.generate(3)
    return gmsh


def punch_problem(h_contact: float, h_far: float, *, method: str = "auto", steps: int = 60, beta: float = 1.0,
                  cycles: int = 3, depth: float = DEPTH):
    """The composed problem of the punch (``cycles`` cycles of 1 s in ``steps`` steps) and the seconds meshing
    took."""
    import vpcontact

    started = time.perf_counter()
    gmsh = make_punch(h_contact, h_far)
    meshed = time.perf_counter() - started
    try:
        problem = vpcontact.compose(
            gmsh, {"E": E, "nu": NU},
            dirichlet={"sym_x": "x", "sym_y": "y", "top": {"z": top_displacement(depth)}},
            contact={"part": "contact", "g": G, "probe": [0, 0, 0],
                     "stiffness": {"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": beta}},
            time={"T": float(cycles), "steps": steps}, solver={"method": method, "tolerance": 1e-10})
    finally:
        gmsh.finalize()
    return problem, meshed


def run(h_contact: float, h_far: float, method: str, steps: int, beta: float, cycles: int, depth: float) -> dict:
    """One run of the punch: its JSON record."""
    import vpcontact
    from vpcontact.results.output_options import OutputOptions
    from vpcontact.timeloop.plan import free_operators, plan_run

    started = time.perf_counter()
    problem, meshed = punch_problem(h_contact, h_far, method=method, steps=steps, beta=beta, cycles=cycles,
                                    depth=depth)
    built = time.perf_counter()
    plan = plan_run(problem, OutputOptions(), *free_operators(problem))
    result = vpcontact.solve(problem, output={"progress": False})
    done = time.perf_counter()
    history = result.history
    return {"h_contact_m": h_contact, "h_far_m": h_far, "beta": beta, "steps": steps, "cycles": cycles,
            "depth_m": depth,
            "dofs": int(problem.basis.N), "contact_nodes": int(problem.surface.size),
            "method": result.method, "reason": result.method_reason, "status": result.status,
            "mesh_s": meshed, "build_s": built - started - meshed, "solve_s": done - built,
            "timings_s": {key: float(value) for key, value in result.timings.items()},
            "newton_iterations": int(history["newton_iterations"].sum()), "linear_solves": result.linear_solves,
            "krylov_iterations": result.krylov_iterations, "newton_factorizations": result.newton_factorizations,
            "step_cuts": result.step_cuts,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "largest_force_N": float(np.abs(history["contact_force_z"]).max()),
            "check": {"method": plan.method, "time_s": plan.time_seconds, "memory_bytes": plan.memory_bytes}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", choices=sorted(SIZES), help="the mesh of one of the issue's sizes")
    parser.add_argument("--h-contact", type=float, default=0.1e-3, help="element size at the flat face (m)")
    parser.add_argument("--h-far", type=float, default=0.6e-3, help="element size at the top (m)")
    parser.add_argument("--method", default="auto", choices=("auto", "condensed", "iterative", "full"))
    parser.add_argument("--steps", type=int, default=60, help="time steps over all the cycles")
    parser.add_argument("--cycles", type=int, default=3, help="cycles of 1 s (down, off the layer, back)")
    parser.add_argument("--beta", type=float, default=1.0)
    parser.add_argument("--depth", type=float, default=DEPTH, help=f"deepest point of a cycle (m); beyond G = {G:g} "
                        "the flat face reaches the rigid base")
    args = parser.parse_args()
    h_contact, h_far = SIZES[args.size] if args.size else (args.h_contact, args.h_far)
    record = run(h_contact, h_far, args.method, args.steps, args.beta, args.cycles, args.depth)
    print(json.dumps({"machine": {"platform": platform.platform(), "processor": platform.processor(),
                                  "cores": __import__("os").cpu_count(), "load_average": __import__("os").getloadavg()},
                      **record}, indent=1, default=float))


if __name__ == "__main__":
    main()

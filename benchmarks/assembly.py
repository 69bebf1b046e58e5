"""Assembly of 3D P1 elasticity: vpcontact's NumPy kernels against scikit-fem's forms; prints JSON.

The quarter ball (mesh.quarter_ball, 12 n³ tetrahedra with n = ceil(1.5 / h)) at several sizes;
for each size and implementation ("skfem": the forms vpcontact assembled with before, kept below as
the reference; "numpy": vpcontact.fem.assembly) one fresh process times

- the stiffness A (E = 1000, ν = 0.3; the new one includes computing the element gradients),
- the load vector of a traction on the top: its setup, then F(t) at each of --steps times,
- element strains ε(u) and the nodal force Bᵀz (--steps calls each, the median),

and reports its peak resident memory (getrusage's maximum, and this process's samples of
/proc/PID/statm, every 0.1 s) and its resident memory once the mesh and the basis exist.
Each record of the numpy implementation also holds the speedup over scikit-fem at the same size
and the largest relative difference of A, F(t), ε(u) and Bᵀz computed both ways in one process
(sizes up to --compare-up-to tetrahedra).

    python benchmarks/assembly.py            # h = 0.1, 0.058, 0.0406: 40k, 211k, 608k tetrahedra
    python benchmarks/assembly.py --quick    # h = 0.5 (324 tetrahedra): seconds
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

from watched import watched  # noqa: E402 - this folder's module (the script runs from here)

LEVELS = (0.1, 0.058, 0.0406)
QUICK = 0.5
IMPLEMENTATIONS = ("skfem", "numpy")
E, NU = 1000.0, 0.3


# --- the reference: scikit-fem's forms, as vpcontact.fem.assembly used them --------------------------
def skfem_basis(space):
    """scikit-fem's vector basis of vpcontact's displacement space (fem/space.py) with the centroid rule, exact for
    the bulk forms of P1 × P0: the basis vpcontact assembled on before (``space`` itself if it is one)."""
    from skfem import Basis
    from skfem.assembly.basis import AbstractBasis

    if isinstance(space, AbstractBasis):
        return space
    dim = space.mesh.p.shape[0]
    return Basis(space.mesh, space.elem, quadrature=(np.full((dim, 1), 1.0 / (dim + 1)),
                                                     np.array([1.0 / math.factorial(dim)])))


def skfem_stiffness(space, lam, mu):
    """A by scikit-fem: linear_elasticity for numbers, a P0-coefficient form for per-element arrays."""
    from skfem import BilinearForm, asm
    from skfem.helpers import ddot, eye, sym_grad, trace
    from skfem.models.elasticity import linear_elasticity

    basis = skfem_basis(space)
    if np.ndim(lam) == 0 and np.ndim(mu) == 0:
        return asm(linear_elasticity(lam, mu), basis).tocsr()

    @BilinearForm
    def elastic(u, v, w):
        strain = sym_grad(u)
        return ddot(2.0 * w["mu"] * strain + w["lam"] * eye(trace(strain), strain.shape[0]), sym_grad(v))

    points = basis.X.shape[-1]
    per_element = {name: np.repeat(np.broadcast_to(value, (basis.nelems,))[:, None], points, axis=1)
                   for name, value in (("lam", lam), ("mu", mu))}
    return asm(elastic, basis, **per_element).tocsr()


def skfem_load(load_basis, values):
    """∫ f·v of a density with ``values`` (d, cells, points) at the quadrature points of ``load_basis``
    (a vector FacetBasis or Basis of intorder 4)."""
    from skfem import LinearForm, asm

    @LinearForm
    def density(v, w):
        return sum(w["f"][i] * v[i] for i in range(v.shape[0]))

    return asm(density, load_basis, f=values)


def skfem_strain(space, u):
    from skfem.helpers import sym_grad

    return sym_grad(skfem_basis(space).interpolate(u))[:, :, :, 0]


def skfem_stress_force(space, z):
    from skfem import LinearForm, asm
    from skfem.helpers import ddot, sym_grad

    basis = skfem_basis(space)
    @LinearForm
    def work(v, w):
        return ddot(w["z"], sym_grad(v))

    return asm(work, basis, z=np.repeat(z[..., None], basis.X.shape[-1], axis=-1))


# --- one size, one implementation, in this process -----------------------------------------------
def peak_rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def traction(x, y, z, t):
    """The quarter ball's load: a pressure growing with t and varying over the top."""
    return 0.0 * x, 0.1 * y * t, -(1.0 + x * x) * t


def timed(function, *args):
    started = time.perf_counter()
    value = function(*args)
    return value, time.perf_counter() - started


def run_size(h: float, implementation: str, steps: int) -> dict:
    from skfem import FacetBasis

    from vpcontact.fem.assembly import LoadVector, displacement_space, element_strain, stiffness, stress_force
    from vpcontact.laws.elasticity import Elasticity
    from vpcontact.mesh import quarter_ball

    mesh = quarter_ball(h)
    basis = displacement_space(mesh)
    record = {"h": h, "implementation": implementation, "tetrahedra": int(mesh.mesh.t.shape[1]),
              "dofs": int(basis.N), "rss_before_mb": peak_rss_mb()}
    elasticity = Elasticity(E, NU, None)
    rng = np.random.default_rng(0)
    u = rng.standard_normal(basis.N)
    z = rng.standard_normal((3, 3, basis.nelems))
    if implementation == "skfem":
        basis = skfem_basis(basis)  # built once, untimed, as before
        A, record["stiffness_s"] = timed(skfem_stiffness, basis, *elasticity.lame)
        load_basis, record["load_setup_s"] = timed(lambda: FacetBasis(mesh.mesh, basis.elem, facets=mesh.facets("top"),
                                                                      intorder=4))
        points = load_basis.global_coordinates()
        F = lambda t: skfem_load(load_basis, np.stack([np.broadcast_to(f, points[0].shape) for f in  # noqa: E731
                                                       traction(*points, t)]))
        strain, force = (lambda: skfem_strain(basis, u)), (lambda: skfem_stress_force(basis, z))
    else:
        A, record["stiffness_s"] = timed(stiffness, basis, elasticity)
        F, record["load_setup_s"] = timed(LoadVector, basis, mesh, [("top", "top", traction)], [])
        strain, force = (lambda: element_strain(basis, u)), (lambda: stress_force(basis, z))
    record["nonzeros"] = int(A.nnz)
    record["load_step_s"] = statistics.median(timed(F, t)[1] for t in np.linspace(0.1, 1.0, steps))
    record["strain_s"] = statistics.median(timed(strain)[1] for _ in range(steps))
    record["stress_force_s"] = statistics.median(timed(force)[1] for _ in range(steps))
    record["peak_rss_mb"] = peak_rss_mb()
    return record


def differences(h: float) -> dict:
    """The largest relative difference (max |new − old| / max |old|) of A, F(t), ε(u) and Bᵀz."""
    from skfem import FacetBasis

    from vpcontact.fem.assembly import LoadVector, displacement_space, element_strain, stiffness, stress_force
    from vpcontact.laws.elasticity import Elasticity
    from vpcontact.mesh import quarter_ball

    def relative(new, old):
        return float(abs(new - old).max() / abs(old).max())

    mesh = quarter_ball(h)
    basis = displacement_space(mesh)
    elasticity = Elasticity(E, NU, None)
    rng = np.random.default_rng(1)
    u, z = rng.standard_normal(basis.N), rng.standard_normal((3, 3, basis.nelems))
    load_basis = FacetBasis(mesh.mesh, basis.elem, facets=mesh.facets("top"), intorder=4)
    points = load_basis.global_coordinates()
    old_F = skfem_load(load_basis, np.stack([np.broadcast_to(f, points[0].shape) for f in traction(*points, 0.7)]))
    return {"stiffness": relative(stiffness(basis, elasticity), skfem_stiffness(basis, *elasticity.lame)),
            "load": relative(LoadVector(basis, mesh, [("top", "top", traction)], [])(0.7), old_F),
            "strain": relative(element_strain(basis, u), skfem_strain(basis, u)),
            "stress_force": relative(stress_force(basis, z), skfem_stress_force(basis, z))}


def in_subprocess(h: float, implementation: str, steps: int, memory_limit_mb: float, time_limit_s: float) -> dict:
    command = [sys.executable, __file__, "--h", str(h), "--implementation", implementation, "--steps", str(steps),
               "--inline"]
    status, stdout, stderr, stopped, wall, largest = watched(command, memory_limit_mb, time_limit_s)
    record = {"h": h, "implementation": implementation, "process_s": wall, "sampled_peak_rss_mb": largest}
    if stopped or status != 0:
        return {**record, "status": "stopped" if stopped else "error", "message": stopped or stderr[-2000:]}
    return {**json.loads(stdout), **record, "status": "complete"}


STAGES = ("stiffness_s", "load_setup_s", "load_step_s", "strain_s", "stress_force_s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, help="one size: the element edge h (default: the ladder)")
    parser.add_argument("--quick", action="store_true", help=f"h = {QUICK} only (324 tetrahedra)")
    parser.add_argument("--implementation", choices=(*IMPLEMENTATIONS, "both"), default="both")
    parser.add_argument("--steps", type=int, default=5, help="calls of F(t), ε(u) and Bᵀz timed (medians)")
    parser.add_argument("--compare-up-to", type=int, default=300_000,
                        help="largest number of tetrahedra at which both results are compared")
    parser.add_argument("--time-limit", type=float, default=900.0, help="seconds before a run is stopped")
    parser.add_argument("--memory-limit", type=float, help="MB of resident memory before a run is stopped "
                        "(default: 80 %% of the memory available at its start)")
    parser.add_argument("--inline", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--differences", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.inline:
        print(json.dumps(differences(args.h) if args.differences else run_size(args.h, args.implementation, args.steps)))
        return
    from vpcontact.memory import available_memory

    levels = [QUICK] if args.quick else [args.h] if args.h else list(LEVELS)
    implementations = list(IMPLEMENTATIONS) if args.implementation == "both" else [args.implementation]
    records = []
    for h in levels:
        by_implementation = {}
        for implementation in implementations:
            limit = args.memory_limit or 0.8 * available_memory() / 2**20
            record = by_implementation[implementation] = in_subprocess(h, implementation, args.steps, limit,
                                                                       args.time_limit)
            old = by_implementation.get("skfem", {})
            if implementation == "numpy" and record["status"] == old.get("status") == "complete":
                record["speedup"] = {stage: old[stage] / max(record[stage], 1e-9) for stage in STAGES}
                record["peak_rss_ratio"] = old["peak_rss_mb"] / record["peak_rss_mb"]
                if record["tetrahedra"] <= args.compare_up_to:
                    done = subprocess.run([sys.executable, __file__, "--h", str(h), "--inline",
                                                         "--differences"], capture_output=True, text=True)
                    record["relative_difference"] = json.loads(done.stdout) if done.returncode == 0 else done.stderr
            records.append(record)
            print(json.dumps(record), file=sys.stderr, flush=True)
    print(json.dumps(records, indent=1))


if __name__ == "__main__":
    main()

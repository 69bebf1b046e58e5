"""The GetFEM side of the peer comparison (benchmarks/peer_getfem.py): vpcontact's contact law on a
gmsh half disc, solved by GetFEM's own Newton method and MUMPS. Run by the Python that has GetFEM
(Debian's python3-getfem), not by vpcontact's:

    python3 benchmarks/getfem_half_disc.py MESH.msh --steps 141 --record 64 141 --out peer.npz

The problem is vpcontact's, term by term:
- P1 displacements on the file's triangles, plane-strain isotropic elasticity (Lamé λ, μ of E, ν),
  one-point quadrature (the strains of P1 are constant per triangle);
- the symmetry roller u_x = 0 on "axis" (a P1 multiplier on the axis: u·n = 0 at its nodes);
- the traction (0, −c t) per unit length on "top_arc", t_n = n T / steps;
- on "bottom_arc" (Γ3), frictionless node-to-rigid contact along vpcontact's nodal normal ν_i, the
  length-weighted average of the adjacent facets' outward normals (interpolated as a P1 field): the
  soft layer's pressure K pos_part(u·ν) and, for the rigid base at u·ν = g, a P1 multiplier λ ≥ 0 by
  the Alart–Curnier augmented Lagrangian, both integrated by the trapezoidal rule (IM_NC(2,1)), so
  that, like vpcontact's lumped quadrature, each contact node i carries w_i (K pos(d_i) + λ_i) ν_i
  with d_i = u(x_i)·ν_i and w_i its share of the length of Γ3, and λ_i = pos(λ_i + r (d_i − g)).

Each time step is one call of GetFEM's Newton solver (`Model.solve`, its default line search, MUMPS)
from the last step's solution, to the residual `tolerance`, which GetFEM measures relative to the norm
of the external loads (its residual is 1 at u = 0), as vpcontact's relative equilibrium residual. The
steps in --record are written to --out (NumPy .npz): the nodes and displacements, and at the contact
nodes the penetration u·ν, the compliance and rigid pressures (forces per unit length).
"""

from __future__ import annotations

import argparse
import re
import sys
import time

import getfem as gf
import numpy as np

#: A line of the $PhysicalNames section of a gmsh file: dimension, tag, "name".
PHYSICAL_NAME = re.compile(r'^\s*(\d+)\s+(\d+)\s+"([^"]*)"\s*$')


def physical_tags(path: str) -> dict[str, int]:
    """The tag of each named physical group of a gmsh file (GetFEM's region numbers)."""
    with open(path) as file:
        text = file.read()
    section = text.split("$PhysicalNames", 1)[1].split("$EndPhysicalNames", 1)[0]
    return {match[3]: int(match[2]) for line in section.splitlines()[1:] if (match := PHYSICAL_NAME.match(line))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mesh", help="gmsh 2.2 file with the physical curves axis, top_arc, bottom_arc")
    parser.add_argument("--steps", type=int, default=141)
    parser.add_argument("--T", type=float, default=1.1)
    parser.add_argument("--E", type=float, default=1000.0)
    parser.add_argument("--nu", type=float, default=0.3)
    parser.add_argument("--K", type=float, default=100.0, help="the layer's constant stiffness")
    parser.add_argument("--g", type=float, default=0.2, help="the layer's thickness (the rigid limit u·ν ≤ g)")
    parser.add_argument("--traction", type=float, default=17.977, help="c in the traction (0, −c t) on top_arc")
    parser.add_argument("--tolerance", type=float, default=1e-10)
    parser.add_argument("--contact-rule", choices=("trapezoidal", "midpoint"), default="trapezoidal",
                        help="quadrature of the contact terms on each facet of Γ3: trapezoidal (vpcontact's lumped "
                             "nodal law) or midpoint (one Gauss point: how far another quadrature moves the solution)")
    parser.add_argument("--record", type=int, nargs="*", default=[], help="steps written to --out")
    parser.add_argument("--out", help="the .npz file of the recorded steps")
    args = parser.parse_args()
    started = time.perf_counter()
    gf.util_trace_level(0)
    gf.util_warning_level(0)

    regions = physical_tags(args.mesh)
    axis, top, contact = regions["axis"], regions["top_arc"], regions["bottom_arc"]
    mesh = gf.Mesh("import", "gmsh", args.mesh)
    mf_u = gf.MeshFem(mesh, 2)
    mf_u.set_classical_fem(1)
    mf_scalar = gf.MeshFem(mesh, 1)
    mf_scalar.set_classical_fem(1)
    bulk = gf.MeshIm(mesh, gf.Integ("IM_TRIANGLE(1)"))
    trapezoidal = gf.MeshIm(mesh, gf.Integ("IM_NC(2,1)"))
    on_facets = trapezoidal if args.contact_rule == "trapezoidal" else bulk

    model = gf.Model("real")
    model.add_fem_variable("u", mf_u)
    lame_lambda = args.E * args.nu / ((1 + args.nu) * (1 - 2 * args.nu))
    lame_mu = args.E / (2 * (1 + args.nu))
    model.add_initialized_data("lambda_", [lame_lambda])
    model.add_initialized_data("mu_", [lame_mu])
    model.add_isotropic_linearized_elasticity_brick(bulk, "u", "lambda_", "mu_")
    model.add_normal_Dirichlet_condition_with_multipliers(trapezoidal, "u", mf_scalar, axis)
    model.add_initialized_data("F", [0.0, 0.0])
    model.add_source_term_brick(bulk, "u", "F", top)

    # vpcontact's nodal normal: Σ_facets n_f |f| / 2 at each node of Γ3, normalized
    first, size = model.interval_of_variable("u")
    summed = gf.asm_generic(bulk, 1, "Normal.Test_u", contact, model)[first:first + size].reshape(-1, 2)
    length = np.linalg.norm(summed, axis=1)
    on_contact = length > 0
    normal = np.zeros_like(summed)
    normal[on_contact] = summed[on_contact] / length[on_contact, None]
    model.add_initialized_fem_data("nu_", mf_u, normal.ravel())
    r = args.E / float(np.median(length[on_contact]))  # E over a node's share of Γ3 (w_i): a stiffness per area
    model.add_initialized_data("K", [args.K])
    model.add_initialized_data("g", [args.g])
    model.add_initialized_data("r", [r])
    model.add_filtered_fem_variable("lam", mf_scalar, contact)
    model.add_nonlinear_term(on_facets, "(K*pos_part(u.nu_) + pos_part(lam + r*(u.nu_ - g)))*(nu_.Test_u)", contact)
    model.add_nonlinear_term(on_facets, "(1/r)*(lam - pos_part(lam + r*(u.nu_ - g)))*Test_lam", contact)

    nodes = mf_u.basic_dof_nodes()[:, ::2]  # (2, nodes): the x and y dofs of a node are consecutive
    contact_nodes = np.flatnonzero(on_contact)
    lam_nodes = mf_scalar.basic_dof_nodes(mf_scalar.basic_dof_on_region(contact))
    record = set(args.record)
    saved: dict[str, list] = {"steps": [], "times": [], "displacement": [], "penetration": [],
                              "pressure_compliance": [], "pressure_rigid": []}
    iterations = []
    for n in range(1, args.steps + 1):
        t = n * args.T / args.steps
        model.set_variable("F", [0.0, -args.traction * t])
        done, converged = model.solve("max_res", args.tolerance, "max_iter", 50, "lsolver", "mumps")
        if not converged:
            sys.exit(f"getfem_half_disc: step {n} (t = {t:g}) did not converge in {done} Newton iterations")
        iterations.append(done)
        if n in record:
            u = model.variable("u").reshape(-1, 2)
            d = np.sum(u[contact_nodes] * normal[contact_nodes], axis=1)
            lam = model.variable("lam")
            saved["steps"].append(n)
            saved["times"].append(t)
            saved["displacement"].append(u)
            saved["penetration"].append(d)
            saved["pressure_compliance"].append(args.K * np.maximum(d, 0.0))
            saved["pressure_rigid"].append(_at(lam, lam_nodes, nodes[:, contact_nodes]))
    if args.out:
        np.savez(args.out, nodes=nodes, contact_nodes=contact_nodes, normals=normal[contact_nodes],
                 newton_iterations=np.array(iterations), dofs=mf_u.nbdof(), augmentation_r=r,
                 seconds=time.perf_counter() - started, **{k: np.array(v) for k, v in saved.items()})


def _at(values: np.ndarray, where: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``values`` given at the points ``where`` (2, k), reordered to ``points`` (2, m) (the same set)."""
    order_from = np.lexsort(where)
    order_to = np.lexsort(points)
    out = np.empty(points.shape[1])
    out[order_to] = values[order_from]
    return out


if __name__ == "__main__":
    main()

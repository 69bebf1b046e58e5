"""
Adaptive meshes at the edge of a punch
======================================

A flat rigid punch with a sharp edge is the classic singular contact problem: the contact pressure
grows like r^(−1/2) towards the edge, the displacement is only in H^(3/2−ε) there, and the energy
error of uniformly refined meshes decays like h^(1/2), that is N^(−1/4) in the number of dofs N,
instead of the N^(−1/2) of a smooth solution. An adaptive loop — solve, estimate, mark, refine —
puts the elements where the error is and recovers the better rate.

The body is the unit square (a roller on its left side, x = 0: the symmetry axis), pressed by the
traction (0, −20 t) on its top onto a flat punch under 0 < x < 1/2 of its bottom: the initial gap is
0 there and (x − 1/2)⁺ beside it (a 45° chamfer). The layer has K ≡ 0 and g = 10⁻³ (Signorini's
problem with a thin gap): the body drops 10⁻³, then the rigid punch carries the load. 11 steps;
eight cycles from a mesh of h = 1/8 (coarse, so that the page builds in seconds; docs/adaptivity.md
measures this estimate against the error on this punch, and the adaptive cycles on the paper's
example).
"""

# %%
# The adaptive run
# ----------------
# ``[adapt]`` solves the whole history on each mesh, folds the residual error indicators of every step
# into one per element (their maximum over the steps), marks the fewest elements that hold half of
# their sum (Dörfler, θ = 0.5) and refines those conformingly.
import numpy as np
from matplotlib.figure import Figure
from matplotlib.tri import Triangulation

import vpcontact

EDGE = np.array([0.5, 0.0])  # the punch's edge


def punch(h: float, cycles: int):
    """The case of the punch on a first mesh of size h, with ``cycles`` adaptive cycles."""
    return vpcontact.load_case({
        "mesh": {"shape": "rectangle", "width": 1.0, "height": 1.0, "h": h},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}],
                     "traction": [{"part": "top", "value": ["0", "-20*t"]}]},
        "contact": {"part": "bottom", "gap": "max(x - 0.5, 0)", "g": 1e-3, "probe": [0.0, 0.0],
                    "stiffness": {"law": "constant", "value": 0.0}},
        "time": {"T": 1.1, "steps": 11},
        "output": {"field_steps": "none", "progress": False},
        "adapt": {"cycles": cycles, "theta": 0.5, "functional": "max", "estimator": "residual"},
    })


def adaptive(case):
    """The adaptive cycles of ``case``: its problem, its [adapt] settings and its output options."""
    return vpcontact.adapt(vpcontact.build_problem(case), case.adapt, case.output)


adaptation = adaptive(punch(1 / 8, cycles=8))
print(adaptation.message)
for row in adaptation.rows:
    print(f"cycle {row['cycle']}: {row['dofs']:5d} dofs, estimate {row['estimate']:.4f}")

# %%
# The same estimate on uniform meshes h = 1/4 … 1/32: one cycle each.
uniform = [adaptive(punch(1 / n, cycles=1)).rows[0] for n in (4, 8, 16, 32)]

# %%
# The final mesh
# --------------
# The refinement gathers at the punch's edge, where the contact zone ends. Elsewhere the elements are
# refined less: the estimate also sees the jumps of the piecewise constant stress all over the body.
mesh = adaptation.mesh.mesh
triangulation = Triangulation(*mesh.p, mesh.t.T)
final_mesh = Figure(figsize=(9.0, 4.4), layout="constrained")
whole, zoom = final_mesh.subplots(1, 2)
for ax, (low, high) in ((whole, (0.0, 1.0)), (zoom, (0.5 - 0.06, 0.5 + 0.06))):
    ax.triplot(triangulation, color="0.2", lw=0.3)
    ax.plot(*EDGE, "o", color="C3", ms=8, markerfacecolor="none")
    ax.set(xlim=(low, high), ylim=(0.0, high - low), aspect="equal", xlabel="x", ylabel="y")
whole.plot([0.0, 0.5], [0.0, 0.0], color="C3", lw=3, label="the punch (gap 0)")
whole.legend(loc="upper right", fontsize=8)
whole.set_title(f"cycle {adaptation.rows[-1]['cycle']}: {mesh.t.shape[1]} triangles", fontsize=9)
zoom.set_title("within 0.06 of the edge (0.5, 0)", fontsize=9)

# %%
# The estimate against the dofs
# -----------------------------
# On the uniform meshes the estimate falls like N^(−1/4), the singular rate; on the adaptive ones it
# soon falls like N^(−1/2), the rate of a smooth solution. The slopes are least-squares fits over the
# last three meshes of each sequence.
dofs = np.array([row["dofs"] for row in adaptation.rows])
estimates = np.array([row["estimate"] for row in adaptation.rows])
uniform_dofs = np.array([row["dofs"] for row in uniform])
uniform_estimates = np.array([row["estimate"] for row in uniform])
slope = np.polyfit(np.log(dofs[-3:]), np.log(estimates[-3:]), 1)[0]
uniform_slope = np.polyfit(np.log(uniform_dofs[-3:]), np.log(uniform_estimates[-3:]), 1)[0]
print(f"slopes in log N: adaptive {slope:.2f}, uniform {uniform_slope:.2f}")

convergence = Figure(figsize=(6.0, 4.4), layout="constrained")
ax = convergence.subplots()
ax.loglog(dofs, estimates, "o-", label=f"adaptive (θ = 0.5): slope {slope:.2f}")
ax.loglog(uniform_dofs, uniform_estimates, "s--", label=f"uniform h = 1/4 … 1/32: slope {uniform_slope:.2f}")
for power, style, text in ((-0.25, ":", "1/4"), (-0.5, "-.", "1/2")):
    ax.loglog(dofs, estimates[0] * (dofs / dofs[0]) ** power, style, color="0.5", lw=0.8, label=f"$N^{{-{text}}}$")
ax.set(xlabel="dofs N", ylabel="estimate (Σ_K max_n η_K²)^½")
ax.legend(fontsize=8)
ax.grid(alpha=0.3, which="both")

# %%
# What must hold
# --------------
# Each cycle refines the elements that carry half of the estimate, so the estimate must fall at every
# cycle; and the mesh must be finer at the punch's edge than away from it. An element's size is
# taken as √(2|K|), its edge for a right isosceles triangle.
assert np.all(np.diff(estimates) < 0.0), estimates

corners = mesh.p[:, mesh.t]  # (2, 3, elements)
first, second = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
size = np.sqrt(np.abs(first[0] * second[1] - first[1] * second[0]))  # √(2|K|)
distance = np.linalg.norm(corners.mean(axis=1) - EDGE[:, None], axis=0)
near, far = np.median(size[distance < 0.1]), np.median(size[distance > 0.3])
print(f"median element size within 0.1 of the edge {near:.4f}, beyond 0.3 from it {far:.4f} "
      f"(ratio {far / near:.1f})")

# %%
# Uniform refinement keeps this ratio at 1. A ratio above 4 means at least two more halvings of the
# elements at the edge than beyond 0.3 from it: a marking that did not single out the edge (the
# estimate spread evenly over the square) would not give it.
assert far / near > 4.0, (near, far)

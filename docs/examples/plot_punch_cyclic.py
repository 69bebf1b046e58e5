"""
A steel punch made in gmsh, indented cyclically
===============================================

A user's own geometry, made with gmsh's Python API and handed to vpcontact as the open gmsh model: a
steel cylinder with a filleted bottom edge (radius R = 5 mm, height H = 10 mm, fillet 1 mm; E = 210 GPa,
ν = 0.3), pressed into a soft layer on a rigid base and lifted off it three times. The loading is
**displacement-controlled**: the top face's vertical displacement u_z = w(t) is prescribed, and the
force is what the run computes, the top's reaction. SI units throughout (m, Pa, N, s; docs/units.md):
the layer's stiffness K is a pressure per length (Pa/m), its history ξ = ∫ u_ν⁺ dt a length × time (m·s).

The layer (thickness g = 0.5 mm, K(ξ) = c_v (1 + α ξ)^β with c_v = 2e10 Pa/m, about a 0.5 mm pad of
10 MPa rubber) either hardens (β = +1) or softens (β = −1) with the penetration it has accumulated. Both
runs follow the same w(t); what differs is the force they need.
"""

# %%
# The punch in gmsh
# -----------------
# The cylinder, its bottom edge filleted, then cut to the quarter x ≥ 0, y ≥ 0 (the problem is symmetric
# about both planes). The faces are found by their centres of mass and named as physical groups: the
# symmetry planes ``sym_x`` (x = 0) and ``sym_y`` (y = 0), which will be on rollers, the flat bottom face
# ``contact`` (a disc of radius R − 1 mm = 4 mm: the fillet curves up from its rim), the ``top`` face where the
# displacement is prescribed, and the volume ``punch``. The mesh is coarse (elements of at most 0.75 mm,
# about 2,600 tetrahedra) so that the page builds in seconds.
import gmsh
import numpy as np
from matplotlib.figure import Figure

import vpcontact

R, H, FILLET = 5e-3, 10e-3, 1e-3  # m
R_FLAT = R - FILLET  # the radius of the flat bottom face

gmsh.initialize(interruptible=False)  # not interruptible: gmsh would keep Python's Ctrl-C handler for itself
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("punch")
occ = gmsh.model.occ
cylinder = occ.addCylinder(0, 0, 0, 0, 0, H, R)  # the axis from (0, 0, 0) to (0, 0, H)
occ.synchronize()
bottom_edge = [tag for _, tag in gmsh.model.getEntities(1) if abs(occ.getCenterOfMass(1, tag)[2]) < 1e-9 * H]
filleted = occ.fillet([cylinder], bottom_edge, [FILLET])
quarter, _ = occ.intersect(filleted, [(3, occ.addBox(0, 0, 0, R, R, H))])
occ.synchronize()
faces = [tag for _, tag in gmsh.model.getBoundary(quarter, oriented=False)]


def faces_at(axis: int, value: float) -> list[int]:
    """The faces whose centre of mass has the coordinate ``axis`` (0, 1, 2: x, y, z) equal to ``value``."""
    return [face for face in faces if abs(occ.getCenterOfMass(2, face)[axis] - value) < 1e-9 * H]


for name, tags in {"sym_x": faces_at(0, 0.0), "sym_y": faces_at(1, 0.0), "contact": faces_at(2, 0.0),
                   "top": faces_at(2, H)}.items():
    assert len(tags) == 1, (name, tags)
    gmsh.model.addPhysicalGroup(2, tags, name=name)
gmsh.model.addPhysicalGroup(3, [tag for _, tag in quarter], name="punch")
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.75e-3)
gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 8)  # about 8 elements around a full turn of the fillet
gmsh.model.mesh.generate(3)

# %%
# The cycles
# ----------
# Each cycle lasts 1 s: the top goes down to w = −0.3 mm in 0.4 s, comes back up to +0.1 mm (lifted off
# the layer: the force returns to zero) in the next 0.4 s, and back to the layer's surface at the end of
# the second. In each second s = t − floor(t), w is the smallest of three straight lines, written as one
# expression of the case (a Python function f(x, y, z, t) would do as well). 20 steps per cycle put a time
# level on every corner of w. The deepest point, 0.3 mm, stays above the rigid base (g = 0.5 mm): the punch
# is steel, so once a node reached the base the force would grow with the steel's own stiffness, about
# E (π R_flat²/4) / H ≈ 2.6e8 N/m, a thousand times the layer's K (π R_flat²/4) ≈ 2.5e5 N/m.
DEPTH, LIFT = 0.3e-3, 0.1e-3  # m
DOWN, UP = 0.4, 0.8  # s: the deepest and the highest point of each cycle
CYCLES, STEPS_PER_CYCLE = 3, 20
phase = "(t - floor(t))"  # s, the time within the cycle
W = (f"min({LIFT:g}*(1 - {phase})/{1 - UP:g}, max(-{DEPTH:g}*{phase}/{DOWN:g}, "
     f"-{DEPTH:g} + {DEPTH + LIFT:g}*({phase} - {DOWN:g})/{UP - DOWN:g}))")
print("w(t) =", W)

E, NU = 210e9, 0.3  # Pa
G, C_V, ALPHA = 0.5e-3, 2e10, 1e4  # m, Pa/m, 1/(m·s)


def punch(beta: float):
    """The quarter punch on rollers, its top moved by w(t), on the layer of exponent ``beta``. The solver's
    tolerance is tightened from 1e-10 to 1e-12: the right-hand side of a step is the steel's stiffness times
    the prescribed displacement, internal forces far larger than the layer's, and the balance below is checked
    to a fraction of the layer's force."""
    return vpcontact.compose(
        gmsh,  # the open gmsh model: its nodes, tetrahedra and physical groups
        {"E": E, "nu": NU},
        dirichlet={"sym_x": "x", "sym_y": "y", "top": {"z": W}},  # rollers; the top's u_z prescribed
        contact={"part": "contact", "g": G, "probe": [0, 0, 0],
                 "stiffness": {"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": beta}},
        time={"T": float(CYCLES), "steps": CYCLES * STEPS_PER_CYCLE},
        solver={"tolerance": 1e-12},
    )


problems = {beta: punch(beta) for beta in (1.0, -1.0)}
gmsh.finalize()  # the problems hold their own copy of the mesh
print(problems[1.0])
DEEPEST = STEPS_PER_CYCLE * (CYCLES - 1) + round(DOWN * STEPS_PER_CYCLE)  # the last cycle's deepest step
runs = {beta: vpcontact.solve(problem, output={"field_steps": [DEEPEST], "progress": False})
        for beta, problem in problems.items()}
for beta, result in runs.items():
    print(f"beta = {beta:+g}: {result}")

# %%
# The punch at the deepest point of the last cycle (β = +1), coloured by the von Mises stress: the
# displacement is nearly a rigid translation by w; the stress, about the force over the flat face
# (1129 N / 50 mm² ≈ 23 MPa), is largest just above the flat face and spreads out higher up.
punch_figure = runs[1.0].plot.deformed(step=DEEPEST)

# %%
# Force against displacement
# --------------------------
# The top's reaction ``reaction_top_z`` (the force the prescribed displacement exerts on the quarter; it pushes
# down, so it is negative) against its displacement ``displacement_top_z``, from ``result.history``, in N and
# mm for the whole punch (4 × the quarter), one colour per cycle; and the contact area over time
# (``contact_area``, also 4 × the quarter's).
#
# The penetration is nearly the prescribed depth −w in both runs (the steel hardly deforms against the
# layer), so the layer's history ξ(t) = ∫ u_ν⁺ dt grows alike in both: by the area under the penetration,
# ½ × 0.3 mm × 0.7 s ≈ 1.05e-4 m·s, α Δξ ≈ 1, per cycle. What differs is K(ξ): on the hardening layer it
# grows with every cycle, and so does the peak force; on the softening one it falls, and each cycle needs
# less force to reach the same depth. Within a cycle the loop opens because ξ grows while the punch is in
# the layer: going back up, at the same depth, K is larger (β = +1, the unloading branch above the loading
# one) or smaller (β = −1, below). Between the cycles the punch is lifted off: the force is zero and the
# contact area drops to zero, then jumps back to the whole flat face as soon as it touches again (50.0 mm²
# as meshed: its polygon is inside the disc, π R_flat² = 50.3 mm²).
loops = Figure(figsize=(10.0, 3.8), layout="constrained")
axes = loops.subplots(1, 3)
for ax, (beta, result) in zip(axes, runs.items()):
    history = result.history
    t = np.concatenate([[0.0], history.t])  # from the start, t = 0, where w = 0 and the force is 0
    indentation = -1e3 * np.concatenate([[0.0], history.displacement_top_z])  # mm
    force = -4 * np.concatenate([[0.0], history.reaction_top_z])  # N, on the whole punch
    cycle = np.ceil(t).astype(int)  # cycle n: (n − 1, n] s, drawn from the point before it
    for n in range(1, CYCLES + 1):
        rows = slice(np.argmax(cycle == n) - 1, np.nonzero(cycle == n)[0][-1] + 1)
        ax.plot(indentation[rows], force[rows], marker=".", color=f"C{n - 1}", label=f"cycle {n}")
    ax.set_title(f"β = {beta:+g} ({'hardening' if beta > 0 else 'softening'})", fontsize=10)
    ax.set_xlabel("indentation −w (mm)")
    ax.set_ylabel("force on the punch (N)")
    ax.legend(fontsize=8, frameon=False)
    axes[2].plot(history.t, 4e6 * history.contact_area, marker=".", lw=1.0, label=f"β = {beta:+g}",
                 ls="-" if beta > 0 else "--")
axes[2].set_xlabel("t (s)")
axes[2].set_ylabel("contact area (mm²)")
axes[2].legend(fontsize=8, frameon=False)
for ax in axes:
    ax.grid(alpha=0.3)
loops.suptitle("Displacement-controlled cycles of the filleted steel punch", fontsize=10)

# %%
# The peak force of each cycle (N, the whole punch) is K(ξ) at the deepest point times the same depth and area:
# on the hardening layer, K = c_v (1 + αξ) is linear in ξ, and each cycle adds the same Δξ, so the peak rises
# by the same amount every cycle; on the softening layer it falls like 1 / (1 + αξ).
peaks = {beta: [-4 * result.history.reaction_top_z[np.ceil(result.history.t) == n].min()
                for n in range(1, CYCLES + 1)] for beta, result in runs.items()}
for beta, peak in peaks.items():
    print(f"beta = {beta:+g}: peak force per cycle {np.round(peak, 1)} N")
assert np.all(np.diff(peaks[1.0]) > 0) and np.all(np.diff(peaks[-1.0]) < 0), peaks

# %%
# The same curve is one call away for any Dirichlet part, in the run's own units (the quarter's force):
built_in = runs[-1.0].plot.force_displacement("top", force="z", displacement="z")

# %%
# What the numbers must satisfy
# -----------------------------
# **The balance.** Nothing is applied to the punch but the prescribed displacement: the top's reaction and
# the foundation's force must cancel (the rollers hold only u_x and u_y). At every step, their sum is the
# residual of the discrete equilibrium summed over the vertical dofs; with the solver's relative tolerance of
# 1e-12 on a right-hand side of the steel's internal forces (each top node's E h × 0.1 mm ≈ 3e4 N, about a hundred
# times the largest layer force) it is a few 1e-11 of the largest force (measured: 5e-11). 1e-9 leaves a
# margin of about 20; a single contact node's force left out (about 1/50 of the force) would fail it by seven
# orders of magnitude.
for beta, result in runs.items():
    history = result.history
    largest = history.contact_force_z.abs().max()
    imbalance = (history.reaction_top_z + history.contact_force_z).abs().max() / largest
    print(f"beta = {beta:+g}: largest |reaction + contact force| / largest force = {imbalance:.1e}")
    assert imbalance < 1e-9, (beta, imbalance)

# %%
# **The first step, by hand.** At t_1 = 0.05 s the top has moved w_1 = −37.5 µm. A rigid punch would press the
# whole flat face uniformly by d = −w_1, so that the layer's implicit history is ξ_1 = k d (k = 0.05 s) and the
# force on the quarter is F = K(ξ_1) d A, with A the area of the quarter of the flat face as the mesh has it
# (its flat triangles, whose lumped weights add up to it: a polygon inside the quarter disc π R_flat²/4, short
# of it by O(h²)). The steel is not rigid: it shortens under F by about F H / (E A), which the layer does not
# see, so F falls short of the rigid value by about K H / E ≈ 1e-3 (a column of the flat face's section over
# the whole height; the fillet and the wider section above it make it less). 2 K H / E is the tolerance: it
# is met with a margin of about 3 (measured 7e-4), while a layer law evaluated at ξ = 0 instead of ξ_1
# (K off by α ξ_1 ≈ 2 %) or the area of the exact quarter disc instead of the mesh's would fail it.
body = problems[1.0].mesh
corners = body.mesh.p[:, body.mesh.facets[:, body.facets("contact")]]  # (3 coordinates, 3 corners, facets)
area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0], axis=0),
                            axis=0).sum()
k = 1.0 / STEPS_PER_CYCLE
for beta, result in runs.items():
    first = result.history.iloc[0]
    d = -first.displacement_top_z
    rigid = C_V * (1.0 + ALPHA * k * d) ** beta * d * area
    shortfall = 1.0 - first.contact_force_z / rigid
    print(f"beta = {beta:+g}: w_1 = {first.displacement_top_z:.4g} m, force {first.contact_force_z:.6g} N, "
          f"rigid punch {rigid:.6g} N (area {area:.6g} m², π R_flat²/4 = {np.pi * R_FLAT**2 / 4:.6g} m²): "
          f"short by {shortfall:.2e}")
    assert 0.0 < shortfall < 2 * C_V * H / E, (beta, shortfall)

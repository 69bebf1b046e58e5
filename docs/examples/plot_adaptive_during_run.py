"""
Adapting the mesh during one run
================================

A viscoplastic block (the unit square, E = 1000, ν = 0.3, Perzyna with a yield stress of 3) is pressed
down onto a hardening layer (g = 0.05, K(ξ) = c_v (1 + α ξ)), under which a rigid step rises under its right
half: the initial gap is 0.02 (x − ½)⁺, so the layer's edge at x = ½ concentrates the pressure. From t = 0.5
the block is also pushed sideways, (60 (t − ½)⁺, −20 t) on its top, and the stress concentrates at the layer's
edge more and more.

With ``adapt.mode = "run"`` one run adapts its mesh as it goes: after every step the residual estimator
gives η(t_n), and while η(t_n) > ``adapt.tolerance`` times the largest energy norm of the solution so far,
the elements carrying the estimate are refined, the level before the step (ξ on Γ3, the viscoplastic history
z per element) is carried to the new mesh and the step is solved again there. docs/adaptivity.md,
"Adapting during the run", says what each transfer conserves and measures what it saves.
"""

# %%
# The run
# -------
# ``after_step`` sees each accepted level on the mesh it was solved on: we keep ∫_Γ3 ξ there, to compare
# below with the history the run hands back on its last mesh.
import numpy as np
from matplotlib.figure import Figure
from matplotlib.tri import Triangulation

import vpcontact

case = vpcontact.load_case({
    "mesh": {"shape": "rectangle", "width": 1.0, "height": 1.0, "h": 1 / 8},
    "material": {"E": 1000.0, "nu": 0.3, "viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}},
    "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}],
                 "traction": [{"part": "top", "value": ["60*max(t-0.5,0)", "-20*t"]}]},
    "contact": {"part": "bottom", "gap": "0.02*max(x - 0.5, 0)", "g": 0.05,
                "stiffness": {"law": "power", "c_v": 1000.0, "alpha": 20.0, "beta": 1.0}},
    "time": {"T": 1.1, "steps": 11},
    "solver": {"tolerance": 1e-12},
    "output": {"field_steps": [11], "progress": False},
    "adapt": {"mode": "run", "tolerance": 0.25},
})
computed = {}  # step -> ∫_Γ3 ξ on the mesh the level was solved on


def remember(loop):
    computed[loop.state.step] = loop.problem.surface.weights @ loop.state.xi


adaptation = vpcontact.adapt(vpcontact.build_problem(case), case.adapt, case.output, after_step=remember)
result = adaptation.result
print(adaptation.message)
for row in adaptation.rows:
    if row["refined"]:
        print(f"step {row['step']} (t = {row['t']:.1f}): η/‖u‖ = {row['relative_estimate']:.3f} on "
              f"{row['dofs']:,} dofs: refined, the step solved again")

# %%
# The estimate along the run
# --------------------------
# η(t_n) over the largest ‖u_h‖_E so far, for every level estimated (the refined ones marked), and the dofs.
# The first step needs a finer mesh than the first one; the estimate then falls while the block is only pressed
# (the solution grows smoother relative to its size) and rises once it is pushed sideways, until a second
# refinement brings it under the tolerance.
rows = adaptation.rows
t = np.array([row["t"] for row in rows])
relative = np.array([row["relative_estimate"] for row in rows])
refined = np.array([row["refined"] for row in rows])
dofs = np.array([row["dofs"] for row in rows])
along = Figure(figsize=(8.0, 3.8), layout="constrained")
left, right = along.subplots(1, 2)
left.plot(t[~refined], relative[~refined], "o-", label="accepted")
left.plot(t[refined], relative[refined], "x", color="C3", ms=9, label="refined, solved again")
left.axhline(case.adapt.tolerance, color="0.5", ls="--", lw=0.8, label="adapt.tolerance")
left.set(xlabel="t", ylabel="η / max ‖u_h‖_E")
left.legend(fontsize=8)
right.step(t, dofs, where="post")
right.set(xlabel="t", ylabel="dofs", yscale="log")
for ax in (left, right):
    ax.grid(alpha=0.3)

# %%
# The last mesh
# -------------
# Refined at the layer's edge (½, 0), where the pressure concentrates, and where the sideways push loads the
# block's bottom corner.
mesh = adaptation.mesh.mesh
final_mesh = Figure(figsize=(5.0, 4.6), layout="constrained")
ax = final_mesh.subplots()
ax.triplot(Triangulation(*mesh.p, mesh.t.T), color="0.2", lw=0.3)
ax.plot([0.5, 1.0], [0.0, 0.0], color="C3", lw=3, label="the rigid step (gap > 0)")
ax.set(aspect="equal", xlabel="x", ylabel="y", title=f"{result.dofs:,} dofs after {adaptation.refinements} refinements")
ax.legend(loc="upper right", fontsize=8)

# %%
# What must hold
# --------------
# The history is carried, not recomputed: ξ along Γ3 (a P1 function, interpolated at the new nodes) keeps its
# integral Σ_i w_i ξ_i through every refinement, to rounding, so each row of the history handed back on the last
# mesh integrates to what the level had on its own mesh. And the block stays in balance at every level, before
# and after each refinement: the contact force, the load and the roller's reaction add up to zero.
w = adaptation.problem.surface.weights
carried = result.contact_history("xi") @ w
expected = np.array([computed[n] for n in range(1, 12)])
print(f"largest relative difference of ∫ξ: {np.max(np.abs(carried - expected) / expected):.1e}")
assert np.allclose(carried, expected, rtol=1e-12), (carried, expected)
assert adaptation.refinements >= 2 and max(r["step"] for r in rows if r["refined"]) > 5, rows

history = result.history
balance = history["contact_force_y"] + history["applied_force_y"] + history["reaction_left_y"]
assert np.all(np.abs(balance) < 1e-9 * history["applied_force_y"].abs().max()), balance

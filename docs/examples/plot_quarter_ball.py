"""
The 3D quarter ball
===================

The paper's example in three dimensions: a quarter of a ball of radius 1,
{x > 0, y > 0, x² + y² + (z − 1)² < 1}, pressed by a vertical traction on its upper half onto a soft
layer of thickness g = 0.2 that conforms to its lower half, with the history-dependent stiffness
K(ξ) = 100 (1 + 20 ξ)^β. Rollers on the two symmetry planes x = 0 and y = 0 make it a whole ball.

This is ``examples/quarter_ball.toml`` composed in Python (``vpcontact.compose``, no case file), on a
mesh coarser than the example's (h = 0.15 instead of 0.1: about 8,000 dofs instead of 24,000) so that
the page builds in a few seconds.
"""

# %%
# The problem, composed in Python
# -------------------------------
# In the order a mechanician writes it: the mesh, the material, the supports, the load, the contact
# law, the time grid. The load (0, 0, −c t) with c = 11.4443 is the 3D calibration of the paper's
# load: with β = 1 the stiffness at the bottom point reaches K = 323 at t = 1.1, the value the paper
# reports in 2D.
import tempfile
from pathlib import Path

import numpy as np

import vpcontact
from vpcontact import mesh
from vpcontact.results import plots

C = 11.4443  # the traction's rate, per unit area of the upper half

problem = vpcontact.compose(
    mesh.quarter_ball(h=0.15),
    material={"E": 1000.0, "nu": 0.3},
    dirichlet={"sym_x": "x", "sym_y": "y"},  # u_x = 0 on x = 0, u_y = 0 on y = 0
    traction={"top": ["0", "0", f"-{C}*t"]},
    contact={"part": "bottom", "g": 0.2, "probe": [0, 0, 0],
             "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
    time={"T": 1.1, "steps": 11},
)
print(problem)

# %%
# The problem knows its sizes before anything is solved. The time loop keeps the fields (displacement,
# stress) at the steps asked for:
result = vpcontact.solve(problem, output={"field_steps": [2, 5, 8, 11]})
print(result)

# %%
# The contact patch
# -----------------
# The layer conforms to the whole lower half, so every node of Γ3 presses on it from the first step
# on; the pressure K(ξ) u_ν⁺ is largest at the bottom point, where the penetration, and with it the
# hardening, is largest. Seen from below, at four times:
patch = plots.contact_pressure(result, steps=[2, 5, 8, 11])

# %%
# The deformed body, coloured by the von Mises stress (the displacements magnified):
body = plots.deformed_body(result, step=11)

# %%
# The history
# -----------
# One row per time step (a pandas DataFrame, the table of ``history.csv``): the stiffness and the
# penetration at the probe (the bottom point), the node counts, and the vertical resultant of the
# contact pressure.
history = result.history
history[["t", "K_probe", "penetration_probe", "nodes_in_compliance", "nodes_at_limit", "contact_force_z"]]

# %%
# The same columns against t:
series = plots.time_series(result, ["K_probe", "penetration_probe", "contact_force_z"])

# %%
# And the contact nodes at the last step, one row each (``result.contact_table()``), here the five
# lowest: the pressure is largest at the bottom point and falls towards the equator.
nodes = result.contact_table()
nodes.sort_values("z")[["x", "y", "z", "penetration", "xi", "K", "pressure_compliance"]].head()

# %%
# The standard outputs of a run directory (ParaView series, CSV tables, ``summary.json``) are one call
# away; here into a temporary directory:
with tempfile.TemporaryDirectory() as folder:
    written = vpcontact.write_run(result, Path(folder) / "quarter_ball")
    print(sorted(path.name for path in written.iterdir()))

# %%
# Equilibrium
# -----------
# Nothing holds the ball vertically but the foundation: the rollers react only along x and y. So the
# vertical contact force must balance the applied load, c t times the area of the upper half as the
# mesh represents it (its flat triangles: about π/2, the area of a quarter of a unit hemisphere,
# short by the facets' sag, O(h²)).
ball = problem.mesh
corners = ball.mesh.p[:, ball.mesh.facets[:, ball.facets("top")]]  # (3 coordinates, 3 corners, facets)
area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0], axis=0),
                            axis=0).sum()
print(f"area of the upper half: {area:.6f} (π/2 = {np.pi / 2:.6f})")
load = C * result.times * area
imbalance = np.abs(result.series("contact_force_z") - load) / load
print(f"largest relative imbalance over the steps: {imbalance.max():.2e}")

# The discrete equilibrium holds to the Newton solver's tolerance: the residual is below 1e-10 times
# the Euclidean norm of the load vector (solver.tolerance), so its sum over the z components is below
# about 1e-10 √(dofs / loaded dofs), a few 1e-10 of the load (measured: 7e-11). 1e-8 leaves a margin
# of 30 for that, while the pressure of a single node missing (about 1/331 of the force) would fail
# it by five orders of magnitude.
assert imbalance.max() < 1e-8, imbalance

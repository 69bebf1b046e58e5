r"""
The limit ρ → 0: towards Signorini's problem with a gap
=======================================================

The paper's Problem :math:`P_V^\rho` scales the layer's stiffness, :math:`K_\rho = \rho K`: as ρ → 0 the
soft layer carries nothing and the solution tends to that of the Signorini problem with gap g (the body
moves freely until it reaches the rigid base). The paper shows the convergence in its Fig. 8; here it
is measured on the paper's example (``examples/paper_ball.toml``, β = 1, on a coarser mesh h = 0.05)
for ρ = 1, 10⁻¹, …, 10⁻⁵, against the run with K ≡ 0, at the final time t = 1.1, in the norms of the
paper's convergence study: ‖u_ρ − u_*‖_V = ‖ε(u_ρ − u_*)‖ and ‖σ_ρ − σ_*‖_Q (L² over the body,
:func:`vpcontact.results.norms.differences`).
"""

# %%
# The runs
# --------
# ``contact.rho`` is ρ; the limit is the same case with ``contact.stiffness`` the constant 0.
import numpy as np
from matplotlib.figure import Figure

import vpcontact
from vpcontact.results import norms

CASE = "../../examples/paper_ball.toml"  # relative to this example's folder, docs/examples
coarse = {"mesh.h": 0.05, "output.field_steps": "final", "output.progress": False}
limit = vpcontact.solve(vpcontact.load_case(CASE, {**coarse, "contact.stiffness": {"law": "constant", "value": 0.0}}))

RHO = np.array([1.0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5])
difference, at_limit = [], []
for rho in RHO:
    result = vpcontact.solve(vpcontact.load_case(CASE, {**coarse, "contact.rho": rho}))
    norm = norms.differences(result.snapshot(), limit.snapshot())
    difference.append(norm["V"] + norm["Q"])
    at_limit.append(result.series("nodes_at_limit")[-1])
    print(f"rho = {rho:7.0e}: |u - u*|_V + |sigma - sigma*|_Q = {difference[-1]:.4e}, "
          f"{at_limit[-1]} of {result.contact_nodes} contact nodes at the limit g")
difference = np.array(difference)
print(f"K = 0: {limit.series('nodes_at_limit')[-1]} of {limit.contact_nodes} contact nodes at the limit g")

# %%
# The difference against ρ
# ------------------------
figure = Figure(figsize=(5.5, 4), layout="constrained")
axes = figure.subplots()
axes.loglog(RHO, difference, "o-", label="‖u_ρ − u_*‖_V + ‖σ_ρ − σ_*‖_Q")
axes.loglog(RHO, difference[-1] * RHO / RHO[-1], "k--", label="slope 1")
axes.set(xlabel="ρ", ylabel="difference at t = 1.1", title="P_V^ρ against Signorini with gap g")
axes.legend()
figure

# %%
# What the study must satisfy
# ---------------------------
# The difference must decrease with ρ at every step of the sweep. Once ρ is small enough that the same
# nodes reach the rigid base as in the limit (ρ ≤ 10⁻²), the layer's force ρK(ξ)p(u_ν) is a
# perturbation of order ρ of a problem whose active set no longer changes, so the difference is linear
# in ρ: the log–log slope over ρ = 10⁻², …, 10⁻⁵ must be 1 (to 0.02: the O(ρ²) terms change it by
# about 10⁻² at ρ = 10⁻²; measured 0.999).
assert np.all(np.diff(difference) < 0), difference
small = RHO <= 1e-2
assert all(n == limit.series("nodes_at_limit")[-1] for n, s in zip(at_limit, small) if s)
slope = np.polyfit(np.log10(RHO[small]), np.log10(difference[small]), 1)[0]
print(f"slope in rho over rho <= 1e-2: {slope:.4f}")
assert abs(slope - 1) < 0.02, slope

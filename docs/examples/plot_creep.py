"""
Creep under a held load
=======================

A viscoplastic body keeps deforming under a load that no longer changes. The model's constitutive
law (2.1) is σ' = ℰε(u') + 𝒢(σ, ε(u)), here with the Perzyna function::

    𝒢(σ, ε) = −(1/η) (1 − σ_y / ‖dev σ‖)⁺ dev σ

the stress is elastic inside the yield set ‖dev σ‖ ≤ σ_y and relaxes towards it outside, at the rate
1/η. Where the stress cannot relax, because the load holds it, the strain grows instead: creep.

This is ``examples/viscoplastic_ball.toml`` (see docs/viscoplasticity.md) on a coarser mesh
(h = 0.025 instead of 0.0125), then a homogeneous block whose creep rate is known in closed form.
"""

# %%
# The ball: ramp, then hold
# -------------------------
# The paper's half disc with its calibrated load, ramped up to t = 0.5 and held until t = 2
# (k = 0.1, as in the paper; η = 0.5, σ_y = 3 against an elastic peak ‖dev σ‖ of about 20). The same
# case with an elastic body (no ``viscoplastic`` table) is the reference. The probe is the rim of the
# contact part, (1, 1).
import numpy as np
from matplotlib.figure import Figure

import vpcontact
from vpcontact.results import plots

HOLD = 0.5  # the load is ramped up to this time, then held


def ball(viscoplastic: bool):
    material = {"E": 1000.0, "nu": 0.3}
    if viscoplastic:
        material["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
    return vpcontact.load_case({
        "mesh": {"shape": "half_disc", "h": 0.025},
        "material": material,
        "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                     "traction": [{"part": "top_arc", "value": ["0", f"-17.977*min(t, {HOLD})"]}]},
        "contact": {"part": "bottom_arc", "g": 0.2, "probe": [1.0, 1.0],
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
        "time": {"T": 2.0, "steps": 20},
        "output": {"field_steps": [5, 20], "progress": False},
    })


viscous_case = ball(True)
viscous = vpcontact.build_problem(viscous_case)
creeping = vpcontact.solve(viscous, output=viscous_case.output)  # the fields at steps 5 and 20
elastic = vpcontact.solve(ball(False))  # built and solved in one call
print(creeping)

# %%
# While the load is held, the viscoplastic ball keeps flattening: the penetration at the rim grows
# every step, four-fold over the hold, where the elastic ball's hardly moves. At the bottom point both
# fall: the layer hardens under the accumulated penetration (β = 1) and carries the same load with less
# penetration, the more so under the creeping ball, which spreads the load towards the rim.
t = creeping.times
bottom = viscous.surface.nearest_node([0.0, 0.0])  # the contact node at the bottom point
creep = Figure(figsize=(7.0, 5.0), layout="constrained")
axes = creep.subplots(2, 1, sharex=True)
for result, label, style in ((creeping, "Perzyna body", "-"), (elastic, "elastic body", "--")):
    axes[0].plot(t, result.series("penetration_probe"), "o" + style, ms=3, color="C0", label=label)
    axes[1].plot(t, result.contact_history("penetration")[:, bottom], "o" + style, ms=3, color="C1", label=label)
axes[0].set_ylabel("penetration at the rim (1, 1)")
axes[1].set_ylabel("penetration at (0, 0)")
axes[1].set_xlabel("t")
for ax in axes:
    ax.axvspan(HOLD, t[-1], color="0.92", zorder=0)
    ax.legend(fontsize=8, frameon=False)
    ax.grid(alpha=0.3)
creep.suptitle("Load ramped up to t = 0.5 (white), then held (grey)", fontsize=10)

# %%
# The deformed ball at the end of the hold, coloured by the von Mises stress:
deformed = plots.deformed_body(creeping, step=20)

# %%
# Creep is the growth of the penetration at constant load: at the rim it must grow at every step of
# the hold.
held = t >= HOLD
rim = creeping.series("penetration_probe")[held]
print(f"penetration at the rim: {rim[0]:.5f} at t = {HOLD}, {rim[-1]:.5f} at t = {t[-1]:g}")
assert np.all(np.diff(rim) > 0.0), rim

# %%
# A block creeping at a known rate
# --------------------------------
# A unit square on the same kind of layer (here of constant stiffness K = 100, no rigid base), a
# roller on its left side, its top pressed by −q(t) ramped to q = 10 and held; its right side is
# free. The stress is then uniaxial and homogeneous, σ = diag(0, −q): statically determined, so the
# viscoplastic law cannot relax it. Once q is held, 𝒢(σ) is a constant and the strain grows at the
# constant rate ε' = −ℰ⁻¹𝒢(σ). With dev σ = diag(q/2, −q/2), trace free, so that
# ℰ⁻¹ dev σ = dev σ / 2μ::
#
#     ε'_yy = −(1 − √2 σ_y / q) q / (4 μ η),
#
# and since the layer's penetration q/K stays put, the top sinks at the rate H ε'_yy (H = 1). A P1
# displacement and P0 stress represent this state exactly, and the explicit step of the history,
# z ← z + k 𝒢(σ), integrates a constant rate exactly, so the discrete rate must be the closed form
# to rounding, on any mesh.
E, NU, ETA, YIELD, Q = 1000.0, 0.3, 0.5, 3.0, 10.0
block = vpcontact.load_case({
    "mesh": {"shape": "rectangle", "width": 1.0, "height": 1.0, "h": 0.25},
    "material": {"E": E, "nu": NU, "viscoplastic": {"law": "perzyna", "eta": ETA, "yield_stress": YIELD}},
    "boundary": {"dirichlet": [{"part": "left", "components": ["x"]}],
                 "traction": [{"part": "top", "value": ["0", f"-{Q}*min(t, {HOLD})/{HOLD}"]}]},
    "contact": {"part": "bottom", "g": "inf", "stiffness": {"law": "constant", "value": 100.0}},
    "time": {"T": 2.0, "steps": 20},
    "output": {"field_steps": "all", "progress": False},
})
square_problem = vpcontact.build_problem(block)
square = vpcontact.solve(square_problem, output=block.output)
top = square_problem.mesh.nodes("top")
settlement = np.array([square.fields[n].displacement[top, 1].mean() for n in range(1, square.steps + 1)])
rates = np.diff(settlement) / square_problem.k  # the top's velocity between consecutive steps
mu = E / (2.0 * (1.0 + NU))
expected = -(1.0 - np.sqrt(2.0) * YIELD / Q) * Q / (4.0 * mu * ETA)
holding = square.times[:-1] >= HOLD  # both ends of the interval in the hold
print(f"creep rate of the top during the hold: {rates[holding]} (closed form {expected:.10f})")

# %%
# With K constant and every contact node pressed, each step's problem is linear and solved to
# rounding (relative residuals below 1e-13): the rates agree with the closed form to about 2e-12. The
# tolerance 1e-9 leaves a margin of 500 for rounding, while a yield stress off by 1 % would change
# the rate by 0.7 %.
assert np.allclose(rates[holding], expected, rtol=1e-9, atol=0.0), (rates[holding], expected)

"""
Cyclic loading: a layer that remembers
======================================

The paper loads its ball monotonically. What the history-dependent stiffness K(ξ) is made for shows
under repeated loading: the accumulated penetration ξ(t) = ∫₀ᵗ u_ν⁺ ds (2.15) only grows, a little
more at every cycle, so a hardening layer (β > 0) stiffens cycle after cycle and the body sinks less
into it each time, while a softening layer (β < 0) gives way more each time. Between two loads most
of the contact boundary lifts off: a separated node adds nothing to its ξ, and its stiffness stays
where it was.

Here the paper's half disc (radius 1, E = 1000, ν = 0.3, plane strain) rests on a flat foundation: a
soft layer of thickness g = 0.2 below the plane y = 0, K(ξ) = 100 (1 + 20 ξ)^β, touched at first only
at the bottom point (the initial gap along the vertical is y). Its upper arc is pushed down three
times, f(t) = −(0.02 + 2 max(0, sin 2πt)), three periods of length 1, with 20 steps per period on a
mesh of h = 0.025 (coarse, for a page built in seconds; the numbers below change by about 1 % from
h = 0.05).
"""

# %%
# Two runs, β = 1 and β = −1
# --------------------------
# The small constant part of the load (0.02, 1 % of the peak) keeps the ball resting on the layer
# between the pulses: a body that left the foundation entirely would have nothing to fix its vertical
# position, and the run would stop there (exit 3, "no contact node carries a force"). The probe is the contact node nearest to (0.2, 0), off the bottom point, in contact only
# around the peaks.
import numpy as np
from matplotlib.figure import Figure

import vpcontact
from vpcontact.results import plots

PERIODS, STEPS_PER_PERIOD = 3, 20
C_V, ALPHA = 100.0, 20.0


def cyclic_case(beta: float):
    return vpcontact.load_case({
        "mesh": {"shape": "half_disc", "h": 0.025},
        "material": {"E": 1000.0, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],  # the symmetry axis
                     "traction": [{"part": "top_arc", "value": ["0", "-(0.02 + 2*max(0, sin(2*pi*t)))"]}]},
        "contact": {"part": "bottom_arc", "g": 0.2, "normal": [0, -1], "gap": "y", "probe": [0.2, 0.0],
                    "stiffness": {"law": "power", "c_v": C_V, "alpha": ALPHA, "beta": beta}},
        "time": {"T": float(PERIODS), "steps": PERIODS * STEPS_PER_PERIOD},
        "output": {"field_steps": "none", "progress": False},
    })


runs = {beta: vpcontact.solve(cyclic_case(beta)) for beta in (1.0, -1.0)}
for beta, result in runs.items():
    print(f"beta = {beta:+g}: {result}")

# %%
# The probe, cycle after cycle
# ----------------------------
# While the load is off (the second half of each period) the probe is separated, its penetration
# negative, and its stiffness K(ξ) stays flat: the curves are staircases. With β = 1 each step goes up
# and each peak of the penetration is lower than the one before; with β = −1 each step goes down and
# each peak is higher.
t = runs[1.0].times
load = 0.02 + 2.0 * np.maximum(0.0, np.sin(2.0 * np.pi * t))
cycles = Figure(figsize=(7.0, 8.0), layout="constrained")
axes = cycles.subplots(4, 1, sharex=True)
axes[0].plot(t, load, color="0.3", marker=".")
axes[0].set_ylabel("traction |f|")
for color, (beta, result) in zip(("C0", "C1"), runs.items()):
    label = f"β = {beta:+g} ({'hardening' if beta > 0 else 'softening'})"
    axes[1].plot(t, result.series("penetration_probe"), color=color, marker=".", label=label)
    axes[2].plot(t, result.series("K_probe"), color=color, marker=".", label=label)
    in_contact = result.series("nodes_in_compliance") + result.series("nodes_at_limit")
    axes[3].plot(t, in_contact, color=color, marker=".", label=label)
axes[1].axhline(0.0, color="0.5", lw=0.8)
axes[1].set_ylabel("penetration at the probe")
axes[2].set_ylabel("K at the probe")
axes[3].set_ylabel("nodes in contact")
axes[3].set_xlabel("t")
axes[1].legend(fontsize=8, frameon=False)
for ax in axes:
    ax.grid(alpha=0.3)
cycles.suptitle(f"Three load cycles on the half disc ({runs[1.0].contact_nodes} contact nodes)", fontsize=10)

# %%
# Along Γ3 at the end, the history the layer keeps: ξ is largest at the bottom point, where the ball
# pressed every time, and zero beyond the widest contact patch.
along = plots.along_contact({f"β = {beta:+g}": result for beta, result in runs.items()}, ("xi", "K"))

# %%
# What the numbers must satisfy
# -----------------------------
# Three properties of the discrete model, checked at every node and every step:
#
# * the history follows the implicit rectangle rule ξᵢⁿ = ξᵢⁿ⁻¹ + k (dᵢⁿ)⁺ (README, "The model"),
#   so it is constant while a node is separated and grows only in contact;
# * the stiffness is the law evaluated at the run's ξ, K = c_v (1 + α ξ)^β;
# * the body really separates: nodes leave the layer at the unloaded times, but never all of them
#   (the preload keeps the ball resting on the layer).
k = 1.0 / STEPS_PER_PERIOD
unloaded = np.sin(2.0 * np.pi * t) < 0.0
peaks = {}
for beta, result in runs.items():
    xi, d, K = (result.contact_history(name) for name in ("xi", "penetration", "K"))
    increments = np.diff(np.vstack([np.zeros(xi.shape[1]), xi]), axis=0)
    # ξ is a sum of at most 60 terms of size ≤ k·0.2: its rounding is a few 1e-16 of its largest value.
    assert np.allclose(increments, k * np.maximum(d, 0.0), rtol=0.0, atol=1e-13 * xi.max())
    assert np.allclose(K, C_V * (1.0 + ALPHA * xi) ** beta, rtol=1e-13, atol=0.0)  # one power: rounding only
    assert np.all(result.series("nodes_separated")[unloaded] > 0)
    assert np.all(result.series("nodes_separated") < result.contact_nodes)
    assert np.all(result.series("penetration_probe")[unloaded] < 0.0)  # the probe lifts off between pulses
    penetration = result.series("penetration_probe")
    peaks[beta] = np.array([penetration[(t > n) & (t <= n + 1)].max() for n in range(PERIODS)])
    print(f"beta = {beta:+g}: peak penetration at the probe per cycle {np.round(peaks[beta], 4)}")

# %%
# The ratchet itself: the peaks fall cycle after cycle on the hardening layer and rise on the softening
# one. The relative change per cycle is 17–34 % here, far above the solver's tolerance (1e-10) and the
# 1 % the mesh changes them by, so a strict ordering is a safe test of the sign of the effect.
assert np.all(np.diff(peaks[1.0]) < 0.0) and np.all(np.diff(peaks[-1.0]) > 0.0), peaks

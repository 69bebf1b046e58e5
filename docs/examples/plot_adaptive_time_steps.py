"""
Time steps chosen by the error in time
======================================

The paper's half disc, viscoplastic (Perzyna, η = 0.5, yield stress 3) on a hardening layer, is loaded in 0.1 s
by the calibrated traction, which is then held to t = 4 while the body creeps. The run has 8 steps of 0.5 s.

With ``time.adaptive = true`` each step is done in as many sub-steps as keep the estimate of the error in time
within its share of the space estimate (``time.balance`` = 0.3 here). The estimate in time comes from a companion
of the run that integrates the histories ξ and z by the trapezoid rule (second order) where the run uses the
rectangle rules (first order): η_k(t) = ‖ũ − u‖_E. docs/adaptivity.md, "The error in time", measures it against
the error of runs with 8× as many steps and says when adaptive steps pay.
"""

# %%
# The runs
# --------
# The adaptive run, and a uniform run with as many levels as the adaptive one has history rows.
import numpy as np
from matplotlib.figure import Figure

import vpcontact


def case(steps, adaptive):
    return {
        "mesh": {"shape": "half_disc", "h": 0.1},
        "material": {"E": 1000.0, "nu": 0.3, "viscoplastic": {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}},
        "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                     "traction": [{"part": "top_arc", "value": ["0", "-17.977*min(t/0.1, 1)"]}]},
        "contact": {"part": "bottom_arc", "g": 0.2,
                    "stiffness": {"law": "power", "c_v": 100.0, "alpha": 20.0, "beta": 1.0}},
        "time": {"T": 4.0, "steps": steps, **({"adaptive": True, "balance": 0.3} if adaptive else {})},
        "output": {"field_steps": "final", "error_estimate": True, "progress": False},
    }


adaptive = vpcontact.solve(case(8, adaptive=True))
history = adaptive.history
uniform = vpcontact.solve(case(len(history), adaptive=False)).history
summary = adaptive.summary()
print(f"{len(history)} levels in 8 steps, {summary['time_cuts']} sub-steps done again as halves, "
      f"{summary['time_over_share']} accepted above their share")

# %%
# The steps and the estimates along the run
# -----------------------------------------
# Short sub-steps while the load rises and the body starts to flow (a kink in the rates where each element
# yields, where halving helps little), long ones while it creeps. The ratio η_k / η_h of the adaptive run stays
# below that of the uniform run with as many levels, whose error in time is largest where the load rises.
figure = Figure(figsize=(8.5, 3.8), layout="constrained")
left, right = figure.subplots(1, 2)
left.step(history["t"], history["k"], where="pre", label="adaptive")
left.axhline(4.0 / len(history), color="C1", label=f"uniform, {len(history)} steps")
left.set(xlabel="t", ylabel="step length k", yscale="log")
right.plot(history["t"], history["time_estimate"] / history["error_estimate"], label="adaptive")
right.plot(uniform["t"], uniform["time_estimate"] / uniform["error_estimate"], label="uniform")
right.set(xlabel="t", ylabel="η_k / η_h", xscale="symlog", xlim=(0, 4.0))
for ax in (left, right):
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)

# %%
# What must hold
# --------------
# D = ũ − u changes by what each level adds, so the estimate at every level is within the sum of what the
# levels so far added (the triangle inequality); each step ends at its own time; the adaptive run has the smaller
# largest ratio of the two.
eta_k, theta = history["time_estimate"].to_numpy(), history["time_estimate_step"].to_numpy()
assert np.all(eta_k <= np.cumsum(theta) * (1 + 1e-12))
ends = history.drop_duplicates("step", keep="last")
assert np.allclose(ends["t"], 0.5 * np.arange(1, 9), rtol=1e-15, atol=0)
largest = (history["time_estimate"] / history["error_estimate"]).max()
largest_uniform = (uniform["time_estimate"] / uniform["error_estimate"]).max()
print(f"largest η_k / η_h: adaptive {largest:.3f}, uniform {largest_uniform:.3f}")
assert largest < largest_uniform

r"""
A stiffness law K(ξ) written in Python
======================================

The case file knows three families of K(ξ) (power, constant, exponential). Any other law is a Python
object passed to :func:`vpcontact.solve` as ``stiffness_law``: a function of a NumPy array of ξ (one
value per contact node) and, for Newton's method, its derivative dK/dξ as a ``derivative`` method (a
plain function gets a central-difference derivative). Here a layer that hardens and saturates,

.. math:: K(\xi) = K_\infty + (K_0 - K_\infty)\, e^{-\xi/\xi_0},

from K_0 for a fresh layer to K_∞ for one penetrated long enough, on the paper's example
(``examples/paper_ball.toml``, on a coarser mesh h = 0.05).
"""

# %%
# The law
# -------
from dataclasses import dataclass

import numpy as np
from matplotlib.figure import Figure

import vpcontact


@dataclass(frozen=True)
class SaturatingStiffness:
    """K(ξ) = K_∞ + (K_0 − K_∞) exp(−ξ/ξ_0), vectorized over the contact nodes' ξ."""

    K0: float
    K_inf: float
    xi0: float

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.K_inf + (self.K0 - self.K_inf) * np.exp(-xi / self.xi0)

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return -(self.K0 - self.K_inf) / self.xi0 * np.exp(-xi / self.xi0)


CASE = "../../examples/paper_ball.toml"  # relative to this example's folder, docs/examples
coarse = {"mesh.h": 0.05, "output.progress": False}
case = vpcontact.load_case(CASE, coarse)

# %%
# A first check: a law the case file knows too
# --------------------------------------------
# With K_∞ = 0 the law is K_0 exp(−ξ/ξ_0), the built-in ``exponential`` law with c_v = K_0 and
# α = −1/ξ_0 (a softening layer). The two runs solve the same discrete problem, one through the Python
# object, one through the case's keys: they must agree to the solver's tolerance.
softening = SaturatingStiffness(K0=100.0, K_inf=0.0, xi0=0.05)
in_python = vpcontact.solve(case, stiffness_law=softening)
built_in = vpcontact.solve(vpcontact.load_case(CASE, {
    **coarse, "contact.stiffness": {"law": "exponential", "c_v": 100.0, "alpha": -1 / 0.05}}))
gap = np.abs(in_python.final.displacement - built_in.final.displacement).max()
scale = np.abs(built_in.final.displacement).max()
print(f"K(0, 0; 1.1): {in_python.series('K_probe')[-1]:.10g} (Python law), "
      f"{built_in.series('K_probe')[-1]:.10g} (built-in); largest displacement difference {gap:.2e} of {scale:.3g}")

# %%
# The saturating layer, between its two limits
# --------------------------------------------
# K_0 = 100 stiffening to K_∞ = 400 over ξ_0 = 0.05, against the constant layers K ≡ K_0 and K ≡ K_∞.
hardening = SaturatingStiffness(K0=100.0, K_inf=400.0, xi0=0.05)
saturating = vpcontact.solve(case, stiffness_law=hardening)
bounds = {value: vpcontact.solve(vpcontact.load_case(CASE, {
    **coarse, "contact.stiffness": {"law": "constant", "value": value}})) for value in (100.0, 400.0)}

figure = Figure(figsize=(9, 3.5), layout="constrained")
law_axes, penetration_axes = figure.subplots(1, 2)
xi = np.linspace(0, 0.3, 200)
law_axes.plot(xi, hardening(xi), "k-", label="K(ξ)")
law_axes.plot(saturating.contact_history("xi")[-1], saturating.contact_history("K")[-1], "o",
              label="the contact nodes at t = 1.1")
law_axes.set(xlabel="ξ", ylabel="K", title="the saturating law")
law_axes.legend()
for label, result in (("K ≡ 100", bounds[100.0]), ("saturating", saturating), ("K ≡ 400", bounds[400.0])):
    penetration_axes.plot(result.times, result.series("penetration_probe"), "o-", label=label)
penetration_axes.set(xlabel="t", ylabel="u_ν(0, 0; t)", title="penetration at the bottom point")
penetration_axes.legend()
figure

# %%
# What the runs must satisfy
# --------------------------
# - The Python law and the built-in law give the same solution: the same discrete problem solved by the
#   same Newton iteration, the two laws' values differing by rounding only, so the displacements must
#   agree to far below the solver's tolerance (10⁻¹⁰): we ask for 10⁻¹⁰ of their size (measured 10⁻¹⁵).
# - The K reported at every node and step is the law at the reported ξ (to rounding): the run used the
#   Python object, not the case's power law.
# - The saturating layer is at least as stiff as K ≡ K_0 and at most as stiff as K ≡ K_∞ everywhere and
#   always, so the bottom point sinks no less than under K_∞ and no more than under K_0 at every step
#   (a comparison that holds for this monotone load; to 10⁻⁹ of g for the solver's tolerance).
assert gap < 1e-10 * scale, gap
np.testing.assert_allclose(saturating.contact_history("K"), hardening(saturating.contact_history("xi")), rtol=1e-12)
below, above = bounds[400.0].series("penetration_probe"), bounds[100.0].series("penetration_probe")
middle = saturating.series("penetration_probe")
assert np.all(below - 2e-10 <= middle) and np.all(middle <= above + 2e-10)
assert below[-1] < middle[-1] < above[-1]

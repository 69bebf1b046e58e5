"""What the paper states (Barboteu, Han, Sofonea, Sect. 4): its example with the calibrated load, the
numbers it prints, the times of its figures and its four contact conditions."""

from __future__ import annotations

#: The paper's example with the calibrated load: the content of examples/paper_ball.toml (a test
#: checks that the two resolve to the same case), carried by the package so that `reproduce` does not
#: depend on a source checkout.
PAPER_CASE = """\
# The paper's example (Barboteu, Han, Sofonea, Sect. 4.1), load calibrated (README, "The paper's load").
[mesh]
shape = "half_disc"
h = 0.0125

[material]
E = 1000.0
nu = 0.3
hypothesis = "plane_strain"

[[boundary.dirichlet]]
part = "axis"
components = ["x"]

[[boundary.traction]]
part = "top_arc"
value = ["0", "-17.977*t"]

[contact]
part = "bottom_arc"
g = 0.2
p = "positive_part"
rho = 1.0
probe = [0.0, 0.0]

[contact.stiffness]
law = "power"
c_v = 100.0
alpha = 20.0
beta = 1.0

[time]
T = 1.1
steps = 11

[solver]
method = "auto"

[output]
field_steps = [2, 5, 8, 11]
"""
PRINTED_LOAD = 1000.0
"""N/m: the magnitude of f2 printed in the paper (Sect. 4.1)."""
CALIBRATED_LOAD = 17.977
"""N/m: the magnitude in PAPER_CASE, calibrated so that β = 1 gives K = 323 at the bottom point at t = 1.1."""
T = 1.1
FIGURE_TIMES = (0.2, 0.5, 0.8, 1.1)
"""The times of the paper's Figs. 2 and 3 (steps 2, 5, 8, 11 with k = 0.1)."""
PAPER = {
    "K_hardening": 323.0,
    "K_softening": 21.0,
    "c_v": 100.0,
    "g": 0.2,
    "dofs_512": 472_074,
    "elements_512": 470_252,
    "figure_elements": 30_808,
    "figure_contact_edges": 128,
}
"""The numbers the paper states in Sect. 4."""

CONTACT_CONDITIONS = {
    "beta+1": ("β = 1 (hardening)", {"contact.stiffness.beta": 1.0}),
    "beta-1": ("β = −1 (softening)", {"contact.stiffness.beta": -1.0}),
    "alpha0_g0.2": ("α = 0, g = 0.2 m (normal compliance + unilateral constraint)", {"contact.stiffness.alpha": 0.0}),
    "alpha0_g2000": ("α = 0, g = 2000 m (normal compliance)", {"contact.stiffness.alpha": 0.0, "contact.g": 2000.0}),
}
"""The four contact conditions of Figs. 5–7: name -> (label, overrides of the paper case)."""
SHORT_LABELS = {
    "beta+1": "β = 1",
    "beta-1": "β = −1",
    "alpha0_g0.2": "α = 0, g = 0.2 m",
    "alpha0_g2000": "α = 0, g = 2000 m",
}


def load_overrides(c: float) -> dict:
    """The overrides of PAPER_CASE for a traction of magnitude c·t N/m on Γ2 (pushing the body down)."""
    return {"boundary.traction[0].value": ["0", f"-{c!r}*t"]}

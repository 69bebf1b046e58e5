r"""
Hertz contact of a cylinder on a rigid plane
============================================

A validation against an analytic solution: an elastic cylinder of radius R pressed onto a rigid flat
foundation with a force P per unit length, in plane strain. Hertz's theory gives the half-width b of
the contact strip and the pressure profile

.. math:: b = \sqrt{\frac{4 P R}{\pi E^*}}, \qquad p(x) = p_0 \sqrt{1 - x^2 / b^2}, \qquad
          p_0 = \frac{2 P}{\pi b}, \qquad E^* = \frac{E}{1 - \nu^2}.

The body is the built-in half disc (the cylinder's half x > 0, a roller on its axis) pushed down by a
uniform vertical traction on its upper arc. The foundation is rigid and flat: the layer carries nothing
(K ≡ 0), ``contact.normal = [0, -1]`` and the gap ``y - G`` with the limit ``g = G`` place the rigid
plane at y = 0, where the bottom point touches it. The load is chosen for b = 0.1 R.
"""

# %%
# The case, as a Python dict
# --------------------------
import math

import numpy as np
from matplotlib.figure import Figure

import vpcontact

E, NU, R = 1000.0, 0.3, 1.0
E_STAR = E / (1 - NU**2)
HALF_WIDTH = 0.1 * R  # b/R: Hertz assumes b ≪ R
P = math.pi * E_STAR * HALF_WIDTH**2 / (4 * R)  # the force per unit length that gives b
TRACTION = P / (math.pi * R)  # on the half disc's upper arc (length πR/2) it makes P/2, the half's share
G = 0.05  # any g: the rigid plane is y = 0 whatever it is


def hertz_case(h: float) -> dict:
    """The cylinder's half on the rigid plane, meshed with triangles of size h."""
    return {
        "mesh": {"shape": "half_disc", "radius": R, "h": h},
        "material": {"E": E, "nu": NU, "hypothesis": "plane_strain"},
        "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                     "traction": [{"part": "top_arc", "value": ["0", f"-{TRACTION!r}"]}]},
        "contact": {"part": "bottom_arc", "g": G, "gap": f"y - {G}", "normal": [0, -1], "probe": [0.0, 0.0],
                    "stiffness": {"law": "constant", "value": 0.0}},
        "time": {"T": 1.0, "steps": 1},
        "solver": {"tolerance": 1e-12},
        "output": {"field_steps": "none", "progress": False},
    }


# %%
# Three meshes
# ------------
# The contact strip is 2b = 0.2 R wide: h = 0.04, 0.02, 0.01 put about 2.5, 5 and 10 facets on its
# half. From each run we read the nodal contact forces λ_i (the rigid base's pressure λ_i / w_i times
# the node's weight w_i) and the nodes' x; P is twice the contact force on the half (which equals the
# applied load: equilibrium).
#
# b is measured from the second moment of the contact forces: for Hertz's profile
# ∫ x² p dx / ∫ p dx = b²/4, so b = 2 (Σ λ_i x_i² / Σ λ_i)^½. An integral of the forces, it does not
# depend on where exactly the last node in contact happens to be. p_0 is the pressure at the bottom node.
measured = []
for h in (0.04, 0.02, 0.01):
    result = vpcontact.solve(hertz_case(h))
    surface = result.discretization.surface
    pressure = result.contact_history("pressure_rigid")[-1]
    force = pressure * surface.weights
    x = surface.coordinates[0]
    load = 2 * force.sum()
    b_hertz = math.sqrt(4 * load * R / (math.pi * E_STAR))
    p0_hertz = 2 * load / (math.pi * b_hertz)
    b = 2 * math.sqrt((force * x**2).sum() / force.sum())
    p0 = pressure[result.probe]
    measured.append({"h": h, "b": b / b_hertz - 1, "p0": p0 / p0_hertz - 1, "x": x, "pressure": pressure,
                     "b_hertz": b_hertz, "p0_hertz": p0_hertz})
    print(f"h = {h}: {result.elements} triangles, P = {load:.5g} (applied {P:.5g}); b = {b:.5f} "
          f"({b / b_hertz - 1:+.2%} from Hertz's {b_hertz:.5f}), p0 = {p0:.4g} ({p0 / p0_hertz - 1:+.2%})")

# %%
# The pressure profile
# --------------------
finest = measured[-1]
figure = Figure(figsize=(6, 3.5), layout="constrained")
axes = figure.subplots()
s = np.linspace(0, finest["b_hertz"], 200)
axes.plot(s, finest["p0_hertz"] * np.sqrt(1 - (s / finest["b_hertz"]) ** 2), "k-", label="Hertz")
for run in measured:
    near = run["x"] < 2 * HALF_WIDTH
    axes.plot(run["x"][near], run["pressure"][near], "o", markersize=4, label=f"vpcontact, h = {run['h']}")
axes.set(xlabel="x", ylabel="contact pressure", title="cylinder on a rigid plane, plane strain")
axes.legend()
figure

# %%
# What the runs must satisfy
# --------------------------
# Hertz's formulas are those of a half-plane: they neglect terms of relative order (b/R)² = 1 % in
# a body of finite curvature. On the finest mesh both measures must be within 2 % of Hertz (twice that
# order; measured: about 0.3 % for b and 0.6 % for p0), and the peak pressure's error must shrink as
# the mesh is refined (it is first order in h: the nodal pressure is the mean over the node's share of
# Γ3, and the edge of the strip is resolved to h).
assert abs(finest["b"]) < 0.02 and abs(finest["p0"]) < 0.02
errors = [abs(run["p0"]) for run in measured]
assert errors[0] > errors[1] > errors[2], errors

"""Hertz: a quarter of an elastic sphere pressed on a flat rigid foundation, against
a = (3FR / 4E*)^{1/3} and p0 = 3F / (2πa²), E* = E / (1 − ν²) (the issue's bound: 2 %).

The foundation is rigid (K ≡ 0: the layer carries nothing) and flat: contact.normal = [0, 0, −1], and
the penetration d = u·ν − g0 reaches the limit g where the deformed surface reaches the plane
z + u_z = 0 when g0 = z − G and g = G. The sphere (R = 1) is pushed by a vertical traction on its upper
half; the full sphere's force F is four times the contact force on the quarter. The load gives
a/R = 0.12 (Hertz assumes a ≪ R) and the mesh is graded towards the contact: h_bottom = a/10, so
that the fine zone (10 h_bottom, see vpcontact.mesh.quarter_ball) covers the contact patch.

How a and p0 are measured from the discrete solution (nodal forces λ_i, pressures p_i = λ_i / w_i at
the nodes at the limit, r_i the nodes' distance to the axis):
- a from the second moment of the contact forces: for the Hertz distribution Σλ r² / Σλ = 2a²/5, so
  a = √(5/2 · Σλ_i r_i² / Σλ_i). An integral of the forces, it does not depend on where exactly the
  last node at the limit happens to be (the mesh resolves the edge only to h_bottom = a/10);
- p0 from the weighted least-squares line p² = p0² (1 − r²/a²) through the nodes at the limit (weights
  w_i). The pressures p_i of single nodes scatter by a few percent from node to node on this graded
  mesh (the lumped weights w_i of neighbouring nodes differ by factors of 2 to 4), so the pressure
  at the bottom node alone is not a fair estimate of the peak; the fit uses all nodes of the patch.
Both estimators return a and p0 exactly when the pressures follow Hertz's profile; the test also
checks that the discrete contact edge lies within one h_bottom of Hertz's a.
"""

import math

import numpy as np

from conftest import solved

E, NU, R = 1000.0, 0.3, 1.0
E_STAR = E / (1 - NU**2)
A_TARGET = 0.12  # a/R
H_BOTTOM = A_TARGET / 10
G = 0.05  # the rigid plane is z = 0 (far more than the approach of the sphere, 0.015)


def hertz_case() -> dict:
    force = 4 * E_STAR * A_TARGET**3 / (3 * R)  # F of the full sphere for a = A_TARGET
    traction = force / 4 / (math.pi * R**2 / 2)  # over the quarter of the upper hemisphere (area πR²/2)
    return {
        "mesh": {"shape": "quarter_ball", "radius": R, "h": 0.25, "h_bottom": H_BOTTOM},
        "material": {"E": E, "nu": NU},
        "boundary": {"dirichlet": [{"part": "sym_x", "components": ["x"]}, {"part": "sym_y", "components": ["y"]}],
                     "traction": [{"part": "top", "value": ["0", "0", f"-{traction!r}"]}]},
        "contact": {"part": "bottom", "g": G, "gap": f"z - {G}", "normal": [0, 0, -1], "probe": [0.0, 0.0, 0.0],
                    "stiffness": {"law": "constant", "value": 0.0}},
        "time": {"T": 1.0, "steps": 1},
        "solver": {"tolerance": 1e-12},
        "output": {"field_steps": "none"},
    }


def test_a_sphere_on_a_rigid_plane_follows_hertz():
    problem, result = solved(hertz_case())
    assert result.status == "complete"
    surface = problem.surface
    pressure = result.contact_history("pressure_rigid")[-1]
    np.testing.assert_array_equal(result.contact_history("pressure_compliance")[-1], 0.0)  # K ≡ 0
    force = pressure * surface.weights
    r = np.hypot(surface.coordinates[0], surface.coordinates[1])
    at_limit = result.contact_history("status")[-1] == 2

    # the contact force is the applied load (its resultant on the quarter), straight up
    applied = -problem.loads(1.0)[problem.basis.nodal_dofs[2]].sum()
    assert abs(result.series("contact_force_z")[-1] - applied) < 1e-10 * applied
    assert abs(force.sum() - applied) < 1e-10 * applied
    F = 4 * applied
    a_hertz = (3 * F * R / (4 * E_STAR)) ** (1 / 3)
    p0_hertz = 3 * F / (2 * math.pi * a_hertz**2)
    assert 0.1 < a_hertz / R < 0.15

    a = math.sqrt(2.5 * (force * r**2).sum() / force.sum())
    w = surface.weights[at_limit]
    X = np.stack([np.ones(at_limit.sum()), r[at_limit] ** 2], axis=1)
    (c0, c1), *_ = np.linalg.lstsq(X * np.sqrt(w)[:, None], pressure[at_limit] ** 2 * np.sqrt(w), rcond=None)
    p0, a_fit = math.sqrt(c0), math.sqrt(-c0 / c1)
    bottom = pressure[problem.probe]
    print(f"\nHertz: F = {F:.6g}, a = {a_hertz:.6g} (a/R = {a_hertz / R:.3f}), p0 = {p0_hertz:.6g}; {result.elements} "
          f"tetrahedra, {surface.size} contact nodes, {at_limit.sum()} at the limit, nodes at the limit up to "
          f"r = {r[at_limit].max():.5g}, others from r = {r[~at_limit].min():.5g}\n"
          f"  a from the second moment {a:.6g} ({a / a_hertz - 1:+.2%}), from the fit {a_fit:.6g} "
          f"({a_fit / a_hertz - 1:+.2%}); p0 from the fit {p0:.6g} ({p0 / p0_hertz - 1:+.2%}), at the bottom "
          f"node {bottom:.6g} ({bottom / p0_hertz - 1:+.2%})")
    assert abs(a / a_hertz - 1) < 0.02
    assert abs(p0 / p0_hertz - 1) < 0.02
    # the discrete contact edge is within one h_bottom of Hertz's a
    assert r[at_limit].max() < a_hertz + H_BOTTOM and r[~at_limit].min() > a_hertz - H_BOTTOM
    # the pressures are Hertz's profile: each node's within 5 % of p0, inside 0.9 a
    inner = r < 0.9 * a_hertz
    profile = p0_hertz * np.sqrt(1 - (r[inner] / a_hertz) ** 2)
    assert np.abs(pressure[inner] - profile).max() < 0.05 * p0_hertz

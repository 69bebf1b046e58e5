"""The solver does not care about units or about the ratio of the body's and the layer's stiffness.

- Units: the paper's example restated with lengths × L and stresses × s is the same problem; its
  solution is the same up to those factors (u × L, σ × s, ξ × L, K × s/L, pressures × s), with the
  same Newton iterations, to rounding.
- Stiffness ratio: from a body a thousand times softer than the layer (E / (c_v R) = 1e-3) to a steel
  part in Pa on the paper's layer (1e9), both methods complete without a step cut and agree to the
  accuracy double precision allows: a body held only by a soft layer carries a rigid motion that the
  stiffness matrix annihilates only to rounding, ε E per row (see vpcontact.fem.rigid_modes).
"""

import numpy as np
import pytest

import vpcontact
from vpcontact.solvers.factorization import factorize, installed_backends
from vpcontact.solvers.errors import SingularMatrixError

LOAD, C_V, ALPHA = 17.977, 100.0, 20.0


def paper_case(L=1.0, s=1.0, E=1000.0, beta=1.0, method="auto", h=0.1) -> dict:
    """The paper's example (Sect. 4.1, the calibrated load) in units where a length is L and a stress s."""
    return {
        "mesh": {"shape": "half_disc", "h": h * L, "radius": L},
        "material": {"E": E * s, "nu": 0.3},
        "boundary": {"dirichlet": [{"part": "axis", "components": ["x"]}],
                     "traction": [{"part": "top_arc", "value": ["0", f"-{LOAD * s!r}*t"]}]},
        "contact": {"part": "bottom_arc", "g": 0.2 * L, "probe": [0.0, 0.0],
                    "stiffness": {"law": "power", "c_v": C_V * s / L, "alpha": ALPHA / L, "beta": beta}},
        "time": {"T": 1.1, "steps": 11},
        "solver": {"method": method},
        "output": {"field_steps": "all"},
    }


#: each output and its unit: a length L, a stress s
UNITS = {"penetration": "L", "xi": "L", "K": "s/L", "pressure_compliance": "s", "pressure_rigid": "s"}


def scaled(value, unit, L, s):
    return value / {"L": L, "s": s, "s/L": s / L}[unit]


def assert_same_up_to_units(result, reference, L, s, rtol):
    assert result.status == reference.status == "complete"
    np.testing.assert_array_equal(result.series("newton_iterations"), reference.series("newton_iterations"))
    np.testing.assert_array_equal(result.contact_history("status"), reference.contact_history("status"))
    for name, unit in UNITS.items():
        mine, theirs = scaled(result.contact_history(name), unit, L, s), reference.contact_history(name)
        np.testing.assert_allclose(mine, theirs, rtol=0, atol=rtol * np.abs(theirs).max(), err_msg=name)
    for step, fields in reference.fields.items():
        mine = result.fields[step]
        np.testing.assert_allclose(mine.displacement / L, fields.displacement, rtol=0,
                                   atol=rtol * np.abs(fields.displacement).max())
        np.testing.assert_allclose(mine.stress / s, fields.stress, rtol=0, atol=rtol * np.abs(fields.stress).max())
    force, theirs = result.series("contact_force_y") / (s * L), reference.series("contact_force_y")
    np.testing.assert_allclose(force, theirs, rtol=0, atol=rtol * np.abs(theirs).max())


@pytest.fixture(scope="module", params=["full", "condensed"])
def reference(request):
    """The example in its own units, β = −1 (nodes in compliance and at the rigid limit)."""
    return request.param, vpcontact.solve(paper_case(beta=-1.0, method=request.param))


def test_the_reference_has_both_contact_regimes(reference):
    _, result = reference
    final = result.contact_history("status")[-1]
    assert (final == 1).any() and (final == 2).any()


@pytest.mark.parametrize("L, s", [(1e-3, 1e6), (1e3, 1e-3), (0.3, 2.1e11), (2.0**-10, 2.0**20), (2.0**7, 2.0**-30),
                                  (1e2, 1e60), (1e-2, 1e-60), (1.0, 1e100), (1.0, 1e-100)])
def test_other_units_give_the_same_solution(reference, L, s):
    """mm and MPa, km and kPa, an odd length and steel in Pa, powers of two, and scales far beyond any
    unit system (forces of 1e100, whose squares the norms must not overflow, and 1e-100): the same
    iterations and the same numbers to rounding (1e-13 observed, asserted at 1e-9; the issue asks 1e-6)."""
    method, expected = reference
    result = vpcontact.solve(paper_case(L, s, beta=-1.0, method=method))
    mesh, theirs = result.discretization.mesh.mesh, expected.discretization.mesh.mesh  # the built-in mesh scales
    np.testing.assert_array_equal(mesh.t, theirs.t)
    np.testing.assert_allclose(mesh.p / L, theirs.p, rtol=0, atol=1e-15)
    assert_same_up_to_units(result, expected, L, s, rtol=1e-9)


def attainable(E: float) -> float:
    """The relative accuracy of the condensed method on a body held only by the layer: its contact
    unknowns carry the rounding ε E/(c_v R) of the factored stiffness (observed ≤ 3 ε E/(c_v R));
    the full method evaluates the elastic forces without the rigid motion and is exact to rounding."""
    return 1e-9 + 30 * np.finfo(float).eps * E / C_V


@pytest.mark.parametrize("E", [0.1, 1e3, 1e6, 1e9, 1e11])
def test_both_methods_complete_and_agree_for_any_stiffness_ratio(E):
    """E / (c_v R) from 1e-3 to 1e9: no step cut (a residual at rounding level is converged), the
    same contact states, and the same numbers to the attainable accuracy."""
    results = {method: vpcontact.solve(paper_case(E=E, method=method)) for method in ("full", "condensed")}
    for method, result in results.items():
        assert result.status == "complete", (method, result.message)
        assert result.step_cuts == 0, method
    full, condensed = results["full"], results["condensed"]
    np.testing.assert_array_equal(condensed.contact_history("status"), full.contact_history("status"))
    for name in ("penetration", "xi", "K", "pressure_compliance"):
        a, b = condensed.contact_history(name), full.contact_history(name)
        assert np.abs(a - b).max() <= attainable(E) * np.abs(b).max(), name
    for step, fields in full.fields.items():
        u = condensed.fields[step].displacement
        assert np.abs(u - fields.displacement).max() <= attainable(E) * np.abs(fields.displacement).max()


@pytest.mark.parametrize("method", ["full", "condensed"])
def test_a_stiff_body_on_a_soft_layer_approaches_the_rigid_limit(method):
    """As E grows the penetration at the bottom tends to its rigid-body limit like 1/E: the values at
    E = 1e9 and 1e11 are those of d∞ − c/E fitted at E = 1e6 and 1e7, to the attainable accuracy
    (without removing the rigid motion from A u both were off by 4e-7 here at 1e11, and by 5e-4 on
    46k DOFs)."""
    probe = {E: vpcontact.solve(paper_case(E=E, method=method)).series("penetration_probe")[-1]
             for E in (1e6, 1e7, 1e9, 1e11)}
    c = (probe[1e7] - probe[1e6]) / (1 / 1e6 - 1 / 1e7)  # d(E) = d∞ − c/E + O(1/E²)
    limit = probe[1e7] + c / 1e7
    for E in (1e9, 1e11):
        accuracy = 1e-8 if method == "full" else attainable(E)  # 1e-8: the fit's own accuracy
        assert abs(probe[E] - (limit - c / E)) <= accuracy * limit, (E, probe[E] - (limit - c / E))


@pytest.mark.parametrize("backend", installed_backends())
def test_a_singular_stiffness_is_a_typed_error(backend):
    """A dof that no element holds: every backend raises SingularMatrixError (never a crash or a
    RuntimeError to be recognised by its text)."""
    import scipy.sparse as sp

    n = 40
    A = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1]).tolil()
    A[7, :], A[:, 7] = 0.0, 0.0
    N = sp.csr_matrix((np.ones(1), ([0], [3])), shape=(1, n))
    with pytest.raises(SingularMatrixError):
        factorize(A.tocsr(), N, backend)


@pytest.mark.parametrize("L, s", [(1e-3, 1e6), (1e3, 1e-3)])
def test_python_laws_without_derivatives_are_unit_free(L, s):
    """K and p as plain functions (derivatives by central differences, with steps taken from the
    values' own scale): the same iterations and solution in any units."""
    def laws(L, s):
        return {"p": lambda r: np.maximum(r, 0.0),
                "stiffness_law": lambda xi: C_V * s / L * (1.0 + ALPHA / L * xi) ** -1.0}

    expected = vpcontact.solve(paper_case(beta=-1.0), **laws(1.0, 1.0))
    result = vpcontact.solve(paper_case(L, s, beta=-1.0), **laws(L, s))
    assert_same_up_to_units(result, expected, L, s, rtol=1e-9)

"""Linear elasticity without contact against exact solutions, plane strain and plane stress."""

import numpy as np
import pytest
from skfem import Basis

import vpcontact
from conftest import solved
from vpcontact.laws.elasticity import Elasticity

E, NU, S = 1000.0, 0.3, 5.0


def block(hypothesis, h, dirichlet, traction=(), body_force=()):
    return {
        "mesh": {"shape": "rectangle", "width": 1.0, "height": 1.0, "h": h},
        "material": {"E": E, "nu": NU, "hypothesis": hypothesis},
        "boundary": {"dirichlet": dirichlet, "traction": list(traction), "body_force": list(body_force)},
        "time": {"T": 1.0, "steps": 1},
        "output": {"field_steps": "all"},
    }


@pytest.mark.parametrize("hypothesis", ["plane_strain", "plane_stress"])
def test_uniaxial_tension_is_reproduced_exactly(hypothesis):
    """Rollers on the left and bottom, traction S on the right: the exact field is linear,
    u = (S/E' x, −ν' S/E' y) with E' = E/(1−ν²), ν' = ν/(1−ν) in plane strain (E' = E, ν' = ν in
    plane stress), and P1 must reproduce it to round-off."""
    case = block(hypothesis, 0.25, [{"part": "left", "components": ["x"]}, {"part": "bottom", "components": ["y"]}],
                 traction=[{"part": "right", "value": [S, 0]}])
    result = vpcontact.solve(case)
    E_, nu_ = (E / (1 - NU**2), NU / (1 - NU)) if hypothesis == "plane_strain" else (E, NU)
    x, y = result.discretization.mesh.mesh.p
    exact = np.column_stack([S / E_ * x, -nu_ * S / E_ * y])
    np.testing.assert_allclose(result.final.displacement, exact, rtol=0, atol=1e-13)
    np.testing.assert_allclose(result.final.stress[:, 0, 0], S, rtol=1e-12)
    np.testing.assert_allclose(result.final.stress[:, 1, 1], 0.0, atol=1e-11)
    expected_33 = NU * S if hypothesis == "plane_strain" else 0.0
    np.testing.assert_allclose(result.final.stress33, expected_33, atol=1e-11)
    np.testing.assert_allclose(result.final.von_mises, np.sqrt(S**2 - S * expected_33 + expected_33**2), rtol=1e-12)


def _manufactured(hypothesis):
    """u = (φ, φ), φ = x(1−x)y(1−y) on the clamped unit square, and the body force −Div σ(u)."""
    lam, mu = Elasticity(E, NU, hypothesis).lame
    fxx, fyy, fxy = "(-2*y*(1-y))", "(-2*x*(1-x))", "((1-2*x)*(1-2*y))"
    f1 = f"-({lam + 2 * mu!r}*{fxx} + {lam + mu!r}*{fxy} + {mu!r}*{fyy})"
    f2 = f"-({mu!r}*{fxx} + {lam + mu!r}*{fxy} + {lam + 2 * mu!r}*{fyy})"
    return f1, f2


def _energy_error(problem, result) -> tuple[float, float]:
    """‖ε(u_h) − ε(u)‖_{L²} and ‖ε(u)‖_{L²} with a 4th-order quadrature."""
    basis = Basis(problem.mesh.mesh, problem.basis.elem, intorder=4)
    u = np.zeros(basis.N)
    u[basis.nodal_dofs.T.ravel()] = result.final.displacement.ravel()
    grad = np.asarray(basis.interpolate(u).grad)
    x, y = np.asarray(basis.global_coordinates())
    phx, phy = (1 - 2 * x) * y * (1 - y), x * (1 - x) * (1 - 2 * y)
    exact = np.array([[phx, phy], [phx, phy]])  # ∇u, rows: components
    def norm(g):
        sym = 0.5 * (g + np.swapaxes(g, 0, 1))
        return float(np.sqrt(np.sum(np.einsum("ij...,ij...->...", sym, sym) * basis.dx)))

    return norm(grad - exact), norm(exact)


@pytest.mark.parametrize("hypothesis", ["plane_strain", "plane_stress"])
def test_manufactured_solution_converges_at_first_order_in_energy(hypothesis):
    clamped = [{"part": p} for p in ("left", "right", "bottom", "top")]
    errors = []
    for h in (1 / 8, 1 / 16, 1 / 32):
        problem, result = solved(block(hypothesis, h, clamped, body_force=[{"value": list(_manufactured(hypothesis))}]))
        error, exact = _energy_error(problem, result)
        errors.append(error / exact)
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 1.0) < 0.05), (errors, rates)
    assert errors[-1] < 0.06, errors


@pytest.mark.parametrize("dim", [2, 3])
def test_von_mises_is_that_of_the_deviator_of_the_3d_tensor(dim):
    """sqrt(3/2 dev τ : dev τ) of the 3 × 3 tensor formed explicitly (in 2D: σ, σ33 and zero σ13, σ23), for
    random tensors, symmetric or not (a user's 𝒢 may add a history that is not)."""
    from vpcontact.laws.elasticity import von_mises

    rng = np.random.default_rng(dim)
    sigma = rng.standard_normal((dim, dim, 50))
    sigma33 = rng.standard_normal(50) if dim == 2 else None
    full = np.zeros((3, 3, 50))
    full[:dim, :dim] = sigma
    if dim == 2:
        full[2, 2] = sigma33
    dev = full - np.einsum("ii...->...", full) / 3 * np.eye(3)[:, :, None]
    np.testing.assert_allclose(von_mises(sigma, sigma33), np.sqrt(1.5 * np.einsum("ij...,ij...->...", dev, dev)),
                               rtol=1e-13)

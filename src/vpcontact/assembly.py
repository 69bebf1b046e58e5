"""Finite element operators on P1 displacements and P0 stresses (scikit-fem forms).

- the elastic stiffness A: (ℰε(u), ε(v))_Q, the bulk term of (3.3);
- the load vector F(t) of (2.24): ∫_Ω f0·v dx + ∫_Γ2 f2·v da;
- element strains ε(u) (constant on each triangle) and the nodal force Bᵀz of a P0 stress z.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import scipy.sparse as sp
from skfem import Basis, ElementTriP1, ElementVector, FacetBasis, LinearForm, asm
from skfem.helpers import ddot, sym_grad
from skfem.models.elasticity import linear_elasticity

from .material import Elasticity
from .mesh import Mesh

#: A load density: f(x, y, t) -> (fx, fy), each an array broadcastable to x's shape.
Density = Callable[[np.ndarray, np.ndarray, float], tuple]


#: The centroid rule: exact for the bulk forms of P1 × P0 (their integrands are constant per element).
CENTROID = (np.array([[1.0 / 3.0], [1.0 / 3.0]]), np.array([0.5]))


def displacement_basis(mesh: Mesh) -> Basis:
    """The P1 vector basis (dofs of node i: ``basis.nodal_dofs[:, i]``) with the centroid rule."""
    return Basis(mesh.mesh, ElementVector(ElementTriP1()), quadrature=CENTROID)


def stiffness(basis: Basis, elasticity: Elasticity) -> sp.csr_matrix:
    """The elastic stiffness matrix A_ij = (ℰε(φ_j), ε(φ_i))_Q."""
    return asm(linear_elasticity(*elasticity.lame), basis).tocsr()


@LinearForm
def _density_form(v, w):
    return w["f"][0] * v[0] + w["f"][1] * v[1]


def _evaluate_density(density: Density, basis, t: float) -> np.ndarray:
    x = np.asarray(basis.global_coordinates())
    values = density(x[0], x[1], t)
    return np.stack([np.broadcast_to(np.asarray(c, dtype=float), x[0].shape) for c in values])


class LoadVector:
    """F(t) of (2.24) for traction densities on boundary parts and body force densities."""

    def __init__(self, basis: Basis, mesh: Mesh, tractions: list[tuple[object, Density]], body_forces: list[Density]):
        self._ndofs = basis.N
        self._terms = [(FacetBasis(mesh.mesh, basis.elem, facets=mesh.facets(part), intorder=4), f) for part, f in tractions]
        self._terms += [(Basis(mesh.mesh, basis.elem, intorder=4), f) for f in body_forces]

    def __call__(self, t: float) -> np.ndarray:
        F = np.zeros(self._ndofs)
        for term_basis, density in self._terms:
            F += asm(_density_form, term_basis, f=_evaluate_density(density, term_basis, t))
        return F


def element_strain(basis: Basis, u: np.ndarray) -> np.ndarray:
    """ε(u) on each triangle, shape (2, 2, nelements) (constant for P1)."""
    return sym_grad(basis.interpolate(u))[:, :, :, 0]


@LinearForm
def _stress_work(v, w):
    return ddot(w["z"], sym_grad(v))


def stress_force(basis: Basis, z: np.ndarray) -> np.ndarray:
    """The nodal force Bᵀz = ∫_Ω z : ε(v) dx of a P0 stress field z of shape (2, 2, nelements)."""
    return asm(_stress_work, basis, z=np.repeat(z[..., None], basis.X.shape[-1], axis=-1))

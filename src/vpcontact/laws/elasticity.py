"""Isotropic linear elasticity: the tensor ℰ of the constitutive law (2.1), for d = 2 or 3::

    (ℰτ)_ij = λ τ_kk δ_ij + 2μ τ_ij,   λ = Eν/((1+ν)(1−2ν)),  μ = E/(2(1+ν)):

the full isotropic tensor on S³ in 3D and, in 2D, plane strain, which is the paper's formula (4.1).
Plane stress (2D only) replaces λ by λ* = Eν/(1−ν²) (the same μ). The plane hypotheses are the only
place the dimension enters: in 3D there is none (``hypothesis=None``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

HYPOTHESES = ("plane_strain", "plane_stress")


@dataclass(frozen=True)
class Elasticity:
    """Young's modulus E, Poisson's ratio ν and the 2D hypothesis (None in 3D)."""

    E: float
    nu: float
    hypothesis: str | None = "plane_strain"

    @property
    def lame(self) -> tuple[float, float]:
        """The Lamé parameters (λ, μ) (in-plane ones under plane stress)."""
        E, nu = self.E, self.nu
        mu = E / (2.0 * (1.0 + nu))
        if self.hypothesis == "plane_stress":
            return E * nu / (1.0 - nu**2), mu
        return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu

    def on(self, elements: np.ndarray) -> "Elasticity":
        """ℰ on the elements ``elements`` alone (indices): the same E, ν where they are numbers, else theirs."""
        if np.ndim(self.E) == 0 and np.ndim(self.nu) == 0:
            return self
        return replace(self, E=_at(self.E, elements), nu=_at(self.nu, elements))

    def stress(self, strain: np.ndarray) -> np.ndarray:
        """ℰε = λ tr(ε) I + 2μ ε for strains of shape (d, d, ...)."""
        lam, mu = self.lame
        trace = np.einsum("ii...->...", strain)
        sigma = 2.0 * mu * strain
        for i in range(strain.shape[0]):
            sigma[i, i] += lam * trace
        return sigma

    def out_of_plane_stress(self, strain: np.ndarray) -> np.ndarray | None:
        """σ33 of a 2D elastic response: λ tr(ε) in plane strain (ε33 = 0), 0 in plane stress; None in 3D
        (the stress is the whole tensor)."""
        if self.hypothesis is None:
            return None
        if self.hypothesis == "plane_stress":
            return np.zeros_like(strain[0, 0])
        return self.lame[0] * (strain[0, 0] + strain[1, 1])


def _at(value, elements: np.ndarray):
    """A coefficient's values at ``elements``: a number itself, an array over the elements taken there."""
    return value if np.ndim(value) == 0 else np.asarray(value)[elements]


def von_mises(sigma: np.ndarray, sigma33: np.ndarray | None = None) -> np.ndarray:
    """von Mises stress sqrt(3/2 ‖dev σ‖²) of the 3D tensor (σ (3, 3, n) in 3D; in 2D σ (2, 2, n) with σ33
    (n) and σ13 = σ23 = 0), as sqrt(½ Σ_(i<j) (σ_ii − σ_jj)² + 3/2 Σ_(i≠j) σ_ij²): no 3 × 3 array and no
    deviator to form (a field step at 475k triangles)."""
    d = sigma.shape[0]
    diagonal = [sigma[i, i] for i in range(d)] + ([] if sigma33 is None else [sigma33])
    normal = sum((diagonal[i] - diagonal[j]) ** 2 for i in range(3) for j in range(i + 1, 3))
    shear = sum(sigma[i, j] ** 2 for i in range(d) for j in range(d) if i != j)
    return np.sqrt(0.5 * normal + 1.5 * shear)


# --- tensors of S^d (the viscoplastic laws' algebra, vpcontact.laws.viscoplastic) ------------------------
def deviator(tau: np.ndarray) -> np.ndarray:
    """dev τ = τ − (tr τ / d) I of tensors of S^d, shape (d, d, ...)."""
    d = tau.shape[0]
    mean = np.einsum("ii...->...", tau) / d
    dev = np.array(tau, dtype=float, copy=True)
    for i in range(d):
        dev[i, i] -= mean
    return dev


def tensor_norm(tau: np.ndarray) -> np.ndarray:
    """‖τ‖ = (τ_ij τ_ij)^{1/2} over the first two axes."""
    return np.sqrt(np.einsum("ij...,ij...->...", tau, tau))

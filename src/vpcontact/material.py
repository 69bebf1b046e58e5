"""Isotropic linear elasticity in 2D: the tensor ℰ of the constitutive law (2.1).

Plane strain uses the paper's formula (4.1),
    (ℰτ)_ij = Eν/((1+ν)(1−2ν)) τ_kk δ_ij + E/(1+ν) τ_ij,
i.e. the Lamé form with λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)). Plane stress replaces λ by
λ* = Eν/(1−ν²) (the same μ).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

HYPOTHESES = ("plane_strain", "plane_stress")


@dataclass(frozen=True)
class Elasticity:
    """Young's modulus E, Poisson's ratio ν and the 2D hypothesis."""

    E: float
    nu: float
    hypothesis: str = "plane_strain"

    @property
    def lame(self) -> tuple[float, float]:
        """The in-plane Lamé parameters (λ, μ) of the hypothesis."""
        E, nu = self.E, self.nu
        mu = E / (2.0 * (1.0 + nu))
        if self.hypothesis == "plane_strain":
            return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu
        return E * nu / (1.0 - nu**2), mu

    def stress(self, strain: np.ndarray) -> np.ndarray:
        """ℰε for strains of shape (2, 2, ...): λ tr(ε) I + 2μ ε."""
        lam, mu = self.lame
        trace = strain[0, 0] + strain[1, 1]
        sigma = 2.0 * mu * strain
        sigma[0, 0] += lam * trace
        sigma[1, 1] += lam * trace
        return sigma

    def out_of_plane_stress(self, strain: np.ndarray) -> np.ndarray:
        """σ33 of the elastic response: λ tr(ε) in plane strain (ε33 = 0), 0 in plane stress."""
        if self.hypothesis == "plane_stress":
            return np.zeros_like(strain[0, 0])
        return self.lame[0] * (strain[0, 0] + strain[1, 1])


def von_mises(sigma: np.ndarray, sigma33: np.ndarray) -> np.ndarray:
    """von Mises stress sqrt(3/2 |dev σ|²) of the 3D tensor with in-plane part σ (2, 2, n) and σ33 (n)."""
    s11, s22, s12 = sigma[0, 0], sigma[1, 1], sigma[0, 1]
    return np.sqrt(0.5 * ((s11 - s22) ** 2 + (s22 - sigma33) ** 2 + (sigma33 - s11) ** 2) + 3.0 * s12**2)

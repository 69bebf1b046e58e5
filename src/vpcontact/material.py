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


# --- viscoplastic laws 𝒢(σ, ε) of (2.1) ------------------------------------------------------------
# Each law is a callable on arrays of shape (2, 2, ...) (one tensor of S² per element), returning an
# array of the same shape, and Lipschitz in (σ, ε) as (2.17)(b) asks, with the constant ``lipschitz``.
# The norm of S² is the paper's ‖τ‖ = (τ_ij τ_ij)^{1/2}; the deviator is the one of S² (d = 2):
# dev τ = τ − (tr τ / 2) I, with tr τ = τ_11 + τ_22 (σ33 is not part of the model's stress).


def deviator(tau: np.ndarray) -> np.ndarray:
    """dev τ = τ − (tr τ / 2) I of tensors of S², shape (2, 2, ...)."""
    mean = 0.5 * (tau[0, 0] + tau[1, 1])
    dev = np.array(tau, dtype=float, copy=True)
    dev[0, 0] -= mean
    dev[1, 1] -= mean
    return dev


def tensor_norm(tau: np.ndarray) -> np.ndarray:
    """‖τ‖ = (τ_ij τ_ij)^{1/2} over the first two axes."""
    return np.sqrt(np.einsum("ij...,ij...->...", tau, tau))


def von_mises_projection(sigma: np.ndarray, yield_stress: float) -> np.ndarray:
    """P(σ): the ‖·‖-orthogonal projection onto {τ ∈ S² : ‖dev τ‖ ≤ σ_y}: the spherical part is kept
    and the deviator is scaled back onto the sphere of radius σ_y when it lies outside."""
    dev = deviator(sigma)
    size = tensor_norm(dev)
    scale = np.minimum(1.0, np.divide(yield_stress, size, out=np.ones_like(size), where=size > yield_stress))
    return sigma - (1.0 - scale) * dev


@dataclass(frozen=True)
class Perzyna:
    """𝒢(σ, ε) = −(1/η) (σ − P(σ)), P the projection onto the von Mises set ‖dev σ‖ ≤ σ_y.

    Zero inside the yield set (the response is elastic there); outside, ‖dev σ‖ − σ_y relaxes at the
    rate 1/η when the strain is held. Lipschitz with constant 1/η (I − P is non-expansive)."""

    eta: float
    yield_stress: float

    def __call__(self, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
        return -(sigma - von_mises_projection(sigma, self.yield_stress)) / self.eta

    @property
    def lipschitz(self) -> float:
        return 1.0 / self.eta


@dataclass(frozen=True)
class Relaxation:
    """𝒢(σ, ε) = −μ (σ − 𝒞ε), 𝒞 an isotropic elasticity tensor (the relaxed modulus): at constant
    strain the stress relaxes to 𝒞ε at the rate μ. 𝒞 = ℰ gives back linear elasticity from zero
    initial data. Lipschitz with constant μ max(1, ‖𝒞‖)."""

    mu: float
    relaxed: Elasticity

    def __call__(self, sigma: np.ndarray, strain: np.ndarray) -> np.ndarray:
        return -self.mu * (sigma - self.relaxed.stress(strain))

    @property
    def lipschitz(self) -> float:
        lam, mu = self.relaxed.lame
        return self.mu * max(1.0, 2.0 * abs(mu) + 2.0 * abs(lam))  # ‖𝒞‖ ≤ 2|μ| + 2|λ| on S²

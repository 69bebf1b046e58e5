"""Stress relaxation: 𝒢(σ, ε) = −μ (σ − 𝒞ε) towards a relaxed elasticity 𝒞."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..elasticity import Elasticity
from ..spec import Law, Parameter


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
        return self.mu * max(1.0, 2.0 * abs(mu) + 3.0 * abs(lam))  # ‖𝒞‖ ≤ 2|μ| + d|λ| on S^d


def relaxation(mu: float, E_inf: float, nu_inf: float, hypothesis: str | None) -> Relaxation:
    """The relaxation law of a material's table: 𝒞 = (E_inf, nu_inf) under the material's hypothesis."""
    return Relaxation(mu, Elasticity(E_inf, nu_inf, hypothesis))


LAW = Law(
    name="relaxation",
    summary="𝒢(σ, ε) = −μ (σ − 𝒞ε), 𝒞 isotropic (E_inf, nu_inf) with the material's hypothesis.",
    parameters=(Parameter("mu", "the relaxation rate μ (1/time)", minimum=0.0, strict=True),
                Parameter("E_inf", "Young's modulus of 𝒞", minimum=0.0, strict=True),
                Parameter("nu_inf", "Poisson's ratio of 𝒞", poisson_ratio=True)),
    make=relaxation,
)

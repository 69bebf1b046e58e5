"""K(ξ) = c_v (1 + α ξ)^β: the paper's stiffness law (2.18)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spec import Law, Parameter


@dataclass(frozen=True)
class PowerStiffness:
    """K(ξ) = c_v (1 + α ξ)^β: the paper's law; β > 0 hardens, β < 0 softens, α = 0 is constant."""

    c_v: float | np.ndarray
    alpha: float | np.ndarray
    beta: float | np.ndarray

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * (1.0 + self.alpha * xi) ** self.beta

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * self.alpha * self.beta * (1.0 + self.alpha * xi) ** (self.beta - 1.0)


LAW = Law(
    name="power",
    summary="K(ξ) = c_v (1 + α ξ)^β (the paper's law).",
    parameters=(Parameter("c_v", "K(0), the stiffness of the fresh layer", minimum=0.0),
                Parameter("alpha", "α, how fast the history ξ changes the stiffness", minimum=0.0),
                Parameter("beta", "β: > 0 hardens, < 0 softens")),
    make=PowerStiffness,
)

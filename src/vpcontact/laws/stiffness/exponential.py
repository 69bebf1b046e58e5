"""K(ξ) = c_v exp(α ξ)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spec import Law, Parameter


@dataclass(frozen=True)
class ExponentialStiffness:
    """K(ξ) = c_v exp(α ξ): α > 0 hardens, α < 0 softens."""

    c_v: float | np.ndarray
    alpha: float | np.ndarray

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * np.exp(self.alpha * xi)

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.alpha * self(xi)


LAW = Law(
    name="exponential",
    summary="K(ξ) = c_v exp(α ξ).",
    parameters=(Parameter("c_v", "K(0), the stiffness of the fresh layer", minimum=0.0),
                Parameter("alpha", "α: > 0 hardens, < 0 softens")),
    make=ExponentialStiffness,
)

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
        return self.c_v * elementwise_power(1.0 + self.alpha * xi, self.beta)

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.c_v * self.alpha * self.beta * elementwise_power(1.0 + self.alpha * xi, self.beta - 1.0)


def elementwise_power(base: np.ndarray, exponent: float | np.ndarray) -> np.ndarray:
    """base ** exponent by NumPy's loop for an array of exponents, whether ``exponent`` is a number or an array:
    NumPy 2.4 computes a number exponent (or a broadcast one) by another loop, which differs in the last bit
    (measured for −1), and a layer given by a constant expression must be the layer given by the number, bit for
    bit. So the exponent is always a whole array."""
    base = np.asarray(base, dtype=float)
    return np.power(base, np.array(np.broadcast_to(np.asarray(exponent, dtype=float), base.shape)))


LAW = Law(
    name="power",
    summary="K(ξ) = c_v (1 + α ξ)^β (the paper's law).",
    parameters=(Parameter("c_v", "K(0), the stiffness of the fresh layer", minimum=0.0),
                Parameter("alpha", "α, how fast the history ξ changes the stiffness", minimum=0.0),
                Parameter("beta", "β: > 0 hardens, < 0 softens")),
    make=PowerStiffness,
)

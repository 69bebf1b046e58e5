"""K(ξ) = value: a layer whose stiffness keeps no history."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spec import Law, Parameter


@dataclass(frozen=True)
class ConstantStiffness:
    """K(ξ) = value (value = 0: the Signorini condition with gap g)."""

    value: float | np.ndarray

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return np.zeros_like(xi, dtype=float) + self.value

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return np.zeros_like(xi, dtype=float)


LAW = Law(
    name="constant",
    summary="K(ξ) = value; 0 gives the Signorini condition with gap g.",
    parameters=(Parameter("value", "the stiffness", minimum=0.0),),
    make=ConstantStiffness,
)

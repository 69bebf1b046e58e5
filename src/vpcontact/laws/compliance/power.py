"""p(r) = (r⁺)^m, m ≥ 1."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spec import Law, Parameter
from .positive_part import PositivePart


@dataclass(frozen=True)
class Power:
    """p(r) = (r⁺)^m with m ≥ 1 (Lipschitz on bounded sets; p'(0) = 1 when m = 1); m is a number or one
    exponent per contact node (the paper's p(x, r), (2.19))."""

    exponent: float | np.ndarray

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.maximum(r, 0.0) ** self.exponent

    def derivative(self, r: np.ndarray) -> np.ndarray:
        """m (r⁺)^(m−1), and where m = 1 the derivative of r⁺ (1 for r ≥ 0, 0 below: (r⁺)^0 would be 1
        for r < 0 too)."""
        m = self.exponent
        return np.where(m == 1.0, PositivePart().derivative(r), m * np.maximum(r, 0.0) ** (m - 1.0))


LAW = Law(
    name="power",
    summary="p(r) = (r⁺)^m.",
    parameters=(Parameter("exponent", "m ≥ 1", minimum=1.0),),
    make=Power,
)

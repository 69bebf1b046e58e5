"""p(r) = r⁺: the classical normal compliance (the default)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..spec import Law


@dataclass(frozen=True)
class PositivePart:
    """p(r) = r⁺, with the generalized derivative p'(r) = 1 for r ≥ 0 (so p'(0) = 1), else 0."""

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.maximum(r, 0.0)

    def derivative(self, r: np.ndarray) -> np.ndarray:
        return (r >= 0.0).astype(float)


LAW = Law(name="positive_part", summary="p(r) = r⁺.", parameters=(), make=PositivePart)

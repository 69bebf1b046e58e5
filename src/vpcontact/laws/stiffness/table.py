"""K(ξ) given as a table of points (ξ_i, K_i), piecewise linear between them (:mod:`vpcontact.laws.tabulated`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..spec import Law, Parameter
from ..tabulated import EXTRAPOLATIONS, PiecewiseLinear, check_table


@dataclass(frozen=True, eq=False)
class TableStiffness:
    """K(ξ) interpolated linearly between the points (``xi``, ``K``), ``xi`` from 0 strictly increasing, K ≥ 0;
    beyond the last point constant (K_n) or linear (the last segment's line), as ``extrapolation`` states. Its
    derivative is the slope of the segment [ξ_i, ξ_{i+1}) holding ξ (the right derivative at a breakpoint)."""

    xi: tuple[float, ...]
    K: tuple[float, ...]
    extrapolation: str
    interpolant: PiecewiseLinear = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "interpolant", PiecewiseLinear(self.xi, self.K, self.extrapolation))

    def __call__(self, xi: np.ndarray) -> np.ndarray:
        return self.interpolant(xi)

    def derivative(self, xi: np.ndarray) -> np.ndarray:
        return self.interpolant.derivative(xi)


def check(xi, K, extrapolation) -> None:
    """ParameterError naming the bad key unless (xi, K) is a table of K(ξ): see :func:`check_table`."""
    check_table("xi", xi, "K", K, "extrapolation", extrapolation, argument="ξ")


LAW = Law(
    name="table",
    summary="K(ξ) interpolated linearly between the points (xi, K), constant or linear beyond the last one.",
    parameters=(Parameter("xi", "the points ξ_i of the table: from 0, strictly increasing", points=True),
                Parameter("K", "the stiffness K_i at each ξ_i", minimum=0.0, points=True),
                Parameter("extrapolation", "K beyond the last point: its value (constant) or its last segment's "
                          "line (linear)", choices=EXTRAPOLATIONS)),
    make=TableStiffness,
    check=check,
)

"""p(r) given as a table of points (r_i, p_i), piecewise linear between them (:mod:`vpcontact.laws.tabulated`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..spec import Law, Parameter
from ..tabulated import EXTRAPOLATIONS, PiecewiseLinear, check_table


@dataclass(frozen=True, eq=False)
class TableCompliance:
    """p(r) = 0 for r ≤ 0, interpolated linearly between the points (``r``, ``p_of_r``) above, ``r`` from 0
    strictly increasing, ``p_of_r`` from 0 and non-decreasing (the conditions (2.19)); beyond the last point
    constant or linear, as ``p_extrapolation`` states. Its derivative is 0 for r < 0 and the slope of the segment
    [r_i, r_{i+1}) holding r for r ≥ 0 (the right derivative at a breakpoint: at r = 0 the first segment's slope,
    as p(r) = r⁺ has p'(0) = 1)."""

    r: tuple[float, ...]
    p_of_r: tuple[float, ...]
    p_extrapolation: str
    interpolant: PiecewiseLinear = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "interpolant", PiecewiseLinear(self.r, self.p_of_r, self.p_extrapolation))

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return np.where(r > 0.0, self.interpolant(r), 0.0)

    def derivative(self, r: np.ndarray) -> np.ndarray:
        return np.where(r >= 0.0, self.interpolant.derivative(r), 0.0)


def check(r, p_of_r, p_extrapolation) -> None:
    """ParameterError naming the bad key unless (r, p_of_r) is a table of p(r): see :func:`check_table`."""
    check_table("r", r, "p_of_r", p_of_r, "p_extrapolation", p_extrapolation, argument="r", nondecreasing=True)


LAW = Law(
    name="table",
    summary="p(r) interpolated linearly between the points (r, p_of_r), 0 for r ≤ 0, constant or linear beyond "
            "the last point.",
    parameters=(Parameter("r", "the penetrations r_i of the table: from 0, strictly increasing", points=True),
                Parameter("p_of_r", "p(r_i) at each r_i: from 0, non-decreasing", minimum=0.0, points=True),
                Parameter("p_extrapolation", "p beyond the last point: its value (constant) or its last segment's "
                          "line (linear)", choices=EXTRAPOLATIONS)),
    make=TableCompliance,
    check=check,
)

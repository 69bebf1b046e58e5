"""K(ξ) given as a table of points (ξ_i, K_i), piecewise linear between them (:mod:`vpcontact.laws.tabulated`)."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..spec import Law
from ..tabulated import PiecewiseLinear, TableLaw, check_table, table_parameters


@dataclass(frozen=True, eq=False)
class TableStiffness(TableLaw):
    """K(ξ) interpolated linearly between the points (``xi``, ``K``), ``xi`` from 0 strictly increasing, K ≥ 0;
    beyond the last point constant (K_n) or linear (the last segment's line), as ``extrapolation`` states. Its
    derivative is the slope of the segment [ξ_i, ξ_{i+1}) holding ξ (the right derivative at a breakpoint)."""

    TABLE = ("xi", "K", "extrapolation")
    xi: tuple[float, ...]
    K: tuple[float, ...]
    extrapolation: str
    interpolant: PiecewiseLinear = field(init=False, repr=False)


def check(xi, K, extrapolation) -> None:
    """ParameterError naming the bad key unless (xi, K) is a table of K(ξ): see :func:`check_table`."""
    check_table("xi", xi, "K", K, "extrapolation", extrapolation, argument="ξ")


LAW = Law(
    name="table",
    summary="K(ξ) interpolated linearly between the points (xi, K), constant or linear beyond the last one.",
    parameters=table_parameters("xi", "the points ξ_i of the table: from 0, strictly increasing",
                                "K", "the stiffness K_i at each ξ_i", "extrapolation", "K"),
    make=TableStiffness,
    check=check,
)

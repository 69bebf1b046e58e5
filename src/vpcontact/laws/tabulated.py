"""A law given as a table of points (x_0, y_0), ..., (x_n, y_n), piecewise linear between them: the interpolant
of the tabular laws K(ξ) (:mod:`vpcontact.laws.stiffness.table`) and p(r) (:mod:`vpcontact.laws.compliance.table`).

The table starts at x_0 = 0 (ξ ≥ 0 and p(r) = 0 for r ≤ 0: nothing below the first point is ever asked) and its
abscissae increase strictly. Beyond the last point the law is extrapolated as the user states: ``"constant"``
(y_n) or ``"linear"`` (the line of the last segment). Its derivative is the slope of the segment [x_i, x_{i+1})
that holds the point, so at a breakpoint x_i it is the right derivative (the slope of the segment after x_i), and
beyond the last point, x ≥ x_n, the slope of the extrapolation (0 or the last segment's); this is the convention
of p(r) = r⁺, whose derivative at 0 is 1. Values and derivatives are vectorized (np.interp, np.searchsorted).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .spec import ParameterError

#: The extrapolations beyond the last point a table may state.
EXTRAPOLATIONS = ("constant", "linear")


@dataclass(frozen=True, eq=False)
class PiecewiseLinear:
    """The piecewise-linear interpolant of the points (x, y), extrapolated beyond x_n by ``extrapolation``
    (see the module; the points are checked by :func:`check_table`)."""

    x: np.ndarray
    y: np.ndarray
    extrapolation: str
    slopes: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        x, y = np.asarray(self.x, dtype=float), np.asarray(self.y, dtype=float)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "slopes", np.diff(y) / np.diff(x))

    @property
    def last_slope(self) -> float:
        """The slope beyond the last point: 0 for ``"constant"``, the last segment's for ``"linear"``."""
        return float(self.slopes[-1]) if self.extrapolation == "linear" else 0.0

    def __call__(self, values: np.ndarray) -> np.ndarray:
        values = np.asarray(values, dtype=float)
        inside = np.interp(values, self.x, self.y)
        return np.where(values > self.x[-1], self.y[-1] + self.last_slope * (values - self.x[-1]), inside)

    def derivative(self, values: np.ndarray) -> np.ndarray:
        """The slope of the segment [x_i, x_{i+1}) holding each value (the right derivative at a breakpoint), the
        extrapolation's from x_n on, and 0 below x_0 (where np.interp holds y_0; never asked, see the module)."""
        values = np.asarray(values, dtype=float)
        segment = np.clip(np.searchsorted(self.x, values, side="right") - 1, 0, self.slopes.size - 1)
        slopes = np.where(values >= self.x[-1], self.last_slope, self.slopes[segment])
        return np.where(values < self.x[0], 0.0, slopes)


def check_table(x_name: str, x, y_name: str, y, extrapolation_name: str, extrapolation: str, *,
                argument: str, nondecreasing: bool = False) -> None:
    """ParameterError naming the bad key unless the table (``x``, ``y``) of a law of ``argument`` ("ξ", "r") is one
    :class:`PiecewiseLinear` takes: at least 2 points, as many values as abscissae, all finite, the abscissae
    starting at 0 and strictly increasing, y ≥ 0 (``nondecreasing``: y never decreasing, y_0 = 0, the
    conditions (2.19) of p), and an extrapolation of EXTRAPOLATIONS that keeps y ≥ 0 beyond the last point."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.ndim != 1 or x.size < 2:
        raise ParameterError(x_name, x.tolist(), "expected a list of at least 2 numbers")
    if y.shape != x.shape:
        raise ParameterError(y_name, y.tolist(), f"expected {x.size} values, one for each point of {x_name} "
                                                 f"({x.size} points)")
    for name, values in ((x_name, x), (y_name, y)):
        if not np.isfinite(values).all():
            raise ParameterError(name, values.tolist(), "expected finite numbers")
    if x[0] != 0.0:
        raise ParameterError(x_name, x.tolist(), f"the table must start at {argument} = 0 (the law is asked from "
                                                 f"{argument} = 0 on)")
    if not (np.diff(x) > 0.0).all():
        i = int(np.flatnonzero(np.diff(x) <= 0.0)[0])
        raise ParameterError(x_name, x.tolist(), f"expected strictly increasing values ({x[i]:g} then {x[i + 1]:g})")
    if (y < 0.0).any():
        i = int(np.flatnonzero(y < 0.0)[0])
        raise ParameterError(y_name, y.tolist(), f"expected values >= 0 ({y[i]:g} at {argument} = {x[i]:g})")
    if nondecreasing and y[0] != 0.0:
        raise ParameterError(y_name, y.tolist(), f"expected 0 at {argument} = 0 (the law is 0 for {argument} <= 0)")
    if nondecreasing and (np.diff(y) < 0.0).any():
        i = int(np.flatnonzero(np.diff(y) < 0.0)[0])
        raise ParameterError(y_name, y.tolist(), f"expected non-decreasing values ({y[i]:g} then {y[i + 1]:g}): the "
                                                 f"law must be monotone")
    if extrapolation not in EXTRAPOLATIONS:
        raise ParameterError(extrapolation_name, extrapolation,
                             f"expected one of {', '.join(map(repr, EXTRAPOLATIONS))}")
    if extrapolation == "linear" and y[-1] < y[-2]:
        zero = x[-1] + y[-1] * (x[-1] - x[-2]) / (y[-2] - y[-1])
        raise ParameterError(extrapolation_name, extrapolation,
                             f"the last segment of {y_name} decreases, so the law would be negative beyond "
                             f"{argument} = {zero:g}; use \"constant\" or end the table with a segment that does "
                             f"not decrease")

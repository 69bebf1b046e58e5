"""N A0⁻¹ b of the condensed method's loads, with no solve for a load in the span of those already solved.

At every step the condensed method (:mod:`.condensed`) needs N A0⁻¹ b of the step's load b (its free
penetration is N A0⁻¹ b − g0). Loads affine in t (a constant part and a part proportional to t) lie in a
space of dimension two: once two of them are solved, N A0⁻¹ b of every later one is the combination of
the kept images given by its coordinates on an orthonormal basis of the loads solved, two products with
that basis and no solve with the factor. A checkpoint keeps the basis and the images (``kept``,
``restore``), so a resumed run solves what the uninterrupted one did.
"""

from __future__ import annotations

import numpy as np

from .base import norm


class SolvedSpan:
    """N A0⁻¹ b, reusing the solutions of earlier right-hand sides when b lies in their span.

    ``solve`` is b ↦ A0⁻¹ b (or what stands for it: the condensed method's split solve) and ``observe``
    gives N A0⁻¹ b from what it returns; the span keeps an orthonormal basis Q of the right-hand sides
    solved (rows, at most ``capacity``) and N A0⁻¹ of each, so a right-hand side in their span (loads
    proportional to t, for instance) costs two products with Q and no solve: about five passes over n
    entries instead of a solve with the factor.
    """

    def __init__(self, solve, observe, shape: tuple[int, int], capacity: int = 4, tolerance: float = 1e-13):
        """``shape``: (m, n) of N."""
        self._solve, self._observe, self.tolerance = solve, observe, tolerance
        self._basis = np.empty((capacity, shape[1]))  # orthonormal right-hand sides (the first ``size`` rows)
        self._images = np.empty((capacity, shape[0]))  # N A0⁻¹ of each
        self.size = 0
        self._support = None  # the support every right-hand side in the basis had (None: not one)
        self._restored_support = None  # that support as a checkpoint kept it (see ``restore``)
        self.solves = 0

    def kept(self) -> dict[str, np.ndarray]:
        """What the span carries from step to step: the basis, its images and the support they share."""
        arrays = {"basis": self._basis[: self.size], "images": self._images[: self.size]}
        return arrays if self._support is None else {**arrays, "support": self._support}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of an earlier span of the same operator (a resumed run): right-hand
        sides then cost what they did and give the same bits. The shared support is adopted at the
        next call whose support has the same positions (a new array of the resumed loop)."""
        self.size = arrays["basis"].shape[0]
        self._basis[: self.size], self._images[: self.size] = arrays["basis"], arrays["images"]
        self._restored_support = arrays.get("support")

    def __call__(self, b: np.ndarray, support: np.ndarray | None = None) -> np.ndarray:
        """N A0⁻¹ b; ``support``: the positions where b may be nonzero (None: anywhere). While every
        right-hand side solved had the same support, the basis vanishes off it, and the products
        with Q only run over it."""
        if self._restored_support is not None:
            if support is not None and np.array_equal(support, self._restored_support):
                self._support = support
            self._restored_support = None
        on = support if support is not None and support is self._support else slice(None)
        b_on = b[on]
        size = norm(b_on)
        basis = self._basis[: self.size, on]
        coefficients = basis @ b_on
        combination = coefficients @ self._images[: self.size]
        if size == 0.0:
            return combination
        remainder = b_on - coefficients @ basis
        rest = norm(remainder)
        if rest <= self.tolerance * size:
            return combination
        observed = self._observe(self._solve(b))
        self.solves += 1
        if self.size < self._basis.shape[0]:
            if self.size == 0:
                self._support = support
            elif support is not self._support:
                self._support = None  # the basis may no longer vanish off one support
            self._basis[self.size] = 0.0
            self._basis[self.size, on] = remainder / rest
            self._images[self.size] = (observed - combination) / rest
            self.size += 1
        return observed

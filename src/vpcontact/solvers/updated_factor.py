"""The LU factors of a dense matrix K₀, and the inverse of matrices that differ from it in a few columns.

The condensed method's Newton matrices K (m × m, dense, :mod:`.condensed_systems`) change, from one Newton
iteration to the next, in the columns of the contact nodes whose state changed. GMRES solves them preconditioned
by the inverse of an earlier one; this class holds that inverse without forming it: the LU factors of K₀
(``scipy.linalg.lu_factor``: (2/3) m³ flops, and each application two triangular solves, about the time of one
matrix–vector product with a formed inverse) and Sherman–Morrison–Woodbury corrections for the columns changed
since,

    K⁻¹ = K₀⁻¹ − X Yᵀ        (X, Y: m × r, r the columns corrected so far),

so that applying K⁻¹ costs two triangular solves and 4 m r flops more. Forming K₀⁻¹ itself (LAPACK's getri)
is what the kept inverse cost before: 38 s at m = 5,168 on one thread against 3.1 s for the LU, and applying
either costs the same (18 against 17 ms; docs/performance.md, "The condensed method without the m³ cliff").
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as la

from .errors import SingularMatrixError


class UpdatedFactor:
    """K⁻¹ for K = K₀ + (the columns changed since), applied as K₀⁻¹ − X Yᵀ (see the module's docstring)."""

    def __init__(self, K0: np.ndarray):
        """Factor K0 (overwritten: Fortran order, as ``NewtonSystems.matrix`` makes it); SingularMatrixError for
        an exactly zero pivot."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", la.LinAlgWarning)  # an exactly zero pivot: checked below
            self.lu, self.piv = la.lu_factor(K0, overwrite_a=True, check_finite=False)
        if np.any(np.diagonal(self.lu) == 0.0):
            raise SingularMatrixError("the condensed Newton matrix is singular (an exactly zero pivot)")
        m = self.lu.shape[0]
        self.X, self.Y = np.zeros((m, 0)), np.zeros((m, 0))

    @classmethod
    def restored(cls, lu: np.ndarray, piv: np.ndarray, X: np.ndarray, Y: np.ndarray) -> "UpdatedFactor":
        """The factor ``arrays()`` gave (a resumed run continues with the same bits)."""
        factor = cls.__new__(cls)
        factor.lu, factor.piv = np.array(lu, order="F"), np.array(piv)
        factor.X, factor.Y = np.array(X), np.array(Y)
        return factor

    def arrays(self) -> dict[str, np.ndarray]:
        """What ``restored`` needs."""
        return {"lu": self.lu, "piv": self.piv, "X": self.X, "Y": self.Y}

    @property
    def rank(self) -> int:
        """Columns of the correction X Yᵀ."""
        return self.X.shape[1]

    def apply(self, r: np.ndarray) -> np.ndarray:
        """K⁻¹ r for r of shape (m,) or (m, k)."""
        x = la.lu_solve((self.lu, self.piv), r, check_finite=False)
        return x - self.X @ (self.Y.T @ r) if self.rank else x

    def _apply_transposed(self, r: np.ndarray) -> np.ndarray:
        """K⁻ᵀ r = K₀⁻ᵀ r − Y Xᵀ r."""
        x = la.lu_solve((self.lu, self.piv), r, trans=1, check_finite=False)
        return x - self.Y @ (self.X.T @ r) if self.rank else x

    def update(self, U: np.ndarray, changed: np.ndarray) -> bool:
        """Follow K → K + U E_cᵀ (the columns ``changed`` of K changed by U, m × k): by the Woodbury formula
        K⁻¹ ← K⁻¹ − K⁻¹U (I + E_cᵀ K⁻¹U)⁻¹ E_cᵀ K⁻¹, appended to X Yᵀ (2 solves with k columns each). False, and
        nothing changed, when the capacitance matrix I + E_cᵀ K⁻¹U is singular to working precision (the new K
        is, or nearly: see ``NewtonSystems._follow_changes_of_state``) or the correction is not finite."""
        PU = self.apply(U)
        capacitance = np.eye(changed.size) + PU[changed]
        if not np.all(np.isfinite(capacitance)):
            return False
        # singular to working precision: its smallest singular value at the rounding level of the sum I + E_cᵀK⁻¹U
        # (relative to its largest one, or to the terms summed: a 1 × 1 capacitance 1 + (−1 + δ) has a condition
        # number of 1 whatever δ)
        singular_values = np.linalg.svd(capacitance, compute_uv=False)
        scale = max(singular_values[0], 1.0 + np.linalg.norm(PU[changed], 2))
        if not singular_values[-1] > changed.size * np.finfo(float).eps * scale:
            return False
        E = np.zeros((self.lu.shape[0], changed.size))
        E[changed, np.arange(changed.size)] = 1.0
        rows = self._apply_transposed(E)  # (E_cᵀ K⁻¹)ᵀ, m × k
        try:
            with warnings.catch_warnings():  # the conditioning is checked above (LAPACK's estimate of it differs)
                warnings.simplefilter("ignore", la.LinAlgWarning)
                correction = la.solve(capacitance, rows.T, check_finite=False)  # C⁻¹ E_cᵀ K⁻¹, k × m
        except (la.LinAlgError, ValueError):
            return False
        if not np.all(np.isfinite(correction)):
            return False
        self.X, self.Y = np.hstack([self.X, PU]), np.hstack([self.Y, correction.T])
        return True

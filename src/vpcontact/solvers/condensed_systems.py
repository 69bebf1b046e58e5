"""The condensed method's Newton systems K z = r on the m contact nodes, and the inverse kept across them.

K = diag(1_ℐ) + S diag(w) (:class:`NewtonSystems`) is dense, m × m. Below KRYLOV_FROM contact nodes
(:mod:`.condensed`) each system is solved by a dense LU; from there on by GMRES preconditioned by the
inverse of an earlier iteration's K, kept across Newton iterations and time steps, followed by
Sherman–Morrison–Woodbury updates through the nodes' changes of state (O(m² k) for k nodes instead of
O(m³) for a new inverse), and made again only when GMRES needs more than MAX_KRYLOV_ITERATIONS with it.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as la

from .errors import NotConvergedError, SingularMatrixError
from .gmres import gmres

#: Nodes whose change of state the kept inverse follows at once by a low-rank update (O(m² k) each time,
#: against O(m³) for a new inverse: 64 of 570 nodes cost about a fifth of one).
MAX_STATE_UPDATE = 64
#: GMRES iterations at most with the inverse of an earlier Newton matrix; a system that needs more is
#: solved again with the inverse of its own matrix (which then serves the next systems).
MAX_KRYLOV_ITERATIONS = 20
#: Relative residual ‖r − K z‖ ≤ KRYLOV_TOLERANCE ‖r‖ at which GMRES stops: the directions are those of
#: the dense LU to about this relative accuracy, far below what changes a Newton iteration (the
#: condensed results agree with the dense path's to 1e-12, the Newton iterations are the same:
#: tests/test_condensed_krylov.py).
KRYLOV_TOLERANCE = 1e-12
#: GMRES also stops at ‖r − K z‖ ≤ KRYLOV_TOLERANCE ‖r‖ + KRYLOV_ROUNDING ‖K‖ ‖z‖: the rounding level of
#: the product K z (m-term sums; a normwise backward error of 64 ε), where a nearly singular K stops (a
#: body held only by contact, its separated nodes held by the Jacobian's regularization alone:
#: cond(K) ≈ 1e12, and the dense LU's own relative residual is 3e-5).
KRYLOV_ROUNDING = 64 * np.finfo(float).eps


class NewtonSystems:
    """The condensed Newton systems K z = r, in node order: node i's unknown z_i is Δd_i when it is
    inactive and Δλ_i when it is active (at the limit), its column of K is e_i + S_i (T_i − c0) or S_i:

        K = diag(1_ℐ) + S diag(w),    w_i = T_i − c0 (i ∈ ℐ),  w_i = 1 (i ∈ 𝒜).

    ``solve_direct`` factors K (an LU, O(m³)); ``solve_iterative`` runs GMRES on K applied as
    z ↦ 1_ℐ z + S (w z) (O(m²) per iteration, S being formed), preconditioned by the inverse of the
    K of an earlier iteration (from its LU), kept across Newton iterations and time steps, updated by a
    low-rank formula for the nodes that change state since (``_follow_changes_of_state``), and made again
    only when GMRES needed more than MAX_KRYLOV_ITERATIONS with it (the system is then solved with the
    inverse of its own K).

    Why node order: the dense path's layout [inactive columns | active columns] is a permutation that
    changes with the active set, so a factor made for one layout is no preconditioner for another. In
    node order a change of state of k nodes, or of the compliance tangent T at k nodes, changes k
    columns of K and nothing else: K = K₀ + U Vᵀ with U, V of k columns, K₀⁻¹ K = I + K₀⁻¹ U Vᵀ, and
    GMRES preconditioned by K₀ converges in at most k + 1 iterations whatever the layouts of K and K₀
    (fewer when the changes are small: the tangents of nodes in compliance drift from step to step).
    On the quarter ball the inverse of the first Newton matrix (no node in contact yet) serves every
    Newton iteration of the run, at about 6 GMRES iterations each; on the paper's half disc at 1/512, at
    about 5, for β = −1 too (its nodes reach the limit one after another: the updates follow them, where
    without them GMRES needed 9.2 iterations and 22 new inverses; docs/performance.md).
    """

    def __init__(self, S: np.ndarray, S_row_sums: np.ndarray, max_iterations: int = MAX_KRYLOV_ITERATIONS):
        self.S, self._S_row_sum = S, S_row_sums.max(initial=0.0)  # the largest row sum of |S|
        self.max_iterations = max_iterations
        self._inverse = None  # K⁻¹ of an earlier iteration's K, updated for the changes of state since
        self._kept = None  # (1_ℐ, w) of the K the kept inverse is of, at the nodes whose state it follows
        self.updates = 0  # low-rank updates of the kept inverse for changes of state
        self.iterations = 0  # GMRES iterations, in total
        self.factorizations = 0  # LU factorizations of Newton matrices (dense solves included)

    def kept(self) -> dict[str, np.ndarray]:
        """What the systems carry from step to step: the kept inverse and the (1_ℐ, w) it follows."""
        if self._inverse is None:
            return {}
        return {"inverse": self._inverse, "inactive": self._kept[0], "w": self._kept[1]}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of earlier systems of the same S (a resumed run)."""
        if "inverse" in arrays:
            self._inverse = np.array(arrays["inverse"], order="F")
            self._kept = (arrays["inactive"].copy(), arrays["w"].copy())

    def matrix(self, inactive: np.ndarray, w: np.ndarray) -> np.ndarray:
        """K = diag(1_ℐ) + S diag(w) (Fortran order: LAPACK factors it in place)."""
        K = np.multiply(self.S, w[None, :], order="F")
        K[np.diag_indices_from(K)] += inactive
        return K

    def solve_direct(self, inactive: np.ndarray, w: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """z = K⁻¹ r by a dense LU of K."""
        self.factorizations += 1
        try:
            return np.linalg.solve(self.matrix(inactive, w), rhs)
        except np.linalg.LinAlgError as error:
            raise SingularMatrixError(f"the condensed Newton matrix is singular ({error})") from None

    def solve_iterative(self, inactive: np.ndarray, w: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """z with ‖r − K z‖ ≤ KRYLOV_TOLERANCE ‖r‖ + KRYLOV_ROUNDING ‖K‖ ‖z‖ by GMRES, preconditioned by the
        kept inverse, or by the inverse of this K when the kept one needs more than ``max_iterations`` (or
        there is none). NotConvergedError when even that one does not reach the tolerance (an LU too
        unstable for GMRES to correct in so few iterations); a K or r that is not finite: z is not finite,
        as the dense solve's (the Newton iteration reports iterates that are not finite)."""
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(rhs))):
            return np.full_like(rhs, np.nan)

        def K(z):
            return inactive * z + self.S @ (w * z)

        norm_K = 1.0 + np.abs(w).max(initial=0.0) * self._S_row_sum  # ≥ ‖K‖₁ and ‖K‖∞ (S symmetric), so ≥ ‖K‖₂
        floor = KRYLOV_ROUNDING * norm_K
        if self._inverse is not None:
            self._follow_changes_of_state(inactive, w)
            solution = self._gmres(K, rhs, floor)
            if solution.converged:
                return solution.x
        self._factorize(inactive, w)
        solution = self._gmres(K, rhs, floor)
        if not solution.converged:
            raise NotConvergedError(f"GMRES preconditioned by the inverse of the condensed Newton matrix itself "
                                    f"did not reach the relative residual {KRYLOV_TOLERANCE:g} (nor the rounding "
                                    f"level of the matrix) in {self.max_iterations} iterations")
        return solution.x

    def _factorize(self, inactive: np.ndarray, w: np.ndarray) -> None:
        """Keep the inverse of K, from its LU factors (SingularMatrixError for an exactly zero pivot, as
        the dense solve): applying it is one matrix–vector product, faster than the two triangular
        solves with the factors, and as good a preconditioner."""
        self.factorizations += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", la.LinAlgWarning)  # an exactly zero pivot: checked below
            lu, piv = la.lu_factor(self.matrix(inactive, w), overwrite_a=True, check_finite=False)
        if np.any(np.diagonal(lu) == 0.0):
            self._inverse = None
            raise SingularMatrixError("the condensed Newton matrix is singular (an exactly zero pivot)")
        self._inverse, _ = la.lapack.dgetri(lu, piv, overwrite_lu=True)
        self._kept = (inactive.astype(float), w.copy())

    def _follow_changes_of_state(self, inactive: np.ndarray, w: np.ndarray) -> None:
        """Update the kept inverse for the nodes whose state (inactive or at the limit) changed since it was
        made: their columns of K changed, K = K₀ + U E_cᵀ with U = (K − K₀)[:, c], and by the Sherman–Morrison–
        Woodbury formula K⁻¹ = K₀⁻¹ − K₀⁻¹U (I + E_cᵀ K₀⁻¹ U)⁻¹ E_cᵀ K₀⁻¹: O(m² k) for k nodes instead of
        O(m³) for a new inverse. Nodes reach the rigid limit one after another (β = −1 at 1/512: 22 new
        inverses without this); GMRES is then left with the tangents' drift only, as when no state
        changes. Up to MAX_STATE_UPDATE nodes at once; more, or a capacitance matrix that is singular to
        working precision, and the inverse stays as it is (GMRES, and a new inverse if it needs too many
        iterations, see ``solve_iterative``)."""
        kept_inactive, kept_w = self._kept
        changed = np.flatnonzero(inactive != kept_inactive)
        if changed.size == 0 or changed.size > MAX_STATE_UPDATE:
            return
        U = self.S[:, changed] * (w[changed] - kept_w[changed])
        U[changed, np.arange(changed.size)] += inactive[changed] - kept_inactive[changed]
        PU = self._inverse @ U
        capacitance = np.eye(changed.size) + PU[changed]
        # singular with K: when every contact node of a body held only by contact is separated (w = −c0 on all),
        # K = I − S c0 annihilates N r for each free rigid motion r (S c0 N r = N r, as A r = 0), and cond(K) is
        # 1e14–1e16 in float64. The step problem leaves that motion free there; an inverse of K cannot be
        # followed, the kept one stays and GMRES, whose residual is measured, decides (see solve_iterative).
        if not np.linalg.cond(capacitance) < 1.0 / np.finfo(float).eps:
            return
        try:
            with warnings.catch_warnings():  # the conditioning is checked above (LAPACK's estimate of it differs)
                warnings.simplefilter("ignore", la.LinAlgWarning)
                correction = la.solve(capacitance, self._inverse[changed], check_finite=False)
        except (la.LinAlgError, ValueError):
            return
        if not np.all(np.isfinite(correction)):
            return
        self._inverse -= PU @ correction
        kept_inactive[changed], kept_w[changed] = inactive[changed], w[changed]
        self.updates += 1

    def _gmres(self, K, rhs: np.ndarray, floor: float):
        """GMRES preconditioned by the kept inverse, at most ``max_iterations`` iterations (counted)."""
        solution = gmres(K, self._inverse.__matmul__, rhs, KRYLOV_TOLERANCE, self.max_iterations, floor)
        self.iterations += solution.iterations
        return solution

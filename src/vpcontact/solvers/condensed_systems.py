"""The condensed method's Newton systems K z = r on the m contact nodes, and the factor kept across them.

K = diag(1_ℐ) + S diag(w) (:class:`NewtonSystems`) is dense, m × m. Below KRYLOV_FROM contact nodes
(:mod:`.condensed`) each system is solved by a dense LU; from there on by GMRES preconditioned by the
LU factors of an earlier iteration's K, kept across Newton iterations and time steps, with
Sherman–Morrison–Woodbury corrections for the nodes' changes of state since (:class:`~.updated_factor.UpdatedFactor`:
O(m² k) for k nodes instead of O(m³) for a new factor), and made again only when GMRES needs more than
MAX_KRYLOV_ITERATIONS with it.
"""

from __future__ import annotations

import numpy as np

from .errors import NotConvergedError, SingularMatrixError
from .gmres import gmres
from .updated_factor import UpdatedFactor

#: Nodes whose change of state the kept factor follows at once by a low-rank correction (O(m² k) each time,
#: against O(m³) for a new factor).
MAX_STATE_UPDATE = 64
#: The corrections' rank at most, as a share of m: applying them costs 4 m r flops against the 2 m² of the two
#: triangular solves; beyond it a change of state is left to GMRES (and a new factor if it needs too many
#: iterations).
MAX_RANK_SHARE = 0.25
#: GMRES iterations at most with the factor of an earlier Newton matrix; a system that needs more is
#: solved again with the factor of its own matrix (which then serves the next systems).
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
    z ↦ 1_ℐ z + S (w z) (O(m²) per iteration, S being formed), preconditioned by the LU factors of the
    K of an earlier iteration, kept across Newton iterations and time steps, corrected by a low-rank
    formula for the nodes that change state since (``_follow_changes_of_state``), and made again only
    when GMRES needed more than MAX_KRYLOV_ITERATIONS with them (the system is then solved with the
    factors of its own K).

    Why node order: the dense path's layout [inactive columns | active columns] is a permutation that
    changes with the active set, so a factor made for one layout is no preconditioner for another. In
    node order a change of state of k nodes, or of the compliance tangent T at k nodes, changes k
    columns of K and nothing else: K = K₀ + U Vᵀ with U, V of k columns, K₀⁻¹ K = I + K₀⁻¹ U Vᵀ, and
    GMRES preconditioned by K₀ converges in at most k + 1 iterations whatever the layouts of K and K₀
    (fewer when the changes are small: the tangents of nodes in compliance drift from step to step).
    On the quarter ball the factor of the first Newton matrix (no node in contact yet) serves every
    Newton iteration of the run, at about 6 GMRES iterations each; on the paper's half disc at 1/512, at
    about 5, for β = −1 too (its nodes reach the limit one after another: the updates follow them, where
    without them GMRES needed 9.2 iterations and 22 new factors; docs/performance.md).
    """

    def __init__(self, S: np.ndarray, S_row_sums: np.ndarray, max_iterations: int = MAX_KRYLOV_ITERATIONS):
        self.S, self._S_row_sum = S, S_row_sums.max(initial=0.0)  # the largest row sum of |S|
        self.max_iterations = max_iterations
        self._factor = None  # K⁻¹ of an earlier iteration's K (UpdatedFactor), corrected for the changes of state since
        self._kept = None  # (1_ℐ, w) of the K the kept factor inverts, at the nodes whose state it follows
        self.updates = 0  # low-rank updates of the kept factor for changes of state
        self.iterations = 0  # GMRES iterations, in total
        self.factorizations = 0  # LU factorizations of Newton matrices (dense solves included)

    def kept(self) -> dict[str, np.ndarray]:
        """What the systems carry from step to step: the kept factor (its LU and corrections) and the (1_ℐ, w)
        it follows."""
        if self._factor is None:
            return {}
        return {**{f"factor_{key}": value for key, value in self._factor.arrays().items()},
                "inactive": self._kept[0], "w": self._kept[1]}

    def restore(self, arrays: dict[str, np.ndarray]) -> None:
        """Continue from ``kept()`` of earlier systems of the same S (a resumed run)."""
        if "factor_lu" in arrays:
            self._factor = UpdatedFactor.restored(*(arrays[f"factor_{key}"] for key in ("lu", "piv", "X", "Y")))
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
        kept factor, or by the factor of this K when the kept one needs more than ``max_iterations`` (or
        there is none). NotConvergedError when even that one does not reach the tolerance (an LU too
        unstable for GMRES to correct in so few iterations); a K or r that is not finite: z is not finite,
        as the dense solve's (the Newton iteration reports iterates that are not finite)."""
        if not (np.all(np.isfinite(w)) and np.all(np.isfinite(rhs))):
            return np.full_like(rhs, np.nan)

        def K(z):
            return inactive * z + self.S @ (w * z)

        norm_K = 1.0 + np.abs(w).max(initial=0.0) * self._S_row_sum  # ≥ ‖K‖₁ and ‖K‖∞ (S symmetric), so ≥ ‖K‖₂
        floor = KRYLOV_ROUNDING * norm_K
        if self._factor is not None:
            self._follow_changes_of_state(inactive, w)
            solution = self._gmres(K, rhs, floor)
            if solution.converged:
                return solution.x
        self._factorize(inactive, w)
        solution = self._gmres(K, rhs, floor)
        if not solution.converged:
            raise NotConvergedError(f"GMRES preconditioned by the LU factors of the condensed Newton matrix itself "
                                    f"did not reach the relative residual {KRYLOV_TOLERANCE:g} (nor the rounding "
                                    f"level of the matrix) in {self.max_iterations} iterations")
        return solution.x

    def _factorize(self, inactive: np.ndarray, w: np.ndarray) -> None:
        """Keep the LU factors of K (SingularMatrixError for an exactly zero pivot, as the dense solve)."""
        self.factorizations += 1
        self._factor = None  # release the earlier factor first
        self._factor = UpdatedFactor(self.matrix(inactive, w))
        self._kept = (inactive.astype(float), w.copy())

    def _follow_changes_of_state(self, inactive: np.ndarray, w: np.ndarray) -> None:
        """Correct the kept factor for the nodes whose state (inactive or at the limit) changed since it was
        made: their columns of K changed, K = K₀ + U E_cᵀ with U = (K − K₀)[:, c] (:meth:`UpdatedFactor.update`:
        O(m² k) for k nodes instead of O(m³) for a new factor). Nodes reach the rigid limit one after another
        (β = −1 at 1/512: 22 new factors without this); GMRES is then left with the tangents' drift only, as
        when no state changes. Up to MAX_STATE_UPDATE nodes at once, while the corrections' rank stays within
        MAX_RANK_SHARE of m; more, or a capacitance matrix that is singular to working precision, and the
        factor stays as it is (GMRES, and a new factor if it needs too many iterations, see
        ``solve_iterative``)."""
        kept_inactive, kept_w = self._kept
        changed = np.flatnonzero(inactive != kept_inactive)
        m = inactive.size
        if changed.size == 0 or changed.size > MAX_STATE_UPDATE or \
                self._factor.rank + changed.size > max(MAX_STATE_UPDATE, MAX_RANK_SHARE * m):
            return
        U = self.S[:, changed] * (w[changed] - kept_w[changed])
        U[changed, np.arange(changed.size)] += inactive[changed] - kept_inactive[changed]
        # singular with K: when every contact node of a body held only by contact is separated (w = −c0 on all),
        # K = I − S c0 annihilates N r for each free rigid motion r (S c0 N r = N r, as A r = 0), and cond(K) is
        # 1e14–1e16 in float64. The step problem leaves that motion free there; a factor of K cannot be
        # followed, the kept one stays and GMRES, whose residual is measured, decides (see solve_iterative).
        if self._factor.update(U, changed):
            kept_inactive[changed], kept_w[changed] = inactive[changed], w[changed]
            self.updates += 1

    def _gmres(self, K, rhs: np.ndarray, floor: float):
        """GMRES preconditioned by the kept factor, at most ``max_iterations`` iterations (counted)."""
        solution = gmres(K, self._factor.apply, rhs, KRYLOV_TOLERANCE, self.max_iterations, floor)
        self.iterations += solution.iterations
        return solution
